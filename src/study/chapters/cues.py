"""The chapter *What the network sees*: which cue separates the classes, and how robust the classifier is.

Our classes differ in restitution and friction, as the paper intends, but also in mass, and mass shows in the
motion through air drag: a light box falls measurably slower than a heavy one. :func:`compute` asks which of
those cues a classifier uses, with Table 1's protocol and configuration (no new grid), and returns :class:`Cues`:

1. the drag cue (:func:`drag_cue`): the first fall's vertical acceleration, one threshold on it, and the same
   threshold under tracker noise;
2. the tracker's error on rendered video (``calibration.tracker_error``, ``study.methods.tracker``);
3. four conditions (:func:`conditions`): (a) exact positions with air, (b) the same throws without air, (c)
   Table 1's Z models tested as observed, (d) Z models trained on random observations; the one-feature rules
   (:func:`rules`) on the same input; the fitted ceiling (:func:`ceiling`); whether the network beats the best
   rule without drag;
4. accuracy against each parameter of the observation model (:func:`robustness`);
5. accuracy against each throw's restitution, mass and friction (:func:`by_parameter`, :func:`overlap`);
6. other shapes (:func:`shape_sets`, :func:`mixed_shapes`, :func:`shape_scores`);
7. the exact ceiling of the priors (``study.methods.ceiling``).

:class:`Numbers` is what the chapter reports (``cues.drag_rule.exact`` and so on); ``study.book.publish`` glues
the rest of :class:`Cues` (its sentences and tables).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import Any

import numpy as np

from study.core import cache
from study.learn import baseline
from study.learn.config import Dims, TrainConfig
from study.learn.metrics import Interval, bootstrap_accuracy, bootstrap_difference
from study.learn.train import TrainedModel
from study.methods import calibration, learners
from study.methods.ceiling import exact_ceiling
from study.methods.tracker import LABELS, Decomposition, TrackerError
from study.methods.tracker_model import TrackerFit
from study.methods.windows import DRAG, rules
from study.report import verdicts
from study.report.cues import (
    GROUPS,
    CeilingNumbers,
    Condition,
    Curve,
    DecomposedNumbers,
    DragRuleNumbers,
    ErrorNumbers,
    Group,
    Numbers,
    RuleCondition,
    ShapeNumbers,
    TrackerNumbers,
)
from study.report.reported import Number, Verdict, number
from study.report.text import Table, pct_ci, seeds_ci
from study.runs import paper
from study.runs.runner import Runner
from study.runs.runtable import Runs
from study.runs.stats import scored
from study.simulate import data, measure, observe, synth
from study.simulate.scene import Shape

CONDITIONS: dict[Condition, str] = {"a": "(a) exact, air on", "b": "(b) exact, air off",
                                    "c": "(c) observed (trained exact)",
                                    "d": "(d) observed (trained on random observations)"}
"""Each condition in words."""
PARAMETERS = ("restitution", "mass", "friction")
"""The throw parameters the errors are set against."""
ROBUSTNESS_SEED = 5
"""Seed of the observation noise of every point of the robustness sweeps."""


# ---------------------------------------------------------------------------------------------
# What the chapter reports


DECOMPOSED: dict[str, tuple[str, str, float]] = {
    "bias": ("bias_mm", "mean error, tracked minus true, up positive", 1e-3),
    "offset": ("offset_mm", "spread of the videos' mean errors (a per-throw offset)", 1e-3),
    "noise": ("noise_mm", "error about each video's mean, pooled (standard deviation)", 1e-3),
    "rho": ("rho", "lag-1 autocorrelation of that error from frame to frame", 1.0),
    "flight": ("flight_mm", "its standard deviation in flight", 1e-3),
    "contact": ("contact_mm", "its standard deviation while the object touches the ground", 1e-3),
    "velocity": ("velocity_mps", "root mean square error of the frame-to-frame velocity", 1.0),
    "height_rms": ("height_rms_mm", "end-to-end height error, root mean square", 1e-3),
    "height_rms_median": ("height_rms_median_mm", "the same, each video's median removed", 1e-3),
    "scale_rms_median": ("scale_rms_median_mm", "the depth-free pipeline's (one scale from the object's size at "
                         "rest), median removed", 1e-3),
    "lost": ("lost", "share of the frames in view the tracker lost", 1.0),
}
"""Each decomposed number: the :class:`~study.methods.tracker.Decomposition` field, what it is, the factor to SI
units (metres, m/s; a correlation and a share as they are)."""
UNITS = {"rho": "correlation", "velocity": "m/s", "lost": "fraction"}


def _decomposed(d: Decomposition, which: str) -> DecomposedNumbers:
    return DecomposedNumbers(**{k: number(getattr(d, f) * scale, f"{what}, tracker with {LABELS[which]}",
                                          unit=UNITS.get(k, "m"))
                                for k, (f, what, scale) in DECOMPOSED.items()})


# ---------------------------------------------------------------------------------------------
# 1. The drag cue


@dataclass(frozen=True)
class DragCue:
    """The first fall's vertical acceleration of every test throw, and one threshold on it."""

    fall: np.ndarray
    """(n_test,) m/s², from the first T frames (NaN where the fall is too short to fit)."""
    y: np.ndarray
    """(n_test,) the test labels: 0 light, 1 heavy."""
    rule: dict[str, Any]
    """The threshold rule on exact positions (``measure.best_threshold_rule``: threshold, direction, correct)."""
    noisy: dict[float, Interval]
    """Test accuracy of the same rule, refitted on positions with each tracker noise (millimetres)."""

    @property
    def exact(self) -> Interval:
        """The rule's test accuracy on exact positions."""
        return bootstrap_accuracy(self.rule["correct"])

    @property
    def median(self) -> dict[str, float]:
        """Median fall acceleration of each class, m/s²."""
        return drag_per_class(self.fall, self.y)


