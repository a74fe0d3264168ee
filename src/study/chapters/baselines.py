"""The chapter *What a practitioner would try first*: MiniRocket beside the paper's network and the study's others.

The paper concludes that "a more involved classification algorithm is required" and reaches for an LSTM. The
chapter sets five methods side by side on the same splits, the first T seconds of Table 1, X, Y, Z and Z, exact
positions and (for Z) positions as the calibrated tracker observes them:

1. :func:`splits` -- each network's grid point, the input length, the seeds, the observed splits;
2. :func:`accuracy` -- every method's right answers on the test split (:func:`networks`, :func:`rockets`,
   :func:`physics`, :func:`rules`): the networks' and MiniRocket's runs are cached, the physics baseline and the
   best one-feature rule (chosen on the training split, ``measure.best_rule``) are refitted, on observed training
   positions for the observed column;
3. :func:`costs` -- one training and one prediction of the test split per method, timed afresh on one thread;
4. :func:`result` -- the numbers, the verdict on the paper's claim (the paper's network beats the best
   one-feature rule) and the table.

:func:`compute` does all four. :class:`Numbers` is what the chapter reports (``baselines.minirocket.z.exact``,
``baselines.more_involved_required``, ...); the page glues the rest of :class:`Baselines` with
``study.book.publish``.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable, Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any

import numpy as np
import torch

from study.learn import baseline, train
from study.learn.config import Cell, Dims, TrainConfig
from study.learn.metrics import Interval, bootstrap_accuracy, bootstrap_difference
from study.learn.rocket import MiniRocket
from study.methods import calibration, learners
from study.report import verdicts
from study.report.baselines import Condition, Method, Numbers, Timing
from study.report.learners import WORDS, keys
from study.report.reported import Number, Verdict, number
from study.report.text import Table, points, seeds_ci
from study.runs.runner import Runner
from study.simulate import measure
from study.simulate.observe import Observation

METHOD_NAMES: dict[Method, str] = {m: WORDS[m] for m in keys("baselines")}
"""Each method in words, in the table's order (``study.report.learners``)."""
DIMS_WORDS: dict[Dims, str] = {"xyz": "X, Y, Z", "z": "Z"}
"""The inputs as the table names them."""
NETWORKS: tuple[Cell, ...] = keys("baselines", "network")  # type: ignore[assignment]  (named by their cell)
"""The networks, each at its own grid point."""
CELLS: tuple[tuple[Dims, Condition], ...] = (("xyz", "exact"), ("z", "exact"), ("z", "observed"))
"""The (input, positions) pairs every method is scored on, in order."""
Z_RULES = ("bounces", "max_height_after_1s", "fall_acceleration")
"""The one-feature rules that read Z alone."""

Correct = dict[tuple[Method, Dims, Condition], np.ndarray]
"""(method, input, positions) -> (S, n) bool (or (n,) for a method without seeds): right on test throw i."""


# ---------------------------------------------------------------------------------------------
# What the chapter reports


# ---------------------------------------------------------------------------------------------
# The experiments, one at a time


@dataclass(frozen=True)
class Splits:
    """What every method is fitted and scored on."""

    configs: dict[Cell, TrainConfig]
    """Each network's grid point (its cell's winner)."""
    n_frames: int
    """Input length T, frames (Table 1's)."""
    seeds: tuple[int, ...]
    """Seeds of the methods that have one."""
    x_train_observed: np.ndarray
    """(n_train, T, 3) float, metres: the training split as the calibrated tracker observes it."""
    x_test_observed: np.ndarray
    """(n_test, T, 3) float, metres: the test split, observed."""
    contact: float
    """The shape's bounding radius, metres (where the first fall ends)."""


def splits(runner: Runner, ob: Observation) -> Splits:
    """Each network's grid point, the input length and seeds, and both splits as ``ob`` observes them (the one
    observed draw the chapters share, ``calibration.observed``)."""
    cfgs = {c: runner.winner(c) for c in NETWORKS}
    T = cfgs["peephole"].n_frames(runner.fps)
    return Splits(cfgs, T, runner.preset.grid_seeds, calibration.observed(runner, "train", ob, T), calibration.observed(runner, "test", ob, T),
                  runner.synth_config.shape.bounding_radius)


