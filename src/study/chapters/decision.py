"""The chapter *From accuracy to a decision*: from a classifier's probabilities to a car's decision.

The paper reports accuracy. A car must decide: treat the object as must-avoid (heavy) unless it is
confident enough that it is safe to pass (light). Missing a heavy object is far worse than a needless
swerve, so the decision threshold is set for a target *miss rate* (the share of heavy objects called
light) on a *certification split* that neither training nor model selection has seen, and the miss rate is
then measured on the test split. Probabilities are ``p_heavy`` (n,) floats; labels 1 = heavy.

The decision rules (NumPy and SciPy only):

- :func:`threshold_for_miss_rate`, :func:`rates`: the operating point and what it costs;
- :func:`certified_threshold`, :func:`certified_clearing_thresholds`: operating points whose miss rate on
  data they have not seen is at most the target with 95 % confidence (a one-sided Clopper-Pearson bound,
  :func:`clopper_pearson_upper`, on the certification split's misses), not only on the certification split;
  :func:`operating_point` and :func:`clearing` set them on the certification split and measure them on the test
  split;
- :func:`roc`, :func:`precision_recall`: the curves for must-avoid (heavy) as the positive class;
- :func:`reliability`, :func:`expected_calibration_error`, :func:`fit_temperature`, :func:`scaled`:
  whether the probabilities can be trusted (their *calibration*), before and after temperature scaling;
- :func:`time_to_clear`: when, frame by frame, a light object is first cleared as safe to pass.

:func:`compute` runs the chapter on a runner and returns :class:`CarDecision`:

1. the certification split, and both splits as the tracker observes them (:func:`splits`);
2. the network a camera should use, positions or velocity, chosen on observed validation (:func:`camera_network`);
3. how soon: two networks trained to answer at every frame (:func:`every_frame`), each frame's threshold certified
   so that few heavy objects are ever cleared (:func:`clearing_of`);
4. how wrong, and in which direction: four Z classifiers at their certified and empirical operating points, their
   ROC area and calibration error before and after temperature scaling (:func:`condition`).

:class:`Numbers` is what the chapter reports, under the names ``decision.exact.miss`` and so on.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Literal, Protocol

import numpy as np

from study.core.errors import ConfigError
from study.runs import stats
from study.report.reported import Number, Reported, count, named, number
from study.report.text import Table, fmt, pct, pct_ci
from study.learn.config import Inputs, TrainConfig
from study.methods import calibration, camera
from study.learn.metrics import Interval, bootstrap_accuracy, wilson
from study.simulate import synth

if TYPE_CHECKING:  # a type only: the chapter passes a runner in
    from study.runs.runner import Runner


def _check(p: np.ndarray, y: np.ndarray, what: str = "probabilities") -> tuple[np.ndarray, np.ndarray]:
    p, y = np.asarray(p, dtype=np.float64), np.asarray(y)
    if p.ndim != 1 or p.shape != y.shape:
        raise ConfigError(f"{what}: p_heavy {p.shape} and labels {y.shape} must be (n,) alike")
    if len(p) == 0:
        raise ConfigError(f"{what}: the set is empty; score at least one trajectory")
    if not np.isfinite(p).all() or (p < 0).any() or (p > 1).any():
        raise ConfigError(f"{what}: p_heavy must lie in [0, 1]")
    return p, y


def threshold_for_miss_rate(p_heavy: np.ndarray, y: np.ndarray, target: float) -> float:
    """The highest threshold t such that at most ``target`` of the heavy objects have ``p_heavy < t``
    (and are called light). Decide heavy when ``p_heavy >= t``.

    Raises :class:`ConfigError` for a target outside (0, 1), an empty set or one without heavy objects.
    """
    if not (isinstance(target, (int, float)) and 0 < target < 1):
        raise ConfigError(f"target miss rate = {target!r}; it must lie in (0, 1), e.g. 0.01")
    p, y = _check(p_heavy, y, "certification set")
    heavy = np.sort(p[y == 1])
    if len(heavy) == 0:
        raise ConfigError("certification set: it holds no heavy object; a miss rate needs some")
    k = int(math.floor(target * len(heavy)))  # heavy objects we may call light
    return float(heavy[k]) if k < len(heavy) else 1.0  # below the (k+1)-th smallest: at most k misses


@dataclass(frozen=True)
class Rates:
    """What a threshold does on a set of objects (:func:`rates`)."""

    miss: Interval
    """Heavy objects called light (``p_heavy < threshold``), with its Wilson interval."""
    false_alarm: Interval
    """Light objects called heavy, with its Wilson interval."""


def rates(p_heavy: np.ndarray, y: np.ndarray, threshold: float) -> Rates:
    """At ``threshold``: the miss rate (heavy called light) and the false-alarm rate (light called heavy),
    each with its Wilson interval."""
    p, y = _check(p_heavy, y)
    heavy, light = p[y == 1], p[y == 0]
    if len(heavy) == 0 or len(light) == 0:
        raise ConfigError("test set: it needs light and heavy objects to measure both rates")
    return Rates(wilson(int((heavy < threshold).sum()), len(heavy)), wilson(int((light >= threshold).sum()), len(light)))


def roc(p_heavy: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(false-alarm rate, detection rate) over every threshold, heavy the positive class; both (k,)."""
    p, y = _check(p_heavy, y)
    order = np.argsort(-p, kind="stable")
    pos = np.cumsum(y[order] == 1)
    neg = np.cumsum(y[order] == 0)
    tpr = np.concatenate([[0.0], pos / max(pos[-1], 1)])
    fpr = np.concatenate([[0.0], neg / max(neg[-1], 1)])
    return fpr, tpr


def auc(fpr: np.ndarray, tpr: np.ndarray) -> float:
    """Area under a curve of :func:`roc` (trapezoids)."""
    return float(np.sum(np.diff(fpr) * (tpr[1:] + tpr[:-1]) / 2))


