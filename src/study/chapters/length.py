"""The chapter *Accuracy against input length*: the paper's Figure 4, and its explanation tested one factor at a time.

:func:`compute` runs the chapter's experiments on a runner (every run cached) and returns :class:`Length`:

1. the length sweep: Table 1's configuration trained on the first T seconds for each of the preset's lengths,
   X, Y, Z and Z, several seeds a point, and the same at the long lengths with a memory that spans the input
   (:func:`sweep`, :class:`Sweep`);
2. whether accuracy falls at the longest input: the longest minus the best length, paired on the test throws,
   against the paper's claim that it falls (:func:`drops`);
3. what the shortest windows hold: the one-feature rules of the data chapter on exactly the window the network
   sees (``study.methods.windows.window_cues``);
4. the paper's explanation (vanishing or exploding gradients), one factor at a time at the longest input:
   truncation (Table 1's, or the whole input) x the forget gates' start (constant, or chrono), and the share of
   test objects still moving in the input's last frames (:func:`factorial`, :func:`still_moving`).

:class:`Numbers` is what the chapter reports, under the names ``length.z.1s``, ``length.drop.z``,
``length.factorial.z.whole.chrono`` and so on; the page glues the rest of :class:`Length` with
``study.book.publish``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from study.learn.config import Dims, TrainConfig
from study.learn.metrics import Interval, bootstrap_accuracy, bootstrap_difference
from study.methods import windows
from study.report import verdicts
from study.report.length import (
    Factorial,
    Forget,
    LengthKey,
    Numbers,
    Truncation,
    Window,
)
from study.report.reported import Number, Verdict, count, number
from study.report.text import Table, pct_ci, points, runs_note, seeds_ci
from study.runs import paper, stats
from study.runs.runner import Runner
from study.runs.runtable import Runs
from study.runs.stats import LongInputEffect, Summary
from study.simulate import measure
from study.simulate.data import Dataset

TRUNCATIONS: tuple[Truncation, ...] = ("truncated", "whole")
FORGETS: tuple[Forget, ...] = ("constant", "chrono")
ORDER: tuple[Dims, ...] = ("xyz", "z")
"""The inputs in the order the chapter shows them (and its verdicts combine them)."""
NAMES = paper.DIMS_NAMES


def length_key(length: float) -> str:
    """The name of an input length in the results file: ``1.5`` -> ``"1.5s"``."""
    return f"{length:g}s"


# ---------------------------------------------------------------------------------------------
# What the chapter reports


# ---------------------------------------------------------------------------------------------
# The experiments, one at a time


def prefetch(runner: Runner, cfg: TrainConfig) -> None:
    """Every run of the chapter at once, so that every core stays busy (the steps read them back)."""
    p, fps = runner.preset, runner.fps
    runner.prefetch([(runner, paper.length_configs(cfg, p) + paper.long_memory_configs(cfg, p, fps)
                      + [c for _, _, c in paper.factorial_configs(cfg, p, fps)], True)], desc="lengths")


@dataclass(frozen=True)
class Sweep:
    """The length sweep and its long-memory variant, with their summaries by (dims, length)."""

    runs: Runs
    """One run per (dims, length, seed) at Table 1's configuration."""
    summary: tuple[Summary, ...]
    """Mean and 95 % interval per (dims, length)."""
    long_runs: Runs
    """The long lengths with a memory that spans the input (chrono, full BPTT)."""
    long_summary: tuple[Summary, ...]
    """Their mean and interval per (dims, length)."""

    def at(self, dims: Dims, length: float) -> Summary:
        """The summary of ``dims`` at ``length``."""
        return next(s for s in self.summary if s.keys["dims"] == dims and s.keys["length"] == length)

    def correct(self, dims: Dims, length: float) -> np.ndarray:
        """(S, n) bool: the seeds of ``dims`` at ``length``, test throw by test throw."""
        return self.runs.where(dims=dims, length=length).correct()


def length_runs(runner: Runner, cfg: TrainConfig) -> Runs:
    """Accuracy against input length: one run per (dims, length, seed) at ``cfg``, labelled ``frames``."""
    cfgs = paper.length_configs(cfg, runner.preset)
    return runner.rows(cfgs, desc="lengths").labelled({"frames": c.n_frames(runner.fps)} for c in cfgs)