def networks(runner: Runner, s: Splits) -> Correct:
    """The networks' runs (Table 1's and the ablation's, cached; the GRU with X, Y, Z trained here), trained on
    exact positions (their records' answers on the test split); on Z also tested on observed positions."""
    y = np.asarray(runner.dataset.test.y)
    out: Correct = {}
    for cell in NETWORKS:
        for d in ("xyz", "z"):
            tests = {"observed": (s.x_test_observed, y)} if d == "z" else {}
            scores = learners.Network(cell, s.configs[cell], s.seeds, dims=d).score(runner, None, tests)
            out[cell, d, "exact"] = scores.runs.correct()  # type: ignore[union-attr]
            out.update({(cell, d, cond): c for cond, c in scores.correct.items()})  # type: ignore[misc]
    return out


def rockets(runner: Runner, s: Splits) -> Correct:
    """MiniRocket fitted on the exact training split, once per seed (cached like a run), tested exact and, on Z,
    observed."""
    ds = runner.dataset
    y = np.asarray(ds.test.y)
    out: Correct = {}
    for d in ("xyz", "z"):
        tests = {"exact": (ds.test.x, y)} | ({"observed": (s.x_test_observed, y)} if d == "z" else {})
        scores = learners.Rocket(d, s.n_frames, s.seeds).score(runner, None, tests)
        out.update({("minirocket", d, cond): c for cond, c in scores.correct.items()})  # type: ignore[misc]
    return out


def physics(runner: Runner, s: Splits) -> Correct:
    """The physics baseline, fitted on the exact training split and, for the observed column, on the observed
    one."""
    ds = runner.dataset
    y, length = np.asarray(ds.test.y), s.n_frames / ds.fps
    out: Correct = {}
    for d in ("xyz", "z"):
        out["physics", d, "exact"] = learners.Physics(d, length).score(runner, None, {"t": (ds.test.x, y)}).correct["t"][0]
    observed = learners.Physics("z", length).score(runner, s.x_train_observed, {"t": (s.x_test_observed, y)})
    out["physics", "z", "observed"] = observed.correct["t"][0]
    return out


def rules(runner: Runner, s: Splits) -> tuple[Correct, dict[tuple[Dims, Condition], str]]:
    """The best one-feature rule of each cell, chosen on the training split (``measure.best_rule``), and the
    feature it chose; on Z only the features that read Z."""
    ds, T = runner.dataset, s.n_frames
    inputs = {"exact": (ds.train.x[:, :T], ds.test.x[:, :T]), "observed": (s.x_train_observed, s.x_test_observed)}
    out: Correct = {}
    chosen: dict[tuple[Dims, Condition], str] = {}
    for d, cond in CELLS:
        xtr, xte = inputs[cond]
        rule = learners.Rule(Z_RULES if d == "z" else None, s.contact, height_only=False)
        scores = rule.score(runner, xtr, {cond: (xte, ds.test.y)})
        out["rule", d, cond] = scores.correct[cond][0]
        chosen[d, cond] = scores.feature
    return out, chosen


@dataclass(frozen=True)
class Accuracy:
    """Every method's right answers, and the feature each best rule chose."""

    correct: Correct
    rule_features: dict[tuple[Dims, Condition], str]


def accuracy(runner: Runner, s: Splits) -> Accuracy:
    """:func:`networks`, :func:`rockets`, :func:`physics` and :func:`rules`."""
    rule, chosen = rules(runner, s)
    return Accuracy(networks(runner, s) | rockets(runner, s) | physics(runner, s) | rule, chosen)


@dataclass(frozen=True)
class Cost:
    """What one method costs."""

    fit_s: float
    """One training (with early stopping, for the networks), seconds."""
    infer_s: float
    """Prediction, seconds per test trajectory."""


def timed(fit: Callable[[], Any], predict: Callable[[Any], Any], n: int) -> Cost:
    """The wall time of ``fit()`` and of ``predict(model)`` on ``n`` trajectories."""
    t0 = time.perf_counter()
    model = fit()
    t1 = time.perf_counter()
    predict(model)
    return Cost(t1 - t0, (time.perf_counter() - t1) / n)