def drag_cue(ds: data.Dataset, frames: int, contact_height: float, noise_mm: Sequence[float]) -> DragCue:
    """The drag cue on the first ``frames`` of ``ds``: the threshold on the first fall's acceleration, fitted on
    the training split, scored on the test split, on exact positions and with each noise of ``noise_mm``
    (millimetres; 0 is skipped) drawn on both splits (seeds 1 and 2)."""

    def fall(x: np.ndarray) -> np.ndarray:
        return measure.fall_acceleration(x[:, :frames, 2], ds.fps, contact_height)

    test = fall(ds.test.x)
    rule = measure.best_threshold_rule(fall(ds.train.x), ds.train.y, test, ds.test.y)
    noisy = {}
    for mm in (m for m in noise_mm if m > 0):
        ob = observe.Observation(noise=mm / 1000)
        tr = ob.observe(ds.train.x[:, :frames], ds.fps, seed=1)
        te = ob.observe(ds.test.x[:, :frames], ds.fps, seed=2)
        r = measure.best_threshold_rule(fall(tr), ds.train.y, fall(te), ds.test.y)
        noisy[mm] = bootstrap_accuracy(r["correct"])
    return DragCue(test, np.asarray(ds.test.y), rule, noisy)


def drag_per_class(a: np.ndarray, y: np.ndarray) -> dict[str, float]:
    """Median fall acceleration (m/s^2) of each class, from :func:`study.simulate.measure.fall_acceleration`."""
    return {c: float(np.nanmedian(a[np.asarray(y) == k])) for k, c in enumerate(("light", "heavy"))}


# ---------------------------------------------------------------------------------------------
# What separates the classes without learning


def ceiling(dataset: data.Dataset, with_mass: bool = False) -> Interval:
    """The accuracy the priors allow a classifier that is told each throw's true restitution and friction
    (and, with ``with_mass``, its log mass): a logistic regression on them, fitted on the training
    split, scored on the test split."""
    names = ("restitution", "friction") + (("mass",) if with_mass else ())

    def table(split: data.Split) -> np.ndarray:
        return np.column_stack([np.log(split.params[k]) if k == "mass" else split.params[k] for k in names])

    f_tr, f_te = table(dataset.train), table(dataset.test)
    mean, std = f_tr.mean(0), f_tr.std(0)
    w = baseline.logistic_regression((f_tr - mean) / std, np.asarray(dataset.train.y, float))
    p = baseline.sigmoid(np.column_stack([(f_te - mean) / std, np.ones(len(f_te))]) @ w)
    return bootstrap_accuracy((p > 0.5) == (np.asarray(dataset.test.y) == 1))


# ---------------------------------------------------------------------------------------------
# 3. Which cue carries each classifier


@dataclass(frozen=True)
class Conditions:
    """The peephole LSTM and the one-feature rules in the four conditions (a)-(d)."""

    exact: Runs
    """(a) Table 1's runs, exact positions with air, both inputs."""
    air_off: Runs
    """(b) the same configs on the same throws without air."""
    faithful: list[TrainedModel]
    """Table 1's Z models (trained on exact positions), one per seed."""
    robust: list[TrainedModel]
    """Z models trained on random observations, one per seed."""
    correct: dict[tuple[Condition, Dims], np.ndarray]
    """(S, n_test) bool per (condition, input): seed s got test throw i right ((c) and (d): Z only)."""
    rules: dict[RuleCondition, list[dict]]
    """The one-feature rules (:func:`rules`) of (a), (b) and (c) ((c) sees only a height)."""

    @cached_property
    def accuracy(self) -> dict[tuple[Condition, Dims], Interval]:
        """Mean test accuracy per (condition, input), bootstrap over test throws and seeds."""
        return {k: bootstrap_accuracy(v) for k, v in self.correct.items()}

    def best_rule(self, c: RuleCondition) -> dict:
        """The best one-feature rule of ``c``, chosen on the training split (``measure.best_rule``)."""
        return measure.best_rule(self.rules[c])

    def drag_rule(self, c: RuleCondition) -> dict:
        """The drag rule of ``c``."""
        return next(r for r in self.rules[c] if r["feature"] == DRAG)

    def network_minus_rule(self, d: Dims) -> Interval:
        """Without air: the network on ``d`` (mean of seeds) minus the best rule, paired on the test throws."""
        return bootstrap_difference(self.air_off.where(dims=d).correct(), self.best_rule("b")["correct"])