def long_memory_runs(runner: Runner, cfg: TrainConfig) -> Runs:
    """The length sweep at the preset's long lengths with a memory that spans the input (chrono
    initialisation, full BPTT): one run per (dims, length, seed), labelled ``frames``."""
    cfgs = paper.long_memory_configs(cfg, runner.preset, runner.fps)
    return runner.rows(cfgs, desc="long memory").labelled({"frames": c.n_frames(runner.fps)} for c in cfgs)


def factorial_runs(runner: Runner, cfg: TrainConfig) -> Runs:
    """Figure 4's explanation one factor at a time (``paper.factorial_configs``): one run per (truncation,
    forget start, dims, seed) at the longest input, labelled ``truncated`` and ``forget``."""
    plan = paper.factorial_configs(cfg, runner.preset, runner.fps)
    rows = runner.rows([c for _, _, c in plan], desc="truncation x forget start")
    return rows.labelled({"truncated": trunc, "forget": forget} for trunc, forget, _ in plan)


def sweep(runner: Runner, cfg: TrainConfig) -> Sweep:
    """The length sweep of ``cfg`` and its long-memory variant."""
    runs, long = length_runs(runner, cfg), long_memory_runs(runner, cfg)
    by = ("dims", "length")
    return Sweep(runs, tuple(stats.summarise(runs, by)), long, tuple(stats.summarise(long, by)))


def drops(s: Sweep) -> dict[Dims, Interval]:
    """For each input, the longest length minus the best one (highest mean), paired on the test throws and
    bootstrapped over them and the seeds."""
    out = {}
    for d in ORDER:
        e = stats.long_input_effect(s.summary, d)
        out[d] = bootstrap_difference(s.correct(d, e.last_length), s.correct(d, e.best_length))
    return out


def still_moving(dataset: Dataset, cfg: TrainConfig, lengths: Sequence[float]) -> dict[float, float]:
    """For each length T (s), the share of test objects still moving in the last ``cfg.truncation`` frames of the
    first T seconds (the frames a truncated back-propagation reaches)."""
    rest = measure.time_to_rest(dataset.test.x, dataset.fps)  # (n,) s until each test object stops
    return {L: float((rest > L - cfg.truncation / dataset.fps).mean()) for L in lengths}


@dataclass(frozen=True)
class Cells:
    """The 2 x 2 of one input at the longest input: each cell's runs."""

    runs: dict[tuple[Truncation, Forget], Runs]

    def correct(self, t: Truncation, f: Forget) -> np.ndarray:
        return self.runs[t, f].correct()

    def reach(self) -> Interval:
        """The whole input minus truncated, over both forget starts, paired on the same test throws."""
        return bootstrap_difference(np.concatenate([self.correct("whole", f) for f in FORGETS]),
                                    np.concatenate([self.correct("truncated", f) for f in FORGETS]))

    def memory(self) -> Interval:
        """Chrono minus constant, over both truncations."""
        return bootstrap_difference(np.concatenate([self.correct(t, "chrono") for t in TRUNCATIONS]),
                                    np.concatenate([self.correct(t, "constant") for t in TRUNCATIONS]))

    def fading(self) -> Interval:
        """With the gradient reaching every frame, chrono minus constant: does the gradient fade?"""
        return bootstrap_difference(self.correct("whole", "chrono"), self.correct("whole", "constant"))


def factorial(runner: Runner, cfg: TrainConfig) -> dict[Dims, Cells]:
    """The runs of :func:`factorial_runs` by input and cell."""
    runs = factorial_runs(runner, cfg)
    label = {"truncated": f"{cfg.truncation} frames", "whole": "the whole input"}  # the runner's labels
    return {d: Cells({(t, f): runs.where(dims=d, truncated=label[t], forget=f) for t in TRUNCATIONS for f in FORGETS})
            for d in ORDER}


# ---------------------------------------------------------------------------------------------
# The chapter's result