def precision_recall(p_heavy: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(recall, precision) over every threshold for heavy objects; both (k,)."""
    p, y = _check(p_heavy, y)
    order = np.argsort(-p, kind="stable")
    tp = np.cumsum(y[order] == 1)
    called = np.arange(1, len(p) + 1)
    return tp / max(tp[-1], 1), tp / called


def reliability(p_heavy: np.ndarray, y: np.ndarray, bins: int = 10) -> list[dict[str, float]]:
    """The reliability diagram: per bin of predicted ``p_heavy``, its mean, the observed share of heavy
    objects, and the count (empty bins left out)."""
    p, y = _check(p_heavy, y)
    edges = np.linspace(0, 1, bins + 1)
    which = np.clip(np.digitize(p, edges[1:-1]), 0, bins - 1)
    return [{"predicted": float(p[which == b].mean()), "observed": float((y[which == b] == 1).mean()),
             "n": int((which == b).sum())} for b in range(bins) if (which == b).any()]


def expected_calibration_error(p_heavy: np.ndarray, y: np.ndarray, bins: int = 10) -> float:
    """ECE: the count-weighted mean gap between predicted and observed share of heavy over the bins."""
    rows = reliability(p_heavy, y, bins)
    n = sum(r["n"] for r in rows)
    return float(sum(r["n"] * abs(r["predicted"] - r["observed"]) for r in rows) / n)


def _logit(p: np.ndarray) -> np.ndarray:
    q = np.clip(p, 1e-7, 1 - 1e-7)
    return np.log(q) - np.log1p(-q)


def scaled(p_heavy: np.ndarray, temperature: float) -> np.ndarray:
    """``p_heavy`` with its logit divided by ``temperature`` (temperature scaling)."""
    if not temperature > 0:
        raise ConfigError(f"temperature = {temperature!r}; it must be > 0")
    return 1.0 / (1.0 + np.exp(-_logit(np.asarray(p_heavy, dtype=np.float64)) / temperature))


def fit_temperature(p_heavy: np.ndarray, y: np.ndarray) -> float:
    """The temperature that minimises the negative log-likelihood of ``y`` (the chapter fits it on the certification
    split): a golden-section search over log T in [-3, 3] (T from 0.05 to 20)."""
    p, y = _check(p_heavy, y, "certification set")
    z, t = _logit(p), (y == 1).astype(np.float64)

    def nll(log_t: float) -> float:
        s = z / math.exp(log_t)
        return float(np.mean(np.logaddexp(0.0, s) - t * s))

    lo, hi = -3.0, 3.0
    g = (math.sqrt(5) - 1) / 2
    a, b = hi - g * (hi - lo), lo + g * (hi - lo)
    fa, fb = nll(a), nll(b)
    for _ in range(80):
        if fa < fb:
            hi, b, fb = b, a, fa
            a = hi - g * (hi - lo)
            fa = nll(a)
        else:
            lo, a, fa = a, b, fb
            b = lo + g * (hi - lo)
            fb = nll(b)
    return float(math.exp((lo + hi) / 2))


def time_to_clear(p_heavy: np.ndarray, thresholds: np.ndarray) -> np.ndarray:
    """For each trajectory, the first frame at which it is cleared as light: ``p_heavy[i, t] <
    thresholds[t]`` ((n, T) probabilities frame by frame, (T,) thresholds set per frame for the target miss
    rate). -1 if it never is. A car treats an object as must-avoid until then."""
    p = np.asarray(p_heavy, dtype=np.float64)
    thr = np.asarray(thresholds, dtype=np.float64)
    if p.ndim != 2 or thr.shape != (p.shape[1],):
        raise ConfigError(f"time_to_clear: p_heavy {p.shape} must be (n, T) and thresholds (T,), not {thr.shape}")
    cleared = p < thr[None, :]
    return np.where(cleared.any(axis=1), np.argmax(cleared, axis=1), -1)


def _clearing_search(p_frames: np.ndarray, y: np.ndarray, target: float, allowed: Callable[[int], bool],
                     steps: int, what: str, at_threshold: bool = False) -> np.ndarray:
    """Per-frame thresholds (T,): each frame's :func:`threshold_for_miss_rate` at one per-frame rate a in
    (0, ``target``], the largest a (by bisection, ``steps`` halvings) at which ``allowed(k)`` holds for k
    the number of heavy objects of ``p_frames`` (n, T) ever cleared; zeros (clear nothing) if none does."""
    p = np.asarray(p_frames, dtype=np.float64)
    if p.ndim != 2:
        raise ConfigError(f"{what}: p_frames {p.shape} must be (n, T)")
    threshold_for_miss_rate(p[:, -1], y, target)  # checks the target and the set
    if not np.isfinite(p).all() or (p < 0).any() or (p > 1).any():
        raise ConfigError(f"{what}: p_heavy must lie in [0, 1] at every frame")
    heavy = np.asarray(y) == 1
    ranked = np.sort(p[heavy], axis=0)  # (n_heavy, T): each frame's heavy scores, ascending
    n_heavy, frames = ranked.shape[0], np.arange(p.shape[1])

    def thresholds(a: float) -> np.ndarray:  # threshold_for_miss_rate(p[:, t], y, a) for every frame t
        return ranked[int(math.floor(a * n_heavy)), frames]

    def ok(a: float) -> bool:
        thr = thresholds(a)
        cleared = (p[heavy] <= thr[None, :]) if at_threshold else (p[heavy] < thr[None, :])
        return allowed(int(cleared.any(axis=1).sum()))

    lo, hi = 0.0, float(target)
    if ok(hi):
        return thresholds(hi)
    for _ in range(steps):
        mid = (lo + hi) / 2
        if mid > 0 and ok(mid):
            lo = mid
        else:
            hi = mid
    return thresholds(lo) if lo > 0 else np.zeros(p.shape[1])  # clear nothing: never a miss


def clearing_thresholds(p_frames: np.ndarray, y: np.ndarray, target: float, steps: int = 40) -> np.ndarray:
    """Per-frame thresholds (T,) for :func:`time_to_clear` such that at most ``target`` of the heavy objects
    of the certification set ``p_frames`` (n, T) are *ever* cleared -- a car passes an object the first
    time it is cleared, so a miss at any frame is a miss.

    Each frame's threshold is :func:`threshold_for_miss_rate` at a per-frame rate a <= ``target``; the
    largest a whose cumulative miss rate stays within ``target`` is found by bisection.
    """
    n_heavy = int((np.asarray(y) == 1).sum())
    return _clearing_search(p_frames, y, target, lambda k: k / n_heavy <= target, steps, "clearing_thresholds")


def clopper_pearson_upper(k: int, n: int, level: float = 0.95) -> float:
    """The one-sided upper confidence bound, at ``level``, of a binomial proportion seen as ``k`` of ``n``
    (Clopper-Pearson: the p at which k or fewer successes have probability 1 - level;
    ``scipy.stats.beta.ppf(level, k + 1, n - k)``, 1 when k = n). 0 of 299 gives 0.00997 at 95 %."""
    ints = all(isinstance(v, (int, np.integer)) and not isinstance(v, bool) for v in (k, n))
    if not ints or not 0 <= k <= n or n < 1:
        raise ConfigError(f"clopper_pearson_upper: k = {k!r} of n = {n!r}; need integers 0 <= k <= n, n >= 1")
    _check_level(level)
    if k == n:
        return 1.0
    from scipy.stats import beta

    return float(beta.ppf(level, k + 1, n - k))


def _check_level(level: float) -> None:
    if not (isinstance(level, (int, float)) and 0 < level < 1):
        raise ConfigError(f"confidence level = {level!r}; it must lie in (0, 1), e.g. 0.95")


@functools.lru_cache(maxsize=256)
def _certified_misses(n: int, target: float, level: float) -> int:
    """The most misses k of ``n`` heavy objects whose :func:`clopper_pearson_upper` is <= ``target``;
    -1 if not even k = 0 qualifies. The bound rises with k, so a bisection finds it."""
    if clopper_pearson_upper(0, n, level) > target:
        return -1
    lo, hi = 0, n  # bound(lo) <= target < bound(hi) = 1
    while hi - lo > 1:
        mid = (lo + hi) // 2
        lo, hi = (mid, hi) if clopper_pearson_upper(mid, n, level) <= target else (lo, mid)
    return lo


def certified_threshold(p_heavy: np.ndarray, y: np.ndarray, target: float, level: float = 0.95) -> float | None:
    """The highest threshold t (decide heavy when ``p_heavy >= t``) whose miss rate on data it has not seen
    is at most ``target`` with confidence ``level``: k, the number of the certification set's heavy objects
    with ``p_heavy < t``, has :func:`clopper_pearson_upper` (k, n_heavy) <= ``target``. None if not even
    k = 0 does (too few heavy objects: for a 1 % target at 95 %, fewer than 299).

    t is the (k_max + 1)-th smallest heavy score, k_max the most misses the bound allows: below it lie at
    most k_max heavy scores (fewer where scores tie with it), and any higher t would count one more. For
    scores of a continuous distribution its true miss rate exceeds ``target`` with probability at most
    1 - ``level``. Input checks as :func:`threshold_for_miss_rate`.
    """
    threshold_for_miss_rate(p_heavy, y, target)  # checks the target and the set
    _check_level(level)
    p, y = _check(p_heavy, y, "certification set")
    heavy = np.sort(p[y == 1])
    k = _certified_misses(len(heavy), float(target), float(level))
    return None if k < 0 else float(heavy[k])


def certified_clearing_thresholds(p_frames: np.ndarray, y: np.ndarray, target: float, level: float = 0.95,
                                  steps: int = 40) -> np.ndarray | None:
    """Per-frame thresholds (T,) for :func:`time_to_clear` whose share of heavy objects *ever* cleared, on
    data they have not seen, is at most ``target`` with confidence ``level``: k, the number of the
    certification set's heavy objects ``p_frames`` (n, T) ever cleared, has :func:`clopper_pearson_upper`
    (k, n_heavy) <= ``target``. The same bisection over a per-frame rate as :func:`clearing_thresholds`.
    None if not even k = 0 qualifies (too few heavy objects); zeros (clear nothing) if no per-frame rate
    does.

    Here k counts a heavy object as cleared when its score at some frame is at or below that frame's
    threshold (``<=``, where :func:`time_to_clear` clears below it): each frame's threshold is one of the
    certification set's heavy scores, and counting it is what makes the bound hold for thresholds chosen on the
    same split that counts k. Counted strictly, k falls short of what fresh data would show by up to one
    object a frame, and with independent frames the bound then held in only about 2 of 3 certification
    draws (measured: 0.67 at T = 8, target 5 %, 500 heavy throws); counted so, it holds in 97-100 %
    (tests/test_decide.py). The price: with many frames whose scores are nearly independent it may clear
    nothing. For one frame, :func:`certified_threshold` is exact and one miss less strict.
    """
    p = np.asarray(p_frames, dtype=np.float64)
    if p.ndim != 2:
        raise ConfigError(f"certified_clearing_thresholds: p_frames {p.shape} must be (n, T)")
    threshold_for_miss_rate(p[:, -1], y, target)  # checks the target and the set
    _check_level(level)
    n_heavy = int((np.asarray(y) == 1).sum())
    k_max = _certified_misses(n_heavy, float(target), float(level))
    if k_max < 0:
        return None
    return _clearing_search(p, y, target, lambda k: k <= k_max, steps, "certified_clearing_thresholds",
                            at_threshold=True)


def heavy_needed(target: float, level: float = 0.95) -> int:
    """The fewest heavy certification throws with which a miss rate of ``target`` can be certified at all
    (:func:`clopper_pearson_upper` (0, n) <= ``target``): 299 for 1 % at 95 %, 59 for 5 %."""
    if not (isinstance(target, (int, float)) and 0 < target < 1):
        raise ConfigError(f"target miss rate = {target!r}; it must lie in (0, 1), e.g. 0.01")
    _check_level(level)
    n = max(1, math.ceil(math.log(1 - level) / math.log1p(-target)))  # (1 - target)^n <= 1 - level
    while n > 1 and clopper_pearson_upper(0, n - 1, level) <= target:
        n -= 1
    while clopper_pearson_upper(0, n, level) > target:
        n += 1
    return n


@dataclass(frozen=True)
class OperatingPoint:
    """The certified and the empirical operating point, set on the certification split and measured on the test
    split (:func:`operating_point`)."""

    certified: float | None
    """:func:`certified_threshold` on p(heavy) (decide heavy at or above it); None: not certifiable."""
    miss: Interval | None
    """Heavy test objects called light there (None when not certifiable)."""
    false_alarm: Interval | None
    """Light test objects called heavy there: what the safety margin costs."""
    empirical: float
    """:func:`threshold_for_miss_rate` of the certification split: its empirical quantile."""
    miss_empirical: Interval
    """Heavy test objects called light at the empirical quantile."""
    false_alarm_empirical: Interval
    """Light test objects called heavy there."""


def operating_point(p_cert: np.ndarray, y_cert: np.ndarray, p_test: np.ndarray, y_test: np.ndarray, target: float,
                    level: float = 0.95) -> OperatingPoint:
    """The certified and the empirical operating points for ``target``, set on the certification split and
    measured on the test split (both (n,) ``p_heavy`` with labels)."""
    certified = certified_threshold(p_cert, y_cert, target, level)
    empirical = threshold_for_miss_rate(p_cert, y_cert, target)
    at_emp = rates(p_test, y_test, empirical)
    if certified is None:
        return OperatingPoint(None, None, None, empirical, at_emp.miss, at_emp.false_alarm)
    at_cert = rates(p_test, y_test, certified)
    return OperatingPoint(certified, at_cert.miss, at_cert.false_alarm, empirical, at_emp.miss, at_emp.false_alarm)


@dataclass(frozen=True)
class Clearing:
    """Frame-by-frame clearing at certified thresholds, measured on the test split (:func:`clearing`)."""

    thresholds: np.ndarray
    """(T,) each frame's threshold on p(heavy): an object is cleared the first time it falls below."""
    cleared: np.ndarray
    """(m_light,) bool: whether each light test object is ever cleared."""
    share_cleared: Interval
    """Their share, with its Wilson interval."""
    times: np.ndarray
    """(k,) the frame at which each cleared light object is first cleared."""
    miss: Interval
    """The share of heavy test objects ever cleared, with its Wilson interval."""


def clearing(f_cert: np.ndarray, y_cert: np.ndarray, f_test: np.ndarray, y_test: np.ndarray, target: float,
             level: float = 0.95) -> Clearing | None:
    """Frame-by-frame clearing with :func:`certified_clearing_thresholds` set on the certification split
    ``f_cert`` (n, T) and applied to the test split ``f_test`` (m, T); None if not certifiable (too few heavy
    objects)."""
    thr = certified_clearing_thresholds(f_cert, y_cert, target, level)
    if thr is None:
        return None
    y = np.asarray(y_test)
    at = time_to_clear(f_test, thr)
    if at.shape != y.shape:
        raise ConfigError(f"clearing: f_test has {at.shape[0]} objects and y_test {y.shape}; they must match")
    light, heavy = at[y == 0], at[y == 1]
    if len(light) == 0 or len(heavy) == 0:
        raise ConfigError("clearing: the test split needs light and heavy objects")
    cleared = light >= 0
    return Clearing(thr, cleared, wilson(int(cleared.sum()), len(light)), light[cleared],
                    wilson(int((heavy >= 0).sum()), len(heavy)))


# ---------------------------------------------------------------------------------------------
# What the chapter reports

NetworkKey = Literal["exact", "observed"]
"""The networks that answer at every frame: the paper's on exact positions, the camera's through the tracker."""
ConditionKey = Literal["exact", "observed", "randomised", "camera"]
"""The Z classifiers whose operating points the chapter sets: Table 1's on exact and on observed positions, the
same trained on random observations, and the camera's network at its last frame."""

TARGET_MISS = 0.01
"""The chapter's target: at most this share of heavy objects may be called light."""
CERTIFY_SEED = 500
"""The certification split is simulated from the data set's seed plus this (throws no other split holds)."""
OBSERVE_SEEDS: dict[str, int] = {"test": 11, "certify": 12}
"""Seeds of the chapter's own observed draws of the test and the certification split."""


@dataclass(frozen=True)
class Choice(Reported):
    """The camera's network, chosen between positions and velocity."""

    val: dict[Inputs, Number]
    """Each one's observed validation accuracy, mean over the grid seeds."""


@dataclass(frozen=True)
class SeedClearing(Reported):
    """One seed's clearing on the test split."""

    share: Number
    """Light test objects cleared within the input."""
    miss: Number
    """Heavy test objects ever cleared."""


@dataclass(frozen=True)
class ClearNumbers(Reported):
    """How soon one network answering at every frame clears the light objects (certifiable, or a count of 0)."""

    certifiable: Number | None = None
    """0 (a count) when no per-frame thresholds can be certified; absent when they can."""
    share_by_end: Number | None = None
    """Light test objects cleared within the input, pooled over the seeds."""
    per_seed: dict[str, SeedClearing] = named("seed{key}", default_factory=dict)
    """Each seed's (keys: the seeds)."""
    median_s: Number | None = None
    """Median time to clear the light objects cleared, seconds."""


@dataclass(frozen=True)
class ConditionNumbers(Reported):
    """One Z classifier's operating points and the trust its probabilities deserve."""

    auc: Number
    """Area under the ROC curve, mean over seeds."""
    ece: Number
    """Expected calibration error, mean over seeds."""
    ece_scaled: Number
    """The same after temperature scaling."""
    miss: Number | None
    """Heavy called light at the certified point, seed 0 (absent when not certifiable)."""
    false_alarm: Number | None
    """Light called heavy there, seed 0."""
    miss_empirical: Number
    """Heavy called light at the certification split's empirical quantile, seed 0."""


@dataclass(frozen=True)
class CertifiedNumbers(Reported):
    """Whether the certificates carried to the test split."""

    points: Number
    """Certified operating points, every classifier and seed."""
    above_target: Number
    """Of them, those whose test miss rate's interval lies wholly above the target."""
    point_above: Number
    """Of them, those whose test miss rate's point estimate lies above the target."""


@dataclass(frozen=True)
class Numbers(Reported):
    """Every number the chapter *From accuracy to a decision* reports."""

    CHAPTER = "decision"
    choice: Choice
    clear: dict[NetworkKey, ClearNumbers]
    conditions: dict[ConditionKey, ConditionNumbers] = named("")
    certified: CertifiedNumbers = named("certified")


# ---------------------------------------------------------------------------------------------
# The chapter's steps


@dataclass(frozen=True)
class Splits:
    """The test split and the certification split, exact and as the tracker observes them."""

    n_frames: int
    """T, the input length (Table 1's), frames."""
    fps: float
    """Frames per second."""
    test_x: np.ndarray
    """(n, T_data, 3) metres: the data set's test split, exact."""
    test_y: np.ndarray
    """(n,) its labels, 1 = heavy."""
    certify_x: np.ndarray
    """(m, T + 2, 3) metres: the certification split, exact."""
    certify_y: np.ndarray
    """(m,) its labels."""
    observed_test: np.ndarray
    """(n, T, 3) metres: the test split's first T frames observed with the tracker's error."""
    observed_certify: np.ndarray
    """(m, T, 3) metres: the certification split's, observed."""

    @property
    def times(self) -> np.ndarray:
        """(T,) each frame's time since the first, seconds."""
        return np.arange(self.n_frames) / self.fps


def certification_config(runner: Runner) -> synth.SynthConfig:
    """The certification split's synthesis: the study's priors and scene, ``preset.certify_per_class`` throws of
    each class (its test split; a training split of one), as long as Table 1's input and two frames more."""
    T = runner.table1_config().n_frames(runner.fps)
    return runner.synth_config.replace(duration=(T + 2) / runner.fps, n_train=1, n_test=runner.preset.certify_per_class)


def splits(runner: Runner) -> Splits:
    """The certification split (simulated once, from seed :data:`CERTIFY_SEED` above the data set's; throws that
    neither training, early stopping nor the grid search has seen) beside the data set's test split, both also
    observed with the tracker's error (``calibration.observation``; seeds :data:`OBSERVE_SEEDS`)."""
    T = runner.table1_config().n_frames(runner.fps)
    seed = int(runner.dataset.meta["seed"]) + CERTIFY_SEED
    certify = synth.dataset(certification_config(runner), seed, data_dir=runner.data_dir, progress=False).test
    test, ob = runner.dataset.test, calibration.observation(runner)
    return Splits(T, runner.fps, test.x, np.asarray(test.y), certify.x, np.asarray(certify.y),
                  ob.observe(test.x[:, :T], runner.fps, seed=OBSERVE_SEEDS["test"]),
                  ob.observe(certify.x[:, :T], runner.fps, seed=OBSERVE_SEEDS["certify"]))


@dataclass(frozen=True)
class CameraChoice:
    """The network a camera should use (:func:`camera_network`)."""

    val: dict[Inputs, float]
    """Observed validation accuracy of the paper's network reading positions and reading velocity, each trained
    observed, mean over the grid seeds (the runs of the chapter *What the motion allows*)."""
    best: Inputs
    """The one with the higher."""
    config: TrainConfig
    """It, trained observed with the loss at every frame."""


def camera_network(runner: Runner) -> CameraChoice:
    """Positions or velocity for a camera: the paper's network trained and validated observed with the tracker's
    error (the motion chapter's column), chosen by its mean validation accuracy."""
    column = next(c for c in camera.columns(calibration.observation(runner)) if c.air and c.name == "calibrated")
    choices: dict[Inputs, TrainConfig] = {"positions": runner.table1_config(),
                                          "velocity": runner.table1_config("velocity")}
    val: dict[Inputs, float] = {
        k: float(np.mean(runner.train_runs(camera.trained_config(c, column), ("z",), runner.preset.grid_seeds,
                                           desc=f"{k}, observed").val_accuracies()))
        for k, c in choices.items()}
    best = max(val, key=val.__getitem__)  # ties: positions
    return CameraChoice(val, best, dataclasses.replace(camera.trained_config(choices[best], column), loss_at="every"))


@dataclass(frozen=True)
class EveryFrame:
    """A network trained to answer at every frame, one model per seed, and its p(heavy) after every frame."""

    name: str
    """What it is, in words."""
    config: TrainConfig
    """Its configuration (``loss_at = 'every'``)."""
    test: np.ndarray
    """(S, n, T) p(heavy) of each seed on the test split."""
    certify: np.ndarray
    """(S, m, T) the same on the certification split."""


def every_frame(runner: Runner, camera: CameraChoice, sp: Splits) -> dict[NetworkKey, EveryFrame]:
    """The paper's network on exact positions and the camera's network through the tracker, both trained with the
    loss at every frame on Table 1's seeds (all trained at once, then read back)."""
    T, seeds = sp.n_frames, runner.preset.seeds
    paper_every = dataclasses.replace(runner.table1_config(), loss_at="every")
    nets = {"exact": ("the paper's network, exact positions", paper_every, sp.test_x[:, :T], sp.certify_x[:, :T]),
            "observed": (f"the {camera.best} network under the calibrated tracker", camera.config, sp.observed_test,
                         sp.observed_certify)}
    runner.prefetch([(runner, [dataclasses.replace(c, dims="z", seed=s) for _, c, _, _ in nets.values() for s in seeds],
                      True)], desc="every frame")
    out: dict[NetworkKey, EveryFrame] = {}
    for key, (name, c, x_test, x_cert) in nets.items():
        runner.train_runs(c, ("z",), seeds, desc=f"every frame, {key}")
        ms = runner.models(c, seeds, dims="z")
        p_test, p_cert = (np.stack([m.predict_proba_frames(x)[:, :, 1] for m in ms]) for x in (x_test, x_cert))
        out[key] = EveryFrame(name, c, p_test, p_cert)  # type: ignore[index]
    return out


@dataclass(frozen=True)
class FrameClearing:
    """How soon one network answering at every frame decides (:func:`clearing_of`)."""

    name: str
    """The network, in words."""
    accuracy: np.ndarray
    """(T,) test accuracy after each frame, mean over seeds and throws."""
    per_seed: tuple[Clearing, ...] | None
    """Each seed's clearing at certified thresholds; None: not certifiable."""

    @property
    def shares(self) -> list[Interval]:
        """Each seed's share of light test objects cleared."""
        return [c.share_cleared for c in self.per_seed or ()]

    @property
    def stable(self) -> bool:
        """Every seed's share lies within every other seed's interval (``stats.intervals_agree``)."""
        return stats.intervals_agree(self.shares)

    def pooled(self) -> Interval:
        """The share of light test objects cleared, pooled over the seeds (bootstrap over throws and seeds)."""
        if self.per_seed is None:
            raise ConfigError(f"{self.name}: not certifiable, so nothing was cleared")
        return bootstrap_accuracy(np.stack([c.cleared for c in self.per_seed]))


def clearing_of(net: EveryFrame, y_test: np.ndarray, y_cert: np.ndarray, target: float) -> FrameClearing:
    """``net``'s accuracy after every frame and each seed's :func:`clearing` at ``target``."""
    y = np.asarray(y_test)
    right = (net.test > 0.5) == (y == 1)[None, :, None]  # (S, n, T)
    per_seed = [clearing(net.certify[s], y_cert, net.test[s], y, target) for s in range(len(net.test))]
    certifiable = all(c is not None for c in per_seed)
    return FrameClearing(net.name, right.mean(axis=(0, 1)),
                         tuple(per_seed) if certifiable else None)  # type: ignore[arg-type]


class Scorer(Protocol):
    """What :func:`condition` needs of a trained model (``study.learn.train.TrainedModel``)."""

    def predict_proba(self, x: np.ndarray) -> np.ndarray: ...


@dataclass(frozen=True)
class SeedPoint:
    """One seed of a Z classifier at its operating points."""

    point: OperatingPoint
    """Its certified and empirical operating points, measured on the test split."""
    p_test: np.ndarray
    """(n,) its p(heavy) on the test split."""
    temperature: float
    """The temperature fitted on the certification split."""
    auc: float
    """Area under its ROC curve on the test split."""
    ece: float
    """Its expected calibration error on the test split."""
    ece_scaled: float
    """The same after temperature scaling."""


@dataclass(frozen=True)
class Condition:
    """One Z classifier, every seed, at the operating points set on the certification split (:func:`condition`)."""

    name: str
    """The classifier and its inputs, in words."""
    per_seed: tuple[SeedPoint, ...]
    """Each seed's."""

    @property
    def certified(self) -> bool:
        """Whether a threshold could be certified (on seed 0; every seed shares the certification split)."""
        return self.per_seed[0].point.certified is not None

    @property
    def auc(self) -> float:
        return float(np.mean([s.auc for s in self.per_seed]))

    @property
    def ece(self) -> float:
        return float(np.mean([s.ece for s in self.per_seed]))

    @property
    def ece_scaled(self) -> float:
        return float(np.mean([s.ece_scaled for s in self.per_seed]))


def condition(name: str, models: Sequence[Scorer], x_cert: np.ndarray, y_cert: np.ndarray, x_test: np.ndarray,
              y_test: np.ndarray, target: float) -> Condition:
    """Each of ``models`` (one per seed) scored on the certification inputs ``x_cert`` and the test inputs
    ``x_test`` ((n, T, 3) metres): its operating points for ``target``, ROC area, and calibration error before and
    after a temperature fitted on the certification split."""
    per_seed = []
    for m in models:
        pc, pt = m.predict_proba(x_cert)[:, 1], m.predict_proba(x_test)[:, 1]
        temp = fit_temperature(pc, y_cert)
        per_seed.append(SeedPoint(operating_point(pc, y_cert, pt, y_test, target), pt, temp, auc(*roc(pt, y_test)),
                                  expected_calibration_error(pt, y_test),
                                  expected_calibration_error(scaled(pt, temp), y_test)))
    return Condition(name, tuple(per_seed))


# ---------------------------------------------------------------------------------------------
# The chapter's result


@dataclass(frozen=True)
class CarDecision:
    """Everything the chapter shows: its numbers, its tables and sentences, its figures' data."""

    numbers: Numbers
    """What the chapter reports (the results file's ``decision.*``)."""
    splits: Splits
    """The test and the certification split, exact and observed."""
    camera: CameraChoice
    """The network a camera should use."""
    networks: dict[NetworkKey, FrameClearing]
    """How soon each network answering at every frame decides."""
    conditions: dict[ConditionKey, Condition]
    """Each Z classifier at its operating points."""
    seeds: tuple[int, ...]
    """Table 1's seeds, every network's."""
    target_miss: float
    """The target miss rate."""
    clear_table: Table
    """How soon: the light objects cleared, per network and seed."""
    decision_table: Table
    """How wrong: every classifier's operating points and calibration error."""
    n_certify_heavy: int
    """Heavy throws in the certification split."""
    n_needed: int
    """The fewest heavy throws with which the target can be certified at all."""

    # Sentences whose words depend on the numbers -------------------------------------------------

    @property
    def n_seeds(self) -> int:
        return len(self.seeds)

    @property
    def input_seconds(self) -> float:
        return self.splits.n_frames / self.splits.fps

    @property
    def heavy_share(self) -> str:
        return pct(float((self.splits.test_y == 1).mean()))

    @property
    def target(self) -> str:
        return pct(self.target_miss, 0)

    @property
    def best(self) -> str:
        return self.camera.best

    @property
    def val_words(self) -> str:
        return " against ".join(f"{pct(v)} ({k})" for k, v in self.camera.val.items())

    @property
    def acc_1s(self) -> str:
        return pct(float(self.networks["exact"].accuracy[int(self.splits.fps) - 1]))

    @property
    def acc_end(self) -> str:
        return pct(float(self.networks["exact"].accuracy[-1]))

    @property
    def acc_end_obs(self) -> str:
        return pct(float(self.networks["observed"].accuracy[-1]))

    @property
    def stable_words(self) -> str:
        unstable = [n.name for n in self.networks.values() if n.per_seed is not None and not n.stable]
        if not unstable:
            return "Every seed's share lies within every other seed's interval: the number is stable."
        return ("For " + " and ".join(unstable) + " some seeds' shares lie outside others' intervals (the training of "
                "these networks splits into groups): the pooled number is not stable, and the table shows each seed "
                "instead.")

    @property
    def certified_points(self) -> list[tuple[str, int, Interval]]:
        """(classifier, seed, test miss rate) of every certified operating point."""
        return _certified_points(self.conditions, self.seeds)

    @property
    def cert_check(self) -> str:
        points = self.certified_points
        if not points:
            return "No operating point could be certified on this certification split."
        over, point_over = _above(points, self.target_miss)
        text = f"Of the {len(points)} certified points (every classifier, every seed), "
        text += (f"{len(over)} miss more heavy test throws than the target beyond their interval ({'; '.join(over)}): "
                 "the certificate did not carry to the test split there" if over else
                 "none misses more heavy test throws than the target beyond its interval")
        if point_over and not over:
            text += (f"; {len(point_over)} have a point estimate above it ({'; '.join(point_over)}), within their "
                     "intervals: a certificate at 95 % confidence bounds the miss rate of the throws a classifier will "
                     "meet, and a test split of its own still samples around it")
        return text + "."

    @property
    def answer(self) -> str:
        """What the chapter finds about a car's decision, in one or two sentences."""
        exact = self.numbers.conditions["exact"]
        if exact.miss is None or exact.false_alarm is None:
            return (f"With {self.n_certify_heavy} heavy throws the certification split is too small to certify a "
                    f"{self.target} miss rate (at least {self.n_needed} are needed even with no miss), so the chapter "
                    "gives no threshold rather than one it cannot back.")
        text = (f"At the threshold certified for a {self.target} miss rate, Table 1's network on exact positions calls "
                f"{fmt(exact.miss)} of the heavy test throws light and {fmt(exact.false_alarm)} of the "
                "light ones heavy (seed 0)")
        share = self.numbers.clear["observed"].share_by_end
        if share is not None:
            text += (f"; answering at every frame through the tracker, the camera's network clears "
                     f"{fmt(share)} of the light objects within {self.input_seconds:g} s")
        return text + "."


def compute(runner: Runner, target_miss: float = TARGET_MISS) -> CarDecision:
    """The chapter *From accuracy to a decision* on ``runner``'s preset and data set, for a target miss rate of
    ``target_miss``: every run of it cached (the networks answering at every frame are its own; the others are
    Table 1's and the motion chapter's)."""
    sp = splits(runner)
    camera = camera_network(runner)
    nets = every_frame(runner, camera, sp)
    seeds = runner.preset.seeds
    cfg = runner.table1_config()
    faithful = runner.models(cfg, seeds, dims="z")
    robust = runner.models(calibration.randomised_config(runner, cfg), seeds, dims="z")
    cameras = runner.models(camera.config, seeds, dims="z")
    exact = (sp.certify_x, sp.certify_y, sp.test_x, sp.test_y)
    observed = (sp.observed_certify, sp.certify_y, sp.observed_test, sp.test_y)
    conditions: dict[ConditionKey, Condition] = {
        "exact": condition("Table 1's, exact", faithful, *exact, target_miss),
        "observed": condition("Table 1's, observed", faithful, *observed, target_miss),
        "randomised": condition("trained on random observations, observed", robust, *observed, target_miss),
        "camera": condition(f"the camera's network ({camera.best}), observed", cameras, *observed, target_miss),
    }
    return assemble(sp, camera, nets, conditions, seeds, target_miss)


def assemble(sp: Splits, camera: CameraChoice, nets: dict[NetworkKey, EveryFrame],
             conditions: dict[ConditionKey, Condition], seeds: tuple[int, ...], target_miss: float) -> CarDecision:
    """The chapter's result from its steps' outputs (no runs, no models): the clearing of each network of ``nets``,
    every number, table and sentence."""
    networks = {k: clearing_of(net, sp.test_y, sp.certify_y, target_miss) for k, net in nets.items()}
    seconds = sp.n_frames / sp.fps
    points = _certified_points(conditions, seeds)
    over, point_over = _above(points, target_miss)
    numbers = Numbers(
        Choice({k: number(v, f"observed validation accuracy of the {k} network (mean over seeds)")
                for k, v in camera.val.items()}),
        {k: _clear_numbers(fc, seeds, seconds, sp.fps, target_miss) for k, fc in networks.items()},
        {k: _condition_numbers(c, target_miss) for k, c in conditions.items()},
        CertifiedNumbers(count(len(points), "certified operating points (conditions x seeds)"),
                         count(len(over), "of them, test miss rate's interval wholly above the target"),
                         count(len(point_over), "of them, test miss rate's point estimate above the target")))
    return CarDecision(numbers, sp, camera, networks, conditions, seeds, target_miss,
                       _clear_table(networks, seconds, target_miss), _decision_table(conditions, target_miss),
                       n_certify_heavy=int((sp.certify_y == 1).sum()), n_needed=heavy_needed(target_miss))


# ---------------------------------------------------------------------------------------------
# Each part of the result


def _certified_points(conditions: dict[ConditionKey, Condition],
                      seeds: tuple[int, ...]) -> list[tuple[str, int, Interval]]:
    """(classifier, seed, test miss rate) of every certified operating point, in the order of the conditions."""
    return [(c.name, seed, s.point.miss) for c in conditions.values()  # type: ignore[misc]
            for seed, s in zip(seeds, c.per_seed) if s.point.certified is not None]


def _above(points: Sequence[tuple[str, int, Interval]], target: float) -> tuple[list[str], list[str]]:
    """The certified points whose test miss rate lies above ``target``: wholly (its interval), and by its point
    estimate."""
    over = [f"{name}, seed {i}" for name, i, m in points if m.lo > target]
    point_over = [f"{name}, seed {i} ({pct(m.value)})" for name, i, m in points if m.value > target]
    return over, point_over


def _clear_numbers(fc: FrameClearing, seeds: tuple[int, ...], seconds: float, fps: float,
                   target: float) -> ClearNumbers:
    if fc.per_seed is None:
        return ClearNumbers(count(0, f"per-frame thresholds certifiable, {fc.name}"))
    times = np.concatenate([c.times for c in fc.per_seed])
    median = float(np.median(times)) / fps if len(times) else math.nan
    return ClearNumbers(
        None,
        number(fc.pooled(), f"light objects cleared within {seconds:g} s, {fc.name}",
               per_seed=[s.value for s in fc.shares], stable=fc.stable),
        {str(s): SeedClearing(number(c.share_cleared, f"the same, seed {s}"),
                              number(c.miss, f"heavy test throws ever cleared, seed {s} (target {target:.0%})"))
         for s, c in zip(seeds, fc.per_seed)},
        number(median, f"median time to clear the light objects cleared, {fc.name}", unit="s"))


def _condition_numbers(c: Condition, target: float) -> ConditionNumbers:
    s0 = c.per_seed[0].point
    return ConditionNumbers(
        number(c.auc, f"area under the ROC curve, {c.name}, mean over seeds"),
        number(c.ece, f"expected calibration error, {c.name}, mean over seeds"),
        number(c.ece_scaled, f"the same after temperature scaling on the calibration split, {c.name}"),
        None if s0.miss is None else
        number(s0.miss, f"heavy called light at the certified {target:.0%} point, {c.name}, seed 0"),
        None if s0.false_alarm is None else number(s0.false_alarm, f"light called heavy there, {c.name}, seed 0"),
        number(s0.miss_empirical, f"heavy called light at the calibration split's empirical {target:.0%} quantile, "
               f"{c.name}, seed 0"))


def _clear_table(networks: dict[NetworkKey, FrameClearing], seconds: float, target: float) -> Table:
    rows = []
    for fc in networks.values():
        if fc.per_seed is None:
            rows.append({"network": fc.name, "share": "not certifiable", "seeds": "—", "miss": "—",
                         "stable": "—"})
            continue
        rows.append({"network": fc.name, "share": pct_ci(fc.pooled()),
                     "seeds": ", ".join(f"{100 * s.value:.1f}" for s in fc.shares),
                     "miss": ", ".join(f"{100 * c.miss.value:.1f}" for c in fc.per_seed),
                     "stable": "yes" if fc.stable else "**no**: the seeds split"})
    return Table(rows, {"network": "answers at every frame",
                        "share": f"light objects cleared within {seconds:g} s [95 % CI]", "seeds": "each seed (%)",
                        "miss": f"heavy test throws ever cleared, each seed (%; target {target:.0%})",
                        "stable": "do the seeds agree?"})


def _decision_table(conditions: dict[ConditionKey, Condition], target: float) -> Table:
    rows = []
    for c in conditions.values():
        points = [s.point for s in c.per_seed]
        rows.append({
            "condition": c.name, "auc": f"{c.auc:.3f}",
            "thr": ", ".join(f"{p.certified:.3f}" for p in points) if c.certified else "not certifiable",
            "miss": "; ".join(pct_ci(p.miss) for p in points) if c.certified else "not certifiable",
            "alarm": "; ".join(pct_ci(p.false_alarm) for p in points) if c.certified else "—",
            "quantile": "; ".join(pct_ci(p.miss_empirical) for p in points),
            "ece": f"{c.ece:.3f} → {c.ece_scaled:.3f}"})
    return Table(rows, {
        "condition": "Z classifier", "auc": "ROC AUC (mean)", "thr": "certified threshold on p(heavy), per seed",
        "miss": f"heavy called light there, test split, per seed [95 % Wilson] (target {target:.0%})",
        "alarm": "light called heavy there (the cost)",
        "quantile": "heavy called light at the empirical quantile instead",
        "ece": "calibration error before → after scaling"})