def condition_configs(runner: Runner, cfg: TrainConfig) -> list[tuple[Runner, list[TrainConfig], bool]]:
    """The runs of (a), (b) and (d), as ``Runner.prefetch`` takes them (all at once keeps every core busy)."""
    seeds = runner.preset.grid_seeds
    both = paper.seed_configs(cfg, seeds, ("z", "xyz"))
    return [(runner, both + paper.seed_configs(calibration.randomised_config(runner, cfg), seeds, ("z",)), True),
            (runner.air_off(), both, True)]


def conditions(runner: Runner, cfg: TrainConfig) -> Conditions:
    """The four conditions at Table 1's ``cfg`` and the grid's seeds (trained once, then read from the cache)."""
    ds, seeds = runner.dataset, runner.preset.grid_seeds
    T, fps = cfg.n_frames(ds.fps), ds.fps
    contact = runner.synth_config.shape.bounding_radius
    runner.prefetch(condition_configs(runner, cfg), desc="conditions (a), (b), (d)")
    exact = runner.train_runs(cfg, ("z", "xyz"), seeds, desc="(a)")
    still = runner.air_off()  # the same throws, no air
    air_off = still.train_runs(cfg, ("z", "xyz"), seeds, desc="(b)")
    faithful = runner.models(cfg, seeds, dims="z")
    rand_cfg = calibration.randomised_config(runner, cfg)
    runner.train_runs(rand_cfg, ("z",), seeds, desc="(d)")
    robust = runner.models(rand_cfg, seeds, dims="z")
    calibrated = calibration.observation(runner)
    x_obs, x_obs_train = calibration.observed(runner, "test", calibrated, T), calibration.observed(runner, "train", calibrated, T)

    def observed_correct(c: TrainConfig) -> np.ndarray:
        return learners.Network("observed", c, seeds).score(runner, None, {"t": (x_obs, ds.test.y)}).correct["t"]

    correct: dict[tuple[Condition, Dims], np.ndarray] = {
        ("a", "xyz"): exact.where(dims="xyz").correct(), ("a", "z"): exact.where(dims="z").correct(),
        ("b", "xyz"): air_off.where(dims="xyz").correct(), ("b", "z"): air_off.where(dims="z").correct(),
        ("c", "z"): observed_correct(cfg), ("d", "z"): observed_correct(rand_cfg)}
    no_air = still.dataset
    rule_sets: dict[RuleCondition, list[dict]] = {
        "a": rules(ds.train.x[:, :T], ds.train.y, ds.test.x[:, :T], ds.test.y, fps, contact),
        "b": rules(no_air.train.x[:, :T], no_air.train.y, no_air.test.x[:, :T], no_air.test.y, fps, contact),
        "c": rules(observe.height_only(x_obs_train), ds.train.y, observe.height_only(x_obs), ds.test.y, fps,
                   contact),
    }
    return Conditions(exact, air_off, faithful, robust, correct, rule_sets)


# ---------------------------------------------------------------------------------------------
# 4. Robustness


@dataclass(frozen=True)
class Sweep:
    """One parameter of the observation model, swept with the others at their exact values."""

    label: str
    """The axis label, with its unit."""
    values: Sequence[Any]
    """The values swept."""
    make: Callable[[Any], observe.Observation]
    """The observation at a value."""


@dataclass(frozen=True)
class Point:
    """One group of Z models at one value of one sweep."""

    sweep: str
    """The sweep's name."""
    value: Any
    """The sweep's value."""
    group: Group
    """Which models."""
    interval: Interval
    """Mean test accuracy, bootstrap over test throws and seeds."""


def robustness(models: Mapping[Group, Sequence[Any]], x: np.ndarray, y: np.ndarray, fps: float, frames: int,
               sweeps: Mapping[str, Sweep], seed: int = ROBUSTNESS_SEED, rest_height: float = 0.1,
               high: tuple[np.ndarray, float] | None = None) -> list[Point]:
    """Accuracy of each group of ``models`` under each point of each sweep, on test trajectories ``x`` (n, T, 3)
    metres at ``fps`` with labels ``y``, cut to ``frames`` after observing: one point per (sweep, value, group).

    ``high``: the same test trajectories recorded at a higher frame rate (x, fps), for camera rates above
    ``fps`` (without it those values are left out)."""
    out = []
    for name, sweep in sweeps.items():
        for value in sweep.values:
            ob = sweep.make(value)
            if ob.camera_fps is not None and ob.camera_fps > fps:
                if high is None:
                    continue
                xo = ob.apply(high[0], high[1], np.random.default_rng(seed), out_fps=fps, rest_height=rest_height)
            else:
                xo = ob.apply(x, fps, np.random.default_rng(seed), rest_height=rest_height)
            xo = xo[:, :frames]
            out += [Point(name, value, g, scored(ms, xo, y)) for g, ms in models.items()]
    return out