@dataclass(frozen=True)
class Length:
    """Everything the chapter shows: its numbers (:attr:`numbers`), tables, sentences and its figure's data."""

    numbers: Numbers
    """What the chapter reports (the results file's ``length.*``)."""
    config: TrainConfig
    """Table 1's configuration, trained at every length."""
    sweep: Sweep
    """The runs and summaries the figure draws."""
    effects: dict[Dims, LongInputEffect]
    """Best and longest length per input."""
    cells: dict[Dims, Cells]
    """The 2 x 2's runs."""
    window: list[dict[str, Any]]
    """``windows.window_cues`` rows, one per length."""
    length_table: Table
    """Every length, every seed."""
    window_table: Table
    """What each window holds."""
    control_table: Table
    """The 2 x 2, cell by cell."""
    n_lengths: int
    n_len_seeds: int
    trunc: int
    """Table 1's truncation, frames."""
    n_failed: int
    """Length-sweep runs that failed to train."""
    n_runs: int
    """Length-sweep runs."""
    failed_where: str
    """Where they failed, in words."""
    window_why: str
    """Why the runs at the shortest length failed, or that none did."""
    moving_last: float
    """Share of test objects still moving in the last truncation frames of the longest input, percent."""
    control_last: float
    """The longest input, seconds."""
    fps: float = 30.0
    """Frames per second of the data set."""

    @property
    def xyz_best_len(self) -> float:
        return self.effects["xyz"].best_length

    @property
    def xyz_best_mean(self) -> float:
        return 100 * self.effects["xyz"].best_mean

    @property
    def xyz_last_mean(self) -> float:
        return 100 * self.effects["xyz"].last_mean

    @property
    def z_best_len(self) -> float:
        return self.effects["z"].best_length

    @property
    def z_best_mean(self) -> float:
        return 100 * self.effects["z"].best_mean

    @property
    def z_last_mean(self) -> float:
        return 100 * self.effects["z"].last_mean

    @property
    def last_len(self) -> float:
        return self.effects["z"].last_length

    @property
    def window_first(self) -> float:
        return float(self.window[0]["length"])

    @property
    def window_landed(self) -> str:
        return f"{100 * self.window[0]['landed']:.0f} %"

    @property
    def drop_claim(self) -> str:
        hurt = [NAMES[d] for d, n in self.numbers.drop.items() if n.verdict == "reproduced"]
        if hurt:
            return (f"Long inputs hurt with {' and '.join(hurt)}: the interval of the drop from the best length lies "
                    "below zero, as in the paper.")
        return ("In our runs the drop at the longest input is not shown: the interval of the difference from the best "
                "length does not lie below zero for either input.")

    @property
    def drop_words(self) -> str:
        return "; ".join(f"{NAMES[d]} {points(n)} ({n.verdict})" for d, n in self.numbers.drop.items())

    @property
    def control_verdict(self) -> str:
        return " ".join(_fading_words(d, c, self.numbers.factorial[d].vanishing) for d, c in self.cells.items())

    @property
    def untrainable(self) -> str:
        """Which cells of the 2 x 2 have runs that failed to train, and why they cannot, in numbers
        (:func:`untrainable_words`)."""
        return untrainable_words(self.cells, self.config, self.fps, self.control_last, self.moving_last)


_FADES = {
    "reproduced": "with the gradient reaching every frame the spanning memory still adds accuracy, as fading "
                  "(vanishing) gradients would",
    "differs": "with the gradient reaching every frame the spanning memory adds nothing, so what was missing was the "
               "gradient's reach (the truncation), not a gradient that fades",
    "inconclusive": "whether the spanning memory still adds accuracy once the gradient reaches every frame, the "
                    "intervals cannot say",
}


def memory_left(forget_bias: float, frames: int) -> float:
    """The share of its state an LSTM whose forget gates sit at their constant start (``sigmoid(forget_bias)`` per
    frame) keeps over ``frames`` frames: what reaches the last frame of something seen that long before."""
    return (1.0 / (1.0 + math.exp(-forget_bias))) ** frames


def untrainable_words(cells: dict[Dims, Cells], cfg: TrainConfig, fps: float, last: float, moving: float) -> str:
    """The 2 x 2's cells whose runs failed to train, and why, computed: a truncated cell's gradient reaches only the
    last ``cfg.truncation`` frames, where ``moving`` % of test objects still move; a constant start keeps
    ``sigmoid(forget_bias)`` of its state per frame, so of the first second's bounces, ``(last - 1) * fps`` frames
    before the answer, :func:`memory_left` is left. A sentence saying so when every run trained."""
    failed = [(d, t, f, r.n_failed, len(r)) for d, c in cells.items() for (t, f), r in c.runs.items() if r.n_failed]
    if not failed:
        return f"Every run of the 2 × 2 at {last:g} s trained."
    where = "; ".join(f"{NAMES[d]}, {'truncated' if t == 'truncated' else 'whole input'}, {f} start: {n} of {k}"
                      for d, t, f, n, k in failed)
    frames = round((last - 1.0) * fps)
    why = []
    if any(t == "truncated" for _, t, _, _, _ in failed):
        why.append(f"a truncated run's gradient reaches only the last {cfg.truncation} frames, where only {moving:.1f} "
                   "% of the test objects still move, so the answer at the last frame has almost nothing to learn from")
    if any(f == "constant" for _, _, f, _, _ in failed):
        why.append(f"forget gates that start at a constant bias of {cfg.forget_bias:g} keep "
                   f"{memory_left(cfg.forget_bias, 1):.2f} of the state per "
                   f"frame, so of a bounce in the first second, {frames} frames before the answer, "
                   f"{memory_left(cfg.forget_bias, frames):.0e} is left at the start of training")
    return (f"Runs that failed to train in the 2 × 2 at {last:g} s (each stayed on the coin's plateau): {where}. "
            f"They cannot, for a reason the numbers give: {'; and '.join(why)}.")


