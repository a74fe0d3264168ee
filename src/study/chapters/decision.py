"""The chapter *From accuracy to a decision*: from a classifier's probabilities to a car's decision.

The paper reports accuracy. A car must decide: treat the object as must-avoid (heavy) unless it is
confident enough that it is safe to pass (light). Missing a heavy object is far worse than a needless
swerve, so the decision threshold is set for a target *miss rate* (the share of heavy objects called
light) on a *certification split* that neither training nor model selection has seen, and the miss rate is
then measured on the test split. Probabilities are ``p_heavy`` (n,) floats; labels 1 = heavy.

The decision rules are ``study.methods.operating``'s (NumPy and SciPy only).

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
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from study.core.errors import ConfigError
from study.learn.config import Inputs, TrainConfig
from study.learn.metrics import Interval, bootstrap_accuracy
from study.methods import calibration, camera, certify, learners, operating
from study.report.decision import (
    CertifiedNumbers,
    Choice,
    ClearNumbers,
    ConditionKey,
    ConditionNumbers,
    NetworkKey,
    Numbers,
    SeedClearing,
)
from study.report.reported import count, number
from study.report.text import Table, fmt, pct, pct_ci
from study.runs import stats

if TYPE_CHECKING:  # a type only: the chapter passes a runner in
    from study.runs.runner import Runner


# ---------------------------------------------------------------------------------------------
# What the chapter reports


TARGET_MISS = 0.01
"""The chapter's target: at most this share of heavy objects may be called light."""
OBSERVE_SEEDS: dict[str, int] = {"test": 11, "certify": 12}
"""Seeds of the chapter's own observed draws of the test and the certification split."""


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


def splits(runner: Runner) -> Splits:
    """The certification split (``study.methods.certify``: throws that neither training, early stopping nor the
    grid search has seen) beside the data set's test split, both also
    observed with the tracker's error (``calibration.observation``; seeds :data:`OBSERVE_SEEDS`)."""
    T = runner.table1_config().n_frames(runner.fps)
    cx, cy = certify.split(runner)
    test, ob = runner.dataset.test, calibration.observation(runner)
    return Splits(T, runner.fps, test.x, np.asarray(test.y), cx, cy,
                  ob.observe(test.x[:, :T], runner.fps, seed=OBSERVE_SEEDS["test"]),
                  ob.observe(cx[:, :T], runner.fps, seed=OBSERVE_SEEDS["certify"]))


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
        net = learners.Network(name, c, seeds, desc=f"every frame, {key}", frames=True)
        s = net.score(runner, None, {"test": (x_test, sp.test_y), "certify": (x_cert, sp.certify_y)})
        out[key] = EveryFrame(name, c, s.p_heavy["test"], s.p_heavy["certify"])  # type: ignore[index]
    return out


@dataclass(frozen=True)
class FrameClearing:
    """How soon one network answering at every frame decides (:func:`clearing_of`)."""

    name: str
    """The network, in words."""
    accuracy: np.ndarray
    """(T,) test accuracy after each frame, mean over seeds and throws."""
    per_seed: tuple[operating.Clearing, ...] | None
    """Each seed's clearing at certified thresholds; None: not certifiable."""
    ensemble: operating.Clearing | None = None
    """The seeds as one classifier, the mean of their probabilities, certified once; None: not certifiable."""

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
    per_seed = [operating.clearing(net.certify[s], y_cert, net.test[s], y, target) for s in range(len(net.test))]
    certifiable = all(c is not None for c in per_seed)
    ensemble = operating.clearing(net.certify.mean(axis=0), y_cert, net.test.mean(axis=0), y, target)
    return FrameClearing(net.name, right.mean(axis=(0, 1)),
                         tuple(per_seed) if certifiable else None, ensemble)  # type: ignore[arg-type]


@dataclass(frozen=True)
class SeedPoint:
    """One seed of a Z classifier at its operating points."""

    point: operating.OperatingPoint
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
    ensemble: operating.OperatingPoint
    """The seeds as one classifier (the mean of their p(heavy)), its threshold certified once: the number a car
    would use whatever the seed."""

    @property
    def p_test(self) -> np.ndarray:
        """(n,) the seeds' mean p(heavy) on the test split: what :attr:`ensemble` thresholds."""
        return np.mean([s.p_test for s in self.per_seed], axis=0)

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


