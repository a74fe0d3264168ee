"""The chapter *Another engine*: the same throws simulated in Bullet (the paper's engine, through Blender) and in
MuJoCo.

Both data sets hold the same sampled objects and launches, index by index, without air. :func:`compute` checks
Bullet as MuJoCo is checked (:func:`bullet_checks`), compares the engines throw by throw (:func:`agreement`),
asks whether what a learner learns in one engine holds in the other (:func:`cross_entries`: every learner
trained on one engine's training split and tested on both engines' test splits, exact and through the
calibrated tracker), and trains Table 1's faithful row in each engine. It then asks whether the mass reaches a
trajectory in either engine: the same throw simulated as a light and as a heavy object (:func:`paired_throws`), and
the chapter's best learner trained on two classes whose only difference is the mass (:func:`mass_only_prior`,
:func:`mass_test`). It returns :class:`AnotherEngine`, whose :class:`Numbers` are what the chapter reports
(``engine.table1.xyz.paper_way``, ``engine.mass_only.bullet.accuracy`` and so on).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from functools import cached_property
from typing import Literal, get_args

import numpy as np

from study import CLASSES
from study.learn.config import Dims, TrainConfig
from study.learn.metrics import Interval, bootstrap_accuracy, bootstrap_difference
from study.methods import calibration, camera, ceiling, learners
from study.methods.tracker import TrackerError
from study.report import verdicts
from study.report.engine import (
    ClassName,
    Feature,
    Learner,
    MassOnly,
    Numbers,
    Pair,
    PairedNumbers,
    Table1Row,
    View,
)
from study.report.reported import Number, count, number
from study.report.text import Table, pct, pct_ci, points, seeds_ci
from study.runs import paper, stats
from study.runs.runner import Runner
from study.runs.runtable import Runs
from study.simulate import bullet, measure, observe, synth
from study.simulate.data import Dataset
from study.simulate.synth import ENGINES, ClassPrior, Engine, SynthConfig

Network = Literal["peephole_positions", "peephole_velocity"]
"""Its networks."""

LEARNERS: tuple[Learner, ...] = get_args(Learner)
NETWORKS: tuple[Network, ...] = get_args(Network)
VIEWS: tuple[View, ...] = get_args(View)
NAMES: dict[Learner, str] = {name: learners.NAMES[name] for name in LEARNERS}
"""Each learner in words."""
AGREEMENT: dict[Feature, str] = {"bounces": "bounces", "time_to_rest": "time to rest, s",
                                 "first_rebound": "first rebound's height, m", "distance": "horizontal distance, m"}
"""What :func:`agreement` compares, in words."""
UNITS: dict[Feature, str] = {"bounces": "count", "time_to_rest": "s", "first_rebound": "m", "distance": "m"}
"""The unit of each difference of :data:`AGREEMENT`."""
CONDITIONS: dict[View, str] = {"exact": "exact", "calibrated": "calibrated tracker"}
"""Each view in a table's rows."""
ENGINE_NAMES: dict[Engine, str] = {"mujoco": "MuJoCo", "bullet": "Bullet"}
"""Each engine in a sentence."""

FLIGHT_QPOS = np.array([0.0, 0.0, 13.0, 0.9, 0.1, 0.3, 0.3])
"""The free-flight check's launch: 13 m up (it never lands within the second), a unit quaternion (w, x, y, z)."""
FLIGHT_QVEL = np.array([1.0, -0.5, 2.0, 3.0, -2.0, 1.0])
"""Its velocity, m/s, and spin, rad/s."""
DROPS = (0.6, 1.0, 1.4)
"""Heights of the flat-drop check, metres."""
REST_SPEED = 0.05
"""The speed below which the figure calls a throw at rest, m/s."""


# ---------------------------------------------------------------------------------------------
# Bullet checked as MuJoCo is


@dataclass(frozen=True)
class BulletChecks:
    """What the chapter's figure of Bullet's checks draws."""

    flight_t: np.ndarray
    """(k,) s: the free flight's times."""
    flight_error: np.ndarray
    """(k,) m: its distance from the analytic parabola."""
    restitution: np.ndarray
    """(r,) the restitutions asked for, across both priors."""
    rebound: dict[float, np.ndarray]
    """Drop height (m) -> (r,) the measured sqrt(h1 / h0) of a flat drop."""
    friction: np.ndarray
    """(f,) the frictions asked for, across both priors."""
    deceleration: np.ndarray
    """(f,) the measured deceleration of a slide over g."""
    speeds: tuple[tuple[np.ndarray, np.ndarray, int], ...]
    """Throws of both classes coming to rest: (t (k,) s, speed (k,) m/s, label) each."""