def high_rate_test(preset: str, seed: int, seconds: float, fps: float = 120.0,
                   data_dir: str | Path | None = None) -> data.Dataset:
    """The same test throws recorded at ``fps`` for ``seconds`` (a fast camera's view), one training throw
    per class (the test split's random streams do not depend on the training split's size)."""
    cfg = synth.SynthConfig.preset(preset).replace(fps=fps, duration=seconds + 2 / fps, n_train=1)
    return synth.dataset(cfg, seed, data_dir=data_dir, progress=False)


# ---------------------------------------------------------------------------------------------
# 5. Where the errors fall


@dataclass(frozen=True)
class Bin:
    """One quantile bin of one class's values of a throw parameter."""

    label: int
    """The class: 0 light, 1 heavy."""
    index: int
    """The bin, from the lowest values."""
    centre: float
    """Median of the parameter in the bin (its unit: restitution and friction none, mass kg)."""
    accuracy: float
    """Mean over the bin's throws of the share of runs that got the throw right."""
    n: int
    """Throws in the bin."""


def by_parameter(correct: np.ndarray, split: data.Split, name: str, bins: int = 8) -> list[Bin]:
    """Accuracy of runs against the test throws' parameter ``name``, per class and in ``bins`` quantile bins of
    that class's values. ``correct``: (S, n) bool, run s got test throw i right."""
    share = np.atleast_2d(correct).mean(axis=0)  # (n,) share of runs right
    out = []
    for label in (0, 1):
        sel = np.flatnonzero(np.asarray(split.y) == label)
        v = split.params[name][sel]
        edges = np.quantile(v, np.linspace(0, 1, bins + 1))
        which = np.clip(np.searchsorted(edges, v, side="right") - 1, 0, bins - 1)
        for b in range(bins):
            m = which == b
            if m.any():
                out.append(Bin(label, b, float(np.median(v[m])), float(share[sel][m].mean()), int(m.sum())))
    return out


@dataclass(frozen=True)
class Overlap:
    """Accuracy inside and outside the restitutions both class priors allow."""

    lo: float
    """Lowest restitution of the light prior."""
    hi: float
    """Highest restitution of the heavy prior."""
    inside: Interval
    """Accuracy on throws with a restitution in [lo, hi]."""
    outside: Interval
    """Accuracy on the others."""


def overlap(correct: np.ndarray, restitution: np.ndarray, prior: synth.SynthConfig) -> Overlap:
    """:class:`Overlap` of runs ``correct`` (S, n) bool on test throws of restitution ``restitution`` (n,)."""
    lo, hi = prior.light.restitution[0], prior.heavy.restitution[1]
    inside = (restitution >= lo) & (restitution <= hi)
    return Overlap(lo, hi, bootstrap_accuracy(correct[:, inside]), bootstrap_accuracy(correct[:, ~inside]))


# ---------------------------------------------------------------------------------------------
# 6. Shapes


SHAPES: dict[str, Shape] = {
    "20 cm cube (trained)": Shape("box", (0.1, 0.1, 0.1)),
    "10 cm cube": Shape("box", (0.05, 0.05, 0.05)),
    "30 cm cube": Shape("box", (0.15, 0.15, 0.15)),
    "flat box 30 x 30 x 10 cm": Shape("box", (0.15, 0.15, 0.05)),
    "ball, 20 cm": Shape("sphere", (0.1,)),
    "cylinder, 20 cm": Shape("cylinder", (0.1, 0.1)),
}
"""The shapes the classifier is tested on; the mixed training set uses :data:`MIXED`."""
MIXED = ("20 cm cube (trained)", "flat box 30 x 30 x 10 cm", "ball, 20 cm", "cylinder, 20 cm")
"""The shapes whose throws make up the mixed training set (the other two sizes of cube stay unseen)."""
SHAPE_SEED_OFFSET = 7
"""The shapes' data sets are simulated from the runner's data seed plus this."""


def shape_key(name: str) -> str:
    """A shape's name in the results file: ``"ball, 20 cm"`` -> ``"ball"``, ``"20 cm cube (trained)"`` ->
    ``"20_cm_cube"``."""
    return name.split(",")[0].split(" (")[0].replace(" ", "_")


def shape_config(preset: str, shape: Shape, duration: float, n_train: int, n_test: int) -> synth.SynthConfig:
    """The preset's synthesis config for another ``shape``, recorded for ``duration`` seconds."""
    return synth.SynthConfig.preset(preset).replace(shape=shape, duration=duration, n_train=n_train, n_test=n_test)


