"""Scores of a classifier and their 95 % intervals, without torch.

- :func:`metrics`: accuracy, per-class accuracy and the confusion matrix of one set of predictions.
- :func:`wilson`: the Wilson score interval of k successes in n trials (small counts: 20 videos).
- :func:`bootstrap_accuracy`: the mean accuracy of S runs scored on the same n test items, with a
  percentile interval from resampling the items and, where S > 1, the runs (seeds) too;
  :func:`bootstrap_difference`: the same for the difference between two groups of runs.
- :func:`at_chance`, :func:`failed_to_train`: a run indistinguishable from guessing, or still on its
  initial plateau.

Every interval is an :class:`Interval`: the estimate, its bounds and how it was computed.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from study import CLASSES
from study.core.errors import ConfigError

LEVEL = 0.95
"""Coverage of every interval in the study."""
BOOTSTRAP = 2000
"""Bootstrap resamples per interval."""


@dataclass(frozen=True)
class Interval:
    """An estimate with its 95 % interval."""

    value: float
    """The estimate (an accuracy: a fraction in [0, 1])."""
    lo: float
    """Lower bound of the interval."""
    hi: float
    """Upper bound of the interval."""
    method: str
    """How the interval was computed, in words ("bootstrap over 2000 test trajectories and 5 seeds")."""

    def contains(self, x: float) -> bool:
        """Whether ``x`` lies inside the interval (bounds included)."""
        return self.lo <= x <= self.hi

    def overlaps(self, other: Interval) -> bool:
        """Whether the two intervals share a point."""
        return self.lo <= other.hi and other.lo <= self.hi

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


def metrics(y_true: np.ndarray, y_pred: np.ndarray) -> dict[str, Any]:
    """Accuracy, per-class accuracy and the confusion matrix (rows true class, columns predicted)."""
    y_true, y_pred = np.asarray(y_true), np.asarray(y_pred)
    cm = np.zeros((len(CLASSES), len(CLASSES)), dtype=np.int64)
    np.add.at(cm, (y_true, y_pred), 1)
    per_class = {c: (float(cm[k, k] / cm[k].sum()) if cm[k].sum() else math.nan) for k, c in enumerate(CLASSES)}
    return {
        "n": int(len(y_true)),
        "accuracy": float((y_true == y_pred).mean()) if len(y_true) else math.nan,
        "per_class_accuracy": per_class,
        "confusion": cm.tolist(),
        "classes": list(CLASSES),
    }


def _z(level: float) -> float:
    """The standard normal quantile for a two-sided ``level`` interval (1.96 for 0.95)."""
    from statistics import NormalDist

    return NormalDist().inv_cdf(0.5 + level / 2)


def wilson(k: int, n: int, level: float = LEVEL) -> Interval:
    """The Wilson score interval of ``k`` successes in ``n`` trials: good coverage at small n and near 0 or 1."""
    if not (isinstance(n, (int, np.integer)) and n > 0) or not 0 <= k <= n:
        raise ConfigError(f"wilson: k = {k!r} successes of n = {n!r} trials; need 0 <= k <= n and n >= 1")
    z = _z(level)
    p = k / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return Interval(p, max(0.0, centre - half), min(1.0, centre + half), f"Wilson interval, {k} of {n}")


def bootstrap_accuracy(correct: np.ndarray, n_boot: int = BOOTSTRAP, seed: int = 0, level: float = LEVEL) -> Interval:
    """Mean accuracy of S runs on the same n test items, with a percentile bootstrap interval.

    ``correct``: (n,) or (S, n) bool, whether run s got item i right. Each resample draws n items with
    replacement (the same draw for every run: they share the test set) and, if S > 1, S runs with
    replacement, so the interval holds both the test set's and the seeds' variation. Seeded: the same
    input gives the same interval.
    """
    c = np.atleast_2d(np.asarray(correct, dtype=bool))
    S, n = c.shape
    if n == 0 or S == 0:
        raise ConfigError("bootstrap_accuracy: no test items or no runs to score")
    rng = np.random.default_rng(seed)
    stats = np.empty(n_boot)
    for b in range(n_boot):
        items = rng.integers(0, n, n)
        runs = rng.integers(0, S, S) if S > 1 else np.zeros(1, int)
        stats[b] = c[np.ix_(runs, items)].mean()
    alpha = (1 - level) / 2
    lo, hi = np.quantile(stats, [alpha, 1 - alpha])
    what = f"bootstrap over {n} test trajectories" + (f" and {S} seeds" if S > 1 else "")
    return Interval(float(c.mean()), float(lo), float(hi), what)


def bootstrap_difference(a: np.ndarray, b: np.ndarray, n_boot: int = BOOTSTRAP, seed: int = 0,
                         level: float = LEVEL) -> Interval:
    """Mean accuracy of the runs ``a`` minus that of the runs ``b``, all scored on the same n test items.

    ``a`` (Sa, n) and ``b`` (Sb, n) bool (or (n,) for one run). Each resample draws the same n items for
    both (the comparison is paired) and each group's runs with replacement.
    """
    a, b = np.atleast_2d(np.asarray(a, bool)), np.atleast_2d(np.asarray(b, bool))
    if a.shape[1] != b.shape[1] or a.shape[1] == 0:
        raise ConfigError(f"bootstrap_difference: runs scored on {a.shape[1]} and {b.shape[1]} items; need the same test set")
    n = a.shape[1]
    rng = np.random.default_rng(seed)
    stats = np.empty(n_boot)
    for i in range(n_boot):
        items = rng.integers(0, n, n)
        ra = rng.integers(0, len(a), len(a)) if len(a) > 1 else np.zeros(1, int)
        rb = rng.integers(0, len(b), len(b)) if len(b) > 1 else np.zeros(1, int)
        stats[i] = a[np.ix_(ra, items)].mean() - b[np.ix_(rb, items)].mean()
    alpha = (1 - level) / 2
    lo, hi = np.quantile(stats, [alpha, 1 - alpha])
    what = f"paired bootstrap over {n} test trajectories ({len(a)} and {len(b)} runs)"
    return Interval(float(a.mean() - b.mean()), float(lo), float(hi), what)


def at_chance(accuracy: float, n: int) -> bool:
    """Whether an accuracy on ``n`` items cannot be told from guessing: the lower end of its Wilson interval
    is at or below 1/2."""
    return wilson(int(round(accuracy * n)), n).lo <= 0.5


PLATEAU_LOSS = 0.9 * math.log(2)
"""Cross-entropy (nats) above which a classifier has not left the initial plateau: within 10 % of a coin's
ln 2. Trained runs of the study reach 0.4-0.5; a stalled one stays near 0.69 at 55 % accuracy."""


def failed_to_train(val_accuracy: float, val_loss: float, n_val: int) -> bool:
    """A run failed to train if its validation accuracy is :func:`at_chance`, or its validation loss never
    left the initial plateau (:data:`PLATEAU_LOSS`): it ended where it started."""
    return at_chance(val_accuracy, n_val) or not val_loss < PLATEAU_LOSS