def bullet_checks(prior: SynthConfig) -> BulletChecks:
    """Bullet's free flight, flat drops, slide and coming to rest under ``prior`` without air (the tests assert
    what these show)."""
    still = prior.replace(air=False)
    pos, _ = bullet.flight(still, FLIGHT_QPOS, FLIGHT_QVEL, 1.0)
    t = bullet.TIMESTEP * np.arange(1, len(pos) + 1)
    exact = FLIGHT_QPOS[:3] + FLIGHT_QVEL[:3] * t[:, None] - [0, 0, synth.GRAVITY / 2] * t[:, None] ** 2
    e = np.linspace(min(prior.light.restitution[0], prior.heavy.restitution[0]),
                    max(prior.light.restitution[1], prior.heavy.restitution[1]), 9)
    rebound = {}
    for drop in DROPS:
        h = bullet.flat_drops(prior.shape, bullet.restitution_setting(e, prior.shape), drop)
        rebound[drop] = np.sqrt(h[:, 1] / h[:, 0])
    mu = np.linspace(min(prior.light.friction[0], prior.heavy.friction[0]),
                     max(prior.light.friction[1], prior.heavy.friction[1]), 7)
    slowing = bullet.slide_deceleration(prior.shape, bullet.friction_setting(mu, prior.shape))
    params = synth.sample_split(prior.replace(n_train=3, air=False), 0, "train")
    traces = [bullet.trace(still, params, i, duration=6.0) for i in range(len(params["mass"]))]
    return BulletChecks(t, np.linalg.norm(pos - exact, axis=1), e, rebound, mu, slowing / synth.GRAVITY,
                        tuple((tr.t, tr.speed, int(params["label"][i])) for i, tr in enumerate(traces)))


# ---------------------------------------------------------------------------------------------
# Throw by throw


def first_rebound(z: np.ndarray, rest_height: float) -> np.ndarray:
    """The height of the first rebound's apex above the resting height, metres, for each height series of ``z``
    (n, T); 0 for a throw that never rebounds by ``measure.MIN_RISE``."""
    out = np.zeros(len(z))
    for i, s in enumerate(np.asarray(z, float)):
        b = measure.bounces(s)
        if len(b.apexes):
            out[i] = s[b.apexes[0]] - rest_height
    return out


def agreement(a: np.ndarray, b: np.ndarray, fps: float, rest_height: float) -> dict[Feature, np.ndarray]:
    """Per throw, ``b`` minus ``a`` (two engines' trajectories of the same throws, (n, T, 3) metres) for each
    summary of :data:`AGREEMENT`: name -> (n,) differences."""
    fa, fb = measure.features(a, fps), measure.features(b, fps)
    out = {k: fb[k] - fa[k] for k in ("bounces", "time_to_rest", "distance")}
    out["first_rebound"] = first_rebound(b[..., 2], rest_height) - first_rebound(a[..., 2], rest_height)
    return {k: out[k] for k in AGREEMENT}


# ---------------------------------------------------------------------------------------------
# Across engines


def engine_runner(runner: Runner, engine: str) -> Runner:
    """This runner on the same throws, without air, simulated by ``engine`` ('mujoco' or 'bullet'): the same
    sampled objects and launches, index by index."""
    cfg = synth.SynthConfig.from_dict(runner.dataset.meta["config"]).replace(air=False, engine=engine)
    return runner.on(synth.dataset(cfg, int(runner.dataset.meta["seed"]), data_dir=runner.data_dir,
                                 progress=runner.progress))


def configs(runner: Runner) -> dict[Network, TrainConfig]:
    """The networks' configurations: the paper's network at Table 1's point, and the same fed velocity at its own
    grid's point."""
    return {"peephole_positions": runner.table1_config(), "peephole_velocity": runner.table1_config("velocity")}


def columns(tracker: TrackerError | observe.Observation) -> list[camera.Column]:
    """The conditions of the cross-engine table: air off, exact and through the calibrated tracker."""
    return [c for c in camera.columns(tracker) if not c.air and c.name in VIEWS]


def plan(runners: Mapping[Engine, Runner], cfgs: Mapping[Network, TrainConfig], cols: Sequence[camera.Column],
         seeds: tuple[int, ...], table1_seeds: tuple[int, ...]) -> list[tuple[Runner, list[TrainConfig], bool]]:
    """Every network run of the chapter, as ``Runner.prefetch`` takes them: the cross-engine networks in each
    engine and column, and Table 1's positions network on X, Y, Z and Z with ``table1_seeds``."""
    table1 = [dataclasses.replace(cfgs["peephole_positions"], dims=d, seed=s) for d in ("z", "xyz")
              for s in table1_seeds]
    return [(r, [dataclasses.replace(camera.trained_config(cfgs[n], c), seed=s)
                 for c in cols for n in NETWORKS for s in seeds] + table1, True)
            for r in runners.values()]


@dataclass(frozen=True, eq=False)
class Cross:
    """One learner trained on one engine and tested on one engine's test split, in one condition."""

    learner: Learner
    train: Engine
    test: Engine
    column: camera.Column
    correct: np.ndarray
    """(S, n) bool: seed s got test throw i right (S = 1 for the rule)."""
    failed: int = 0
    """Seeds that failed to train."""

    @cached_property
    def interval(self) -> Interval:
        """Mean test accuracy with its bootstrap interval over the test throws and the seeds."""
        return bootstrap_accuracy(self.correct)


