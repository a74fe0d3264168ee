"""The build's results file: every number the book reports, with its 95 % interval and what produced it.

Each chapter records its numbers with a :class:`Results`; when the book builder runs the chapter it
sets :data:`ENV` to a file of its own (its *part*), and :meth:`Results.save` writes the numbers there.
The builder merges the parts of the book's chapters into one file, ``_build/results.json``
(:func:`merge`), which the summary page reads
and ``study results --compare OTHER`` compares with another build's (:func:`compare`). A chapter run
by hand, outside the builder, writes nothing.

Verdicts use one vocabulary for the whole book (:data:`VERDICTS`) and one rule, decided here from
intervals and never typed by a chapter:

- a number of the paper ``p`` against our 95 % interval (:func:`number`): *reproduced* if the interval
  lies inside ``p`` ± :func:`margin` (the equivalence margin :data:`DELTA` plus the paper's own sampling
  error on :data:`N_PAPER` test videos), *differs* if it lies wholly outside, *inconclusive* otherwise;
- a claimed order, A above (or below) B, against the interval of our difference A - B (:func:`order`):
  *reproduced* if it lies on the claimed side of 0, *differs* if it lies wholly on the other side or
  wholly inside [-δ, δ] (no difference), *inconclusive* otherwise;
- *not comparable* (:func:`not_comparable`: our experiment differs in kind, with the reason) and
  *qualitative* (:func:`qualitative`: a figure without a number, with the criterion it is judged by);
- several of these made one (:func:`combined`, :func:`combine`): the same verdict, or *mixed*.

Each is a :class:`Decision`: the verdict and the inputs it was decided from, which the results file
stores beside the verdict (:attr:`Number.decision`), so any reader can decide it again
(:func:`decide`, at another margin too) and check a file (:func:`recompute`).
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from study.core.cache import write_text_atomic
from study.core.errors import ConfigError, DataError, check_file, check_range
from study.learn.metrics import Interval

FORMAT = "study.results/1"
"""The results file's format; :attr:`Number.decision` is an optional field of it (files without it load)."""
ENV = "STUDY_RESULTS_PART"
"""Environment variable naming the file a chapter writes its numbers to (set by ``study book``)."""
FILE = Path("_build") / "results.json"
"""Where the builder writes the merged results, relative to the book's root."""
VERDICTS = ("reproduced", "differs", "inconclusive", "not comparable", "qualitative", "mixed")
"""The book's one vocabulary for comparing our numbers with the paper's."""
RULES = ("number", "order", "not comparable", "qualitative", "combined")
"""The kinds of :class:`Decision`, as stored under ``inputs["rule"]``."""

DELTA = 0.03
"""The equivalence margin δ, a fraction (3 points of accuracy): the smallest difference the book treats
as a difference. The paper's own finding that X, Y, Z beats Z alone rests on a 3-point gap (81 % against
78 %), so a gap surely smaller than that is smaller than any effect the paper reports; a number of ours
within δ of the paper's (beyond the paper's sampling error) reproduces it, and a difference of two of
ours that lies wholly inside [-δ, δ] is no difference."""
N_PAPER = 1000
"""Test videos behind each of the paper's accuracies. The paper tests on "1000 test videos for both
categories"; we read that as 1000 in all (500 a class), the smaller of its two readings (the other is
1000 a class), which gives the paper's number the larger sampling error and so the wider margin: at
81 %, 1.96 · sqrt(0.81 · 0.19 / 1000) = 2.4 points (1.7 points at 2000)."""
Z = 1.96
"""The standard normal quantile of a two-sided 95 % interval, for the paper's sampling error."""


@dataclass(frozen=True)
class Rule:
    """The parameters of the verdict rule: the equivalence margin and the paper's test-set size."""

    delta: float = DELTA
    """Equivalence margin δ, a fraction in [0, 1) (:data:`DELTA`)."""
    n_paper: int = N_PAPER
    """Test items behind the paper's number (:data:`N_PAPER`); a chapter comparing with a number the
    paper measured on fewer (20 real videos) passes its own ``Rule(n_paper=20)``."""

    def __post_init__(self) -> None:
        check_range("Rule.delta", self.delta, 0.0, 1.0, hi_open=True)
        if isinstance(self.n_paper, bool) or not isinstance(self.n_paper, int) or self.n_paper < 1:
            raise ConfigError(f"Rule.n_paper = {self.n_paper!r}: give the paper's number of test items, "
                              "an integer >= 1")