def shape_sets(preset: str, seed: int, duration: float, n_train: int, n_test: int,
               data_dir: str | Path | None = None) -> dict[str, data.Dataset]:
    """One dataset per shape of :data:`SHAPES`, recorded for ``duration`` seconds, cached like any other."""
    return {name: synth.dataset(shape_config(preset, s, duration, n_train, n_test), seed, data_dir=data_dir,
                                progress=False) for name, s in SHAPES.items()}


def mixed_shapes(sets: dict[str, data.Dataset], names: Sequence[str] = MIXED) -> data.Dataset:
    """The training splits of ``names`` pooled into one training set (the test split: the first's), with a
    key that names its parts, so runs on it are cached like any other."""
    parts = [sets[n] for n in names]
    train = data.Split(x=np.concatenate([d.train.x for d in parts]), y=np.concatenate([d.train.y for d in parts]))
    key = cache.key({"mixed": [d.key for d in parts]})
    return data.Dataset(train=train, test=parts[0].test, fps=parts[0].fps, meta={"key": key})


@dataclass(frozen=True)
class ShapeScore:
    """Both groups of Z models on one test shape."""

    name: str
    """The shape, in words (a key of :data:`SHAPES`)."""
    cube: Interval
    """Table 1's Z models (trained on the 20 cm cube): mean test accuracy."""
    mixed: Interval
    """The Z models trained on mixed shapes."""

    @property
    def seen(self) -> bool:
        """Whether the mixed training set holds this shape."""
        return self.name in MIXED


def saved(runner: Runner, dataset: data.Dataset, name: str) -> data.Dataset:
    """An in-memory ``dataset`` (one with a key but no file) written to the cache once, so that workers read
    it from the shared folder; returns it as read back."""
    path = runner.data_dir / f"{name}-{dataset.key}.npz"
    if not path.is_file():
        data.save(dataset, path)
    return data.load(path)


def _shapes(runner: Runner, cfg: TrainConfig) -> tuple[dict[str, data.Dataset], Runner]:
    """The test sets of every shape of :data:`SHAPES` and the runner on the :data:`MIXED` training set, read once
    per runner (the chapter's plan and its scores both need them)."""
    p, ds = runner.preset, runner.dataset
    seed = int(ds.meta["seed"]) + SHAPE_SEED_OFFSET
    T = cfg.n_frames(ds.fps)

    def make() -> tuple[dict[str, data.Dataset], Runner]:
        sets = shape_sets(p.name, seed, T / ds.fps, p.shape_train, p.shape_test, data_dir=runner.data_dir)
        return sets, runner.on(saved(runner, mixed_shapes(sets), "mixed"))  # workers read it

    return runner.memo(f"shapes-{T}", make)


def chapter_runs(runner: Runner, cfg: TrainConfig) -> list[tuple[Runner, list[TrainConfig], bool]]:
    """Every run of the chapter at Table 1's ``cfg``, as ``Runner.prefetch`` takes them: the conditions' and the
    mixed shapes'. Asked for at once, before anything is measured: a planned build stops the chapter once, here."""
    _, shapes = _shapes(runner, cfg)
    return condition_configs(runner, cfg) + [(shapes, paper.seed_configs(cfg, runner.preset.grid_seeds, ("z",)),
                                              True)]


def shape_scores(runner: Runner, cfg: TrainConfig, cube_models: Sequence[TrainedModel]) -> list[ShapeScore]:
    """Table 1's Z models (``cube_models``) and Z models trained on :data:`MIXED` at ``cfg`` (the grid's
    seeds), each tested on every shape of :data:`SHAPES`, the first T seconds."""
    p, T = runner.preset, cfg.n_frames(runner.fps)
    sets, shapes = _shapes(runner, cfg)
    shapes.train_runs(cfg, ("z",), p.grid_seeds, desc="mixed")
    mixed = shapes.models(cfg, p.grid_seeds, dims="z")
    return [ShapeScore(name, scored(cube_models, sd.test.x[:, :T], sd.test.y), scored(mixed, sd.test.x[:, :T],
                                                                                      sd.test.y))
            for name, sd in sets.items()]


# ---------------------------------------------------------------------------------------------
# The chapter's result