def cross_entries(runners: Mapping[Engine, Runner], cfgs: Mapping[Network, TrainConfig], column: camera.Column,
                  seeds: tuple[int, ...], contact_height: float) -> list[Cross]:
    """Every learner of :data:`LEARNERS`, trained on each engine (``runners``: engine -> the runner on its data
    set) under ``column``'s condition and tested on every engine's test split the same way."""
    T = cfgs["peephole_positions"].n_frames(next(iter(runners.values())).fps)
    data = {e: column.inputs(r.dataset, T) for e, r in runners.items()}  # the same noise in both engines
    tests = {e: (data[e][1], np.asarray(r.dataset.test.y)) for e, r in runners.items()}
    out = []
    for train_engine, runner in runners.items():
        x_train = data[train_engine][0]
        fitted: list[tuple[learners.Learner, np.ndarray | None]] = [
            (learners.Network(name, camera.trained_config(cfgs[name], column), seeds, desc=f"{train_engine} {name}"),
             None) for name in NETWORKS]
        fitted += [(learners.Rocket("z", T, seeds), None if column.noise is None else x_train),
                   (learners.Rule(camera.RULE_FEATURES, contact_height), x_train)]  # chosen on the training engine
        for learner, train_x in fitted:
            s = learner.score(runner, train_x, tests)
            out += [Cross(learner.name, train_engine, test_engine, column, s.correct[test_engine], s.failed)  # type: ignore[arg-type]
                    for test_engine in tests]
    return out


def transfer(entries: Sequence[Cross], learner: Learner, column: camera.Column) -> dict[Engine, Interval]:
    """What ``learner`` loses when the test engine is not its training engine, in ``column``: for each training
    engine, the accuracy on the other engine minus that on its own (paired on the same throws), with a
    bootstrap interval."""
    by = {(c.train, c.test): c for c in entries if c.learner == learner and c.column == column}
    out = {}
    for e in ENGINES:
        other = next(o for o in ENGINES if o != e)
        if (e, e) in by and (e, other) in by:
            out[e] = bootstrap_difference(by[e, other].correct, by[e, e].correct)
    return out


Outcome = Literal["transfers", "loses", "unclear"]
"""What the intervals of :func:`transfer` say of a learner that changes engine."""


def outcome(diffs: Mapping[Engine, Interval], delta: float = verdicts.MARGIN.delta) -> Outcome:
    """Whether a learner transfers: every difference of :func:`transfer` inside the book's margin ``delta`` either
    way; or loses: one wholly below ``-delta``; else the intervals cannot say."""
    if all(-delta < d.lo and d.hi < delta for d in diffs.values()):
        return "transfers"
    if any(d.hi < -delta for d in diffs.values()):
        return "loses"
    return "unclear"


# ---------------------------------------------------------------------------------------------
# Mass alone: does the mass reach a trajectory without air?


PAIRED_THROWS = 8
"""Throws of the paired check (:func:`paired_throws`), each simulated as a light and as a heavy object."""
PART = 1e-6
"""m: the distance at which two trajectories of the same throw count as parted (a micrometre: far above MuJoCo's
rounding, 1e-12 m, and far below anything a camera sees)."""
FIRST_SECOND = 1.0
"""s: the first part of the record, where the paired check also reports the largest distance."""
CHANCE = 0.5
"""The accuracy of a guess between two classes of equal size."""


def shared_range(a: tuple[float, float], b: tuple[float, float]) -> tuple[float, float]:
    """The span of two ranges: from the lower of their low ends to the higher of their high ends."""
    return min(a[0], b[0]), max(a[1], b[1])


def mass_only_prior(prior: SynthConfig, engine: Engine = "mujoco") -> SynthConfig:
    """``prior``'s throws without air in ``engine``, its two classes the same but for their mass: each keeps its own
    mass prior, both draw restitution and friction from one prior, the span of the two classes' own
    (:func:`shared_range`), and both share the launch prior as every data set does. The Bayes rule told a throw's
    restitution and friction is then at chance: whatever a classifier finds beyond that is the mass itself."""
    shared = {"restitution": shared_range(prior.light.restitution, prior.heavy.restitution),
              "friction": shared_range(prior.light.friction, prior.heavy.friction)}
    return prior.replace(air=False, engine=engine, light=ClassPrior(prior.light.mass, **shared),
                         heavy=ClassPrior(prior.heavy.mass, **shared))


def mass_only_runner(runner: Runner, engine: Engine, duration: float | None = None) -> Runner:
    """``runner`` on the mass-only data set (:func:`mass_only_prior`) of its own config and data seed, simulated by
    ``engine`` and cached by content like every data set; each throw recorded for ``duration`` s (None: the
    config's own; the learners' input length is all they read, and spares simulating the rest)."""
    cfg = mass_only_prior(SynthConfig.from_dict(runner.dataset.meta["config"]), engine)
    if duration is not None:
        cfg = cfg.replace(duration=duration)
    return runner.on(synth.dataset(cfg, int(runner.dataset.meta["seed"]), data_dir=runner.data_dir,
                                   progress=runner.progress))


