"""Scores of a classifier and their 95 % intervals, without torch.

- :func:`metrics`: accuracy, per-class accuracy and the confusion matrix of one set of predictions.
- :func:`wilson`: the Wilson score interval of k successes in n trials (small counts: 20 videos).
- :func:`bootstrap_accuracy`: the mean accuracy of S runs scored on the same n test items, with a
  percentile interval from resampling the items and, where S > 1, the runs (seeds) too;
  :func:`bootstrap_difference`: the same for the difference between two groups of runs.
- :func:`t_interval`: the mean of a few per-seed values with a Student-t interval.
- :func:`hierarchical_bootstrap`: the mean accuracy over several data sets (each with its own seeds and
  test set), with an interval that holds the data sets' spread too; :func:`between_share`: how much of a
  run's variance lies between data sets.
- :func:`at_chance`, :func:`training_state`, :func:`failed_to_train`: a run indistinguishable from guessing, or
  still on its initial plateau, judged on its validation loss and accuracy (or too few validation items to tell).

Every interval is an :class:`Interval`: the estimate, its bounds and how it was computed.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
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
    lo = 0.0 if k == 0 else max(0.0, centre - half)  # exactly 0 (1) at no (every) success, not 2e-19 off it
    hi = 1.0 if k == n else min(1.0, centre + half)
    return Interval(p, lo, hi, f"Wilson interval, {k} of {n}")


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


TRAINING_STATES = ("trained", "failed", "too few to tell")
"""What a run's validation part says of it (:func:`training_state`)."""


def too_few_to_tell(n: int) -> bool:
    """Whether ``n`` validation items are too few for any accuracy to be told from guessing: even all of them right,
    the Wilson interval reaches 1/2 (3 or fewer)."""
    return n < 1 or wilson(n, n).lo <= 0.5


def training_state(val_accuracy: float, val_loss: float, n_val: int) -> str:
    """What the validation part says of a run, judged on its loss and its accuracy:

    - ``"failed"``: its loss is not finite (it diverged) or never left the initial plateau (:data:`PLATEAU_LOSS`),
      or its accuracy cannot be told from guessing (:func:`at_chance`) on a validation part large enough to tell;
    - ``"too few to tell"``: its loss left the plateau, but the validation part is too small for its accuracy to
      say anything (:func:`too_few_to_tell`: 3 right of 3 is within a coin's reach);
    - ``"trained"`` otherwise.
    """
    if not (math.isfinite(val_loss) and math.isfinite(val_accuracy)) or not val_loss < PLATEAU_LOSS:
        return "failed"
    if too_few_to_tell(n_val):
        return "too few to tell"
    return "failed" if at_chance(val_accuracy, n_val) else "trained"


def failed_to_train(val_accuracy: float, val_loss: float, n_val: int) -> bool:
    """A run failed to train (:func:`training_state` says ``"failed"``): it ended where it started."""
    return training_state(val_accuracy, val_loss, n_val) == "failed"


def t_interval(values: Sequence[float], level: float = LEVEL) -> Interval:
    """The mean of a few values (one per seed, say) with a Student-t interval: mean ± t(n - 1) · sd / sqrt(n),
    sd the sample standard deviation. One value has no spread to measure: lo = hi = the value."""
    v = np.asarray(values, dtype=np.float64).ravel()
    if len(v) == 0 or not np.isfinite(v).all():
        raise ConfigError(f"t_interval: values {list(v)!r}; give one or more finite numbers")
    if not 0 < level < 1:
        raise ConfigError(f"t_interval: level = {level!r}; it must lie in (0, 1), e.g. 0.95")
    mean = float(v.mean())
    if len(v) == 1:
        return Interval(mean, mean, mean, "one value: no interval")
    from scipy.stats import t

    half = float(t.ppf(0.5 + level / 2, len(v) - 1)) * float(v.std(ddof=1)) / math.sqrt(len(v))
    return Interval(mean, mean - half, mean + half, f"Student-t interval over {len(v)} values")


def _runs(correct: Sequence[np.ndarray], what: str) -> list[np.ndarray]:
    """Each data set's (S_d, n_d) bool array; (n_d,) is one run."""
    sets = [np.atleast_2d(np.asarray(c, dtype=bool)) for c in correct]
    if not sets:
        raise ConfigError(f"{what}: no data sets; pass one (S, n) bool array per data set")
    for d, c in enumerate(sets):
        if c.ndim != 2 or c.size == 0:
            raise ConfigError(f"{what}: data set {d} is {c.shape}; need (seeds, test throws) with both >= 1")
    return sets


