"""The book's one rule for comparing our numbers with the paper's: a verdict, decided from intervals, never typed.

One vocabulary (:data:`VERDICTS`) and one rule per kind of comparison, each a frozen dataclass that holds the
inputs it decides from and decides again at any margin (:meth:`Decision.at`):

- :class:`NumberDecision` -- a number of the paper ``p`` against our 95 % interval: *reproduced* if the
  interval lies inside ``p`` ± :func:`margin` (the equivalence margin δ plus the paper's own sampling error on
  its ``n_paper`` test items), *differs* if it lies wholly outside, *inconclusive* otherwise;
- :class:`OrderDecision` -- a claimed order, A above (or below) B, against the interval of our difference
  A - B: *reproduced* if it lies on the claimed side of 0, *differs* if it lies wholly on the other side or
  wholly inside [-δ, δ] (no difference), *inconclusive* otherwise;
- :class:`NotComparable` (our experiment differs in kind, with the reason) and :class:`Qualitative` (a figure
  without a number, with the criterion it is judged by);
- :class:`Combined` -- several made one (:func:`combine`): the same verdict, or *mixed*.

Build them with :func:`number`, :func:`order`, :func:`not_comparable`, :func:`qualitative` and
:func:`combined`. :attr:`Decision.inputs` is the JSON form the results file stores beside the verdict;
:func:`from_inputs` reads it back and :func:`decide` decides a stored form again.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import Any, ClassVar

from study.core.errors import ConfigError, check_range
from study.learn.metrics import Interval

VERDICTS = ("reproduced", "differs", "inconclusive", "not comparable", "qualitative", "mixed")
"""The book's one vocabulary for comparing our numbers with the paper's."""
KINDS = ("number", "order", "not comparable", "qualitative", "combined")
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
class Margin:
    """The settings of the rule: the equivalence margin and the paper's test-set size."""

    delta: float = DELTA
    """Equivalence margin δ, a fraction in [0, 1) (:data:`DELTA`)."""
    n_paper: int = N_PAPER
    """Test items behind the paper's number (:data:`N_PAPER`); a comparison with a number the paper
    measured on fewer (20 real videos) passes its own ``Margin(n_paper=20)``."""

    def __post_init__(self) -> None:
        check_range("Margin.delta", self.delta, 0.0, 1.0, hi_open=True)
        if isinstance(self.n_paper, bool) or not isinstance(self.n_paper, int) or self.n_paper < 1:
            raise ConfigError(f"Margin.n_paper = {self.n_paper!r}: give the paper's number of test items, "
                              "an integer >= 1")


MARGIN = Margin()
"""The book's settings: δ = :data:`DELTA`, n_paper = :data:`N_PAPER`."""


def margin(p: float, m: Margin = MARGIN) -> float:
    """The half-width M (a fraction) around a paper's number ``p`` (a fraction) inside which our interval
    reproduces it: ``δ + 1.96 · sqrt(p (1 - p) / n_paper)``."""
    _check_fraction("paper", p)
    return _margin(float(p), m.delta, m.n_paper)


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


# ---------------------------------------------------------------------------------------------
# One rule per kind


class Decision(ABC):
    """A verdict with the inputs it is decided from; :attr:`verdict` is always decided, never stored apart."""

    kind: ClassVar[str]
    """Its kind, one of :data:`KINDS` (``inputs["rule"]``)."""

    @abstractmethod
    def at(self, delta: float | None = None) -> str:
        """The verdict at the equivalence margin ``delta`` (a fraction; None: the margin it was made with)."""

    @property
    def verdict(self) -> str:
        """The verdict at the margin it was made with: one of :data:`VERDICTS`."""
        return self.at()

    @property
    @abstractmethod
    def inputs(self) -> dict[str, Any]:
        """Its JSON form: ``{"rule": kind, ...}``, what :func:`from_inputs` reads back."""