@dataclass(frozen=True)
class Cues:
    """Everything the chapter shows: its numbers (:attr:`numbers`), its tables and sentences, its figures' data."""

    numbers: Numbers
    """What the chapter reports (the results file's ``cues.*``)."""
    drag: DragCue
    """The drag cue (the headline figure draws it)."""
    tracker: TrackerError
    """The tracker's error on the rendered videos."""
    conditions: Conditions
    """The four conditions."""
    sweeps: Mapping[str, Sweep]
    """The robustness sweeps."""
    points: tuple[Point, ...]
    """Every point of every sweep (the robustness figure)."""
    by_parameter: dict[tuple[str, Dims], list[Bin]]
    """Table 1's accuracy against each of :data:`PARAMETERS`, per input (the errors figure)."""
    overlap: Overlap
    """Z accuracy inside and outside the priors' overlap in restitution."""
    shapes: tuple[ShapeScore, ...]
    """Every test shape."""
    drag_noise_table: Table
    """The drag rule under each tracker noise."""
    cue_table: Table
    """The network and the rules in each condition."""
    shape_table: Table
    """Both groups of models on every shape."""
    n_videos: int
    """Rendered videos the tracker was measured on."""
    length_frames: int
    """The frames every classifier of the chapter sees (Table 1's T)."""
    tracker_fit: TrackerFit | None = None
    decomposed: Mapping[str, Decomposition] = field(default_factory=dict)
    """The tracked height's error taken apart on the book's renders, before issue 28's tracker and after."""
    """The tracker's error model fitted on development renders: the calibrated observation (``calibration.observation``)."""

    # The fitted error model in the chapter's words (empty without one) ------------------------

    def _fit(self, say: Callable[[TrackerFit], str]) -> str:
        return say(self.tracker_fit) if self.tracker_fit is not None else ""

    @property
    def model_description(self) -> str:
        """The fitted model in words, millimetres."""
        return self._fit(lambda c: c.model.describe())

    @property
    def model_fitted_on(self) -> str:
        """What it was fitted on."""
        return self._fit(lambda c: c.fitted_on or f"{c.n_videos} rendered videos")

    @property
    def model_band_mm(self) -> str:
        """How far above its rest height the exact centre counts as touching the ground, millimetres."""
        return self._fit(lambda c: f"{1000 * c.model.band:g}")

    @property
    def tracker_step_mm(self) -> str:
        """The tracker's frame-to-frame error, millimetres (root mean square)."""
        return self._fit(lambda c: f"{1000 * c.step_sd:.1f}")

    @property
    def tracker_pooled_mm(self) -> str:
        """The tracker's position error with each video's mean removed, pooled, millimetres."""
        return self._fit(lambda c: f"{1000 * c.pooled_sd:.1f}")

    @property
    def white_step_mm(self) -> str:
        """The frame-to-frame error white noise at that position error would have, millimetres."""
        return self._fit(lambda c: f"{1000 * c.white_step_sd:.1f}")

    @property
    def white_ratio(self) -> str:
        """How many times white noise overstates the tracker's frame-to-frame error."""
        return self._fit(lambda c: f"{c.white_overstates:.1f}")

    @property
    def tracker_drop_pct(self) -> str:
        """Share of the frames in view the tracker lost, percent."""
        return self._fit(lambda c: f"{100 * c.drop:.1f}")

    # Sentences and numbers in the chapter's words ---------------------------------------------

    @property
    def fall_light(self) -> str:
        """Median first-fall acceleration of the light test throws, m/s²."""
        return f"{self.drag.median['light']:.2f}"

    @property
    def fall_heavy(self) -> str:
        """The same for the heavy ones."""
        return f"{self.drag.median['heavy']:.2f}"

    @property
    def noise_px(self) -> str:
        """The tracker's error, pixels."""
        return f"{self.tracker.noise_px:.2f}"

    @property
    def tracker_table(self) -> Table:
        """The tracked height's error taken apart, with the old bounds and now, on the book's renders."""
        if not self.decomposed:
            return Table([], {"what": "quantity"}, empty="*Not measured in this build.*")
        keys = [k for k in ("before", "after") if k in self.decomposed]

        def cell(d: Decomposition, f: str) -> str:
            v = getattr(d, f)
            return f"{v:.2f}" if f == "rho" else f"{100 * v:.1f} %" if f == "lost" else \
                f"{v:.3f}" if f == "velocity_mps" else f"{v:.1f}"

        rows = [{"what": what + ("" if f in ("rho", "lost", "velocity_mps") else ", mm")
                 + (", m/s" if f == "velocity_mps" else ""), **{k: cell(self.decomposed[k], f) for k in keys}}
                for f, what, _ in DECOMPOSED.values()]
        return Table(rows, {"what": "the height's error", **{k: LABELS[k] for k in keys}})

    @property
    def noise_mm(self) -> str:
        """The tracker's error, millimetres."""
        return f"{1000 * self.tracker.noise_m:.1f}"

    @property
    def mm_per_px(self) -> str:
        """A pixel at the camera's distance, millimetres."""
        return f"{1000 * self.tracker.metres_per_pixel:.1f}"

    @property
    def n_cal_frames(self) -> int:
        """Frames the tracker measured."""
        return self.tracker.n_frames

    @property
    def n_sweeps(self) -> int:
        return len(self.sweeps)

    @property
    def overlap_range(self) -> str:
        """The restitutions both priors allow, ``0.35–0.5``."""
        return f"{self.overlap.lo:g}–{self.overlap.hi:g}"

    @property
    def ceil_gap(self) -> str:
        """The exact ceiling minus the fitted estimate, points."""
        c = self.numbers.ceiling
        return f"{100 * (c.exact.value - c.restitution_friction.value):+.1f}"

    @property
    def cue_verdict(self) -> str:
        """What taking the air away did, and whether the paper's claim survives it."""
        acc = self.conditions.accuracy
        carries = acc["b", "z"].hi < acc["a", "z"].lo
        claims = {d: n.verdict for d, n in self.numbers.network_minus_rule_b.items()}
        beaten = [d for d, v in claims.items() if v != "reproduced"]
        return " ".join([
            "Without air the Z network's accuracy changes by " + _gap(acc["b", "z"], acc["a", "z"])
            + " and the X, Y, Z network's by " + _gap(acc["b", "xyz"], acc["a", "xyz"])
            + f" (the drag rule falls to {pct_ci(self.numbers.drag_rules['b'])}: every object falls at −g)"
            + (": with air, the drag cue carried part of what the Z network did." if carries else
               ": the Z network does not rest on drag."),
            "Without drag the networks still beat the best one-feature rule: the paper's claim that the motion "
            "pattern needs a learnt classifier survives." if not beaten else
            "Without drag the paper's network does not beat the best one-feature rule for "
            + " and ".join(f"{paper.DIMS_NAMES[d]} ({claims[d]})" for d in beaten)
            + ": on our data the claim that no simple rule suffices does not survive for the paper's network.",
        ])

    @property
    def obs_verdict(self) -> str:
        """Table 1's Z models through the calibrated tracker, and those trained on random observations."""
        acc = self.conditions.accuracy
        return (f"Observed through the calibrated tracker, Table 1's Z models score {pct_ci(acc['c', 'z'])} "
                f"({_gap(acc['c', 'z'], acc['a', 'z'])} against exact positions); trained on random observations, "
                f"{pct_ci(acc['d', 'z'])}.")