@contextmanager
def one_thread() -> Iterator[None]:
    """PyTorch and numba (MiniRocket's kernels) on one thread, as NumPy is; restored after."""
    import numba  # sktime's: only the timing needs it

    before = torch.get_num_threads(), numba.get_num_threads()
    torch.set_num_threads(1)
    numba.set_num_threads(1)
    try:
        yield
    finally:
        torch.set_num_threads(before[0])
        numba.set_num_threads(before[1])


def costs(runner: Runner, s: Splits) -> dict[Method, Cost]:
    """Each method timed afresh on Z with exact positions and seed 0, one thread: one full training and the
    prediction of the whole test split."""
    ds, T = runner.dataset, s.n_frames
    z = {c: dataclasses.replace(s.configs[c], dims="z", cell=c, seed=0) for c in NETWORKS}
    n = len(ds.test.y)

    def network(cell: Cell) -> Cost:
        return timed(lambda: train.fit(ds, z[cell], progress=False, warn=False),
                     lambda m: m.predict_proba(ds.test.x), n)

    with one_thread():
        return {
            "peephole": network("peephole"),
            "gru": network("gru"),
            "minirocket": timed(lambda: MiniRocket("z", T, 0).fit(ds.train.x, ds.train.y),
                                lambda m: m.predict(ds.test.x), n),
            "physics": timed(lambda: baseline.fit(ds, "z", T / ds.fps), lambda m: m.predict_proba(ds.test.x), n),
            "rule": timed(lambda: measure.features(ds.train.x[:, :T], ds.fps, s.contact),
                          lambda m: measure.features(ds.test.x[:, :T], ds.fps, s.contact), n),
        }


# ---------------------------------------------------------------------------------------------
# The chapter's result


@dataclass(frozen=True)
class FigureRow:
    """One row of the chapter's figure: one method's test accuracy in each condition it is scored in."""

    method: Method
    name: str
    """The method in words."""
    accuracy: dict[tuple[Dims, Condition], Number]
    """(input, positions) -> its mean test accuracy with the 95 % interval, in :data:`CELLS` order."""


@dataclass(frozen=True)
class Baselines:
    """Everything the chapter shows: its numbers (:attr:`numbers`), its table and its sentences."""

    numbers: Numbers
    """What the chapter reports (the results file's ``baselines.*``)."""
    splits: Splits
    accuracy: Accuracy
    costs: dict[Method, Cost]
    baseline_table: Table
    """Every method, exact and observed, with its cost."""
    n_seeds: int
    """Seeds of the methods that have one."""

    @property
    def figure(self) -> tuple[FigureRow, ...]:
        """The figure's rows: every method, in the table's order, with its accuracy in each of :data:`CELLS`."""
        acc = self.numbers.accuracy
        return tuple(FigureRow(m, METHOD_NAMES[m], {(d, c): acc[m][d][c] for d, c in CELLS
                                                     if c in acc.get(m, {}).get(d, {})}) for m in METHOD_NAMES)

    def leader(self, d: Dims, cond: Condition) -> tuple[Method, float]:
        """The method with the highest mean accuracy on (``d``, ``cond``) (ties: the later name in the alphabet),
        and its lead over the runner-up, in points."""
        acc = self.numbers.accuracy
        cands = sorted(((acc[m][d][cond].value, m) for m in METHOD_NAMES if cond in acc[m].get(d, {})), reverse=True)
        return cands[0][1], 100 * (cands[0][0] - cands[1][0])

    @property
    def winners(self) -> str:
        texts = []
        for d, cond in CELLS:
            m, lead = self.leader(d, cond)
            vs = self.numbers.peephole_minus_rule[d][cond]
            texts.append(f"with {DIMS_WORDS[d]} and {cond} positions the {METHOD_NAMES[m]} wins, {lead:.1f} points "
                         f"ahead of the next; the paper's network is {points(vs)} from the best one-feature rule "
                         f"({vs.verdict})")
        return "; ".join(texts)

    @property
    def paper_claim(self) -> str:
        verdict = self.numbers.more_involved_required.verdict
        if verdict == "reproduced":
            return "holds in every condition: the paper's network beats the best one-feature rule"
        claims = self.numbers.peephole_minus_rule
        return (f"is {verdict} on our data ("
                + ", ".join(f"{DIMS_WORDS[d]} {c}: {claims[d][c].verdict}" for d, c in CELLS) + ")")

    @property
    def rule_drag(self) -> str:
        chosen = self.accuracy.rule_features
        drag = [f"{DIMS_WORDS[d]}, {c}" for (d, c), f in chosen.items() if f == "fall_acceleration"]
        if not drag:
            return "never the first fall's acceleration"
        return "the first fall's acceleration, the air-drag cue of the chapter on cues, for " + "; ".join(drag)