def paired_masses(prior: SynthConfig) -> tuple[float, float]:
    """The light and the heavy mass of the paired check, kg: each class prior's geometric centre (the middle of the
    log-uniform range)."""
    return tuple(math.sqrt(p.mass[0] * p.mass[1]) for p in (prior.light, prior.heavy))  # type: ignore[return-value]


@dataclass(frozen=True, eq=False)
class Paired:
    """The same throws simulated twice in one engine, once as a light and once as a heavy object."""

    engine: Engine
    masses: tuple[float, float]
    """The light and the heavy mass, kg."""
    distance: np.ndarray
    """(n, T) m: frame by frame, how far the heavy object's centre is from the light one's."""
    fps: float

    @property
    def t(self) -> np.ndarray:
        """(T,) s: the frame times."""
        return np.arange(self.distance.shape[1]) / self.fps

    @property
    def max_distance(self) -> np.ndarray:
        """(n,) m: each throw's largest distance over the whole record."""
        return self.distance.max(axis=1)

    @property
    def first_second(self) -> np.ndarray:
        """(n,) m: each throw's largest distance in the record's first :data:`FIRST_SECOND`."""
        return self.distance[:, : round(FIRST_SECOND * self.fps) + 1].max(axis=1)

    @property
    def parting_time(self) -> np.ndarray:
        """(n,) s: when each throw's two trajectories first part by more than :data:`PART` (NaN: never)."""
        apart = self.distance > PART
        return np.where(apart.any(axis=1), apart.argmax(axis=1) / self.fps, np.nan)


def paired_throws(prior: SynthConfig, engine: Engine, n: int = PAIRED_THROWS, seed: int = 0) -> Paired:
    """``n`` throws of the mass-only prior (:func:`mass_only_prior`: its light class's test throws of ``seed``,
    restitution, friction and launch as sampled) simulated in ``engine`` at each mass of :func:`paired_masses`,
    over ``prior``'s duration and frame rate, on one thread."""
    cfg = mass_only_prior(prior, engine).replace(n_test=n)
    params = synth.sample_split(cfg, seed, "test")
    light = {k: v[params["label"] == 0] for k, v in params.items()}
    masses = paired_masses(prior)
    sim = synth.engine(engine)
    x = [sim.simulate_split(cfg, {**light, "mass": np.full(n, m)}, 1, False, "paired") for m in masses]
    return Paired(engine, masses, np.linalg.norm(x[1] - x[0], axis=2), cfg.fps)


def best_learner(entries: Sequence[Cross], column: camera.Column) -> Learner:
    """The chapter's best learner: of :data:`LEARNERS`, the one with the highest accuracy in ``column`` trained and
    tested in the same engine, both engines' test throws together (ties: the first)."""
    score = {n: np.mean([_find(entries, n, column, e, e).correct.mean() for e in ENGINES]) for n in LEARNERS}
    return max(LEARNERS, key=lambda n: score[n])


def mass_configs(cfgs: Mapping[Network, TrainConfig], learner: Learner, column: camera.Column,
                 seeds: tuple[int, ...]) -> list[TrainConfig]:
    """The runs of the mass-only test: ``learner``'s configuration in ``column`` for each seed (none for a learner
    that is not a network)."""
    if learner not in NETWORKS:
        return []
    return [dataclasses.replace(camera.trained_config(cfgs[learner], column), seed=s) for s in seeds]  # type: ignore[index]


@dataclass(frozen=True, eq=False)
class MassTest:
    """One learner trained and tested in one engine on two classes whose only difference is the mass."""

    engine: Engine
    learner: Learner
    correct: np.ndarray
    """(S, n) bool: seed s got test throw i right (S = 1 for the rule)."""
    seeds: tuple[int, ...]
    failed: int = 0
    """Seeds that failed to train (a network at chance on validation fails, as it should here)."""
    data_key: str = ""

    @cached_property
    def interval(self) -> Interval:
        """Mean test accuracy with its bootstrap interval over the test throws and the seeds."""
        return bootstrap_accuracy(self.correct)

    @property
    def above_chance(self) -> Interval:
        """The accuracy minus :data:`CHANCE`, with the same interval shifted."""
        iv = self.interval
        return Interval(iv.value - CHANCE, iv.lo - CHANCE, iv.hi - CHANCE, iv.method)

    @property
    def signal(self) -> bool:
        """Whether the whole interval lies above chance: the classes are told apart by their mass."""
        return self.interval.lo > CHANCE


