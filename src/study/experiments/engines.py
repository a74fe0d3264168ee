"""Another engine: the same throws simulated in Bullet (the paper's engine, through Blender) and in MuJoCo.

Both data sets hold the same sampled objects and launches, index by index, without air. This module compares
them throw by throw (:func:`agreement`) and asks whether what a learner learns in one engine holds in the
other (:func:`cross_cells`): every learner trained on one engine's training split and tested on both engines'
test splits, exact and through the calibrated tracker.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

import numpy as np

from study.experiments import motion
from study.learn.config import TrainConfig
from study.learn.metrics import Interval, bootstrap_accuracy, bootstrap_difference
from study.simulate import measure
from study.simulate.data import Dataset

ENGINES = ("mujoco", "bullet")
"""The engines compared, the study's first."""
LEARNERS = ("lstm_positions", "lstm_velocity", "minirocket", "rule")
"""The learners of the cross-engine table."""
AGREEMENT = {"bounces": "bounces", "time_to_rest": "time to rest, s", "first_rebound": "first rebound's height, m",
             "distance": "horizontal distance, m"}
"""What :func:`agreement` compares, throw by throw."""


def first_rebound(z: np.ndarray, rest_height: float) -> np.ndarray:
    """The height of the first rebound's apex above the resting height, metres, for each height series of ``z``
    (n, T); 0 for a throw that never rebounds by ``measure.MIN_RISE``."""
    out = np.zeros(len(z))
    for i, s in enumerate(np.asarray(z, float)):
        b = measure.bounces(s)
        if len(b.apexes):
            out[i] = s[b.apexes[0]] - rest_height
    return out


def agreement(a: np.ndarray, b: np.ndarray, fps: float, rest_height: float) -> dict[str, np.ndarray]:
    """Per throw, ``b`` minus ``a`` (two engines' trajectories of the same throws, (n, T, 3) metres) for each
    summary of :data:`AGREEMENT`: name -> (n,) differences."""
    fa, fb = measure.features(a, fps), measure.features(b, fps)
    out = {k: fb[k] - fa[k] for k in ("bounces", "time_to_rest", "distance")}
    out["first_rebound"] = first_rebound(b[..., 2], rest_height) - first_rebound(a[..., 2], rest_height)
    return {k: out[k] for k in AGREEMENT}


@dataclass
class Cross:
    """One learner trained on one engine and tested on one engine's test split, in one condition."""

    learner: str
    train: str
    test: str
    column: motion.Column
    correct: np.ndarray
    """(S, n) bool: seed s got test throw i right."""
    failed: int = 0

    @property
    def interval(self) -> Interval:
        return bootstrap_accuracy(self.correct)


def cross_cells(runners: dict[str, Any], cfgs: dict[str, TrainConfig], column: motion.Column,
                seeds: tuple[int, ...], contact_height: float) -> list[Cross]:
    """Every learner of :data:`LEARNERS`, trained on each engine (``runners``: engine -> the runner on its data
    set) under ``column``'s condition and tested on every engine's test split the same way."""
    T = cfgs["lstm_positions"].n_frames(next(iter(runners.values())).fps)
    data = {e: column.inputs(r.dataset, T) for e, r in runners.items()}  # the same noise in both engines
    y = {e: np.asarray(r.dataset.test.y) for e, r in runners.items()}
    out = []
    for train_engine, runner in runners.items():
        for name in ("lstm_positions", "lstm_velocity"):
            cfg = motion.trained_config(cfgs[name], column)
            rows = runner.train_runs(cfg, ("z",), seeds, desc=f"{train_engine} {name}")
            models = runner.models(cfg, seeds, dims="z")
            for test_engine, (_, x_test) in data.items():
                correct = np.stack([m.predict_proba(x_test).argmax(1) == y[test_engine] for m in models])
                out.append(Cross(name, train_engine, test_engine, column, correct, sum(r["failed"] for r in rows)))
        x_train = data[train_engine][0]
        tests = {e: x for e, (_, x) in data.items()}
        labels = [runner.rocket("z", T, s, tests, train_x=None if column.noise is None else x_train) for s in seeds]
        for test_engine in data:
            out.append(Cross("minirocket", train_engine, test_engine, column,
                             np.stack([lab[test_engine] == y[test_engine] for lab in labels])))
        z_only = lambda x: np.concatenate([np.zeros_like(x[..., :2]), x[..., 2:]], axis=-1)  # noqa: E731
        f_train = measure.features(z_only(x_train), runner.fps, contact_height)
        fits = {k: measure.best_threshold_rule(f_train[k], runner.dataset.train.y, f_train[k], runner.dataset.train.y)
                for k in motion.RULE_FEATURES}
        best = max(fits, key=lambda k: fits[k]["train_accuracy"])  # chosen on the training engine's split
        rule = fits[best]
        for test_engine, (_, x_test) in data.items():
            f = measure.features(z_only(x_test), runner.fps, contact_height)[best]
            f = np.where(np.isfinite(f), f, np.nanmedian(f_train[best]))
            pred = f > rule["threshold"] if rule["direction"] == ">" else f <= rule["threshold"]
            out.append(Cross("rule", train_engine, test_engine, column, (pred == (y[test_engine] == 1))[None]))
    return out


def transfer(cells: list[Cross], learner: str, column: motion.Column) -> dict[str, Interval]:
    """What ``learner`` loses when the test engine is not its training engine, in ``column``: for each training
    engine, the accuracy on the other engine minus that on its own (paired on the same throws), with a
    bootstrap interval."""
    by = {(c.train, c.test): c for c in cells if c.learner == learner and c.column == column}
    out = {}
    for e in ENGINES:
        other = next(o for o in ENGINES if o != e)
        if (e, e) in by and (e, other) in by:
            out[e] = bootstrap_difference(by[e, other].correct, by[e, e].correct)
    return out


def plan(runners: dict[str, Any], cfgs: dict[str, TrainConfig], cols: list[motion.Column], seeds: tuple[int, ...],
         table1_seeds: tuple[int, ...]) -> list[tuple[Any, list[TrainConfig], bool]]:
    """Every network run of the chapter, as ``Runner.prefetch`` takes them: the cross-engine networks in each
    engine and column, and Table 1's positions network on X, Y, Z and Z with ``table1_seeds``."""
    table1 = [dataclasses.replace(cfgs["lstm_positions"], dims=d, seed=s) for d in ("z", "xyz") for s in table1_seeds]
    return [(r, [dataclasses.replace(motion.trained_config(cfgs[n], c), seed=s)
                 for c in cols for n in ("lstm_positions", "lstm_velocity") for s in seeds] + table1, True)
            for r in runners.values()]
