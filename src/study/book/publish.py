"""One call that hands a chapter's typed result to its page and to the results file.

A chapter's computation returns a frozen dataclass (``study.chapters.table1.Table1`` and the like) with a
``numbers`` field, a :class:`~study.report.reported.Reported` tree of the numbers and verdicts it reports.
``publish(result)``, the chapter's one hidden line:

- glues every number and verdict of ``result.numbers`` under its name less the chapter's
  (``table1.xyz.paper_way`` as ``xyz.paper_way``), formatted as the book writes it (``70.8 % [69.6, 72.0]``),
  and a number's verdict, if it has one, as ``xyz.paper_way.verdict``;
- glues every other field and public property of ``result`` that is text (a sentence the result builds), a
  :class:`~study.report.text.Table` or :class:`~study.report.text.Bullets` (as Markdown) or a plain number (raw, so the page may format it:
  ``{glue:text}`n_params:d```); figure data, configs and run tables are left to the page's visible code;
- writes the numbers to the chapter's part of the results file when the book builder runs the chapter
  (``study.book.results.write_part``).

So a page's prose and tables come from the result, and its visible cells hold only the code a reader learns from.
"""

from __future__ import annotations

import dataclasses
import numbers as _numbers
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from study.book import results
from study.core.errors import ConfigError
from study.report.reported import Leaf, Number, Reported
from study.report.text import Bullets, Table, fmt


def glued(result: Any) -> Iterator[tuple[str, Any]]:
    """(name, value) of everything :func:`publish` glues for ``result``, numbers first; :class:`ConfigError` if
    two share a name."""
    numbers = _numbers_of(result)
    seen: set[str] = set()
    prefix = numbers.CHAPTER + "."
    for name, leaf in numbers.entries():
        short = name.removeprefix(prefix)
        yield _once(seen, short), fmt(leaf)
        if isinstance(leaf, Number) and leaf.decision is not None:
            yield _once(seen, f"{short}.verdict"), leaf.verdict
    names = [f.name for f in dataclasses.fields(result) if f.name != "numbers"]
    names += [n for n, v in vars(type(result)).items() if isinstance(v, property) and not n.startswith("_")]
    for name in names:
        value = getattr(result, name)
        if isinstance(value, (Table, Bullets)):
            yield _once(seen, name), value
        elif isinstance(value, str) or (isinstance(value, _numbers.Real) and not isinstance(value, bool)):
            yield _once(seen, name), value


def _once(seen: set[str], name: str) -> str:
    if name in seen:
        raise ConfigError(f"publish: two fields of the result are glued as {name!r}; rename one")
    seen.add(name)
    return name


def _numbers_of(result: Any) -> Reported:
    numbers = getattr(result, "numbers", None)
    if not dataclasses.is_dataclass(result) or not isinstance(numbers, Reported) or not numbers.CHAPTER:
        raise ConfigError(f"publish: got {type(result).__name__}; pass a chapter's result, a dataclass whose "
                          "'numbers' field is a Reported tree with its CHAPTER set")
    return numbers


def leaves(result: Any) -> list[tuple[str, Leaf]]:
    """The numbers and verdicts ``result`` reports, with their full names."""
    return list(_numbers_of(result).entries())


def publish(result: Any) -> Path | None:
    """Glue ``result``'s numbers, sentences and tables for its page, and write its numbers to the results file
    when the builder runs the chapter; returns the part written, if any."""
    from IPython.display import Markdown
    from myst_nb import glue

    for name, value in glued(result):
        glue(name, Markdown(value.markdown()) if isinstance(value, (Table, Bullets)) else value, display=False)
    return results.write_part(_numbers_of(result).CHAPTER, leaves(result))