def mass_test(runner: Runner, engine: Engine, learner: Learner, cfgs: Mapping[Network, TrainConfig],
              column: camera.Column, seeds: tuple[int, ...], contact_height: float) -> MassTest:
    """``learner`` trained on the mass-only data set's training split (``runner`` on it: :func:`mass_only_runner`)
    in ``column``'s condition and tested on its test split, as :func:`cross_entries` trains it."""
    ds: Dataset = runner.dataset
    y = np.asarray(ds.test.y)
    T = cfgs["peephole_positions"].n_frames(ds.fps)
    x_train, x_test = column.inputs(ds, T)
    failed, used = 0, tuple(seeds)
    if learner in NETWORKS:
        runs = runner.rows(mass_configs(cfgs, learner, column, seeds), desc=f"{engine} mass only")
        correct, failed = runs.correct(), runs.n_failed
    else:
        fit: learners.Learner = (learners.Rocket("z", T, seeds) if learner == "minirocket"
                                 else learners.Rule(camera.RULE_FEATURES, contact_height))
        scores = fit.score(runner, None if learner == "minirocket" and column.noise is None else x_train,
                           {"test": (x_test, y)})
        correct, used = scores.correct["test"], scores.seeds
    return MassTest(engine, learner, np.asarray(correct, bool), used, failed, ds.key)


# ---------------------------------------------------------------------------------------------
# What the chapter reports


def agreement_numbers(diff: Mapping[Feature, np.ndarray],
                      y: np.ndarray) -> tuple[dict[Feature, dict[ClassName, Number]], Table]:
    """The median difference of each summary of :func:`agreement` (``diff``) by class (``y`` (n,) the labels),
    and the table of its spread."""
    out: dict[Feature, dict[ClassName, Number]] = {}
    rows = []
    for k, label in AGREEMENT.items():
        for c, name in enumerate(CLASSES):
            d = diff[k][y == c]
            iv = stats.bootstrap_mean(d)
            out.setdefault(k, {})[name] = number(float(np.median(d)), f"median of Bullet minus MuJoCo, {label}, {name}",
                                                 unit=UNITS[k])  # type: ignore[index]
            rows.append({"what": label, "class": name, "median": f"{np.median(d):+.3g}",
                         "iqr": f"{np.percentile(d, 25):+.3g} to {np.percentile(d, 75):+.3g}",
                         "mean": f"{iv.value:+.3g} [{iv.lo:+.3g}, {iv.hi:+.3g}]",
                         "same": f"{100 * np.mean(np.abs(d) < 1e-9):.0f} %" if k == "bounces" else "—"})
    return out, Table(rows, {"what": "Bullet minus MuJoCo, per throw", "class": "class", "median": "median",
                             "iqr": "interquartile range", "mean": "mean [95 % CI]", "same": "same count"})


def _find(entries: Sequence[Cross], learner: Learner, column: camera.Column, train: Engine, test: Engine) -> Cross:
    return next(x for x in entries if x.learner == learner and x.column == column and x.train == train
                and x.test == test)


def cross_numbers(entries: Sequence[Cross], cols: Sequence[camera.Column],
                  length: float) -> tuple[dict[Learner, dict[View, dict[Pair, Number]]], Table]:
    """Every learner trained in each engine and tested in each, and the table of them."""
    out: dict[Learner, dict[View, dict[Pair, Number]]] = {}
    rows = []
    for c in cols:
        for name in LEARNERS:
            row = {"learner": NAMES[name], "cond": CONDITIONS[c.name]}  # type: ignore[index]
            for tr in ENGINES:
                for te in ENGINES:
                    x = _find(entries, name, c, tr, te)
                    out.setdefault(name, {}).setdefault(c.name, {})[f"{tr}_to_{te}"] = number(  # type: ignore[index]
                        x.interval, f"{NAMES[name]}, trained in {tr}, tested in {te}, {c.label}", failed=x.failed)
                    row[f"{tr}_{te}"] = seeds_ci(x.correct) + (f"; {x.failed} failed" if x.failed else "")
            rows.append(row)
    heads = {"learner": f"learner (Z, {length:g} s)", "cond": "positions",
             **{f"{tr}_{te}": f"trained {tr}, tested {te}" for tr in ENGINES for te in ENGINES}}
    return out, Table(rows, heads)


OUTCOME_WORDS: dict[Outcome, str] = {
    "transfers": "it transfers: within the book's margin of {delta} points either way",
    "loses": "it loses more than that margin",
    "unclear": "whether it loses more than the margin, the intervals cannot say"}
"""What each :data:`Outcome` says, in the transfer table."""


def transfer_numbers(entries: Sequence[Cross], cols: Sequence[camera.Column]) -> tuple[
        dict[Learner, dict[View, dict[Engine, Number]]], Table, dict[tuple[Learner, View], Outcome]]:
    """What each learner loses when the engine changes, its table, and each (learner, view)'s outcome."""
    out: dict[Learner, dict[View, dict[Engine, Number]]] = {}
    rows, outcomes = [], {}
    delta = verdicts.MARGIN.delta
    for c in cols:
        for name in LEARNERS:
            t = transfer(entries, name, c)
            out.setdefault(name, {})[c.name] = {  # type: ignore[index]
                tr: number(dv, f"{NAMES[name]} trained in {tr}: the other engine minus its own, {c.label}", signed=True)
                for tr, dv in t.items()}
            outcomes[name, c.name] = o = outcome(t, delta)
            rows.append({"learner": NAMES[name], "cond": CONDITIONS[c.name],  # type: ignore[index]
                         **{tr: points(dv) for tr, dv in t.items()},
                         "says": OUTCOME_WORDS[o].format(delta=f"{100 * delta:g}")})
    heads = {"learner": "learner", "cond": "positions",
             **{e: f"trained in {e}: in the other engine, minus in its own" for e in ENGINES}, "says": "does it transfer?"}
    return out, Table(rows, heads), outcomes  # type: ignore[return-value]