def _table(acc: Accuracy, ivs: Mapping[tuple[Method, Dims, Condition], Interval], cost: Mapping[Method, Cost]) -> Table:
    rows = []
    for m in METHOD_NAMES:
        for d in ("xyz", "z"):
            row: dict[str, str] = {"method": METHOD_NAMES[m], "dims": DIMS_WORDS[d]}
            for cond in ("exact", "observed"):
                c = acc.correct.get((m, d, cond))  # type: ignore[call-overload]
                row[cond] = "—" if c is None else seeds_ci(c) + (
                    f" ({acc.rule_features[d, cond]})" if m == "rule" else "")  # type: ignore[index]
            row["fit"] = f"{cost[m].fit_s:.1f}" if d == "z" else ""
            row["infer"] = f"{1e6 * cost[m].infer_s:.0f}" if d == "z" else ""
            rows.append(row)
    return Table(rows, {"method": "method", "dims": "input", "exact": "exact positions [95 % CI]",
                        "observed": "observed positions [95 % CI]", "fit": "training, s (Z, 1 thread)",
                        "infer": "inference per trajectory, µs"})


def result(s: Splits, acc: Accuracy, cost: Mapping[Method, Cost]) -> Baselines:
    """The chapter's numbers, verdict and table from what :func:`accuracy` and :func:`costs` measured."""
    ivs = {k: bootstrap_accuracy(np.asarray(c)) for k, c in acc.correct.items()}
    tree: dict[Any, dict[Any, dict[Any, Number]]] = {}
    for m in METHOD_NAMES:
        for d in ("xyz", "z"):
            for cond in ("exact", "observed"):
                if (m, d, cond) in ivs:
                    tree.setdefault(m, {}).setdefault(d, {})[cond] = number(
                        ivs[m, d, cond], f"{METHOD_NAMES[m]}, {DIMS_WORDS[d]}, {cond} positions")  # type: ignore[index]
    timing = {m: Timing(number(c.fit_s, f"training time, {METHOD_NAMES[m]}, Z, one thread", unit="s"),
                        number(1e6 * c.infer_s, f"inference per trajectory, {METHOD_NAMES[m]}", unit="µs"))
              for m, c in cost.items()}
    minus: dict[Any, dict[Any, Number]] = {}
    for d, cond in CELLS:  # the paper: its network beats the simplest rule
        dv = bootstrap_difference(acc.correct["peephole", d, cond], acc.correct["rule", d, cond])
        minus.setdefault(d, {})[cond] = number(
            dv, f"the paper's network minus the best one-feature rule, {DIMS_WORDS[d]}, {cond}",
            decision=verdicts.order(dv, +1), signed=True)
    claim = verdicts.combined([minus[d][c].decision for d, c in CELLS])  # type: ignore[misc]
    numbers = Numbers(tree, timing, minus,
                      Verdict(claim, "the paper's network beats the best one-feature rule on the same input"))
    return Baselines(numbers, s, acc, dict(cost), _table(acc, ivs, cost), len(s.seeds))


def compute(runner: Runner, ob: Observation | None = None, cost: Mapping[Method, Cost] | None = None) -> Baselines:
    """The chapter on ``runner``'s preset and data set: observed as ``ob`` (default: the calibrated tracker,
    ``calibration.observation``), with the costs ``cost`` (default: timed afresh, :func:`costs`)."""
    s = splits(runner, ob or calibration.observation(runner))
    acc = accuracy(runner, s)
    return result(s, acc, costs(runner, s) if cost is None else cost)