def condition(name: str, scores: learners.Scores, target: float) -> Condition:
    """A Z classifier's ``scores`` (one row per seed) on the certification split (``"certify"``) and the test split
    (``"test"``): each seed's operating points for ``target``, ROC area, and calibration error before and after a
    temperature fitted on the certification split."""
    y_cert, y_test = scores.y["certify"], scores.y["test"]
    per_seed = []
    for pc, pt in zip(scores.p_heavy["certify"], scores.p_heavy["test"]):
        temp = operating.fit_temperature(pc, y_cert)
        per_seed.append(SeedPoint(operating.operating_point(pc, y_cert, pt, y_test, target), pt, temp, operating.auc(*operating.roc(pt, y_test)),
                                  operating.expected_calibration_error(pt, y_test),
                                  operating.expected_calibration_error(operating.scaled(pt, temp), y_test)))
    p_test = np.mean([s.p_test for s in per_seed], axis=0)
    return Condition(name, tuple(per_seed), operating.operating_point(np.mean(scores.p_heavy["certify"], axis=0), y_cert,
                                                                      p_test, y_test, target))


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
        ensemble = ("The seeds together, as one classifier (the mean of their probabilities, certified once), give the "
                    "number a car would use whatever the seed (the table's last column).")
        if not unstable:
            return "Every seed's share lies within every other seed's interval: the number is stable. " + ensemble
        return ("For " + " and ".join(unstable) + " some seeds' shares lie outside others' intervals (the training of "
                "these networks splits into groups): the pooled number is not stable, and the table shows each seed. "
                + ensemble)

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
                f"light ones heavy (its {len(self.seeds)} seeds as one classifier: the mean of their probabilities, "
                "certified once)")
        clear = self.numbers.clear["observed"]
        if clear.headline is not None:
            whose = "its seeds as one classifier" if clear.ensemble is not None else "pooled over its seeds"
            text += (f"; answering at every frame through the tracker, the camera's network ({whose}) clears "
                     f"{fmt(clear.headline)} of the light objects within {self.input_seconds:g} s")
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
    exact = {"certify": (sp.certify_x, sp.certify_y), "test": (sp.test_x, sp.test_y)}
    observed = {"certify": (sp.observed_certify, sp.certify_y), "test": (sp.observed_test, sp.test_y)}
    faithful = learners.Network("Table 1's", cfg, seeds)
    robust = learners.Network("randomised", calibration.randomised_config(runner, cfg), seeds)
    cameras = learners.Network("camera", camera.config, seeds)
    conditions: dict[ConditionKey, Condition] = {
        "exact": condition("Table 1's, exact", faithful.score(runner, None, exact), target_miss),
        "observed": condition("Table 1's, observed", faithful.score(runner, None, observed), target_miss),
        "randomised": condition("trained on random observations, observed", robust.score(runner, None, observed),
                                target_miss),
        "camera": condition(f"the camera's network ({camera.best}), observed", cameras.score(runner, None, observed),
                            target_miss),
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
                       n_certify_heavy=int((sp.certify_y == 1).sum()), n_needed=operating.heavy_needed(target_miss))


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
        number(median, f"median time to clear the light objects cleared, {fc.name}", unit="s"),
        None if fc.ensemble is None else SeedClearing(
            number(fc.ensemble.share_cleared, f"light objects cleared within {seconds:g} s by the seeds' ensemble (the "
                   f"mean of their probabilities, certified once), {fc.name}", seeds=list(seeds)),
            number(fc.ensemble.miss, f"heavy test throws ever cleared by the ensemble (target {target:.0%})")))


def _condition_numbers(c: Condition, target: float) -> ConditionNumbers:
    e, n = c.ensemble, len(c.per_seed)
    return ConditionNumbers(
        number(c.auc, f"area under the ROC curve, {c.name}, mean over seeds"),
        number(c.ece, f"expected calibration error, {c.name}, mean over seeds"),
        number(c.ece_scaled, f"the same after temperature scaling on the calibration split, {c.name}"),
        None if e.miss is None else
        number(e.miss, f"heavy called light at the certified {target:.0%} point, {c.name}, its {n} seeds' ensemble"),
        None if e.false_alarm is None else
        number(e.false_alarm, f"light called heavy there, {c.name}, its {n} seeds' ensemble"),
        number(e.miss_empirical, f"heavy called light at the calibration split's empirical {target:.0%} quantile, "
               f"{c.name}, its {n} seeds' ensemble"))


def _clear_table(networks: dict[NetworkKey, FrameClearing], seconds: float, target: float) -> Table:
    rows = []
    for fc in networks.values():
        if fc.per_seed is None:
            rows.append({"network": fc.name, "share": "not certifiable", "seeds": "—", "miss": "—",
                         "stable": "—", "ensemble": "—"})
            continue
        rows.append({"network": fc.name, "share": pct_ci(fc.pooled()),
                     "seeds": ", ".join(f"{100 * s.value:.1f}" for s in fc.shares),
                     "miss": ", ".join(f"{100 * c.miss.value:.1f}" for c in fc.per_seed),
                     "stable": "yes" if fc.stable else "**no**: the seeds split",
                     "ensemble": "—" if fc.ensemble is None else pct_ci(fc.ensemble.share_cleared)})
    return Table(rows, {"network": "answers at every frame",
                        "share": f"light objects cleared within {seconds:g} s [95 % CI]", "seeds": "each seed (%)",
                        "miss": f"heavy test throws ever cleared, each seed (%; target {target:.0%})",
                        "stable": "do the seeds agree?",
                        "ensemble": "the seeds' ensemble (mean probability, certified once)"})


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
            "ens_miss": pct_ci(c.ensemble.miss) if c.ensemble.miss is not None else "not certifiable",
            "ens_alarm": pct_ci(c.ensemble.false_alarm) if c.ensemble.false_alarm is not None else "—",
            "ece": f"{c.ece:.3f} → {c.ece_scaled:.3f}"})
    return Table(rows, {
        "condition": "Z classifier", "auc": "ROC AUC (mean)", "thr": "certified threshold on p(heavy), per seed",
        "miss": f"heavy called light there, test split, per seed [95 % Wilson] (target {target:.0%})",
        "alarm": "light called heavy there (the cost)",
        "quantile": "heavy called light at the empirical quantile instead",
        "ens_miss": "the seeds' ensemble (mean probability, certified once): heavy called light",
        "ens_alarm": "the ensemble: light called heavy",
        "ece": "calibration error before → after scaling"})
