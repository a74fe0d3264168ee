"""The build's results file: every number the book reports, with its 95 % interval and what produced it.

Each chapter records its numbers with a :class:`Results`; when the book builder runs the chapter it
sets :data:`ENV` to a file of its own (its *part*), and :meth:`Results.save` writes the numbers there.
The builder merges the parts of the book's chapters into one file, ``_build/results.json``
(:func:`merge`), which the summary page reads
and ``study results --compare OTHER`` compares with another build's (:func:`compare`). A chapter run
by hand, outside the builder, writes nothing.

Verdicts use one vocabulary for the whole book (:data:`VERDICTS`), computed from intervals: a number
of the paper is *reproduced* when it lies inside our interval, else ours *differs*; several verdicts
that disagree make a *mixed* outcome (:func:`combine`).
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from study.core.cache import write_text_atomic
from study.core.errors import ConfigError, DataError, check_file
from study.learn.metrics import Interval

FORMAT = "study.results/1"
ENV = "STUDY_RESULTS_PART"
"""Environment variable naming the file a chapter writes its numbers to (set by ``study book``)."""
FILE = Path("_build") / "results.json"
"""Where the builder writes the merged results, relative to the book's root."""
VERDICTS = ("reproduced", "differs", "mixed")
"""The book's one vocabulary for comparing our numbers with the paper's."""


def verdict(paper: float, interval: Interval) -> str:
    """``"reproduced"`` if the paper's number lies inside our interval, else ``"differs"``."""
    return "reproduced" if interval.contains(paper) else "differs"


def claim_verdict(difference: Interval, expected_sign: int) -> str:
    """A claim of the paper that one number exceeds another (``expected_sign`` +1) or falls below it (-1),
    against the interval of our difference: ``"reproduced"`` if the interval lies wholly on the claimed
    side of zero, else ``"differs"``."""
    side = difference.lo > 0 if expected_sign > 0 else difference.hi < 0
    return "reproduced" if side else "differs"


def combine(verdicts: list[str]) -> str:
    """One verdict from several: all reproduced, all differ, or ``"mixed"``."""
    unknown = set(verdicts) - set(VERDICTS)
    if unknown or not verdicts:
        raise ConfigError(f"verdicts {verdicts!r}: need one or more of {VERDICTS}")
    if all(v == "reproduced" for v in verdicts):
        return "reproduced"
    if all(v == "differs" for v in verdicts):
        return "differs"
    return "mixed"


@dataclass
class Number:
    """One number of the book."""

    name: str
    """Unique within the build, dotted: ``"table1.z.mean"``."""
    value: float
    """The estimate (accuracies as fractions)."""
    lo: float
    """Lower bound of its 95 % interval (``value`` when it has none: a count, a setting)."""
    hi: float
    """Upper bound of its 95 % interval."""
    method: str
    """How the interval was computed."""
    chapter: str
    """The chapter that reported it."""
    what: str = ""
    """What the number is, in words."""
    unit: str = "fraction"
    """``"fraction"`` (shown as a percentage), ``"count"``, or a physical unit ("s", "m/s^2")."""
    paper: float | None = None
    """The paper's number it is compared with, if any."""
    verdict: str | None = None
    """:func:`verdict` against ``paper``, or a verdict the chapter computed for a claim."""
    source: dict[str, Any] = field(default_factory=dict)
    """What produced it: configs, seeds, data key, backend."""

    @property
    def interval(self) -> Interval:
        return Interval(self.value, self.lo, self.hi, self.method)


