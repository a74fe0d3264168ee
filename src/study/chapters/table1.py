"""The chapter *Table 1*: the paper's network on Z alone and on X, Y, Z, and everything a single best number hides.

:func:`compute` runs the chapter's experiments on a runner (every run cached) and returns :class:`Table1`:

1. the grid search on Z for each cell of the ablation, and for the paper's network fed its velocity, every point
   scored by its mean validation accuracy over seeds (:class:`GridSearch`);
2. what each change to the training protocol did, on validation data (:class:`Protocols`);
3. Table 1 itself: for the paper's network reading positions and reading velocity, X, Y, Z and Z, the run
   validation picks on each of the preset's data sets (the paper's statistic, computed fairly), the mean of the
   first data set's seeds, the mean over data sets and seeds, and the share of variance between data sets;
   the verdicts against the paper's 81 % and 78 % and its claim that X, Y, Z does better;
4. the heading: every throw starts at x = y = 0 with its heading uniform on the circle, so the signed horizontal
   channels carry it and no class. The same network fed what of the motion does not turn with the heading (the
   height, its velocity, the horizontal speed: ``inputs='speed'``), the paper's network trained on throws turned
   about the vertical (``TrainConfig.rotate``), and how many answers of each change when a test throw is turned
   (:class:`Heading`); the velocity network's learning-rate schedule, chosen on validation (:class:`ScheduleChoice`);
5. the ablation of the peepholes (each cell at its own grid winner);
6. a physics baseline without learning.

:class:`Numbers` is what the chapter reports, under the names ``table1.xyz.paper_way`` and so on; the page
glues the rest of :class:`Table1` (its sentences and tables) with ``study.book.publish``.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from study.learn import baseline, train
from study.learn.config import Cell, Dims, Inputs, Schedule, TrainConfig
from study.learn.inputs import rotated
from study.learn.protocols import PROTOCOLS, STUDY, ProtocolKey
from study.learn.metrics import (
    PLATEAU_LOSS,
    Interval,
    between_share,
    bootstrap_accuracy,
    bootstrap_difference,
    hierarchical_bootstrap,
    t_interval,
)
from study.methods import learners
from study.report import verdicts
from study.report.reported import Number, Verdict, count, number
from study.report.table1 import (
    ORDER,
    Ablation,
    AblationCell,
    GridNumbers,
    Network,
    Numbers,
    ProtocolRow,
    Rotated,
    Row,
    ScheduleRow,
    Speed,
    Velocity,
)
from study.report.text import Table, pct, pct_ci, pct_pm, points, runs_note, seeds_ci
from study.runs import failures, paper, stats
from study.runs.runner import Runner
from study.runs.runtable import Fitted, Run, Runs

CELL_NAMES: dict[Cell, str] = {"peephole": "peephole LSTM (paper)", "no-peephole": "LSTM, peepholes fixed at 0",
                               "torch-lstm": "LSTM (torch.nn.LSTM)", "gru": "GRU"}
"""Each cell in words."""
INPUT_NAMES: dict[Inputs, str] = {"positions": "positions (the paper's)", "velocity": "with velocity (beyond the paper)",
                                   "speed": "height, its velocity, horizontal speed (beyond the paper)"}
"""What the network reads, in words."""
NETWORKS: tuple[Network, ...] = ("positions", "velocity", "speed", "rotated")
NETWORK_NAMES: dict[Network, str] = {**INPUT_NAMES, "rotated": "positions, trained on turned throws (beyond the paper)"}
"""Each network in words."""
SCHEDULE_NAMES: dict[Schedule, str] = {"constant": "constant (the study's protocol)", "plateau": "halved on plateaus",
                                       "cosine": "warm-up, then cosine decay"}
"""Each learning-rate schedule in words."""
ROTATE = 180.0
"""The augmentation's range, degrees: any heading, as the throws are launched."""
TURN_SEED = 28
"""Seed of the angles the test throws are turned by (:func:`heading_flips`)."""


# ---------------------------------------------------------------------------------------------
# What the chapter reports


# ---------------------------------------------------------------------------------------------
# The experiments, one at a time


@dataclass(frozen=True)
class GridSearch:
    """The grid search on Z: every cell's grid and the velocity network's, and the points they chose."""

    grids: dict[Cell, Runs]
    """Each ablation cell's grid runs (positions)."""
    velocity: Runs
    """The paper's network fed velocity, the same points."""
    winners: dict[Cell, TrainConfig]
    """Each cell's best point."""
    config: TrainConfig
    """Table 1's configuration: the paper's network at its best point."""
    velocity_config: TrainConfig
    """The velocity network at the best point of its own grid."""


def grid_search(runner: Runner) -> GridSearch:
    """Every grid of the chapter at once (so both cores stay busy), then each winner."""
    p = runner.preset
    runner.prefetch([(runner, paper.grid_configs(p, cell), False) for cell in p.cells]
                    + [(runner, paper.grid_configs(p, "peephole", "velocity"), False)], desc="grids")
    grids = {cell: runner.grid(cell) for cell in p.cells}
    winners = {cell: paper.best_config(rows, p) for cell, rows in grids.items()}
    return GridSearch(grids, runner.grid("peephole", "velocity"), winners, runner.table1_config(),
                      runner.table1_config("velocity"))


def rotated_config(cfg: TrainConfig) -> TrainConfig:
    """``cfg`` (the paper's network on positions) on X, Y, Z, its training throws turned by any angle every epoch."""
    return dataclasses.replace(cfg, dims="xyz", rotate=ROTATE)


def prefetch(runner: Runner, g: GridSearch) -> None:
    """Every run of the chapter that does not wait for a choice at once: the protocols, the paper's network on
    every data set, the ablation, the rotated training throws, the velocity network's schedules."""
    p = runner.preset
    runner.prefetch([(runner, [c for _, c in paper.protocol_plan(g.config, p)], False),
                     (runner, paper.schedule_configs(g.velocity_config, p), False),
                     (runner, paper.seed_configs(g.config, p.seeds) + paper.seed_configs(rotated_config(g.config),
                                                                                          p.seeds, ("xyz",)), True),
                     (runner, paper.ablation_configs(g.winners, p), True)]
                    + [(o, paper.seed_configs(g.config, p.grid_seeds), True)
                       for o in (runner.with_data_seed(s) for s in p.data_seeds[1:])],
                    desc="Table 1, protocols, ablation")


