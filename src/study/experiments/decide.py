"""From a classifier's probabilities to a car's decision, without torch.

The paper reports accuracy. A car must decide: treat the object as must-avoid (heavy) unless it is
confident enough that it is safe to pass (light). Missing a heavy object is far worse than a needless
swerve, so the decision threshold is set for a target *miss rate* (the share of heavy objects called
light) on a calibration split that neither training nor model selection has seen, and the miss rate is
then measured on the test split. Probabilities are ``p_heavy`` (n,) floats; labels 1 = heavy.

- :func:`threshold_for_miss_rate`, :func:`rates`: the operating point and what it costs;
- :func:`roc`, :func:`precision_recall`: the curves for must-avoid (heavy) as the positive class;
- :func:`reliability`, :func:`expected_calibration_error`, :func:`fit_temperature`, :func:`scaled`:
  whether the probabilities can be trusted, before and after temperature scaling;
- :func:`time_to_clear`: when, frame by frame, a light object is first cleared as safe to pass.
"""

from __future__ import annotations

import math

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
    p, y = _check(p_heavy, y, "calibration set")
    heavy = np.sort(p[y == 1])
    if len(heavy) == 0:
        raise ConfigError("calibration set: it holds no heavy object; a miss rate needs some")
    k = int(math.floor(target * len(heavy)))  # heavy objects we may call light
    return float(heavy[k]) if k < len(heavy) else 1.0  # below the (k+1)-th smallest: at most k misses


def rates(p_heavy: np.ndarray, y: np.ndarray, threshold: float) -> dict[str, Interval]:
    """At ``threshold``: the miss rate (heavy called light) and the false-alarm rate (light called heavy),
    each with its Wilson interval."""
    p, y = _check(p_heavy, y)
    heavy, light = p[y == 1], p[y == 0]
    if len(heavy) == 0 or len(light) == 0:
        raise ConfigError("test set: it needs light and heavy objects to measure both rates")
    miss = wilson(int((heavy < threshold).sum()), len(heavy))
    alarm = wilson(int((light >= threshold).sum()), len(light))
    return {"miss": miss, "false_alarm": alarm}


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
    """The temperature that minimises the negative log-likelihood of ``y`` (calibration split): a golden-
    section search over log T in [-3, 3] (T from 0.05 to 20)."""
    p, y = _check(p_heavy, y, "calibration set")
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


def clearing_thresholds(p_frames: np.ndarray, y: np.ndarray, target: float, steps: int = 40) -> np.ndarray:
    """Per-frame thresholds (T,) for :func:`time_to_clear` such that at most ``target`` of the heavy objects
    of the calibration set ``p_frames`` (n, T) are *ever* cleared -- a car passes an object the first
    time it is cleared, so a miss at any frame is a miss.

    Each frame's threshold is :func:`threshold_for_miss_rate` at a per-frame rate a <= ``target``; the
    largest a whose cumulative miss rate stays within ``target`` is found by bisection.
    """
    p = np.asarray(p_frames, dtype=np.float64)
    if p.ndim != 2:
        raise ConfigError(f"clearing_thresholds: p_frames {p.shape} must be (n, T)")
    threshold_for_miss_rate(p[:, -1], y, target)  # checks the target and the set
    heavy = np.asarray(y) == 1

    def thresholds(a: float) -> np.ndarray:
        return np.array([threshold_for_miss_rate(p[:, t], y, a) for t in range(p.shape[1])])

    def cumulative_miss(a: float) -> float:
        return float((time_to_clear(p[heavy], thresholds(a)) >= 0).mean())

    lo, hi = 0.0, float(target)
    if cumulative_miss(hi) <= target:
        return thresholds(hi)
    for _ in range(steps):
        mid = (lo + hi) / 2
        if mid > 0 and cumulative_miss(mid) <= target:
            lo = mid
        else:
            hi = mid
    return thresholds(lo) if lo > 0 else np.zeros(p.shape[1])  # clear nothing: never a miss