def table1_numbers(in_engine: Mapping[Engine, Runs]) -> tuple[dict[Engine, dict[Dims, Table1Row]], Table]:
    """Table 1 in each engine: the run validation picks (``stats.validation_pick``, over one data set) and the
    mean over the seeds, each row of X, Y, Z and of Z; in Bullet, against the paper's numbers."""
    out: dict[Engine, dict[Dims, Table1Row]] = {}
    rows = []
    for d, dname in paper.DIMS_NAMES.items():
        row = {"dims": dname, "paper": pct(paper.TABLE1[d], 0)}
        for e, runs in in_engine.items():
            runs_d = runs.where(dims=d)
            pick = stats.validation_pick([runs_d])
            paper_way = number(pick.interval, f"Table 1 in {e}, air off: the run validation picks, {dname}",
                               paper=paper.TABLE1[d] if e == "bullet" else None, seed=pick.picked[0].seed)
            mean = number(stats.summary(runs_d).interval,  # type: ignore[arg-type]
                          f"Table 1 in {e}, air off: mean over {len(runs_d)} seeds, {dname}")
            out.setdefault(e, {})[d] = Table1Row(paper_way, mean)
            row[e] = f"{pct_ci(pick.interval)}; mean {seeds_ci(runs_d.correct())}"
            if e == "bullet":
                row["verdict"] = f"**{paper_way.verdict}**"
        rows.append(row)
    return out, Table(rows, {
        "dims": "trajectory dimension(s)", "paper": "paper (Blender, i.e. Bullet)",
        "mujoco": "MuJoCo, air off: the run validation picks; mean of seeds [95 % CI]; t-interval; each seed",
        "bullet": "Bullet: the same", "verdict": "paper vs Bullet"})


def mass_numbers(tests: Mapping[Engine, MassTest]) -> tuple[dict[Engine, MassOnly], Table]:
    """Each engine's mass-only test as numbers, and the table of them."""
    out: dict[Engine, MassOnly] = {}
    rows = []
    for e, t in tests.items():
        name = NAMES[t.learner]
        out[e] = MassOnly(
            number(t.interval, f"{name}, two classes that share all but the mass, air off, in {e}",
                   learner=t.learner, seeds=list(t.seeds), failed=t.failed, data=t.data_key),
            number(t.above_chance, f"the same minus one half (chance), in {e}", signed=True))
        rows.append({"engine": e, "learner": name, "accuracy": seeds_ci(t.correct) + (
            f"; {t.failed} failed" if t.failed else ""), "above": points(t.above_chance), "n": t.correct.shape[1]})
    return out, Table(rows, {"engine": "trained and tested in", "learner": "learner (Z, exact positions)",
                             "accuracy": "accuracy: mean [95 % CI]; t-interval; each seed (%)",
                             "above": "above chance", "n": "test throws"})


def paired_numbers(paired: Mapping[Engine, Paired]) -> tuple[dict[Engine, PairedNumbers], Table]:
    """Each engine's paired check as numbers (medians over the throws, each throw's value in the source), and the
    table of them."""
    out: dict[Engine, PairedNumbers] = {}
    rows = []
    for e, p in paired.items():
        light, heavy = p.masses
        each = {"masses_kg": [light, heavy], "throws": [float(v) for v in p.max_distance]}
        times = p.parting_time[np.isfinite(p.parting_time)]
        out[e] = PairedNumbers(
            number(float(np.median(p.max_distance)), f"{e}: median over {len(p.max_distance)} throws of how far the "
                   f"same throw as {light:.3g} kg and as {heavy:.3g} kg parts over the record", unit="m", **each),
            number(float(p.max_distance.max()), f"{e}: the largest of those", unit="m"),
            number(float(np.median(p.first_second)), f"{e}: the same in the first {FIRST_SECOND:g} s", unit="m",
                   throws=[float(v) for v in p.first_second]),
            count(len(times), f"{e}: throws whose two trajectories part by more than {PART:g} m"),
            number(float(np.median(times)), f"{e}: median time at which they part by more than {PART:g} m",
                   unit="s", throws=[float(v) for v in times]) if len(times) else None)
        rows.append({"engine": e, "median": f"{np.median(p.max_distance):.2g}", "largest": f"{p.max_distance.max():.2g}",
                     "first": f"{np.median(p.first_second):.2g}", "parted": f"{len(times)} of {len(p.max_distance)}",
                     "when": f"{np.median(times):.2f}" if len(times) else "—"})
    return out, Table(rows, {"engine": "engine", "median": "farthest apart over the record, m (median)",
                             "largest": "(largest)", "first": f"in the first {FIRST_SECOND:g} s, m (median)",
                             "parted": f"part by over {PART * 1e6:g} µm", "when": "when, s (median)"})


