"""What a chapter reports, typed: numbers with their intervals, verdicts with their inputs, and their names.

A chapter's computation (``study.chapters.table1.compute`` and the like) returns a frozen dataclass that
holds, among its other fields, a tree of :class:`Reported` dataclasses whose leaves are :class:`Number` (an
estimate with its 95 % interval and what it is) and :class:`Verdict` (a decision that is not one number's).
A leaf's name in the results file is its path in that tree, defined once, by the type: the field names
joined by dots (a field may take another name with ``named("...")``; a ``dict`` field's keys are path
segments too), under the chapter's name (:attr:`Reported.CHAPTER` of the root). So

    @dataclass(frozen=True)
    class Row(Reported):
        mean: Number
        verdict: Verdict

    @dataclass(frozen=True)
    class Numbers(Reported):
        CHAPTER = "table1"
        rows: dict[str, Row] = named("")     # the keys come straight after the chapter: "table1.xyz.mean"

writes ``table1.xyz.mean`` and ``table1.xyz.verdict`` for ``Numbers(rows={"xyz": Row(...)})``, and
:meth:`Reported.read` builds the same typed tree back from a results file (the summary page reads other
chapters' numbers so, never by a name it builds): a missing number is an error that names its chapter.
"""

from __future__ import annotations

import dataclasses
import fnmatch
import math
import re
import types
import typing
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field
from typing import Any, ClassVar, TypeVar

from study.core.errors import ConfigError, StudyError
from study.learn.metrics import Interval
from study.report import verdicts
from study.report.verdicts import Decision, Margin

UNITS_WITHOUT_INTERVAL = ("count", "setting")
"""Units whose numbers are exact by nature."""


@dataclass(frozen=True)
class Number:
    """One number of the book: an estimate, its 95 % interval, what it is and, against the paper, its verdict."""

    value: float
    """The estimate (accuracies as fractions)."""
    lo: float
    """Lower end of its 95 % interval (``value`` when it has none: a count, a setting)."""
    hi: float
    """Upper end of its 95 % interval."""
    method: str
    """How the interval was computed, in words."""
    what: str = ""
    """What the number is, in words."""
    unit: str = "fraction"
    """``"fraction"`` (shown as a percentage), ``"count"``, or a physical unit (``"s"``, ``"m"``)."""
    paper: float | None = None
    """The paper's number it is compared with, if any."""
    decision: Decision | None = None
    """Its verdict against the paper (a number or an order rule), with the inputs it is decided from."""
    source: Mapping[str, Any] = field(default_factory=dict)
    """What produced it: configs, seeds, data key, per-seed values (JSON-able)."""
    signed: bool = False
    """A difference: shown with its sign (``+1.2 points [-0.3, +2.6]``)."""

    @property
    def interval(self) -> Interval:
        return Interval(self.value, self.lo, self.hi, self.method)

    @property
    def verdict(self) -> str | None:
        return None if self.decision is None else self.decision.verdict

    @property
    def exact(self) -> bool:
        """Without an interval (lo = hi = value)."""
        return self.lo == self.hi == self.value


def number(value: Interval | float, what: str = "", *, unit: str = "fraction", paper: float | None = None,
           decision: Decision | None = None, margin: Margin = verdicts.MARGIN, signed: bool = False,
           **source: Any) -> Number:
    """A :class:`Number` of an interval (or of a plain number, which has none).

    With ``paper`` (a fraction), its verdict is :func:`study.report.verdicts.number` of ``paper``
    against the interval under ``margin``; or pass ``decision`` (an order, for a difference). A verdict is
    always decided here, from the interval, never given."""
    iv = value if isinstance(value, Interval) else Interval(float(value), float(value), float(value), "exact")
    if decision is not None and not isinstance(decision, Decision):
        raise ConfigError(f"number({what!r}): decision = {decision!r}; build a Decision with verdicts.number, "
                          "order, not_comparable, qualitative or combined")
    if decision is None and paper is not None:
        if unit != "fraction":
            raise ConfigError(f"number({what!r}): a paper number in {unit!r} has no verdict rule; pass decision= "
                              "(the rule compares fractions)")
        decision = verdicts.number(paper, iv, margin)
    return Number(float(iv.value), float(iv.lo), float(iv.hi), iv.method, what, unit, paper, decision,
                  dict(source), signed)


def count(value: int, what: str, **source: Any) -> Number:
    """A count (runs that failed, throws, videos): exact, no interval."""
    return number(float(value), what, unit="count", **source)


@dataclass(frozen=True)
class Verdict:
    """A verdict that is not one number's: a table's, a claim's, a combination; decided, never typed."""

    decision: Decision
    """The decision and the inputs it is decided from."""
    what: str
    """What is judged, in words."""
    source: Mapping[str, Any] = field(default_factory=dict)
    """What produced it (JSON-able)."""

    def __post_init__(self) -> None:
        if not isinstance(self.decision, Decision):
            raise ConfigError(f"Verdict({self.what!r}): got {self.decision!r}; build a Decision with "
                              "verdicts.number, order, not_comparable, qualitative or combined")

    @property
    def verdict(self) -> str:
        return self.decision.verdict


Leaf = Number | Verdict


class MissingResult(StudyError):
    """A result another page needs is not in the results file: its chapter did not run, or no longer reports it."""


def named(name: str, **kwargs: Any) -> Any:
    """A field stored under ``name`` instead of its own (``""``: its keys or fields come straight after the
    parent's path; in a dict's name, ``{key}`` marks where each key goes: ``"minus_{key}"``)."""
    return field(metadata={"name": name}, **kwargs)


T = TypeVar("T", bound="Reported")