RULE = Rule()
"""The book's rule: δ = :data:`DELTA`, n_paper = :data:`N_PAPER`."""


def margin(p: float, rule: Rule = RULE) -> float:
    """The half-width M (a fraction) around a paper's number ``p`` (a fraction) inside which our interval
    reproduces it: ``δ + 1.96 · sqrt(p (1 - p) / n_paper)``."""
    _check_fraction("paper", p)
    return _margin(float(p), rule.delta, rule.n_paper)


def _margin(p: float, delta: float, n_paper: int) -> float:
    return delta + Z * math.sqrt(p * (1.0 - p) / n_paper)


def _check_fraction(name: str, p: Any) -> None:
    if isinstance(p, bool) or not isinstance(p, (int, float)) or not 0.0 <= p <= 1.0:
        raise ConfigError(f"{name} = {p!r}: give the paper's number as a fraction in [0, 1] (0.81 for 81 %)")


def _bounds(interval: Any, what: str) -> tuple[float, float]:
    """(lo, hi) of an :class:`Interval`, checked finite and ordered."""
    if not isinstance(interval, Interval):
        raise ConfigError(f"{what}: got {type(interval).__name__}; pass an Interval (study.learn.metrics)")
    lo, hi = float(interval.lo), float(interval.hi)
    if not (math.isfinite(lo) and math.isfinite(hi) and lo <= hi):
        raise ConfigError(f"{what}: interval [{lo}, {hi}] must be finite with lo <= hi; "
                          "a verdict needs a real interval")
    return lo, hi


def _verdict_number(inputs: dict[str, Any], delta: float) -> str:
    p, lo, hi = float(inputs["paper"]), float(inputs["lo"]), float(inputs["hi"])
    m = _margin(p, delta, int(inputs["n_paper"]))
    if p - m <= lo and hi <= p + m:
        return "reproduced"
    if lo > p + m or hi < p - m:
        return "differs"
    return "inconclusive"


def _verdict_order(inputs: dict[str, Any], delta: float) -> str:
    sign, lo, hi = int(inputs["sign"]), float(inputs["lo"]), float(inputs["hi"])
    if (sign > 0 and lo > 0) or (sign < 0 and hi < 0):
        return "reproduced"  # the order is established, however small the difference
    if (sign > 0 and hi < 0) or (sign < 0 and lo > 0) or (-delta <= lo and hi <= delta):
        return "differs"  # the other order, or no difference worth the name
    return "inconclusive"


def decide(inputs: dict[str, Any], delta: float | None = None) -> str:
    """The verdict of a decision's stored ``inputs`` (:attr:`Decision.inputs`), decided again; at the
    margin ``delta`` (a fraction) instead of the stored one if given (the summary shows every verdict at
    δ/2 and 2δ too). :class:`ConfigError` for inputs of no known rule or missing a field."""
    if delta is not None:
        check_range("decide: delta", delta, 0.0, 1.0, hi_open=True)
    if not isinstance(inputs, dict) or inputs.get("rule") not in RULES:
        got = inputs.get("rule") if isinstance(inputs, dict) else type(inputs).__name__
        raise ConfigError(f"decision inputs: rule {got!r} is none of {RULES}; build them with results.number, "
                          "order, not_comparable, qualitative or combined")
    rule = inputs["rule"]
    try:
        if rule == "number":
            return _verdict_number(inputs, float(inputs["delta"]) if delta is None else delta)
        if rule == "order":
            scaled = delta is not None and inputs.get("in_points", True)  # no margin for a count or a time
            return _verdict_order(inputs, delta if scaled else float(inputs["delta"]))
        if rule in ("not comparable", "qualitative"):
            return rule
        parts = inputs["parts"]
        if not isinstance(parts, list) or not parts:
            raise ConfigError("decision inputs: a combined decision needs a non-empty list of parts")
        return combine([decide(part, delta) for part in parts])
    except (KeyError, TypeError, ValueError, ArithmeticError) as e:
        if isinstance(e, ConfigError):
            raise
        raise ConfigError(f"decision inputs of rule {rule!r}: malformed ({type(e).__name__}: {e}); "
                          "build them with the constructor of that rule") from None