# ---------------------------------------------------------------------------------------------
# The chapter's result


@dataclass(frozen=True)
class AnotherEngine:
    """Everything the chapter shows: its numbers (:attr:`numbers`), its tables and sentences, its figures' data."""

    numbers: Numbers
    """What the chapter reports (the results file's ``engine.*``)."""
    bullet_setup: str
    """How Bullet is set up, in words (``study.simulate.bullet.DESCRIPTION``)."""
    checks: BulletChecks
    """Bullet checked as MuJoCo is."""
    agreement: dict[Feature, np.ndarray]
    """Per test throw, Bullet minus MuJoCo: name -> (n,)."""
    test_y: np.ndarray
    """(n,) the test throws' labels."""
    columns: tuple[camera.Column, ...]
    """The cross-engine conditions."""
    configs: dict[Network, TrainConfig]
    """The networks' configurations."""
    entries: tuple[Cross, ...]
    """Every learner, training engine, test engine and condition."""
    outcomes: dict[tuple[Learner, View], Outcome]
    """Whether each learner transfers, in each condition."""
    in_engine: dict[Engine, Runs]
    """Table 1's runs in each engine."""
    agree_table: Table
    cross_table: Table
    transfer_table: Table
    engine_table1: Table
    n_seeds: int
    """Seeds of each cross-engine network."""
    mass_prior: SynthConfig
    """The mass-only test's data set config (:func:`mass_only_prior`, MuJoCo's; Bullet's differ in the engine
    alone)."""
    mass_learner: Learner
    """The learner of the mass-only test: the chapter's best (:func:`best_learner`)."""
    mass_tests: dict[Engine, MassTest]
    """Each engine's mass-only test."""
    paired: dict[Engine, Paired]
    """Each engine's paired check."""
    mass_table: Table
    paired_table: Table

    @property
    def transfer_summary(self) -> str:
        """How many learners transfer, in one sentence."""
        n = {o: sum(v == o for v in self.outcomes.values()) for o in get_args(Outcome)}
        return (f"Of {len(self.outcomes)} learners and conditions, {n['transfers']} transfer within the book's margin "
                f"of {100 * verdicts.MARGIN.delta:g} points either way, {n['loses']} lose more than that, and for "
                f"{n['unclear']} the intervals cannot say.")

    @property
    def mass_learner_name(self) -> str:
        """The mass-only test's learner, in words."""
        return NAMES[self.mass_learner]

    @property
    def mass_setup(self) -> str:
        """The mass-only test's two classes, in words."""
        c = self.mass_prior
        (r0, r1), (f0, f1) = c.light.restitution, c.light.friction
        return (f"Both classes draw the restitution from {r0:g}–{r1:g} and the friction from {f0:g}–{f1:g}, the span "
                f"of the light and the heavy prior, so that each class makes every kind of contact the book's throws "
                f"make (bouncing and tumbling as well as sliding), and the launch from the study's one prior; the "
                f"light class's mass is {c.light.mass[0]:g}–{c.light.mass[1]:g} kg and the heavy class's "
                f"{c.heavy.mass[0]:g}–{c.heavy.mass[1]:g} kg, as in the study. Told each throw's restitution and "
                f"friction, the Bayes rule scores {pct(self.numbers.mass_only_ceiling.value)}. Each engine simulates "
                f"its own data set of these priors, {c.n_train} training and {c.n_test} test throws a class as the "
                f"book's, each recorded for {c.duration:g} s, the learners' input.")

    def _found(self, e: Engine) -> str:
        t, name = self.mass_tests[e], ENGINE_NAMES[e]
        if t.signal:
            return f"{name}'s trajectories carry the mass, its classifier {points(t.above_chance)} above chance"
        runs = f"{len(t.seeds)} seeds" if len(t.seeds) > 1 else "one fit"
        return (f"the test found no mass signal in {name} at the book's scale ({t.correct.shape[1]} test throws, "
                f"{runs}): at most {100 * (t.interval.hi - CHANCE):.1f} points above chance, at 95 %")

    @property
    def mass_summary(self) -> str:
        """What the mass-only test found in each engine, in one sentence."""
        acc = " and ".join(f"{pct_ci(t.interval)} in {ENGINE_NAMES[e]}" for e, t in self.mass_tests.items())
        found = "; ".join(self._found(e) for e in self.mass_tests)
        return (f"Trained on two classes that share everything but the mass, air off, the {NAMES[self.mass_learner]} "
                f"scores {acc} (chance: {pct(CHANCE, 0)}): {found}.")

    @property
    def ceiling_words(self) -> str:
        """Whether the exact ceiling of the priors bounds each engine's learners, as the mass-only test says."""
        c = pct(self.numbers.ceiling.value)
        carry = [ENGINE_NAMES[e] for e, t in self.mass_tests.items() if t.signal]
        if not carry:
            return (f"the exact ceiling of the priors, {c}, bounds the learners of both engines alike, since they "
                    f"simulate the same draws and neither engine's mass-only test (below) found the mass in a "
                    f"trajectory.")
        held = [ENGINE_NAMES[e] for e, t in self.mass_tests.items() if not t.signal]
        where = f", and bounds the learners of {' and '.join(held)}" if held else ""
        far = "; ".join(f"in {ENGINE_NAMES[e]} {points(t.above_chance)} above chance"
                        for e, t in self.mass_tests.items() if t.signal)
        return (f"the exact ceiling of the priors is {c}{where}; in {' and '.join(carry)} it is not a ceiling, for "
                f"the mass reaches the trajectories there (the mass-only test below: {far}).")

    @property
    def paired_summary(self) -> str:
        """The paired check in one sentence."""
        light, heavy = next(iter(self.paired.values())).masses
        parts = []
        for e, n in self.numbers.paired.items():
            when = f", the median at {n.parting_time.value:.2f} s" if n.parting_time is not None else ""
            parts.append(f"in {ENGINE_NAMES[e]}, {n.first_second.value:.2g} m apart at most within "
                         f"{FIRST_SECOND:g} s of the launch and {n.max_distance.value:.2g} m over the record (medians; "
                         f"the largest {n.largest.value:.2g} m), {n.parted.value:.0f} of "
                         f"{len(self.paired[e].max_distance)} parting by more than {PART * 1e6:g} µm{when}")
        return (f"The same {len(next(iter(self.paired.values())).max_distance)} throws simulated at {light:.3g} kg "
                f"and at {heavy:.3g} kg: " + "; ".join(parts) + ".")