@dataclass(frozen=True)
class NumberDecision(Decision):
    """The paper's number ``paper`` against our interval [lo, hi] (fractions)."""

    kind: ClassVar[str] = "number"
    paper: float
    """The paper's number, a fraction."""
    lo: float
    """Lower end of our 95 % interval."""
    hi: float
    """Upper end of our 95 % interval."""
    delta: float = DELTA
    """The equivalence margin it was made with."""
    n_paper: int = N_PAPER
    """Test items behind the paper's number."""

    def at(self, delta: float | None = None) -> str:
        m = _margin(self.paper, self.delta if delta is None else _delta(delta), self.n_paper)
        if self.paper - m <= self.lo and self.hi <= self.paper + m:
            return "reproduced"
        if self.lo > self.paper + m or self.hi < self.paper - m:
            return "differs"
        return "inconclusive"

    @property
    def inputs(self) -> dict[str, Any]:
        return {"rule": self.kind, "paper": self.paper, "lo": self.lo, "hi": self.hi, "delta": self.delta,
                "n_paper": self.n_paper}


@dataclass(frozen=True)
class OrderDecision(Decision):
    """A claimed order, A above B (``sign`` +1) or below it (-1), against our difference A - B in [lo, hi]."""

    kind: ClassVar[str] = "order"
    sign: int
    """+1: the paper says A exceeds B; -1: A falls below B."""
    lo: float
    """Lower end of the difference's 95 % interval."""
    hi: float
    """Upper end of the difference's 95 % interval."""
    delta: float = DELTA
    """The margin of no difference it was made with (0 for a difference that is not in accuracy points)."""
    in_points: bool = True
    """Whether the difference is one of accuracies; a count or a time takes no margin, at any δ."""

    def at(self, delta: float | None = None) -> str:
        d = self.delta if delta is None or not self.in_points else _delta(delta)
        s, lo, hi = self.sign, self.lo, self.hi
        if (s > 0 and lo > 0) or (s < 0 and hi < 0):
            return "reproduced"  # the order is established, however small the difference
        if (s > 0 and hi < 0) or (s < 0 and lo > 0) or (-d <= lo and hi <= d):
            return "differs"  # the other order, or no difference worth the name
        return "inconclusive"

    @property
    def inputs(self) -> dict[str, Any]:
        return {"rule": self.kind, "sign": self.sign, "lo": self.lo, "hi": self.hi, "delta": self.delta,
                "in_points": self.in_points}


@dataclass(frozen=True)
class NotComparable(Decision):
    """Our experiment differs in kind from the paper's."""

    kind: ClassVar[str] = "not comparable"
    reason: str
    """How it differs, in words."""

    def at(self, delta: float | None = None) -> str:
        return self.kind

    @property
    def inputs(self) -> dict[str, Any]:
        return {"rule": self.kind, "reason": self.reason}


@dataclass(frozen=True)
class Qualitative(Decision):
    """A figure of the paper without a number."""

    kind: ClassVar[str] = "qualitative"
    criterion: str
    """What it is judged by, in words."""

    def at(self, delta: float | None = None) -> str:
        return self.kind

    @property
    def inputs(self) -> dict[str, Any]:
        return {"rule": self.kind, "criterion": self.criterion}


@dataclass(frozen=True)
class Combined(Decision):
    """Several decisions made one: their common verdict, else *mixed* (:func:`combine`)."""

    kind: ClassVar[str] = "combined"
    parts: tuple[Decision, ...]
    """The decisions combined, each kept whole."""

    def at(self, delta: float | None = None) -> str:
        return combine([p.at(delta) for p in self.parts])

    @property
    def inputs(self) -> dict[str, Any]:
        return {"rule": self.kind, "parts": [p.inputs for p in self.parts]}


def _delta(delta: float) -> float:
    check_range("delta", delta, 0.0, 1.0, hi_open=True)
    return float(delta)


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


# ---------------------------------------------------------------------------------------------
# Constructors (checked inputs) and the stored form


def number(paper: float, interval: Interval, m: Margin = MARGIN) -> NumberDecision:
    """The paper's number ``paper`` (a fraction) against our 95 % ``interval``: *reproduced* if the
    interval lies inside ``paper`` ± :func:`margin`, *differs* if wholly outside it, else *inconclusive*."""
    _check_fraction("paper", paper)
    lo, hi = _bounds(interval, f"number(paper = {paper!r})")
    return NumberDecision(float(paper), lo, hi, float(m.delta), int(m.n_paper))