def combine(verdicts: list[str]) -> str:
    """One verdict from several.

    *not comparable* parts are set aside when any other part exists, then *qualitative* parts when any
    part with a number (reproduced, differs, inconclusive, mixed) remains; if what is left is all one
    verdict, that is the verdict, else it is *mixed*. So: reproduced + reproduced = reproduced;
    reproduced + differs, reproduced + inconclusive, differs + inconclusive = mixed; inconclusive +
    inconclusive = inconclusive; anything + mixed = mixed; reproduced + qualitative = reproduced;
    qualitative + not comparable = qualitative; not comparable alone = not comparable.
    """
    unknown = set(verdicts) - set(VERDICTS)
    if unknown or not verdicts:
        raise ConfigError(f"verdicts {verdicts!r}: need one or more of {VERDICTS}")
    left = list(verdicts)
    for aside in ("not comparable", "qualitative"):
        if any(v != aside for v in left):
            left = [v for v in left if v != aside]
    return left[0] if len(set(left)) == 1 else "mixed"


@dataclass(frozen=True)
class Decision:
    """A verdict with the inputs it was decided from (JSON-able: what :func:`decide` needs to decide it
    again). Build one with :func:`number`, :func:`order`, :func:`not_comparable`, :func:`qualitative` or
    :func:`combined`; a verdict that does not follow from its inputs is refused."""

    verdict: str
    """One of :data:`VERDICTS`."""
    inputs: dict[str, Any]
    """``{"rule": "number", "paper", "lo", "hi", "delta", "n_paper"}``, ``{"rule": "order", "sign", "lo",
    "hi", "delta"}``, ``{"rule": "not comparable", "reason"}``, ``{"rule": "qualitative", "criterion"}`` or
    ``{"rule": "combined", "parts": [inputs, ...]}`` (fractions, as floats)."""

    def __post_init__(self) -> None:
        again = decide(self.inputs)
        if self.verdict != again:
            raise ConfigError(f"Decision: verdict {self.verdict!r} does not follow from its inputs ({again!r}); "
                              "build it with results.number, order, not_comparable, qualitative or combined")


def _decision(inputs: dict[str, Any]) -> Decision:
    return Decision(decide(inputs), inputs)


def number(paper: float, interval: Interval, rule: Rule = RULE) -> Decision:
    """The paper's number ``paper`` (a fraction) against our 95 % ``interval``: *reproduced* if the
    interval lies inside ``paper`` ± :func:`margin`, *differs* if wholly outside it, else *inconclusive*."""
    _check_fraction("paper", paper)
    lo, hi = _bounds(interval, f"number(paper = {paper!r})")
    return _decision({"rule": "number", "paper": float(paper), "lo": lo, "hi": hi,
                      "delta": float(rule.delta), "n_paper": int(rule.n_paper)})


def order(difference: Interval, sign: int, rule: Rule = RULE, *, in_points: bool = True) -> Decision:
    """A claim of the paper that A exceeds B (``sign`` +1) or falls below it (-1), against the interval of
    our difference A - B (a fraction): *reproduced* if it lies on the claimed side of 0; *differs* if it
    lies wholly on the other side, or wholly inside [-δ, δ] (no difference); else *inconclusive*. An
    interval on the claimed side but inside [-δ, δ] is *reproduced*: the order holds, if by little.

    ``in_points=False`` for a difference that is not an accuracy (a count of bounces, a time in seconds):
    δ is a margin in accuracy points and means nothing there, so the order is judged on the side of 0
    alone (stored with δ = 0 and ``in_points`` false; :func:`decide` keeps it so at any other δ)."""
    if sign not in (1, -1) or isinstance(sign, bool):
        raise ConfigError(f"order: sign = {sign!r}; use +1 (the paper says A beats B) or -1 (A falls below B)")
    lo, hi = _bounds(difference, "order(difference)")
    return _decision({"rule": "order", "sign": int(sign), "lo": lo, "hi": hi,
                      "delta": float(rule.delta) if in_points else 0.0, "in_points": bool(in_points)})


def not_comparable(reason: str) -> Decision:
    """*not comparable*: our experiment differs in kind from the paper's; ``reason`` says how."""
    if not isinstance(reason, str) or not reason.strip():
        raise ConfigError("not_comparable: give the reason, in words, why our experiment cannot be compared")
    return _decision({"rule": "not comparable", "reason": reason})


def qualitative(criterion: str) -> Decision:
    """*qualitative*: a figure of the paper without a number; ``criterion`` says what it is judged by."""
    if not isinstance(criterion, str) or not criterion.strip():
        raise ConfigError("qualitative: give the criterion, in words, the figure is compared by")
    return _decision({"rule": "qualitative", "criterion": criterion})