def compute(runner: Runner, tracker: TrackerError | observe.Observation | None = None) -> AnotherEngine:
    """The chapter *Another engine* on ``runner``'s throws, without air, in each engine of ``synth.ENGINES``: every
    network run at once, then the checks, the agreement, the cross-engine table and Table 1 in each engine; then the
    mass-only test of the chapter's best learner in each engine (its runs asked for once that learner is known) and
    the paired check.

    ``tracker``: the calibrated tracker (default ``calibration.observation(runner)``, its error model fitted on rendered
    throws)."""
    runners = {e: engine_runner(runner, e) for e in ENGINES}
    prior, p = runner.synth_config, runner.preset
    mj, bt = (runners[e].dataset for e in ENGINES)
    cols = columns(calibration.observation(runner) if tracker is None else tracker)
    cfgs = configs(runner)
    runner.prefetch(plan(runners, cfgs, cols, p.grid_seeds, p.seeds), desc="both engines")
    diff = agreement(mj.test.x, bt.test.x, mj.fps, prior.shape.rest_height)
    y = np.asarray(mj.test.y)
    agree, agree_table = agreement_numbers(diff, y)
    entries = tuple(x for c in cols
                    for x in cross_entries(runners, cfgs, c, p.grid_seeds, prior.shape.bounding_radius))
    cross, cross_table = cross_numbers(entries, cols, cfgs["peephole_positions"].length)
    moved, transfer_table, outcomes = transfer_numbers(entries, cols)
    in_engine = {e: r.seed_runs(cfgs["peephole_positions"]) for e, r in runners.items()}
    table1, engine_table1 = table1_numbers(in_engine)
    exact = number(ceiling.exact_ceiling(prior, camera.AIR_OFF_PARAMETERS),
                   "exact ceiling of the priors (both engines: the same draws)")
    exact_col = next(c for c in cols if c.noise is None)  # a mass signal is sub-millimetre: exact positions
    learner = best_learner(entries, exact_col)
    length = max(c.length for c in cfgs.values())  # what the learners read of a throw, s
    mass_runners = {e: mass_only_runner(runner, e, length) for e in ENGINES}
    mass_cfgs = mass_configs(cfgs, learner, exact_col, p.grid_seeds)
    if mass_cfgs:
        runner.prefetch([(r, mass_cfgs, True) for r in mass_runners.values()], desc="mass only")
    tests = {e: mass_test(r, e, learner, cfgs, exact_col, p.grid_seeds, prior.shape.bounding_radius)
             for e, r in mass_runners.items()}
    mass, mass_table = mass_numbers(tests)
    mass_prior = SynthConfig.from_dict(mass_runners["mujoco"].dataset.meta["config"])
    mass_ceiling = number(ceiling.exact_ceiling(mass_prior, camera.AIR_OFF_PARAMETERS),
                          "exact ceiling of the mass-only priors (the same restitution and friction)")
    paired = {e: paired_throws(prior, e, seed=int(runner.dataset.meta["seed"])) for e in ENGINES}
    pairs, paired_table = paired_numbers(paired)
    numbers = Numbers(agree, cross, exact, moved, table1["bullet"], table1["mujoco"], mass, mass_ceiling, pairs)
    return AnotherEngine(numbers, bullet.DESCRIPTION, bullet_checks(prior), diff, y, tuple(cols), cfgs, entries,
                         outcomes, in_engine, agree_table, cross_table, transfer_table, engine_table1,
                         len(p.grid_seeds), mass_prior, learner, tests, paired, mass_table, paired_table)
