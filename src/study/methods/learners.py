"""Learners: the ways the study tells light from heavy, each fitted on a training split and scored on test splits
through one interface, so the chapters that compare them (motion, engine, baselines) score them alike.

A :class:`Learner` has a name and :meth:`Learner.score`: which test throws it gets right, on each of several test inputs (the exact and the
observed test split, or each engine's). The implementations:

- :class:`Network`: a recurrent network's runs over seeds, trained (or read) by the runner;
- :class:`Rocket`: MiniRocket fitted once per seed, cached like a run (``study.methods.rockets``);
- :class:`Physics`: the physics baseline (``study.learn.baseline``), fitted on the spot;
- :class:`Rule`: the best one-feature rule, chosen on the training split (``study.simulate.measure.best_rule``).

    tests = {"exact": (x_test, y_test), "observed": (x_seen, y_test)}   # (n, T, 3) metres, (n,) labels
    scores = Network("peephole", cfg, seeds=(0, 1, 2)).score(runner, None, tests)
    scores.p_heavy["observed"]                                          # (S, n) float: seed s's p(heavy) of throw i
    scores.correct["observed"]                                          # (S, n) bool: seed s got throw i right
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Protocol

import numpy as np

from study.learn import baseline
from study.learn.config import Dims, TrainConfig
from study.methods.rockets import rocket_predictions
from study.report.learners import WORDS
from study.runs.stats import probabilities
from study.simulate import measure, observe

if TYPE_CHECKING:
    from study.runs.runner import Runner
    from study.runs.runtable import Runs

Tests = Mapping[str, tuple[np.ndarray, np.ndarray]]
"""Test inputs by name: (x (n, T, 3) float, metres; y (n,) int labels)."""

NAMES: dict[str, str] = WORDS
"""Each learner in words (``study.report.learners``, where each is defined once)."""


@dataclass(frozen=True)
class Scores:
    """How a learner answered each test input: every seed's probability that each throw is heavy.

    A network's is its softmax; the physics baseline's its logistic; MiniRocket's its ridge decision through a
    logistic fitted on held-out values (``study.learn.rocket``); a rule's 0 or 1. A learner that answers at every
    frame (``Network(frames=True)``) gives one per frame. The label is heavy where the probability is above 1/2.
    """

    p_heavy: dict[str, np.ndarray]
    """Test name -> (S, n) float in [0, 1]: seed s's p(heavy) for throw i (S = 1 for a learner without a seed);
    (S, n, T) after each of T frames for a learner that answers at every frame."""
    y: dict[str, np.ndarray]
    """Test name -> (n,) int labels (0 light, 1 heavy)."""
    failed: int = 0
    """Seeds that failed to train."""
    val: float | None = None
    """Mean validation accuracy over the seeds, for the networks."""
    feature: str = ""
    """The feature a rule chose."""
    seeds: tuple[int, ...] = ()
    """The seeds of its runs (none for the physics baseline and the rules)."""
    runs: Runs | None = field(default=None, compare=False, repr=False)
    """A network's run records (their test accuracy on the exact test split, as trained)."""

    @property
    def correct(self) -> dict[str, np.ndarray]:
        """Test name -> (S, n) bool: seed s labelled throw i right (at the last frame, for every-frame answers)."""
        return {k: (last_frame(p) > 0.5) == (np.asarray(self.y[k]) == 1)[None] for k, p in self.p_heavy.items()}


def last_frame(p: np.ndarray) -> np.ndarray:
    """(S, n) of ``p`` (S, n) or (S, n, T): the answer after the last frame."""
    return p[..., -1] if p.ndim == 3 else p


class Learner(Protocol):
    """A way to tell light from heavy, fitted on a training split and scored on test inputs."""

    name: str

    def score(self, runner: Runner, x_train: np.ndarray | None, tests: Tests) -> Scores:
        """Fitted on ``runner``'s training split (``x_train``, (n, T, 3) metres, in place of its positions where
        given: an observed draw) and scored on each of ``tests``."""


@dataclass(frozen=True)
class Network:
    """A network's runs at ``cfg`` on ``dims``, one per seed, trained or read by the runner (a network is trained on
    the condition its config says; ``x_train`` is not used)."""

    name: str
    cfg: TrainConfig
    seeds: tuple[int, ...]
    dims: Dims = "z"
    desc: str = ""
    """What the progress bar says while its runs train."""
    frames: bool = False
    """Answer after every frame (``TrainedModel.predict_proba_frames``), not only the last."""

    def score(self, runner: Runner, x_train: np.ndarray | None, tests: Tests) -> Scores:
        runs = runner.train_runs(self.cfg, (self.dims,), self.seeds, desc=self.desc or self.name)
        models = runner.models(self.cfg, self.seeds, dims=self.dims) if tests else []  # loaded only to be scored
        p = {k: probabilities(models, x, self.frames) for k, (x, _) in tests.items()}
        return Scores(p, _labels(tests), runs.n_failed, float(np.mean(runs.val_accuracies())), seeds=tuple(self.seeds),
                      runs=runs)


@dataclass(frozen=True)
class Rocket:
    """MiniRocket on ``dims``'s first ``n_frames`` frames, fitted once per seed on the training split (the cached
    exact fit when ``x_train`` is None) and cached like a run."""

    dims: Dims
    n_frames: int
    seeds: tuple[int, ...]
    name: str = "minirocket"

    def score(self, runner: Runner, x_train: np.ndarray | None, tests: Tests) -> Scores:
        xs = {k: x for k, (x, _) in tests.items()}
        fits = [rocket_predictions(runner.dataset, self.dims, self.n_frames, s, xs, runner.data_dir, x_train)
                for s in self.seeds]
        return Scores({k: np.stack([f[k] for f in fits]) for k in tests}, _labels(tests), seeds=tuple(self.seeds))


@dataclass(frozen=True)
class Physics:
    """The physics baseline on ``dims``, fitted on the first ``length`` seconds of the training split."""

    dims: Dims
    length: float
    """Input length, seconds."""
    name: str = "physics"

    def score(self, runner: Runner, x_train: np.ndarray | None, tests: Tests) -> Scores:
        ds = runner.dataset
        if x_train is not None:
            ds = dataclasses.replace(ds, train=dataclasses.replace(ds.train, x=x_train))
        fitted = baseline.fit(ds, self.dims, self.length)
        return Scores({k: probabilities([fitted], x) for k, (x, _) in tests.items()}, _labels(tests))


@dataclass(frozen=True)
class Rule:
    """The best one-feature rule of ``features`` (None: every feature), chosen on the training split; with
    ``height_only``, the rules read the height alone (what one camera gives)."""

    features: tuple[str, ...] | None
    contact: float
    """The shape's bounding radius, metres (where the first fall ends)."""
    height_only: bool = True
    name: str = "rule"

    def score(self, runner: Runner, x_train: np.ndarray | None, tests: Tests) -> Scores:
        ds = runner.dataset
        seen = observe.height_only if self.height_only else (lambda x: x)
        xtr = ds.train.x if x_train is None else x_train
        p, feature = {}, ""
        for k, (x, y) in tests.items():
            rules = measure.simple_rules(seen(xtr), ds.train.y, seen(x), y, ds.fps, self.contact, self.features)
            best = measure.best_rule(rules)
            p[k], feature = best["heavy"][None].astype(np.float64), feature or best["feature"]
        return Scores(p, _labels(tests), feature=feature)


def _labels(tests: Tests) -> dict[str, np.ndarray]:
    return {k: np.asarray(y) for k, (_, y) in tests.items()}