def _fading_words(d: Dims, c: Cells, vanishing: Number) -> str:
    """What the 2 x 2 of ``d`` says, in one sentence."""
    reach, memory = c.reach(), c.memory()
    cause = ("back-propagating through the whole input recovers accuracy" if reach.lo > 0 else
             "back-propagating through the whole input does not help")
    cause += ", and so does the chrono start" if memory.lo > 0 else ", the chrono start does not"
    fades = vanishing.verdict or "inconclusive"
    return (f"With {NAMES[d]}, {cause} (truncation {points(reach)}; chrono {points(memory)}); {_FADES[fades]} "
            f"({points(vanishing)}: {fades}).")


def _sweep_numbers(s: Sweep) -> tuple[dict[Dims, dict[LengthKey, Number]], dict[Dims, dict[LengthKey, Number]]]:
    def tree(summary: Sequence[Summary], what: str) -> dict[Dims, dict[LengthKey, Number]]:
        out: dict[Any, dict[Any, Number]] = {}
        for r in summary:
            d, L = r.keys["dims"], r.keys["length"]
            out.setdefault(d, {})[length_key(L)] = number(r.interval, what.format(d=NAMES[d], L=L))  # type: ignore
        return out

    return (tree(s.summary, "mean test accuracy, {d}, T = {L:g} s"),
            tree(s.long_summary, "long-memory variant, {d}, T = {L:g} s"))


def _length_table(s: Sweep, lengths: Sequence[float], fps: float) -> Table:
    def cell(d: Dims, L: float) -> str:
        note = runs_note(s.at(d, L))
        return seeds_ci(s.correct(d, L)) + (f" ({note})" if note else "")

    rows = [{"length": L, "frames": round(L * fps), **{d: cell(d, L) for d in ORDER}} for L in lengths]
    return Table(rows, {"length": "T (s)", "frames": "frames", "xyz": "X, Y, Z: mean [95 % CI]; t-interval; each seed",
                        "z": "Z only: the same"}, {"length": "g"})


def _window(window: list[dict[str, Any]], s: Sweep) -> tuple[dict[LengthKey, Window], Table, str]:
    rows = [{"length": w["length"], "landed": f"{100 * w['landed']:.0f} %", "drag": pct_ci(w["drag"]),
             "other": f"{pct_ci(w['other'])} ({measure.FEATURES[w['other_feature']]})"} for w in window]
    table = Table(rows, {"length": "T (s)", "landed": "test throws whose first fall ended in the window",
                         "drag": "drag rule (fall acceleration) [95 % CI]",
                         "other": "best other one-feature rule [95 % CI]"}, {"length": "g"})
    w0 = window[0]
    L = w0["length"]
    numbers = {length_key(L): Window(number(w0["other"], f"best non-drag rule on the first {L:g} s"),
                                     number(w0["drag"], f"drag rule on the first {L:g} s"))}
    return numbers, table, window_why(w0, s.runs.where(length=L))  # type: ignore[return-value]


def window_why(w0: Mapping[str, Any], runs: Runs) -> str:
    """Why the runs at the shortest length ``w0["length"]`` (``runs``) failed: nothing to learn from (the bounce
    and rest cues not yet in the window, the drag cue there and unread), or a failure to learn."""
    L, failed = w0["length"], runs.n_failed
    if not failed:
        return f"No run at {L:g} s failed to train."
    why = f"{failed} of the {len(runs)} runs at {L:g} s failed to train. "
    if w0["other"].hi < 0.6 and w0["drag"].lo > 0.8:
        return why + ("The bounce and rest cues, which the longer inputs' networks match, are not yet in the window "
                      f"for most throws (no rule on them does better than {100 * w0['other'].hi:.0f} %), and the one "
                      "cue that is there, the fall's curvature, these runs did not learn to read.")
    return why + "The window holds cues a rule can use, so these runs failed to learn, not to find information."