def _gap(a: Interval, b: Interval) -> str:
    return f"{100 * (a.value - b.value):+.1f} points"


# ---------------------------------------------------------------------------------------------
# Each part of the result


def _condition_numbers(c: Conditions) -> tuple[dict[Condition, dict[Dims, Number]], dict[RuleCondition, Number],
                                               dict[RuleCondition, Number]]:
    conds: dict[Condition, dict[Dims, Number]] = {}
    for (k, d), iv in c.accuracy.items():
        conds.setdefault(k, {})[d] = number(iv, f"peephole LSTM, {CONDITIONS[k]}, {paper.DIMS_NAMES[d]}")
    keys: tuple[RuleCondition, ...] = ("a", "b", "c")
    best = {k: number(c.best_rule(k)["interval"], f"best one-feature rule ({c.best_rule(k)['feature']}), "
                                                  f"{CONDITIONS[k]}") for k in keys}
    drag = {k: number(c.drag_rule(k)["interval"], f"drag rule, {CONDITIONS[k]}") for k in keys}
    return conds, best, drag


def _cue_table(c: Conditions) -> Table:
    rows = []
    for k in CONDITIONS:
        rule = k in c.rules
        best = c.best_rule(k) if rule else None  # type: ignore[arg-type]
        rows.append({"condition": CONDITIONS[k],
                     "xyz": seeds_ci(c.correct[k, "xyz"]) if (k, "xyz") in c.correct else "—",
                     "z": seeds_ci(c.correct[k, "z"]),
                     "drag": pct_ci(c.drag_rule(k)["interval"]) if rule else "—",  # type: ignore[arg-type]
                     "best": f"{pct_ci(best['interval'])} ({best['feature']})" if best else "—"})
    return Table(rows, {"condition": "condition", "xyz": "peephole LSTM, X, Y, Z", "z": "peephole LSTM, Z only",
                        "drag": "drag rule", "best": "best one-feature rule (feature)"})


def _robustness_numbers(points: Sequence[Point], sweeps: Mapping[str, Sweep]) -> dict[str, Curve]:
    curves: dict[str, dict[str, dict[Group, Number]]] = {}
    for pt in points:
        curves.setdefault(pt.sweep, {}).setdefault(f"{pt.value:g}", {})[pt.group] = number(
            pt.interval, f"Z models {GROUPS[pt.group]}, {sweeps[pt.sweep].label} = {pt.value:g}")
    return {name: Curve(v) for name, v in curves.items()}


def _shape_numbers(shapes: Sequence[ShapeScore]) -> tuple[dict[str, ShapeNumbers], Table]:
    numbers = {shape_key(s.name): ShapeNumbers(
        number(s.cube, f"Z model trained on the 20 cm cube, tested on {s.name}"),
        number(s.mixed, f"Z model trained on mixed shapes, tested on {s.name}")) for s in shapes}
    rows = [{"shape": s.name, "cube": pct_ci(s.cube), "mix": pct_ci(s.mixed), "seen": "yes" if s.seen else "no"}
            for s in shapes]
    return numbers, Table(rows, {"shape": "test shape", "cube": "trained on the 20 cm cube [95 % CI]",
                                 "mix": "trained on mixed shapes [95 % CI]", "seen": "in the mixed training set"})


