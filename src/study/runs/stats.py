"""Summaries of runs: a mean, a spread and a 95 % interval per group of runs, and the questions the chapters ask
of them.

Runs are a :class:`~study.runs.runtable.Runs` table; a run scored on the test split carries ``correct``,
(n,) bool, which test trajectories it got right, so intervals can resample both the test trajectories and the
seeds.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from study.core.errors import ConfigError
from study.learn.metrics import Interval, bootstrap_accuracy, hierarchical_bootstrap
from study.runs.runtable import Run, Runs


@dataclass(frozen=True)
class Summary:
    """A group of runs: the spread of one of their values, and how many failed, diverged or hit the epoch cap."""

    keys: Mapping[str, Any]
    """The fields the group shares (``{"dims": "z"}``)."""
    n: int
    """Runs in the group."""
    mean: float
    """Mean of the value."""
    std: float
    """Sample standard deviation (ddof = 1; 0 for one run)."""
    min: float
    """Lowest value."""
    max: float
    """Highest value (of a test accuracy: the best *test* run, which no chapter reports as "the best")."""
    failed: int
    """Runs that failed to train (they count in the mean, at chance)."""
    diverged: int
    """Runs whose loss became non-finite."""
    capped: int
    """Runs stopped by the epoch cap."""
    interval: Interval | None = field(default=None)
    """With a test accuracy: the 95 % bootstrap interval of the mean over test trajectories and seeds."""


def summarise(runs: Runs, by: tuple[str, ...] = (), value: str = "accuracy") -> list[Summary]:
    """Group ``runs`` by the ``by`` fields and summarise ``value`` in each group (groups in order of first
    appearance)."""
    out = []
    for k, g in runs.groups(*by).items():
        a = np.asarray([float(v) for v in g.values(value)])
        iv = bootstrap_accuracy(g.correct()) if value == "accuracy" and all(r.correct is not None for r in g) else None
        out.append(Summary(dict(zip(by, k)), len(a), float(a.mean()), float(a.std(ddof=1)) if len(a) > 1 else 0.0,
                           float(a.min()), float(a.max()), g.n_failed,
                           sum(r.diverged_epoch is not None for r in g), sum(r.capped for r in g), iv))
    return out


def summary(runs: Runs, value: str = "accuracy") -> Summary:
    """:func:`summarise` of all ``runs`` as one group."""
    if not runs:
        raise ConfigError("stats.summary: no runs to summarise")
    return summarise(runs, (), value)[0]


@dataclass(frozen=True)
class ValidationPick:
    """The paper's "best accuracy", computed fairly: on each data set, the run its validation split picks, scored
    on the test split it never saw; their mean over the data sets with a hierarchical 95 % interval."""

    picked: tuple[Run, ...]
    """The run each data set's validation picks, in data-set order."""
    interval: Interval
    """Their mean test accuracy with the hierarchical bootstrap over data sets and test throws (over one data set,
    the plain bootstrap of that one run)."""


def validation_pick(per_data: Sequence[Runs]) -> ValidationPick:
    """The run validation picks on each data set (``per_data[d]``: the seeds of one configuration trained on data
    set d) and the interval of their mean: the one statistic behind every "the run validation picks"."""
    if not per_data or any(not g for g in per_data):
        raise ConfigError("validation_pick: give the runs of one or more data sets, each with one run or more")
    picked = tuple(g.picked_by_validation() for g in per_data)
    correct = [r.correct[None] for r in picked]  # type: ignore[index]
    iv = bootstrap_accuracy(correct[0]) if len(correct) == 1 else hierarchical_bootstrap(correct)
    return ValidationPick(picked, iv)


def probabilities(models: Sequence[Any], x: np.ndarray, frames: bool = False) -> np.ndarray:
    """(S, n) float: each of ``models``' (one per seed: a ``TrainedModel``, an ``Ensemble``, the physics baseline)
    p(heavy) for trajectory i of ``x`` (n, T, 3) metres; with ``frames`` (S, n, T) after every frame
    (``predict_proba_frames``). A model labels heavy where this is above 1/2."""
    if frames:
        return np.stack([m.predict_proba_frames(x)[:, :, 1] for m in models])
    return np.stack([np.asarray(m.predict_proba(x))[:, 1] for m in models])


