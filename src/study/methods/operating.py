"""Operating points: from a classifier's probabilities to a car's decision, in NumPy and SciPy.

Probabilities are ``p_heavy`` (n,) floats (frame by frame: ``p_frames`` (n, T)); labels 1 = heavy. A car treats an
object as must-avoid (heavy) unless it is confident enough that it is safe to pass (light), so a threshold is set
for a target *miss rate* (the share of heavy objects called light):

- :func:`threshold_for_miss_rate`, :func:`rates`: the operating point and what it costs;
- :func:`certified_threshold`, :func:`certified_clearing_thresholds`: operating points whose miss rate on
  data they have not seen is at most the target with 95 % confidence (a one-sided Clopper-Pearson bound,
  :func:`clopper_pearson_upper`, on the certification split's misses), not only on the certification split;
  :func:`operating_point` and :func:`clearing` set them on a certification split and measure them on a test split;
- :func:`roc`, :func:`precision_recall`: the curves for must-avoid (heavy) as the positive class;
- :func:`reliability`, :func:`expected_calibration_error`, :func:`fit_temperature`, :func:`scaled`:
  whether the probabilities can be trusted (their *calibration*), before and after temperature scaling;
- :func:`time_to_clear`: when, frame by frame, a light object is first cleared as safe to pass.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from study.core.errors import ConfigError
from study.learn.metrics import Interval, wilson


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