def compute(runner: Runner, noise_mm: Sequence[float], sweeps: Mapping[str, Sweep]) -> Cues:
    """The chapter *What the network sees* on ``runner``'s preset and data set, every run cached: the drag rule
    under each tracker noise of ``noise_mm`` (millimetres), the Z models under each of ``sweeps``."""
    p, ds = runner.preset, runner.dataset
    prior = runner.synth_config
    cfg = runner.table1_config()
    runner.prefetch(chapter_runs(runner, cfg), desc="every run of the chapter")
    T = cfg.n_frames(ds.fps)  # the frames every classifier here sees
    drag = drag_cue(ds, T, prior.shape.bounding_radius, noise_mm)
    videos, _ = calibration.rendered(runner)
    tracker = calibration.tracker_error(runner)
    cond = conditions(runner, cfg)
    high = high_rate_test(p.name, int(ds.meta["seed"]), T / ds.fps, data_dir=runner.data_dir)  # 120 fps
    points = robustness({"exact": cond.faithful, "random": cond.robust}, ds.test.x, ds.test.y, ds.fps, T, sweeps,
                        high=(high.test.x, high.fps))
    by = {(name, d): by_parameter(cond.exact.where(dims=d).correct(), ds.test, name)
          for name in PARAMETERS for d in ("xyz", "z")}
    errors = overlap(cond.correct["a", "z"], ds.test.params["restitution"], prior)
    shapes = shape_scores(runner, cfg, cond.faithful)
    return assemble(drag, tracker, cond, (ceiling(ds), ceiling(ds, with_mass=True)),
                    exact_ceiling(prior, ("restitution", "friction")), sweeps, points, by, errors, shapes,
                    n_videos=len(videos), length_frames=T, tracker_fit=calibration.tracker_fit(runner),
                    decomposed=calibration.decomposition(runner))


def assemble(drag: DragCue, tracker: TrackerError, cond: Conditions, fitted: tuple[Interval, Interval],
             exact: float, sweeps: Mapping[str, Sweep], points: Sequence[Point],
             by: dict[tuple[str, Dims], list[Bin]], errors: Overlap, shapes: Sequence[ShapeScore], *,
             n_videos: int, length_frames: int, tracker_fit: TrackerFit | None = None,
             decomposed: Mapping[str, Decomposition] | None = None) -> Cues:
    """The chapter's result from its parts (what :func:`compute` measured): its numbers, verdicts and tables.
    ``fitted``: the fitted ceiling without and with the mass (:func:`ceiling`); ``exact``: the exact one;
    ``tracker_fit``: the tracker's fitted error model (``calibration.tracker_fit``)."""
    conds, best, drag_rules = _condition_numbers(cond)
    over_rule = {d: cond.network_minus_rule(d) for d in ("xyz", "z")}
    claims = {d: verdicts.order(iv, +1) for d, iv in over_rule.items()}  # the network above the rule
    shape_numbers, shape_table = _shape_numbers(shapes)
    numbers = Numbers(
        DragRuleNumbers(number(drag.exact, "one threshold on the first fall's acceleration, exact positions"),
                        {f"{mm}": number(iv, f"the drag rule with {mm} mm of tracker noise")
                         for mm, iv in drag.noisy.items()}),
        TrackerNumbers(number(tracker.noise_m, "tracker's vertical error (std after removing the offset)", unit="m"),
                       number(tracker.drop, "share of frames the tracker lost on rendered video"),
                       {k: _decomposed(d, k) for k, d in (decomposed or {}).items()}),
        conds, best, drag_rules,
        CeilingNumbers(
            number(fitted[0], "an estimate on the test split: logistic regression on the true restitution and "
                              "friction"),
            number(fitted[1], "the same estimate, told the true mass too"),
            number(exact, "exact ceiling of the priors on the true restitution and friction")),
        {d: number(iv, f"network minus the best rule without air, {paper.DIMS_NAMES[d]}", decision=claims[d],
                   signed=True) for d, iv in over_rule.items()},
        Verdict(verdicts.combined(list(claims.values())),
                "without drag, the network beats every one-feature rule (the paper's 'no simple rule')"),
        _robustness_numbers(points, sweeps),
        ErrorNumbers(number(errors.inside, "Z accuracy on throws whose restitution lies where the priors overlap"),
                     number(errors.outside, "Z accuracy on the other throws")),
        shape_numbers, None if tracker_fit is None else tracker_fit.numbers())
    drag_table = Table([{"noise": f"{mm} mm", "acc": pct_ci(iv)} for mm, iv in drag.noisy.items()],
                       {"noise": "tracker error (standard deviation)", "acc": "drag rule, test accuracy [95 % CI]"})
    return Cues(numbers, drag, tracker, cond, sweeps, tuple(points), by, errors, tuple(shapes), drag_table,
                _cue_table(cond), shape_table, n_videos=n_videos, length_frames=length_frames, tracker_fit=tracker_fit,
                decomposed=dict(decomposed or {}))