class Results:
    """The numbers one chapter reports; :meth:`save` writes them where the builder collects them."""

    def __init__(self, chapter: str) -> None:
        self.chapter = chapter
        self.numbers: dict[str, Number] = {}

    def add(self, name: str, interval: Interval | float, *, what: str = "", unit: str = "fraction",
            paper: float | None = None, verdict_: str | None = None, **source: Any) -> Number:
        """Record ``interval`` (or a plain number, which has no interval) as ``<chapter>.<name>``; with
        ``paper``, its verdict against the paper's number is computed unless ``verdict_`` is given."""
        iv = interval if isinstance(interval, Interval) else Interval(float(interval), float(interval), float(interval), "exact")
        full = f"{self.chapter}.{name}"
        v = verdict_ if verdict_ is not None else (verdict(paper, iv) if paper is not None else None)
        num = Number(full, iv.value, iv.lo, iv.hi, iv.method, self.chapter, what, unit, paper, v, source)
        self.numbers[full] = num
        return num

    def verdict(self, name: str, verdict_: str, what: str, **source: Any) -> Number:
        """Record a verdict that is not one number's (a table's, a claim's) as ``<chapter>.<name>``."""
        if verdict_ not in VERDICTS:
            raise ConfigError(f"verdict {verdict_!r}: use one of {VERDICTS}")
        full = f"{self.chapter}.{name}"
        num = Number(full, math.nan, math.nan, math.nan, "verdict", self.chapter, what, "verdict", None, verdict_, source)
        self.numbers[full] = num
        return num

    def save(self) -> Path | None:
        """Write this chapter's numbers to ``$STUDY_RESULTS_PART`` if the builder set it; returns its path."""
        part = os.environ.get(ENV)
        if not part:
            return None
        path = Path(part)
        body = {"format": FORMAT, "chapter": self.chapter, "numbers": [asdict(n) for n in self.numbers.values()]}
        write_text_atomic(path, json.dumps(body, indent=1, allow_nan=True) + "\n")
        return path


def _numbers(obj: Any, path: Path) -> dict[str, Number]:
    if not isinstance(obj, dict) or obj.get("format") != FORMAT or not isinstance(obj.get("numbers"), list):
        raise DataError(f"results file {path}: not a {FORMAT} file; rebuild the book to write one")
    out = {}
    for n in obj["numbers"]:
        try:
            num = Number(**n)
        except TypeError as e:
            raise DataError(f"results file {path}: a malformed number ({e}); rebuild the book") from None
        out[num.name] = num
    return out


def merge(parts: list[Path], out: Path, preset: str) -> Path:
    """Merge the chapters' parts (those that exist, in order) into one results file ``out`` (atomically)."""
    numbers: dict[str, Number] = {}
    for part in parts:
        if part.is_file():
            numbers.update(load(part))
    body = {"format": FORMAT, "preset": preset, "numbers": [asdict(n) for n in numbers.values()]}
    write_text_atomic(out, json.dumps(body, indent=1, allow_nan=True) + "\n")
    return out


def load(path: str | Path) -> dict[str, Number]:
    """The numbers of a results file, by name; :class:`DataError` naming the file if it is missing or bad."""
    p = check_file(path, "results file", "build the book (study book) to write _build/results.json")
    try:
        obj = json.loads(p.read_text())
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as e:
        raise DataError(f"results file {p}: cannot be read ({type(e).__name__}); rebuild the book") from None
    return _numbers(obj, p)


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


def compare(a: dict[str, Number], b: dict[str, Number]) -> tuple[list[Moved], list[str], list[str]]:
    """Pair the numbers of two builds: (pairs in name order, names only in ``a``, names only in ``b``)."""
    common = sorted(set(a) & set(b))
    pairs = [Moved(k, a[k], b[k]) for k in common if not (math.isnan(a[k].value) or math.isnan(b[k].value))]
    return pairs, sorted(set(a) - set(b)), sorted(set(b) - set(a))


def _scale(unit: str) -> tuple[float, str, str]:
    """Factor, suffix and format spec of a unit: percentages to a tenth of a point, as in the chapters."""
    if unit == "fraction":
        return 100.0, " %", ".1f"
    return 1.0, "" if unit == "count" else f" {unit}", ".3g"


def fmt_value(value: float, unit: str = "fraction") -> str:
    """``'81.2 %'`` for a fraction, ``'12'`` for a count, ``'0.41 s'`` otherwise."""
    scale, suffix, spec = _scale(unit)
    return f"{scale * value:{spec}}{suffix}"


def fmt(n: Number) -> str:
    """:func:`fmt_value` with the interval: ``'81.2 % [79.9, 82.4]'``; no interval for an exact number."""
    if n.unit == "verdict":
        return "(verdict)"
    if n.lo == n.hi == n.value:
        return fmt_value(n.value, n.unit)
    scale, _, spec = _scale(n.unit)
    return f"{fmt_value(n.value, n.unit)} [{scale * n.lo:{spec}}, {scale * n.hi:{spec}}]"