def speed_config(cfg: TrainConfig) -> TrainConfig:
    """``cfg`` (the velocity network) fed the height, its velocity and the horizontal speed instead."""
    return dataclasses.replace(cfg, inputs="speed")


def prefetch_velocity(runner: Runner, velocity: TrainConfig) -> None:
    """The velocity network's Table 1 (at its chosen schedule) and the speed network's X, Y, Z, every data set."""
    p = runner.preset
    speed = speed_config(velocity)
    runner.prefetch([(runner, paper.seed_configs(velocity, p.seeds) + paper.seed_configs(speed, p.seeds, ("xyz",)),
                      True)]
                    + [(o, paper.seed_configs(velocity, p.grid_seeds) + paper.seed_configs(speed, p.grid_seeds, ("xyz",)),
                        True) for o in (runner.with_data_seed(s) for s in p.data_seeds[1:])],
                    desc="Table 1 with velocity")


@dataclass(frozen=True)
class ScheduleChoice:
    """The velocity network's learning-rate schedule, chosen on validation (``paper.best_schedule``)."""

    runs: Runs
    """Its grid point with each schedule, on Z, the grid's seeds (validation only)."""
    swings: dict[Schedule, np.ndarray]
    """Each schedule's per-seed swing of the validation loss (:func:`swing`), nats."""
    chosen: Schedule
    """What the velocity rows use."""
    config: TrainConfig
    """The velocity network with it."""