def _factorial(cells: dict[Dims, Cells], s: Sweep, effects: dict[Dims, LongInputEffect], cfg: TrainConfig,
               last: float) -> tuple[dict[Dims, Factorial], Table]:
    trunc_words = {"truncated": f"{cfg.truncation} frames", "whole": "the whole input"}
    rows, out = [], {}
    for d, c in cells.items():
        best = s.at(d, effects[d].best_length)
        accs: dict[Truncation, dict[Forget, Number]] = {t: {} for t in TRUNCATIONS}
        for t in TRUNCATIONS:
            for f in FORGETS:
                runs = c.runs[t, f]
                iv = bootstrap_accuracy(runs.correct())
                accs[t][f] = number(iv, f"{NAMES[d]}, T = {last:g} s, truncation {trunc_words[t]}, forget gates {f}",
                                    runs=len(runs), failed=runs.n_failed)
                rows.append({"dims": NAMES[d], "trunc": trunc_words[t], "forget": f, "acc": pct_ci(iv),
                             "vs_best": f"{100 * (iv.value - best.mean):+.1f}",
                             "runs": runs_note(stats.summary(runs)) or "all trained"})
        fading = c.fading()
        out[d] = Factorial(
            accs, number(c.reach(), f"whole input minus truncated, {NAMES[d]}", signed=True),
            number(c.memory(), f"chrono minus constant forget start, {NAMES[d]}", signed=True),
            number(fading, f"full BPTT: chrono minus constant, {NAMES[d]} (the gradient reaches the start; does it "
                           "fade?)", decision=verdicts.order(fading, +1), signed=True))  # vanishing: memory helps
    table = Table(rows, {"dims": "input", "trunc": "back-propagation through", "forget": "forget gates start",
                         "acc": f"test accuracy at {last:g} s [95 % CI]", "vs_best": "minus the best length (points)",
                         "runs": "runs"})
    return out, table


def compute(runner: Runner, cfg: TrainConfig | None = None) -> Length:
    """The chapter *Accuracy against input length* on ``runner``'s preset and data set at ``cfg`` (default: Table
    1's configuration, from the Table 1 chapter's cache): every run of it, cached."""
    cfg = cfg or runner.table1_config()
    p, ds = runner.preset, runner.dataset
    prefetch(runner, cfg)
    s = sweep(runner, cfg)
    effects = {d: stats.long_input_effect(s.summary, d) for d in ORDER}
    diffs = drops(s)
    drop = {d: number(dv, f"longest input minus the best length, {NAMES[d]}", decision=verdicts.order(dv, -1),
                      signed=True) for d, dv in diffs.items()}  # the paper: the longest falls below
    window = windows.window_cues(ds, p.lengths, runner.synth_config.shape.bounding_radius)
    window_numbers, window_table, why = _window(window, s)
    last = max(p.long_lengths)
    cells = factorial(runner, cfg)
    fact, control_table = _factorial(cells, s, effects, cfg, last)
    sweep_numbers, long_numbers = _sweep_numbers(s)
    numbers = Numbers(
        count(s.runs.n_failed, "length-sweep runs that failed to train"), sweep_numbers, long_numbers, drop,
        Verdict(verdicts.combined([n.decision for n in drop.values()]),  # type: ignore[misc]
                "accuracy falls at the longest input (paper's Figure 4)"),
        window_numbers, fact,
        Verdict(verdicts.combined([f.vanishing.decision for f in fact.values()]),  # type: ignore[misc]
                "vanishing gradients: with the gradient reaching every frame, a spanning memory still helps"))
    failed = sorted({(NAMES[r.config.dims], r.config.length) for r in s.runs if r.failed})
    return Length(
        numbers, cfg, s, effects, cells, window, _length_table(s, p.lengths, ds.fps), window_table, control_table,
        n_lengths=len(p.lengths), n_len_seeds=len(p.length_seeds), trunc=cfg.truncation, n_failed=s.runs.n_failed,
        n_runs=len(s.runs), failed_where="; ".join(f"{d} at {L:g} s" for d, L in failed) or "none", window_why=why,
        moving_last=100 * still_moving(ds, cfg, [last])[last], control_last=last, fps=ds.fps)