class Reported:
    """Base of a frozen dataclass of reported numbers (see the module's docstring). Fields may be a
    :class:`Number`, a :class:`Verdict`, another :class:`Reported`, ``X | None`` of these (None: absent from
    the results file), or ``dict[K, X]``: its keys are path segments (``named("diff_{key}")`` puts a key inside
    a segment instead), and for reading back, ``K`` a ``Literal`` names the keys there can be (those present
    are read), ``str`` any segment that is not another field's name."""

    CHAPTER: ClassVar[str] = ""
    """The chapter it belongs to (on the tree's root): the first segment of every name."""

    def entries(self, prefix: str | None = None) -> Iterator[tuple[str, Leaf]]:
        """Every leaf of the tree with its full name, in field order."""
        base = self.CHAPTER if prefix is None else prefix
        for f in dataclasses.fields(self):  # type: ignore[arg-type]
            yield from _entries(getattr(self, f.name), base, f.metadata.get("name", f.name))

    @classmethod
    def read(cls: type[T], stored: Mapping[str, Leaf], prefix: str | None = None) -> T:
        """The tree of this type built from ``stored`` (a results file's leaves by name); :class:`MissingResult`
        naming the chapter if a leaf that is not optional is missing."""
        base = cls.CHAPTER if prefix is None else prefix
        hints = typing.get_type_hints(cls)
        fields = dataclasses.fields(cls)  # type: ignore[arg-type]
        siblings = {f.metadata.get("name", f.name).split(".")[0].replace("{key}", "*") for f in fields} - {""}
        return cls(**{f.name: _read(hints[f.name], stored, base, f.metadata.get("name", f.name), cls, siblings)
                      for f in fields})


def _join(prefix: str, name: str) -> str:
    return ".".join(p for p in (prefix, name) if p)


def _key_path(base: str, pattern: str, key: str) -> str:
    """Where a dict's ``key`` goes: into ``pattern``'s ``{key}``, else a segment after it."""
    return _join(base, pattern.replace("{key}", key)) if "{key}" in pattern else _join(_join(base, pattern), key)


def _entries(value: Any, base: str, pattern: str) -> Iterator[tuple[str, Leaf]]:
    if value is None:
        return
    if isinstance(value, (Number, Verdict)):
        yield _join(base, pattern), value
    elif isinstance(value, Reported):
        yield from value.entries(_join(base, pattern))
    elif isinstance(value, Mapping):
        for k, v in value.items():
            yield from _entries(v, _key_path(base, pattern, str(k)), "")
    else:
        raise ConfigError(f"{_join(base, pattern)}: a reported field holds {type(value).__name__}; only Number, "
                          "Verdict, Reported, None and dicts of them are stored")


def _present(stored: Mapping[str, Leaf], name: str) -> bool:
    return name in stored or any(k.startswith(name + ".") for k in stored)


def _read(hint: Any, stored: Mapping[str, Leaf], base: str, pattern: str, owner: type,
          siblings: set[str] = frozenset()) -> Any:  # type: ignore[assignment]
    """The value of a field of type ``hint`` stored at ``base`` + ``pattern``."""
    name = _join(base, pattern)
    args = typing.get_args(hint)
    if typing.get_origin(hint) in (typing.Union, types.UnionType):
        inner = [a for a in args if a is not type(None)]
        if len(inner) == 1 and len(args) == 2:  # X | None: None when absent
            return _read(inner[0], stored, base, pattern, owner, siblings) if _present(stored, name) else None
        raise ConfigError(f"{owner.__name__}: field {name!r} is a union; use X | None")
    if hint in (Number, Verdict):
        leaf = stored.get(name)
        if not isinstance(leaf, hint):
            chapter = name.split(".")[0]
            raise MissingResult(f"results file: {name} ({hint.__name__}) is missing: chapter {chapter!r} did not run "
                                f"or no longer reports it; rebuild the book (study book), or the chapter "
                                f"with --only {chapter}")
        return leaf
    if isinstance(hint, type) and issubclass(hint, Reported):
        return hint.read(stored, name)
    if typing.get_origin(hint) is dict:
        key_hint, value_hint = args
        if typing.get_origin(key_hint) is typing.Literal:
            keys = [str(k) for k in typing.get_args(key_hint) if _present(stored, _key_path(base, pattern, str(k)))]
        elif key_hint is str:
            keys = _scan(stored, base, pattern, value_hint in (Number, Verdict), siblings if not pattern else set())
        else:
            raise ConfigError(f"{owner.__name__}: dict field {name!r} needs str or Literal keys to be read back")
        return {k: _read(value_hint, stored, _key_path(base, pattern, k), "", owner) for k in keys}
    raise ConfigError(f"{owner.__name__}: field {name!r} of type {hint!r} cannot be read from a results file")


def _scan(stored: Mapping[str, Leaf], base: str, pattern: str, leafy: bool, siblings: set[str]) -> list[str]:
    """The keys of a dict stored at ``base`` + ``pattern`` (see :func:`_key_path`), in order of first appearance:
    for leaves, names that end at the key; otherwise names that go on after it. Keys that are the names of the
    owner's other fields (``siblings``, patterns) are not keys."""
    where = re.escape(_key_path(base, pattern, "\0")).replace(re.escape("\0"), "(?P<key>[^.]+)")
    found = re.compile(where + ("$" if leafy else r"\."))
    keys: list[str] = []
    for k in stored:
        m = found.match(k)
        if m is None:
            continue
        key = m.group("key")
        if key not in keys and not any(fnmatch.fnmatchcase(key, s) for s in siblings):
            keys.append(key)
    return keys


def finite(n: Number) -> bool:
    """Whether a number and its interval are finite."""
    return all(math.isfinite(x) for x in (n.value, n.lo, n.hi))