def swing(history: list[dict[str, float]]) -> float:
    """How far a run's validation loss moves from one epoch to the next: the mean absolute change over the second
    half of its epochs (the first half holds the descent every run makes), nats; 0 for a run of one epoch."""
    loss = np.asarray([e["val_loss"] for e in history], dtype=float)
    tail = loss[len(loss) // 2 :] if len(loss) > 2 else loss
    return float(np.mean(np.abs(np.diff(tail)))) if len(tail) > 1 else 0.0


def schedule_choice(runner: Runner, g: GridSearch) -> ScheduleChoice:
    """The velocity network's point with each schedule on validation, and the one the velocity rows use."""
    cfgs = paper.schedule_configs(g.velocity_config, runner.preset)
    records = runner.runs(cfgs, test=False, desc="schedules")
    runs = Runs(Run.from_record(r, runner.dataset.test.y) for r in records)
    swings = {k: np.asarray([swing(r["history"]) for r, c in zip(records, cfgs) if c.lr_schedule == k])
              for k in paper.SCHEDULES}
    chosen = paper.best_schedule(runs)
    return ScheduleChoice(runs, swings, chosen, dataclasses.replace(g.velocity_config, lr_schedule=chosen))


@dataclass(frozen=True)
class Seeds:
    """Table 1's runs for one network: the first data set's seeds, and the grid's seeds on each other data set."""

    first: Runs
    """Data set 1, Table 1's seeds, both inputs."""
    others: tuple[Runs, ...]
    """Each other data set, the grid's seeds, both inputs."""

    def per_data(self, dims: Dims) -> list[Runs]:
        """The runs of ``dims`` on each data set, the first first."""
        return [self.first.where(dims=dims)] + [o.where(dims=dims) for o in self.others]


def seed_runs(runner: Runner, cfg: TrainConfig, dims: tuple[Dims, ...] = paper.BOTH, every_data: bool = True) -> Seeds:
    """Table 1's runs of ``cfg`` for ``dims`` on the first data set (Table 1's seeds) and, if ``every_data``, the
    others (the grid's seeds)."""
    p = runner.preset
    others = [runner.with_data_seed(s) for s in p.data_seeds[1:]] if every_data else []  # other throws, same priors
    return Seeds(runner.train_runs(cfg, dims, p.seeds, desc="Table 1"),
                 tuple(o.train_runs(cfg, dims, p.grid_seeds, desc=f"data set {i + 2}") for i, o in enumerate(others)))


def heading_flips(runner: Runner, cfgs: dict[Network, TrainConfig]) -> dict[Network, np.ndarray]:
    """For each X, Y, Z network of ``cfgs``: (S, n) bool, whether Table 1's seed s answers test throw i otherwise
    once the throw is turned about the vertical through its launch point by an angle uniform on the circle (one
    seeded angle per throw, :data:`TURN_SEED`, the same for every network)."""
    x = runner.dataset.test.x
    turned = rotated(x, np.random.default_rng(TURN_SEED).uniform(-180.0, 180.0, len(x)))
    y = runner.dataset.test.y
    out = {}
    for k, cfg in cfgs.items():
        net = learners.Network(k, dataclasses.replace(cfg, dims="xyz"), runner.preset.seeds, dims="xyz")
        s = net.score(runner, None, {"as thrown": (x, y), "turned": (turned, y)})
        out[k] = s.correct["as thrown"] != s.correct["turned"]  # the label changed
    return out


# ---------------------------------------------------------------------------------------------
# The chapter's result


SHORT_NAMES: dict[Network, str] = {"positions": "positions", "velocity": "with velocity", "speed": "speed input",
                                   "rotated": "turned in training"}
"""Each network in two words, for the figure's axis."""


@dataclass(frozen=True)
class FigureRow:
    """One column of the chapter's figure: every run of one row of Table 1, our estimate, the paper's number."""

    network: Network
    dims: Dims
    runs: tuple[Runs, ...]
    """The row's runs on each data set, the first first (Table 1's seeds there, the grid's on the others)."""
    picked: tuple[int, ...]
    """The seed validation picks on each data set."""
    estimate: Number
    """Our estimate, a fraction: the run validation picks, mean over the data sets (the mean of data set 1's seeds
    for the rotated network, trained there only); with its verdict on the paper's network's rows."""
    paper: float | None
    """The paper's number, a fraction (the paper's network only)."""
    margin: float | None
    """Its margin M = δ + 1.96 √(p (1 − p) / n), a fraction: ours reproduces it inside paper ± M."""

    @property
    def label(self) -> str:
        """The column's name: its input, and the network where it is not the paper's."""
        dims = paper.DIMS_NAMES[self.dims]
        return dims if self.network == "positions" else f"{dims}\n{SHORT_NAMES[self.network]}"


@dataclass(frozen=True)
class Table1:
    """Everything the chapter shows: its numbers (:attr:`numbers`), its tables and sentences, its figure's data."""

    numbers: Numbers
    """What the chapter reports (the results file's ``table1.*``)."""
    config: TrainConfig
    """Table 1's configuration: the paper's network at its grid's best point."""
    velocity_config: TrainConfig
    """The network fed velocity at its own grid's best point, with the schedule validation chose
    (:attr:`schedule`)."""
    schedule: ScheduleChoice
    """The velocity network's learning-rate schedule, chosen on validation."""
    seeds: dict[Network, Seeds]
    """Table 1's runs for each network (the figure draws every one): both inputs on every data set for the paper's
    network and the velocity network; X, Y, Z only for the speed network (every data set) and the rotated one (data
    set 1)."""
    picked: dict[tuple[Network, Dims], tuple[int, ...]]
    """The seed validation picks on each data set, per row."""
    grid_table: Table
    """Every grid point of every cell, scored over seeds."""
    protocol_table: Table
    """What each change to the training protocol did."""
    table1: Table
    """Table 1 beside the paper's."""
    spread_table: Table
    """Every seed, their t-interval, the mean over data sets, the variance between them."""
    ablation_table: Table
    """The ablation."""
    baseline_table: Table
    """The physics baseline against the network."""
    n_params: int
    """Weights of the network with X, Y, Z."""
    length_s: float
    """Input length, seconds."""
    length_frames: int
    """Input length, frames."""
    n_train: int
    """Training trajectories."""
    n_test: int
    """Test trajectories."""
    min_epochs: int
    patience: int
    plateau_epochs: int
    """Epochs a run may take to leave the initial plateau."""
    ema_decay: float
    """Decay per step of the weights' average every run keeps."""
    epochs: int
    n_grid_seeds: int
    n_seeds: int
    """Table 1's seeds on the first data set."""
    n_data: int
    """Data sets Table 1 is trained on."""
    first_patience: int
    first_epochs: int
    grid_runs: int
    """Runs of every grid."""
    n_protocol_runs: int
    """Runs of the first protocol (both inputs)."""
    stalls_first: int
    """Runs that stalled with the first protocol."""
    stalls_study: int
    """Runs that stalled with the study's protocol."""
    lstm_lrs: str
    gru_lrs: str
    clip_gain: str
    """What clipping changed, in points, per input."""
    average_gain: str
    """What averaging the weights (the study's protocol) changed on top of clipping, in points, per input."""
    last_gain: str
    """What halving the learning rate on plateaus changed on top."""
    last_kept: bool
    """Whether that last change helped both inputs by more than half a point."""
    clip_helps: bool
    """Whether clipping helped both inputs by more than half a point."""
    defaults_moved: dict[str, tuple[float, float]]
    """Grid fields in which Table 1's config differs from TrainConfig's defaults: (default, chosen)."""
    abl_diffs: dict[Cell, Interval]
    """The peephole LSTM minus each other cell."""
    base_beats: dict[Dims, Interval]
    """The network minus the physics baseline."""
    vel_xyz_accuracies: tuple[float, ...]
    """The velocity network's seeds on X, Y, Z (data set 1)."""
    vel_failed_xyz: int
    """Of those, runs that failed to train."""
    shares: tuple[str, ...]
    """Each row's variance between data sets, as shown."""
    speed_xyz_accuracies: tuple[float, ...]
    """The speed network's seeds on X, Y, Z (data set 1)."""
    heading_table: Table
    """What turning a throw about the vertical does to each X, Y, Z network."""
    schedule_table: Table
    """The velocity network's schedules on validation."""
    unsettled: dict[tuple[Network, Dims], tuple[bool, ...]] = dataclasses.field(default_factory=dict)
    """Per row with a validation-pick estimate: whether each data set's pick had not flattened at its epoch cap."""

    @property
    def figure(self) -> tuple[FigureRow, ...]:
        """The figure's columns: the paper's network on X, Y, Z and Z (Table 1), then, beyond the paper, the
        velocity network's two rows, the speed network's X, Y, Z and the rotated network's X, Y, Z."""
        cols = [(k, d) for k in ("positions", "velocity") for d in ORDER] + [("speed", "xyz"), ("rotated", "xyz")]
        out = []
        for k, d in cols:
            row = self.row(k, d)  # type: ignore[arg-type]
            estimate = row.paper_way if row else self.numbers.rotated.mean
            p = paper.TABLE1[d] if k == "positions" else None
            out.append(FigureRow(k, d, tuple(self.seeds[k].per_data(d)), self.picked[k, d],  # type: ignore[index]
                                 estimate, p,
                                 None if p is None else verdicts.margin(p)))
        return tuple(out)

    @property
    def headline_table(self) -> Table:
        """Table 1 against the paper's, short: each column of :attr:`figure`, our estimate and the verdict."""
        rows = [{"row": f"{paper.DIMS_NAMES[c.dims]}, {SHORT_NAMES[c.network]}",
                 "paper": "—" if c.paper is None else pct(c.paper, 0),
                 "ours": pct_ci(c.estimate.interval) + (" (seeds' mean, data set 1)" if c.network == "rotated" else ""),
                 "verdict": f"**{c.estimate.verdict}**" if c.estimate.verdict else "beyond the paper"}
                for c in self.figure]
        return Table(rows, {"row": "input, network", "paper": "paper", "ours": "ours [95 % CI]", "verdict": "verdict"})

    @property
    def paper_xyz(self) -> str:
        """The paper's Table 1, X, Y, Z."""
        return pct(paper.TABLE1["xyz"], 0)

    @property
    def paper_z(self) -> str:
        """The paper's Table 1, Z only."""
        return pct(paper.TABLE1["z"], 0)

    @property
    def failed_runs(self) -> str:
        """How many of Table 1's runs failed to train, and where; the grid's and the protocols' too."""
        where = [(c, sum(r.n_failed for r in c.runs), sum(len(r) for r in c.runs)) for c in self.figure]
        bad = [f"{paper.DIMS_NAMES[c.dims]}, {SHORT_NAMES[c.network]}: {k} of {m}" for c, k, m in where if k]
        n, total = sum(m for *_, m in where), sum(k for _, k, _ in where)
        head = (f"None of Table 1's {n} runs failed to train" if not total else
                f"Of Table 1's {n} runs, {total} failed to train ({'; '.join(bad)}), drawn as crosses and counted "
                "in the means")
        return (f"{head}; of the {self.grid_runs} grid runs, {self.grid_failed}. The study's training protocol "
                f"stalled {self.stalls_study} of {self.n_protocol_runs} validation runs, the first "
                f"{self.stalls_first} (below).")

    @property
    def unsettled_picks(self) -> str:
        """Which of the runs validation picks had not flattened when their epoch budget ran out, by row and data set;
        or that none had."""
        late = []
        for c in self.figure:
            flags = self.unsettled.get((c.network, c.dims), ())
            late += [(c, i, runs.where(seed=seed)[0])
                     for i, (runs, seed, u) in enumerate(zip(c.runs, c.picked, flags), 1) if u]
        n = sum(len(v) for v in self.unsettled.values())
        if not late:
            return f"Each of the {n} runs validation picks had flattened before it stopped."
        which = "; ".join(f"{paper.DIMS_NAMES[c.dims]}, {SHORT_NAMES[c.network]}, data set {i}: "
                          f"{100 * r.accuracy:.1f} %"  # type: ignore[operator]
                          for c, i, r in late)
        rows = len({(c.network, c.dims) for c, _, _ in late})
        one = len(late) == 1
        return (f"Of the {n} runs validation picks, {len(late)} had not flattened when {'its' if one else 'their'} "
                f"{self.epochs} epochs ran out, {'its' if one else 'their'} validation accuracy still climbing or "
                f"swinging ({which}; marked \"not settled\" in the table below), so the estimate of "
                f"{'that row' if rows == 1 else 'those rows'} leans on {'a network' if one else 'networks'} more "
                "epochs could still move.")

    def row(self, network: Network, dims: Dims) -> Row | None:
        """The reported row of ``network`` on ``dims`` (None where the chapter has none: the rotated network's, and
        the speed network's Z, which is the velocity network's)."""
        n = self.numbers
        rows = {"positions": n.rows, "velocity": n.velocity.rows, "speed": n.speed.rows}.get(network, {})
        return rows.get(dims)  # type: ignore[attr-defined]

    # Sentences whose words depend on the numbers -------------------------------------------------

    @property
    def plateau_loss(self) -> str:
        return f"{PLATEAU_LOSS:.3f}"

    @property
    def best_lr(self) -> float:
        return self.config.lr

    @property
    def best_trunc(self) -> int:
        return self.config.truncation

    @property
    def grid_failed(self) -> int:
        return int(self.numbers.grid.failed_runs.value)

    @property
    def vel_point(self) -> str:
        return f"learning rate {self.velocity_config.lr:g}, truncation after {self.velocity_config.truncation} frames"

    @property
    def vel_same(self) -> str:
        same = (self.velocity_config.lr, self.velocity_config.truncation) == (self.config.lr, self.config.truncation)
        return "the same point as Table 1's" if same else "not Table 1's point: validation preferred another"

    @property
    def defaults_note(self) -> str:
        if not self.defaults_moved:
            return ("Table 1's configuration is the study's protocol, TrainConfig's defaults, so study train with its "
                    "defaults trains it.")
        return ("Table 1's configuration differs from TrainConfig's defaults (the study's protocol, what study train "
                "uses unless told otherwise) in " + ", ".join(f"{f} ({a} there, {b} here)" for f, (a, b) in self.defaults_moved.items())
                + ".")

    @property
    def clip_why(self) -> str:
        if self.clip_helps:
            return ("The paper names exploding gradients among the network's troubles: a gradient spike that Adam's "
                    "second-moment estimate remembers for hundreds of steps slows every later step, and clipping "
                    "prevents the spike.")
        return ("At this point of the grid clipping does not help both inputs by more than half a point; the study "
                "keeps it because it costs nothing and guards against the exploding gradients the paper names.")

    @property
    def last_verdict(self) -> str:
        return ("so the study does not keep it" if not self.last_kept else
                "an improvement on validation data that the study's protocol does not include yet")

    @property
    def overall(self) -> str:
        return self.numbers.verdict.verdict

    @property
    def claim_text(self) -> str:
        return {
            "reproduced": "as in the paper, X, Y, Z does better than Z alone: the interval of the difference lies "
                          "above 0",
            "differs": "unlike the paper, X, Y, Z does not do better than Z alone: the interval of the difference "
                       "lies below 0, or within the margin of no difference",
            "inconclusive": "the data cannot say whether X, Y, Z does better than Z alone: the interval of the "
                            "difference straddles 0 (or the margin of no difference)",
        }[self.numbers.xyz_minus_z.verdict or "inconclusive"]

    @property
    def delta_pts(self) -> str:
        return f"{100 * verdicts.MARGIN.delta:g}"

    @property
    def margin_xyz(self) -> str:
        return f"{100 * verdicts.margin(paper.TABLE1['xyz']):.1f}"

    @property
    def vel_order(self) -> str:
        d = self.numbers.velocity.xyz_minus_z
        return "trails" if d.hi < 0 else "beats" if d.lo > 0 else "cannot be told apart from"

    @property
    def vel_xyz_range(self) -> str:
        a = [100 * x for x in self.vel_xyz_accuracies]
        return f"{min(a):.1f} and {max(a):.1f} %"

    @property
    def speed_xyz_range(self) -> str:
        a = [100 * x for x in self.speed_xyz_accuracies]
        return f"{min(a):.1f} and {max(a):.1f} %"

    @property
    def vel_runs_note(self) -> str:
        if self.vel_failed_xyz == 0:
            return ("none of them failed to train, so the gap is not runs stuck at chance but a solution the layer "
                    "settles on when it also reads the horizontal channels")
        return f"{self.vel_failed_xyz} of them failed to train (counted in the mean, not removed)"

    @property
    def speed_order(self) -> str:
        d = self.numbers.speed.xyz_minus_z
        return "trails" if d.hi < 0 else "beats" if d.lo > 0 else "cannot be told apart from"

    @property
    def rot_order(self) -> str:
        d = self.numbers.rotated.gain
        return ("gains" if d.lo > 0 else "loses" if d.hi < 0 else
                "neither gains nor loses measurably (the interval spans 0)")

    @property
    def rot_z_order(self) -> str:
        d = self.numbers.rotated.xyz_minus_z
        return "above" if d.lo > 0 else "below" if d.hi < 0 else "not distinguishable from"

    @property
    def schedule_used(self) -> str:
        if self.schedule.chosen == "constant":
            return ("validation prefers the constant rate, so the velocity rows keep it (the study's protocol)")
        return (f"validation prefers halving the rate on plateaus, so every velocity row below (and the speed "
                f"network's) trains with it ({self.schedule.chosen!r}); the positions rows keep the study's "
                "protocol, as the protocols' comparison above chose")

    @property
    def schedule_steadies(self) -> str:
        sw = self.numbers.velocity.schedule
        return ("halving the rate on plateaus steadies it" if sw["plateau"].swing.value < sw["constant"].swing.value
                else "halving the rate on plateaus does not steady it")

    @property
    def share_range(self) -> str:
        lo, hi = min(self.shares), max(self.shares)
        return f"{lo} to {hi}" if lo != hi else self.shares[0]

    @property
    def abl_verdict(self) -> str:
        def says(c: Cell, dv: Interval) -> str:
            if dv.lo > 0:
                return f"ahead of the {CELL_NAMES[c]} by {100 * dv.value:.1f} points"
            if dv.hi < 0:
                return f"behind the {CELL_NAMES[c]} by {100 * -dv.value:.1f} points"
            return f"not distinguishable from the {CELL_NAMES[c]} ({100 * dv.value:+.1f} points, interval across 0)"

        return "; ".join(says(c, dv) for c, dv in self.abl_diffs.items())

    @property
    def base_verdict(self) -> str:
        ahead = [paper.DIMS_NAMES[d] for d, b in self.base_beats.items() if b.lo > 0]
        behind = [paper.DIMS_NAMES[d] for d, b in self.base_beats.items() if b.hi < 0]
        if len(ahead) == 2:
            return "the LSTM beats physics with both inputs"
        if len(behind) == 2:
            return "physics beats the LSTM with both inputs"
        if not ahead and not behind:
            return "the LSTM and physics cannot be told apart with either input"
        return (f"the LSTM is ahead with {', '.join(ahead) or 'neither input'} and behind with "
                f"{', '.join(behind) or 'neither'}; elsewhere the two cannot be told apart")


# ---------------------------------------------------------------------------------------------
# Each part of the result


def protocol_runs(runner: Runner, cfg: TrainConfig) -> Runs:
    """Every protocol of ``study.learn.protocols.PROTOCOLS`` at ``cfg``, for Z and X, Y, Z, validation only: one run
    per (protocol, dims, seed), labelled ``protocol`` with its key."""
    plan = paper.protocol_plan(cfg, runner.preset)
    rows = runner.rows([c for _, c in plan], test=False, desc="protocols")
    return rows.labelled({"protocol": q.key} for q, _ in plan)


def ablation_runs(runner: Runner, winners: dict[Cell, TrainConfig]) -> Runs:
    """Each cell at its own grid winner on Z with the test seeds: one run per (cell, seed)."""
    return runner.rows(paper.ablation_configs(winners, runner.preset), desc="ablation")


def baseline_runs(runner: Runner) -> dict[Dims, Fitted]:
    """The physics baseline for Z and X, Y, Z at the preset's length, fitted once each (it has no seed)."""
    test, out = runner.dataset.test, {}
    for d in paper.BOTH:
        m = baseline.fit(runner.dataset, d, runner.preset.length)
        s = learners.Scores({"test": stats.probabilities([m], test.x)}, {"test": np.asarray(test.y)})
        res = train.metrics(test.y, (s.p_heavy["test"][0] > 0.5).astype(np.int64))
        out[d] = Fitted(d, res["accuracy"], s.correct["test"][0], res["per_class_accuracy"], m.coefficients)
    return out


def _grid_table(g: GridSearch, p: object) -> tuple[Table, int, int]:
    chosen = {(c, "positions"): w for c, w in g.winners.items()} | {("peephole", "velocity"): g.velocity_config}
    labelled = [(cell, "positions", g.grids[cell]) for cell in g.grids] + [("peephole", "velocity", g.velocity)]
    rows = [{"cell": CELL_NAMES[cell] + (", with velocity" if inputs == "velocity" else ""),
             "lr": pt.config.lr, "truncation": pt.config.truncation,
             "val": pct_pm(pt.val_mean, pt.val_std), "runs": f"{pt.n - pt.failed} of {pt.n}",
             "epochs_mean": pt.epochs_mean, "winner": "✓" if pt.same_point(chosen[cell, inputs]) else ""}
            for cell, inputs, runs in labelled for pt in paper.grid_points(runs)]
    table = Table(rows, {"cell": "cell", "lr": "learning rate", "truncation": "truncation (frames)",
                         "val": "validation accuracy, mean ± std", "runs": "seeds that trained",
                         "epochs_mean": "epochs (mean)", "winner": "chosen"}, {"lr": "g", "epochs_mean": ".0f"})
    return table, sum(r.n_failed for _, _, r in labelled), sum(len(r) for _, _, r in labelled)


def _protocols(protocols: Runs) -> tuple[dict[ProtocolKey, dict[Dims, ProtocolRow]], Table, dict[str, object]]:
    val = {(s.keys["protocol"], s.keys["dims"]): s for s in stats.summarise(protocols, ("protocol", "dims"), "val_accuracy")}
    epochs = {(s.keys["protocol"], s.keys["dims"]): s.mean for s in stats.summarise(protocols, ("protocol", "dims"), "epochs_run")}
    both: tuple[Dims, Dims] = ("xyz", "z")
    rows = [{"protocol": q.words, **{
        d: f"{pct_pm(val[q.key, d].mean, val[q.key, d].std)}; {val[q.key, d].failed} of {val[q.key, d].n} stalled; "
           f"{epochs[q.key, d]:.0f} epochs" for d in both}} for q in PROTOCOLS]
    table = Table(rows, {"protocol": "protocol (each row adds one change)",
                         "xyz": "X, Y, Z: validation accuracy; stalls; epochs", "z": "Z only: the same"})
    numbers = {q.key: {d: ProtocolRow(number(val[q.key, d].mean, f"validation accuracy, {q.words}, {paper.DIMS_NAMES[d]}"),
                                      count(val[q.key, d].failed, f"stalled seeds, {q.words}"))
                       for d in both} for q in PROTOCOLS}
    first = PROTOCOLS[0].key

    def gain(key: ProtocolKey) -> dict[Dims, float]:  # what the protocol of ``key`` added to the one before it
        before = PROTOCOLS[[q.key for q in PROTOCOLS].index(key) - 1].key
        return {d: val[key, d].mean - val[before, d].mean for d in both}

    step, averaged, last = gain("clipping"), gain("average"), gain("plateau")
    facts = {
        "stalls_first": sum(val[first, d].failed for d in both),
        "stalls_study": sum(val[STUDY.key, d].failed for d in both),
        "n_protocol_runs": sum(val[first, d].n for d in both),
        "clip_gain": " and ".join(f"{100 * step[d]:+.1f} points ({paper.DIMS_NAMES[d]})" for d in both),
        "average_gain": " and ".join(f"{100 * averaged[d]:+.1f} points ({paper.DIMS_NAMES[d]})" for d in both),
        "last_gain": " and ".join(f"{100 * last[d]:+.1f} points ({paper.DIMS_NAMES[d]})" for d in both),
        "last_kept": min(last.values()) > 0.005, "clip_helps": min(step.values()) > 0.005,
    }
    return numbers, table, facts


def _unsettled(runner: Runner, picked: tuple[Run, ...]) -> tuple[bool, ...]:
    """Whether each run of ``picked`` (data set i's pick, in the preset's order of data sets) had not flattened when
    its epoch budget ran out, by the rule the builder counts such runs by (``study.runs.failures.unsettled``), read
    from its record."""
    seeds = runner.preset.data_seeds
    on = [runner] + [runner.with_data_seed(s) for s in seeds[1:len(picked)]]
    return tuple(failures.unsettled(r.runs([run.config], desc="Table 1")[0]) for r, run in zip(on, picked))


def _row(runner: Runner, inputs: Inputs, cfg: TrainConfig, s: Seeds, d: Dims
         ) -> tuple[Row, dict, dict, tuple[int, ...], tuple[bool, ...]]:
    p, ds = runner.preset, runner.dataset
    first = s.first.where(dims=d)
    per_data = s.per_data(d)
    pick = stats.validation_pick(per_data)
    unsettled = _unsettled(runner, pick.picked)
    summ = stats.summary(first)
    t = t_interval(first.accuracies())
    balanced = [np.stack([r.correct for r in g if r.seed in p.grid_seeds]) for g in per_data]
    across = hierarchical_bootstrap(balanced)
    share = between_share(balanced)
    src = dict(config=dataclasses.asdict(cfg), data_seeds=list(p.data_seeds), data_key=ds.key)
    where = f"{paper.DIMS_NAMES[d]}, {INPUT_NAMES[inputs]}"
    paper_way = number(pick.interval, f"the run validation picks, mean over {len(pick.picked)} data sets, {where}",
                       paper=paper.TABLE1[d] if inputs == "positions" else None,
                       seeds=[r.seed for r in pick.picked], **src)
    row = Row(
        paper_way,
        number(summ.interval, f"mean test accuracy over {summ.n} seeds, {where}", seeds=list(p.seeds),
               per_seed=[r.accuracy for r in first], **src),
        number(t, f"the same mean, t-interval over its {summ.n} seeds"),
        number(across, f"mean over {len(per_data)} data sets x {len(p.grid_seeds)} seeds, {where}", **src),
        number(share["share"], f"share of a run's variance between data sets ({share['method']})"),
        number(summ.std, "sample standard deviation over seeds"),
        count(summ.failed + sum(g.n_failed for g in per_data[1:]), "runs that failed to train, every data set"),
        number(float(np.ptp(first.accuracies())), f"max minus min test accuracy over {summ.n} seeds, {where}"),
        count(sum(unsettled), f"runs validation picks, one per data set, not flattened at their epoch cap, {where}"),
    )
    table = {"inputs": INPUT_NAMES[inputs], "dims": paper.DIMS_NAMES[d],
             "paper": pct(paper.TABLE1[d], 0) if inputs == "positions" else "—",
             "paper_way": pct_ci(pick.interval),
             "picked": ", ".join(f"{100 * r.accuracy:.1f}" + (" (not settled)" if u else "")  # type: ignore[operator]
                                 for r, u in zip(pick.picked, unsettled)),
             "mean": pct_ci(summ.interval),
             "verdict": f"**{paper_way.verdict}**" if paper_way.verdict else "(beyond the paper)"}
    spread = {"inputs": INPUT_NAMES[inputs], "dims": paper.DIMS_NAMES[d],
              "seeds": ", ".join(f"{100 * r.accuracy:.1f}" for r in first),  # type: ignore[operator]
              "t": pct_ci(t), "across": pct_ci(across), "share": f"{100 * share['share']:.0f} %",
              "runs": runs_note(summ) or "all trained"}
    return row, table, spread, tuple(r.seed for r in pick.picked), unsettled


def _ablation(runner: Runner, winners: dict[Cell, TrainConfig]) -> tuple[Ablation, Table, dict[Cell, Interval]]:
    abl = ablation_runs(runner, winners)
    cells = runner.preset.cells
    correct = {c: abl.where(cell=c).correct() for c in cells}
    summ = {c: stats.summary(abl.where(cell=c)) for c in cells}
    rows = [{"cell": CELL_NAMES[c], "point": f"lr {winners[c].lr:g}, truncation {winners[c].truncation}",
             "mean": seeds_ci(correct[c]), "std": f"{100 * summ[c].std:.1f}",
             "runs": runs_note(summ[c]) or "all trained"} for c in cells]
    table = Table(rows, {"cell": "cell (Z only)", "point": "its grid point",
                         "mean": "test accuracy, mean [95 % CI]; t-interval over seeds; each seed (%)",
                         "std": "seed std (points)", "runs": "runs"})
    diffs = {c: bootstrap_difference(correct["peephole"], correct[c]) for c in cells if c != "peephole"}
    numbers = Ablation(
        {c: AblationCell(number(summ[c].interval, f"mean test accuracy, {CELL_NAMES[c]}, Z",
                                config=dataclasses.asdict(winners[c]))) for c in cells},
        {c: number(dv, f"peephole LSTM minus {CELL_NAMES[c]}", signed=True) for c, dv in diffs.items()})
    return numbers, table, diffs


def _baseline(base: dict[Dims, Fitted], positions: Runs) -> tuple[dict[Dims, Number], dict[Dims, Number], Table,
                                                                  dict[Dims, Interval]]:
    accs, minus, rows, beats = {}, {}, [], {}
    for d in ("xyz", "z"):
        b_iv = bootstrap_accuracy(base[d].correct)
        accs[d] = number(b_iv, f"physics baseline's test accuracy, {paper.DIMS_NAMES[d]}")
        lstm = positions.where(dims=d)
        beats[d] = bootstrap_difference(lstm.correct(), base[d].correct)
        minus[d] = number(beats[d], f"peephole LSTM (mean) minus the baseline, {paper.DIMS_NAMES[d]}", signed=True)
        rows.append({"dims": paper.DIMS_NAMES[d], "physics": pct_ci(b_iv), "lstm": pct_ci(stats.summary(lstm).interval),
                     "diff": points(beats[d]).replace(" points", ""),
                     "coef": ", ".join(f"{k} {v:+.2f}" for k, v in base[d].coefficients.items())})
    table = Table(rows, {"dims": "trajectory dimension(s)", "physics": "physics baseline [95 % CI]",
                         "lstm": "peephole LSTM, mean [95 % CI]", "diff": "LSTM minus baseline (points)",
                         "coef": "baseline weights (standardised features; + means heavy)"})
    return accs, minus, table, beats


def _schedule(choice: ScheduleChoice) -> tuple[dict[Schedule, ScheduleRow], Table]:
    numbers, rows = {}, []
    for k in paper.SCHEDULES:
        runs = choice.runs.where(lr_schedule=k)
        val, sw = runs.val_accuracies(), choice.swings[k]
        numbers[k] = ScheduleRow(number(float(val.mean()), f"velocity network, Z, {k} learning rate: mean validation "
                                        "accuracy over the grid's seeds", seeds=[r.seed for r in runs]),
                                 number(float(sw.mean()), f"velocity network, Z, {k} learning rate: mean absolute "
                                        "epoch-to-epoch change of the validation loss, second half of the epochs",
                                        unit="nats", per_seed=sw.tolist()))
        rows.append({"schedule": SCHEDULE_NAMES[k], "val": pct_pm(float(val.mean()), float(val.std(ddof=1)) if len(val) > 1 else 0.0),
                     "swing": ", ".join(f"{x:.3f}" for x in sw), "epochs": float(np.mean(runs.values("epochs_run"))),
                     "chosen": "✓" if k == choice.chosen else ""})
    table = Table(rows, {"schedule": "learning rate", "val": "validation accuracy, mean ± std",
                         "swing": "swing of the validation loss, each seed (nats)", "epochs": "epochs (mean)",
                         "chosen": "chosen"}, {"epochs": ".0f"})
    return numbers, table


def _rotated(rot: Runs, positions: Runs) -> tuple[Rotated, dict, dict]:
    summ = stats.summary(rot)
    gain = bootstrap_difference(rot.correct(), positions.where(dims="xyz").correct())
    minus_z = bootstrap_difference(rot.correct(), positions.where(dims="z").correct())
    where = "X, Y, Z, positions, training throws turned about the vertical"
    numbers = Rotated(
        number(summ.interval, f"mean test accuracy over {summ.n} seeds, {where}", per_seed=[r.accuracy for r in rot],
               config=dataclasses.asdict(rot[0].config)),
        number(gain, "turned training throws minus the paper's network, X, Y, Z, mean over seeds", signed=True),
        number(minus_z, "turned training throws (X, Y, Z) minus the paper's network on Z only", signed=True),
        count(summ.failed, "runs that failed to train"))
    name = NETWORK_NAMES["rotated"]
    table = {"inputs": name, "dims": paper.DIMS_NAMES["xyz"], "paper": "—", "paper_way": "— (data set 1 only)",
             "picked": "—", "mean": pct_ci(summ.interval), "verdict": "(beyond the paper)"}
    spread = {"inputs": name, "dims": paper.DIMS_NAMES["xyz"],
              "seeds": ", ".join(f"{100 * r.accuracy:.1f}" for r in rot),  # type: ignore[operator]
              "t": pct_ci(t_interval(rot.accuracies())), "across": "— (data set 1 only)", "share": "—",
              "runs": runs_note(summ) or "all trained"}
    return numbers, table, spread


def _heading(flips: dict[Network, np.ndarray], seeds: dict[Network, Seeds]) -> tuple[dict[Network, Number], Table]:
    numbers, rows = {}, []
    for k, changed in flips.items():
        iv = bootstrap_accuracy(changed)
        numbers[k] = number(iv, f"share of test answers that change when the throw is turned about the vertical, "
                                f"{NETWORK_NAMES[k]}, X, Y, Z", per_seed=changed.mean(axis=1).tolist())
        rows.append({"network": NETWORK_NAMES[k], "flips": pct_ci(iv),
                     "mean": pct_ci(stats.summary(seeds[k].first.where(dims="xyz")).interval)})
    return numbers, Table(rows, {"network": "X, Y, Z network", "flips": "answers changed by turning the throw [95 % CI]",
                                 "mean": "its test accuracy, mean of seeds [95 % CI]"})


def compute(runner: Runner) -> Table1:
    """The chapter *Table 1* on ``runner``'s preset and data set: every run of it, cached."""
    from study.learn.model import Classifier  # torch: the network's size

    p, ds = runner.preset, runner.dataset
    g = grid_search(runner)
    prefetch(runner, g)
    choice = schedule_choice(runner, g)
    velocity = choice.config
    prefetch_velocity(runner, velocity)
    grid_table, grid_failed, grid_runs = _grid_table(g, p)
    protocol_numbers, protocol_table, facts = _protocols(protocol_runs(runner, g.config))
    cfgs: dict[Network, TrainConfig] = {"positions": g.config, "velocity": velocity, "speed": speed_config(velocity),
                                        "rotated": rotated_config(g.config)}
    seeds: dict[Network, Seeds] = {"positions": seed_runs(runner, g.config), "velocity": seed_runs(runner, velocity),
                                   "speed": seed_runs(runner, cfgs["speed"], ("xyz",)),
                                   "rotated": seed_runs(runner, cfgs["rotated"], ("xyz",), every_data=False)}
    rows: dict[Inputs, dict[Dims, Row]] = {"positions": {}, "velocity": {}, "speed": {}}
    table, spread, picked, unsettled = [], [], {}, {}
    for inputs, dims in (("positions", ORDER), ("velocity", ORDER), ("speed", ("xyz",))):
        for d in dims:
            rows[inputs][d], t_row, s_row, picked[inputs, d], unsettled[inputs, d] = _row(
                runner, inputs, cfgs[inputs], seeds[inputs], d)
            table.append(t_row)
            spread.append(s_row)
    first = {k: s.first for k, s in seeds.items()}
    diffs = {k: bootstrap_difference(first[k].where(dims="xyz").correct(), first[k].where(dims="z").correct())
             for k in ("positions", "velocity")}  # X, Y, Z minus Z, paired on the test throws, for each input
    diffs["speed"] = bootstrap_difference(first["speed"].correct(), first["velocity"].where(dims="z").correct())
    rotated_numbers, t_row, s_row = _rotated(first["rotated"], first["positions"])
    table.append(t_row)
    spread.append(s_row)
    picked["rotated", "xyz"] = tuple(r.seed for r in stats.validation_pick([first["rotated"]]).picked)
    flips, heading_table = _heading(heading_flips(runner, cfgs), seeds)
    schedule_numbers, schedule_table = _schedule(choice)
    positions = rows["positions"]
    overall = verdicts.combined([positions[d].paper_way.decision for d in ORDER])  # type: ignore[misc]
    ablation, ablation_table, abl_diffs = _ablation(runner, g.winners)
    base_acc, base_minus, baseline_table, beats = _baseline(baseline_runs(runner), seeds["positions"].first)
    numbers = Numbers(
        GridNumbers(count(grid_failed, "grid runs that failed to train (all cells)")), protocol_numbers, positions,
        Velocity(rows["velocity"], number(diffs["velocity"], "with velocity: X, Y, Z minus Z only, mean over seeds",
                                          signed=True), schedule_numbers),
        Verdict(overall, "Table 1, both inputs: the paper's best against the run validation picks"),
        number(diffs["positions"], "X, Y, Z minus Z only, mean over seeds", decision=verdicts.order(diffs["positions"], +1),
               signed=True),
        Speed(rows["speed"], number(diffs["speed"], "height, its velocity and the horizontal speed from X, Y, Z minus "
                                    "the velocity network on Z only, mean over seeds", signed=True)),
        rotated_numbers, flips, ablation, base_acc, base_minus)
    vel_xyz = first["velocity"].where(dims="xyz")
    return Table1(
        numbers, g.config, velocity, choice, seeds, picked, grid_table, protocol_table,
        Table(table, {"inputs": "the network reads", "dims": "trajectory dimension(s)", "paper": "paper, best",
                      "paper_way": "ours, the run validation picks [95 % CI]", "picked": "that run, per data set (%)",
                      "mean": f"ours, mean of {len(p.seeds)} seeds, data set 1 [95 % CI]", "verdict": "verdict"}),
        Table(spread, {"inputs": "the network reads", "dims": "input", "seeds": "each seed, data set 1 (%)",
                       "t": "their mean, t-interval", "across": f"{len(p.data_seeds)} data sets x {len(p.grid_seeds)} "
                       "seeds [hierarchical 95 % CI]", "share": "variance between data sets", "runs": "runs"}),
        ablation_table, baseline_table,
        n_params=sum(t.numel() for t in Classifier(3).parameters()), length_s=p.length,
        length_frames=round(p.length * ds.fps), n_train=len(ds.train), n_test=len(ds.test), min_epochs=p.min_epochs,
        patience=p.patience, plateau_epochs=p.plateau_epochs, epochs=p.epochs, ema_decay=p.ema_decay, n_grid_seeds=len(p.grid_seeds), n_seeds=len(p.seeds),
        n_data=len(p.data_seeds), first_patience=p.first_patience, first_epochs=p.first_epochs,
        grid_runs=grid_runs, lstm_lrs=", ".join(f"{x:g}" for x in p.grid_lrs("peephole")),
        gru_lrs=", ".join(f"{x:g}" for x in p.grid_lrs("gru")), defaults_moved=paper.differs_from_defaults(g.config, p),
        abl_diffs=abl_diffs, base_beats=beats, vel_xyz_accuracies=tuple(vel_xyz.accuracies().tolist()),
        vel_failed_xyz=vel_xyz.n_failed, shares=tuple(r["share"] for r in spread if r["share"] != "—"),
        speed_xyz_accuracies=tuple(first["speed"].accuracies().tolist()), heading_table=heading_table,
        schedule_table=schedule_table, unsettled=unsettled, **facts)  # type: ignore[arg-type]
