"""What Table 1's chapter reports, typed: the names its numbers are glued and stored under (``table1.…``), read back
by the summary without running the chapter (``study.chapters.table1`` computes them)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from study.learn.config import Cell, Dims, Schedule
from study.learn.protocols import ProtocolKey  # the protocols are defined once, there
from study.report.reported import Number, Reported, Verdict, named

Network = Literal["positions", "velocity", "speed", "rotated"]
"""Table 1's networks: the paper's on positions; fed velocity; fed what does not turn with the heading ('speed'); the
paper's on positions, trained on throws turned about the vertical."""


ORDER: tuple[Dims, ...] = ("xyz", "z")
"""Table 1's rows, in the paper's order."""


@dataclass(frozen=True)
class Row(Reported):
    """One row of Table 1: one input (X, Y, Z or Z) of one network (positions or velocity)."""

    paper_way: Number
    """The run validation picks on each data set, mean over data sets (hierarchical bootstrap); with the paper's
    number and its verdict on the positions row."""
    mean: Number
    """Mean test accuracy of the first data set's seeds (bootstrap over test throws and seeds)."""
    mean_t: Number
    """The same mean with a t-interval over its seeds."""
    across_data: Number
    """Mean over every data set and the grid's seeds (hierarchical bootstrap)."""
    between_share: Number
    """Share of a run's variance that lies between data sets."""
    std: Number
    """Sample standard deviation of the first data set's seeds."""
    failed: Number
    """Runs that failed to train, every data set."""
    spread: Number | None = None
    """Max minus min test accuracy over the first data set's seeds: how far one seed's number can land from
    another's (the study's bar: 2 points)."""
    unsettled_picks: Number | None = None
    """Of the runs validation picks (one per data set), those whose validation curve had not flattened when their
    epoch budget ran out (``study.runs.failures.unsettled``): :attr:`paper_way` leans on them (None: a results file
    from before they were counted)."""


@dataclass(frozen=True)
class ScheduleRow(Reported):
    """The velocity network at its grid point with one learning-rate schedule, on Z, the grid's seeds, validation."""

    val_mean: Number
    """Mean validation accuracy at the kept epoch over the seeds."""
    swing: Number
    """How far the validation loss moves from one epoch to the next: the mean absolute change over the second half
    of a run's epochs, nats, mean over the seeds."""


@dataclass(frozen=True)
class Velocity(Reported):
    """Table 1 for the paper's network fed its velocity (beyond the paper)."""

    rows: dict[Dims, Row] = named("")
    xyz_minus_z: Number = named("xyz_minus_z")
    """X, Y, Z minus Z, mean over seeds (paired bootstrap)."""
    schedule: dict[Schedule, ScheduleRow] = named("schedule")
    """Each learning-rate schedule at the velocity network's point; the rows use the one validation prefers."""


@dataclass(frozen=True)
class Speed(Reported):
    """The same network fed the height, its velocity and the horizontal speed (``inputs='speed'``): nothing that
    turns with the throw's heading. Its X, Y, Z row only: on Z alone its channels are the velocity network's."""

    rows: dict[Dims, Row] = named("")
    xyz_minus_z: Number = named("xyz_minus_z")
    """Its X, Y, Z minus the velocity network's Z, mean over seeds (paired bootstrap): the paper's claim when the
    heading cannot be memorised."""


@dataclass(frozen=True)
class Rotated(Reported):
    """The paper's network on X, Y, Z positions, its training throws turned about the vertical every epoch."""

    mean: Number
    """Mean test accuracy of Table 1's seeds, data set 1."""
    gain: Number
    """Minus the paper's network on X, Y, Z without the rotations, the same seeds (paired bootstrap)."""
    xyz_minus_z: Number
    """Minus the paper's network on Z, the same seeds (paired bootstrap)."""
    failed: Number
    """Runs that failed to train."""


@dataclass(frozen=True)
class ProtocolRow(Reported):
    """One training protocol on one input, on validation data."""

    val_mean: Number
    """Mean validation accuracy over the protocol seeds."""
    stalled: Number
    """Seeds that stalled (failed to train)."""


@dataclass(frozen=True)
class AblationCell(Reported):
    """One cell of the ablation, on Z, with Table 1's seeds."""

    mean: Number
    """Mean test accuracy."""


@dataclass(frozen=True)
class Ablation(Reported):
    """Do the peepholes matter?"""

    cells: dict[Cell, AblationCell] = named("")
    minus: dict[Cell, Number] = named("peephole_minus_{key}")
    """The peephole LSTM minus each other cell (paired bootstrap)."""


@dataclass(frozen=True)
class GridNumbers(Reported):
    """The grid search."""

    failed_runs: Number
    """Grid runs that failed to train, every cell."""


@dataclass(frozen=True)
class Numbers(Reported):
    """Every number the chapter *Table 1* reports."""

    CHAPTER = "table1"
    grid: GridNumbers
    protocol: dict[ProtocolKey, dict[Dims, ProtocolRow]]
    rows: dict[Dims, Row] = named("")
    velocity: Velocity = named("velocity")
    verdict: Verdict = named("verdict")
    """Table 1 over both inputs: the paper's best against the run validation picks."""
    xyz_minus_z: Number = named("xyz_minus_z")
    """X, Y, Z minus Z (positions), mean over seeds, with the verdict on the paper's claim that X, Y, Z is better."""
    speed: Speed = named("speed")
    rotated: Rotated = named("rotated")
    flips: dict[Network, Number] = named("flips")
    """Share of the test throws whose answer changes when the throw is turned about the vertical by a random angle,
    each X, Y, Z network, Table 1's seeds, data set 1."""
    ablation: Ablation = named("ablation")
    baseline: dict[Dims, Number] = named("baseline")
    """The physics baseline's test accuracy."""
    lstm_minus_baseline: dict[Dims, Number] = named("lstm_minus_baseline")
    """The paper's network (mean of seeds) minus the physics baseline."""