def _resampled_means(c: np.ndarray, m: int, rng: np.random.Generator, chunk: int = 1 << 22) -> np.ndarray:
    """(m,) mean accuracies of ``c`` (S, n), each over S runs and n test throws drawn with replacement
    (the same throws for every run: they share the test set). As counts: w (S,) times drawn, v (n,),
    mean = w @ c @ v / (S n); in chunks of about ``chunk`` elements."""
    S, n = c.shape
    cf = c.astype(np.float64)
    out = np.empty(m)
    step = max(1, chunk // n)
    for a in range(0, m, step):
        k = min(step, m - a)
        rows = np.arange(k)[:, None]
        w = np.bincount((rows * S + rng.integers(0, S, (k, S))).ravel(), minlength=k * S).reshape(k, S)
        v = np.bincount((rows * n + rng.integers(0, n, (k, n))).ravel(), minlength=k * n).reshape(k, n)
        out[a:a + k] = np.einsum("kn,kn->k", w @ cf, v) / (S * n)
    return out


def hierarchical_bootstrap(correct: Sequence[np.ndarray], n_boot: int = BOOTSTRAP, seed: int = 0,
                           level: float = LEVEL) -> Interval:
    """The mean accuracy over data sets, with a percentile interval that holds the spread between data sets,
    between seeds and between test throws.

    ``correct[d]``: (S_d, n_d) bool, run s of data set d on its own test throw i ((n_d,) for one run).
    Each resample draws D data sets with replacement, then within each drawn one its S_d seeds and its n_d
    test throws with replacement, and averages the drawn data sets' mean accuracies. The estimate is the
    mean over data sets of each one's mean. Seeded: the same input gives the same interval. When the data
    sets agree the interval is a little wider than one with the data sets held fixed (sqrt((2D - 1) / D)
    times, as the test sets' noise enters twice: within each data set and through the spread of their
    means). With few data sets the data-set level is coarse: the interval cannot reach beyond the range of
    their means, so with three, read it beside :func:`t_interval` of the three means.
    """
    sets = _runs(correct, "hierarchical_bootstrap")
    if not (isinstance(n_boot, (int, np.integer)) and n_boot >= 1):
        raise ConfigError(f"hierarchical_bootstrap: n_boot = {n_boot!r}; give a number of resamples >= 1")
    D = len(sets)
    rng = np.random.default_rng(seed)
    drawn = rng.integers(0, D, (n_boot, D))  # the data sets of each resample
    means = np.empty((n_boot, D))
    for d, c in enumerate(sets):
        at = drawn == d  # every slot that drew data set d gets its own draw of seeds and throws
        means[at] = _resampled_means(c, int(at.sum()), rng)
    stats = means.mean(axis=1)
    alpha = (1 - level) / 2
    lo, hi = np.quantile(stats, [alpha, 1 - alpha])
    value = float(np.mean([c.mean() for c in sets]))
    what = f"hierarchical bootstrap over {D} data set{'s' if D != 1 else ''}, their seeds and test throws"
    return Interval(value, float(lo), float(hi), what)


def between_share(correct: Sequence[np.ndarray]) -> dict[str, Any]:
    """The share of the variance of one run's accuracy that lies between data sets.

    ``correct[d]``: (S_d, n_d) bool as for :func:`hierarchical_bootstrap`. Each run's accuracy (its mean
    over its n_d throws) is one observation, grouped by data set; a one-way random-effects ANOVA by the
    method of moments (unbalanced: groups may hold different numbers of runs) gives the within variance
    σ²_w = MS_within and the between variance σ²_b = max(0, (MS_between - MS_within) / n0), with
    n0 = (N - Σ S_d² / N) / (D - 1). Returns ``{"share": σ²_b / (σ²_b + σ²_w)`` (0 when both are 0),
    ``"between_sd": σ_b, "within_sd": σ_w`` (fractions of accuracy) ``, "method"}``. Needs two or more data
    sets and at least one with two or more runs.
    """
    sets = _runs(correct, "between_share")
    groups = [c.mean(axis=1) for c in sets]
    D, sizes = len(groups), np.array([len(g) for g in groups], dtype=np.float64)
    N = float(sizes.sum())
    if D < 2 or N <= D:
        raise ConfigError(f"between_share: {D} data set(s) with {[len(g) for g in groups]} runs; need two or more "
                          "data sets and at least one with two or more seeds")
    means = np.array([g.mean() for g in groups])
    grand = float(np.concatenate(groups).mean())
    ms_between = float((sizes * (means - grand) ** 2).sum()) / (D - 1)
    ms_within = float(sum(((g - g.mean()) ** 2).sum() for g in groups)) / (N - D)
    n0 = (N - float((sizes ** 2).sum()) / N) / (D - 1)
    var_b = max(0.0, (ms_between - ms_within) / n0)
    total = var_b + ms_within
    return {"share": var_b / total if total > 0 else 0.0, "between_sd": math.sqrt(var_b),
            "within_sd": math.sqrt(ms_within),
            "method": f"one-way random-effects ANOVA (method of moments) on the accuracies of {int(N)} runs "
                      f"in {D} data sets: between-data-set variance over between plus within, truncated at 0"}