def combined(decisions: list[Decision]) -> Decision:
    """Several decisions made one (:func:`combine` of their verdicts); the parts' inputs are kept."""
    if not decisions or not all(isinstance(d, Decision) for d in decisions):
        raise ConfigError(f"combined: got {decisions!r}; pass a non-empty list of Decisions "
                          "(results.number, order, not_comparable, qualitative)")
    return _decision({"rule": "combined", "parts": [d.inputs for d in decisions]})


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
    """The verdict of :attr:`decision` (one of :data:`VERDICTS`), or None."""
    source: dict[str, Any] = field(default_factory=dict)
    """What produced it: configs, seeds, data key, backend."""
    decision: dict[str, Any] | None = None
    """The inputs :attr:`verdict` was decided from (:attr:`Decision.inputs`; :func:`decide` decides it
    again); None without a verdict, and in files written before verdicts stored their inputs."""

    @property
    def interval(self) -> Interval:
        return Interval(self.value, self.lo, self.hi, self.method)


_NO_VERDICT_ARGS = ("verdict", "verdict_")


class Results:
    """The numbers one chapter reports; :meth:`save` writes them where the builder collects them."""

    def __init__(self, chapter: str) -> None:
        self.chapter = chapter
        self.numbers: dict[str, Number] = {}

    def add(self, name: str, interval: Interval | float, *, what: str = "", unit: str = "fraction",
            paper: float | None = None, decision: Decision | None = None, rule: Rule = RULE,
            **source: Any) -> Number:
        """Record ``interval`` (or a plain number, which has no interval) as ``<chapter>.<name>``.

        With ``paper`` (a fraction), its verdict is :func:`number` of ``paper`` against ``interval`` under
        ``rule``; or pass ``decision`` (a :class:`Decision`, e.g. :func:`order` for a difference), which
        is stored as given. The verdict and its inputs are stored with the number.
        """
        bad = [k for k in _NO_VERDICT_ARGS if k in source]
        if bad:
            raise ConfigError(f"Results.add({name!r}): {bad[0]}= is gone; pass decision=results.order(...) "
                              "(or paper=, whose verdict is computed) so the verdict is decided, not typed")
        iv = interval if isinstance(interval, Interval) else Interval(float(interval), float(interval), float(interval), "exact")
        full = f"{self.chapter}.{name}"
        if decision is not None and not isinstance(decision, Decision):
            raise ConfigError(f"Results.add({name!r}): decision = {decision!r}; build a Decision with "
                              "results.number, order, not_comparable, qualitative or combined")
        if decision is None and paper is not None:
            if unit != "fraction":
                raise ConfigError(f"Results.add({name!r}): a paper number in {unit!r} has no verdict rule; "
                                  "pass decision= (the rule compares fractions)")
            decision = number(paper, iv, rule)
        v, inputs = (decision.verdict, decision.inputs) if decision is not None else (None, None)
        num = Number(full, iv.value, iv.lo, iv.hi, iv.method, self.chapter, what, unit, paper, v, source, inputs)
        self.numbers[full] = num
        return num

    def verdict(self, name: str, decision: Decision, what: str, **source: Any) -> Number:
        """Record a verdict that is not one number's (a table's, a claim's, a combination) as
        ``<chapter>.<name>``: ``decision`` is a :class:`Decision`, never a typed verdict."""
        if not isinstance(decision, Decision):
            raise ConfigError(f"Results.verdict({name!r}): got {decision!r}; build a Decision with results.number, "
                              "order, not_comparable, qualitative or combined instead of typing a verdict")
        full = f"{self.chapter}.{name}"
        num = Number(full, math.nan, math.nan, math.nan, "verdict", self.chapter, what, "verdict", None,
                     decision.verdict, source, decision.inputs)
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
        if num.decision is not None and not (isinstance(num.decision, dict) and num.decision.get("rule") in RULES):
            raise DataError(f"results file {path}: number {num.name!r} has a malformed decision; rebuild the book")
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


def recompute(numbers: dict[str, Number]) -> list[str]:
    """The names (in order) of the numbers whose stored verdict is not what :func:`decide` makes of their
    stored decision: empty for a sound file. A verdict without a decision (typed, or from a file written
    before decisions were stored) cannot be decided again and is listed; so is a malformed decision."""
    wrong = []
    for name, n in numbers.items():
        if n.decision is None:
            if n.verdict is not None:
                wrong.append(name)
            continue
        try:
            again = decide(n.decision)
        except ConfigError:
            again = None
        if again != n.verdict:
            wrong.append(name)
    return wrong


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
