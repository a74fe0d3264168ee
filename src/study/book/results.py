"""The build's results file: every number the book reports, with its 95 % interval and what produced it, and
every verdict with the inputs it was decided from.

Each chapter publishes its typed result (``study.book.publish``); when the book builder runs the chapter it
names a file of its own in the chapter's ticket (its *part*, ``study.core.ticket``), and the chapter's numbers are
written there
(:func:`write_part`). The builder merges the parts of the book's chapters into one file,
``_build/results.json`` (:func:`merge`), which the summary page reads back into the chapters' own types
(``study.report.reported.Reported.read``) and ``study results --compare OTHER`` compares with another
build's (:func:`compare`). A chapter run by hand, outside the builder, writes nothing.

The file (:data:`FORMAT`)::

    {"format": "study.results/2", "preset": "paper",
     "numbers": [{"name", "chapter", "value", "lo", "hi", "method", "what", "unit", "paper", "verdict",
                  "decision", "source", "signed"}, ...],
     "verdicts": [{"name", "chapter", "what", "verdict", "decision", "source"}, ...]}

``decision`` is a verdict's stored form (``study.report.verdicts``), from which it can be decided again
(:func:`recompute`). Files of the first format (``study.results/1``, verdicts among the numbers with
``unit = "verdict"``) still load.
"""

from __future__ import annotations

import json
import math
import re
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from study.core import ticket
from study.core.cache import write_text_atomic
from study.core.errors import ConfigError, DataError, check_file
from study.report import verdicts
from study.report.reported import Leaf, Number, Verdict

FORMAT = "study.results/2"
"""The results file's format."""
OLD_FORMATS = ("study.results/1",)
"""Formats that still load."""
RENAMED: tuple[tuple[str, str], ...] = (
    (r"\blstm_(positions|velocity|exact_trained)\b", r"peephole_\1"),
)
"""Names that changed with the second format, as (pattern, replacement) regular expressions: a file of the first
format is read under today's names (its names, and the names its sources cite), so two builds still pair up. The
motion table's peephole-LSTM learners were called ``lstm_*``, which read as ``torch.nn.LSTM``."""
FILE = Path("_build") / "results.json"
"""Where the builder writes the merged results, relative to the book's root."""


# ---------------------------------------------------------------------------------------------
# Leaves to JSON and back


def _to_json(name: str, leaf: Leaf) -> dict[str, Any]:
    chapter = name.split(".")[0]
    decision = None if leaf.decision is None else leaf.decision.inputs
    if isinstance(leaf, Verdict):
        return {"name": name, "chapter": chapter, "what": leaf.what, "verdict": leaf.verdict,
                "decision": decision, "source": dict(leaf.source)}
    return {"name": name, "chapter": chapter, "value": leaf.value, "lo": leaf.lo, "hi": leaf.hi,
            "method": leaf.method, "what": leaf.what, "unit": leaf.unit, "paper": leaf.paper,
            "verdict": leaf.verdict, "decision": decision, "source": dict(leaf.source), "signed": leaf.signed}


def _decision(entry: dict[str, Any], path: Path) -> verdicts.Decision | None:
    stored = entry.get("decision")
    if stored is None:
        if entry.get("verdict") is not None:
            raise DataError(f"results file {path}: {entry.get('name')!r} has a verdict without the inputs it was "
                            "decided from; rebuild the book")
        return None
    try:
        d = verdicts.from_inputs(stored)
    except ConfigError:
        raise DataError(f"results file {path}: {entry.get('name')!r} has a malformed decision; rebuild the book") from None
    if entry.get("verdict") != d.verdict:
        raise DataError(f"results file {path}: {entry.get('name')!r} is stored as {entry.get('verdict')!r} but its "
                        f"inputs decide {d.verdict!r}; rebuild the book")
    return d


def _from_json(entry: Any, path: Path) -> tuple[str, Leaf]:
    if not isinstance(entry, dict) or not isinstance(entry.get("name"), str):
        raise DataError(f"results file {path}: an entry without a name; rebuild the book")
    name = entry["name"]
    try:
        decision = _decision(entry, path)
        if entry.get("unit") == "verdict" or "value" not in entry:  # a verdict (in the first format, a NaN number)
            if decision is None:
                raise DataError(f"results file {path}: verdict {name!r} has no decision; rebuild the book")
            return name, Verdict(decision, str(entry.get("what", "")), dict(entry.get("source") or {}))
        return name, Number(float(entry["value"]), float(entry["lo"]), float(entry["hi"]), str(entry["method"]),
                            str(entry.get("what", "")), str(entry.get("unit", "fraction")), entry.get("paper"),
                            decision, dict(entry.get("source") or {}), bool(entry.get("signed", False)))
    except (KeyError, TypeError, ValueError) as e:
        raise DataError(f"results file {path}: {name!r} is malformed ({type(e).__name__}: {e}); rebuild the book") from None


def _leaves(obj: Any, path: Path) -> dict[str, Leaf]:
    fmt = obj.get("format") if isinstance(obj, dict) else None
    if fmt not in (FORMAT, *OLD_FORMATS) or not isinstance(obj.get("numbers"), list):
        raise DataError(f"results file {path}: not a {FORMAT} file; rebuild the book to write one")
    entries = list(obj["numbers"]) + list(obj.get("verdicts") or [])
    if fmt in OLD_FORMATS:
        entries = [_renamed(e) for e in entries]
    return dict(_from_json(e, path) for e in entries)