def order(difference: Interval, sign: int, m: Margin = MARGIN, *, in_points: bool = True) -> OrderDecision:
    """A claim of the paper that A exceeds B (``sign`` +1) or falls below it (-1), against the interval of
    our difference A - B (a fraction): *reproduced* if it lies on the claimed side of 0; *differs* if it
    lies wholly on the other side, or wholly inside [-δ, δ] (no difference); else *inconclusive*. An
    interval on the claimed side but inside [-δ, δ] is *reproduced*: the order holds, if by little.

    ``in_points=False`` for a difference that is not an accuracy (a count of bounces, a time in seconds):
    δ is a margin in accuracy points and means nothing there, so the order is judged on the side of 0
    alone (stored with δ = 0 and ``in_points`` false; it stays so at any other δ)."""
    if sign not in (1, -1) or isinstance(sign, bool):
        raise ConfigError(f"order: sign = {sign!r}; use +1 (the paper says A beats B) or -1 (A falls below B)")
    lo, hi = _bounds(difference, "order(difference)")
    return OrderDecision(int(sign), lo, hi, float(m.delta) if in_points else 0.0, bool(in_points))


def not_comparable(reason: str) -> NotComparable:
    """*not comparable*: our experiment differs in kind from the paper's; ``reason`` says how."""
    if not isinstance(reason, str) or not reason.strip():
        raise ConfigError("not_comparable: give the reason, in words, why our experiment cannot be compared")
    return NotComparable(reason)


def qualitative(criterion: str) -> Qualitative:
    """*qualitative*: a figure of the paper without a number; ``criterion`` says what it is judged by."""
    if not isinstance(criterion, str) or not criterion.strip():
        raise ConfigError("qualitative: give the criterion, in words, the figure is compared by")
    return Qualitative(criterion)


def combined(decisions: list[Decision]) -> Combined:
    """Several decisions made one (:func:`combine` of their verdicts); the parts are kept."""
    if not decisions or not all(isinstance(d, Decision) for d in decisions):
        raise ConfigError(f"combined: got {decisions!r}; pass a non-empty list of Decisions "
                          "(verdicts.number, order, not_comparable, qualitative)")
    return Combined(tuple(decisions))


def from_inputs(inputs: Any) -> Decision:
    """The :class:`Decision` of a stored form (:attr:`Decision.inputs`); :class:`ConfigError` for inputs of
    no known kind or missing a field. A stored order without ``in_points`` (older files) is in points."""
    if not isinstance(inputs, dict) or inputs.get("rule") not in KINDS:
        got = inputs.get("rule") if isinstance(inputs, dict) else type(inputs).__name__
        raise ConfigError(f"decision inputs: rule {got!r} is none of {KINDS}; build them with verdicts.number, "
                          "order, not_comparable, qualitative or combined")
    kind = inputs["rule"]
    try:
        if kind == "number":
            return NumberDecision(float(inputs["paper"]), float(inputs["lo"]), float(inputs["hi"]),
                                  float(inputs["delta"]), int(inputs["n_paper"]))
        if kind == "order":
            return OrderDecision(int(inputs["sign"]), float(inputs["lo"]), float(inputs["hi"]),
                                 float(inputs["delta"]), bool(inputs.get("in_points", True)))
        if kind == "not comparable":
            return NotComparable(str(inputs["reason"]))
        if kind == "qualitative":
            return Qualitative(str(inputs["criterion"]))
        parts = inputs["parts"]
        if not isinstance(parts, list) or not parts:
            raise ConfigError("decision inputs: a combined decision needs a non-empty list of parts")
        return Combined(tuple(from_inputs(p) for p in parts))
    except (KeyError, TypeError, ValueError) as e:
        raise ConfigError(f"decision inputs of rule {kind!r}: malformed ({type(e).__name__}: {e}); "
                          "build them with the constructor of that rule") from None


def decide(inputs: dict[str, Any], delta: float | None = None) -> str:
    """The verdict of a stored decision ``inputs``, decided again; at the margin ``delta`` (a fraction)
    instead of the stored one if given (the summary shows every verdict at δ/2 and 2δ too)."""
    if delta is not None:
        _delta(delta)
    return from_inputs(inputs).at(delta)