def label_of(p_heavy: float) -> int:
    """The class a p(heavy) says: 1 (heavy) above 1/2, else 0 (light): the one rule every score and answer uses."""
    return int(p_heavy > 0.5)


def correct_of(models: Sequence[Any], x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """(S, n) bool: model s labelled trajectory i of ``x`` (n, T, 3) right (:func:`probabilities` above 1/2 for
    heavy)."""
    return (probabilities(models, x) > 0.5) == (np.asarray(y) == 1)[None]


def scored(models: Sequence[Any], x: np.ndarray, y: np.ndarray) -> Interval:
    """The mean accuracy of ``models`` on trajectories ``x`` (n, T, 3) with labels ``y``, and its bootstrap
    interval over the trajectories and the models (seeds)."""
    return bootstrap_accuracy(correct_of(models, x, y))


@dataclass(frozen=True)
class LongInputEffect:
    """Whether accuracy falls at the longest inputs (the paper's Figure 4)."""

    dims: str
    """The input."""
    best_length: float
    """The length with the highest mean accuracy, seconds."""
    best_mean: float
    """Its mean accuracy."""
    last_length: float
    """The longest length, seconds."""
    last_mean: float
    """Its mean accuracy."""
    drop: float
    """Best mean minus the longest's."""
    hurts: bool
    """The longest is below the best and their 95 % intervals do not overlap."""


def long_input_effect(summary: Sequence[Summary], dims: str) -> LongInputEffect:
    """Does accuracy fall at the longest inputs? From :func:`summarise` groups by (dims, length).

    Compares the best mean accuracy over lengths with the mean at the longest length; ``hurts`` when
    their 95 % intervals do not overlap and the longest is below.
    """
    rows = sorted((r for r in summary if r.keys["dims"] == dims), key=lambda r: r.keys["length"])
    best = max(rows, key=lambda r: r.mean)
    last = rows[-1]
    drop = best.mean - last.mean
    assert best.interval is not None and last.interval is not None
    hurts = best is not last and drop > 0 and not best.interval.overlaps(last.interval)
    return LongInputEffect(dims, best.keys["length"], best.mean, last.keys["length"], last.mean, drop, bool(hurts))


def intervals_agree(intervals: Sequence[Interval]) -> bool:
    """Whether every pair of ``intervals`` overlaps: the seeds of a number agree, none differs significantly from
    another. False when the seeds split into groups (some trained, some stalled): the pooled mean of such seeds
    is not yet a number."""
    return all(a.overlaps(b) for i, a in enumerate(intervals) for b in intervals[i + 1:])


def mean_difference(a: np.ndarray, b: np.ndarray, n_boot: int = 2000, seed: int = 0) -> Interval:
    """The mean of ``a`` (n,) minus the mean of ``b`` (m,), two independent samples, with a percentile bootstrap
    interval (each resampled within itself), 95 %."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    rng = np.random.default_rng(seed)
    stats = rng.choice(a, (n_boot, len(a))).mean(1) - rng.choice(b, (n_boot, len(b))).mean(1)
    lo, hi = np.quantile(stats, [0.025, 0.975])
    return Interval(float(a.mean() - b.mean()), float(lo), float(hi),
                    f"bootstrap of the difference of two means ({len(a)} and {len(b)} throws)")


def bootstrap_mean(values: np.ndarray, n_boot: int = 2000, seed: int = 0) -> Interval:
    """The mean of ``values`` (n,) with a percentile bootstrap interval over them, 95 %."""
    v = np.asarray(values, float)
    rng = np.random.default_rng(seed)
    lo, hi = np.quantile(rng.choice(v, (n_boot, len(v))).mean(1), [0.025, 0.975])
    return Interval(float(v.mean()), float(lo), float(hi), f"bootstrap over {len(v)} values")