def _renamed(obj: Any) -> Any:
    """``obj`` with every string it holds (names, sources) under today's names (:data:`RENAMED`)."""
    if isinstance(obj, str):
        for pattern, new in RENAMED:
            obj = re.sub(pattern, new, obj)
        return obj
    if isinstance(obj, dict):
        return {k: (v if k in ("what", "method") else _renamed(v)) for k, v in obj.items()}
    if isinstance(obj, list):
        return [_renamed(v) for v in obj]
    return obj


def dumps(leaves: Iterable[tuple[str, Leaf]], **header: Any) -> str:
    """The results file of ``leaves`` (name, leaf), with ``header`` fields (``preset``, ``chapter``)."""
    numbers, found = [], []
    for name, leaf in leaves:
        (found if isinstance(leaf, Verdict) else numbers).append(_to_json(name, leaf))
    body = {"format": FORMAT, **header, "numbers": numbers, "verdicts": found}
    return json.dumps(body, indent=1, allow_nan=True) + "\n"


# ---------------------------------------------------------------------------------------------
# Parts, the merged file


def write_part(chapter: str, leaves: Iterable[tuple[str, Leaf]]) -> Path | None:
    """Write a chapter's numbers to the results file its ticket names (``study.core.ticket``), if the builder
    gave it one; returns its path. A chapter executed inside another one's kernel (the tutorial re-running the
    data chapter with other parameters) writes nothing: the ticket, and its file, are the other chapter's."""
    t = ticket.current()
    if not t.results or (t.chapter and t.chapter != chapter):
        return None
    path = Path(t.results)
    write_text_atomic(path, dumps(leaves, chapter=chapter))
    return path


def merge(parts: list[Path], out: Path, preset: str) -> Path:
    """Merge the chapters' parts (those that exist, in order) into one results file ``out`` (atomically).

    Raises :class:`DataError` where two parts report the same name (one would silently replace the other)."""
    leaves: dict[str, Leaf] = {}
    where: dict[str, Path] = {}
    for part in parts:
        if not part.is_file():
            continue
        for name, leaf in load(part).items():
            if name in where:
                raise DataError(f"results part {part}: {name} is also reported by {where[name]}; each number "
                                "belongs to one chapter: execute again the one that no longer reports it "
                                f"(`study book --only {where[name].stem}` or `--only {part.stem}`)")
            leaves[name], where[name] = leaf, part
    write_text_atomic(out, dumps(leaves.items(), preset=preset))
    return out


def load(path: str | Path) -> dict[str, Leaf]:
    """The numbers and verdicts of a results file, by name; :class:`DataError` naming the file if it is
    missing or bad."""
    p = check_file(path, "results file", "build the book (study book) to write _build/results.json")
    try:
        obj = json.loads(p.read_text())
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as e:
        raise DataError(f"results file {p}: cannot be read ({type(e).__name__}); rebuild the book") from None
    return _leaves(obj, p)


def recompute(leaves: Mapping[str, Leaf]) -> list[str]:
    """The names (in order) of the leaves whose verdict is not what their inputs decide: empty for a sound
    file (:func:`load` already refuses a file whose stored verdict words disagree with their inputs)."""
    return [name for name, leaf in leaves.items()
            if leaf.decision is not None and verdicts.decide(leaf.decision.inputs) != leaf.verdict]


# ---------------------------------------------------------------------------------------------
# Two builds


@dataclass(frozen=True)
class Moved:
    """A number present in both builds, with whether each lands inside the other's interval."""

    name: str
    a: Number
    b: Number

    @property
    def moved(self) -> bool:
        """True if either build's value lies outside the other's interval."""
        return not (self.a.interval.contains(self.b.value) and self.b.interval.contains(self.a.value))


@dataclass(frozen=True)
class Comparison:
    """Two builds side by side."""

    pairs: list[Moved]
    """The numbers both hold, in name order."""
    only_a: list[str]
    """Names only the first holds."""
    only_b: list[str]
    """Names only the second holds."""
    verdicts: list[tuple[str, str, str]]
    """(name, first's verdict, second's) for each verdict the two builds decide differently."""

    @property
    def moved(self) -> list[Moved]:
        return [m for m in self.pairs if m.moved]


def compare(a: Mapping[str, Leaf], b: Mapping[str, Leaf]) -> Comparison:
    """Pair the numbers and verdicts of two builds."""
    common = sorted(set(a) & set(b))
    pairs = [Moved(k, a[k], b[k]) for k in common if isinstance(a[k], Number) and isinstance(b[k], Number)
             and not (math.isnan(a[k].value) or math.isnan(b[k].value))]
    changed = [(k, a[k].verdict, b[k].verdict) for k in common
               if a[k].decision is not None and b[k].decision is not None and a[k].verdict != b[k].verdict]
    return Comparison(pairs, sorted(set(a) - set(b)), sorted(set(b) - set(a)), changed)  # type: ignore[arg-type]
