"""How much of each experiment a preset runs: one :class:`Preset` per name of ``study.core.presets.NAMES``, with
the numbers of ``study.core.presets.SIZES``.

The training protocol itself is not here: it is ``study.learn.config.TrainConfig``'s defaults (Table 1's
configuration on the paper preset), which a preset only shortens (the smoke preset trains for three
epochs). What a preset sets is the size of every experiment: the grid, the seeds, the lengths, and the
sizes the cue, decision and real-world chapters use.
"""

from __future__ import annotations

from typing import Any

import dataclasses
from dataclasses import dataclass

from study.core import presets
from study.learn.config import Cell, Dims, TrainConfig

_PROTOCOL = TrainConfig()
"""The study's protocol: every preset's default for the fields below."""


@dataclass(frozen=True)
class Preset:
    """How much of each experiment to run."""

    name: str
    """Its name in ``study.core.presets.NAMES``."""
    lrs: tuple[float, ...]
    """Grid: Adam learning rates (of every cell not in ``cell_lrs``)."""
    truncations: tuple[int, ...]
    """Grid: truncated-BPTT lengths, frames."""
    grid_seeds: tuple[int, ...]
    """Seeds every grid point is trained with; a point is scored by its mean validation accuracy over them."""
    seeds: tuple[int, ...]
    """Test seeds of Table 1 and the ablation."""
    lengths: tuple[float, ...]
    """Input lengths of the length sweep, seconds."""
    length_seeds: tuple[int, ...]
    """Seeds per point of the length sweep."""
    data_seeds: tuple[int, ...] = (0,)
    """Data sets Table 1 is trained on (the first is every chapter's): the spread between data sets."""
    length: float = _PROTOCOL.length
    """Input length for Table 1, the grid and the ablation, seconds."""
    dropouts: tuple[float, ...] = (_PROTOCOL.dropout,)
    """Grid: dropout probabilities (0.2 = the paper's keep-probability 0.8)."""
    batch_sizes: tuple[int, ...] = (_PROTOCOL.batch_size,)
    """Grid: trajectories per step."""
    epochs: int = _PROTOCOL.epochs
    """Epoch cap of every run."""
    patience: int = _PROTOCOL.patience
    """Early-stopping patience of every run, epochs."""
    min_epochs: int = _PROTOCOL.min_epochs
    """Epochs before early stopping may end a run."""
    plateau_epochs: int = _PROTOCOL.plateau_epochs
    """Epochs a run may take to leave the initial plateau before it stops as failed."""
    ema_decay: float = _PROTOCOL.ema_decay
    """Decay per step of the weights' average every run keeps (a preset of a few steps needs a short one)."""
    cell_lrs: tuple[tuple[Cell, tuple[float, ...]], ...] = ()
    """Grid: the learning rates of the cells that have their own, as (cell, rates) pairs."""
    cell_epochs: tuple[tuple[Cell, int], ...] = ()
    """The epoch caps of the cells that have their own, as (cell, epochs) pairs (a cell still climbing at ``epochs``)."""
    cells: tuple[Cell, ...] = ("peephole", "no-peephole", "gru")
    """Cells compared in the ablation (``study.learn.config.Cell``), the paper's first."""
    ablation_dims: Dims = "z"
    """Input dims of the grid and the ablation (Z, as in the paper's search)."""
    long_lengths: tuple[float, ...] = ()
    """Lengths at which the long-memory variant runs (chrono initialisation, full BPTT), seconds."""
    long_seeds: tuple[int, ...] = (0,)
    """Seeds of the long-memory runs and of the 2 x 2 of truncation x forget-gate start at the longest input."""
    protocol_seeds: tuple[int, ...] = (0,)
    """Seeds of the training-protocol comparison (validation only)."""
    first_patience: int = 10
    """Early-stopping patience of the study's first protocol (the comparison's first row), epochs."""
    first_epochs: int = 60
    """Epoch cap of the study's first protocol."""
    shape_train: int = 250
    """Training throws per class and shape in the cue chapter's mixed-shape training set."""
    shape_test: int = 500
    """Test throws per class and shape in the cue chapter."""
    certify_per_class: int = 2500
    """Throws per class in the decision chapter's certification split, on which its thresholds are certified
    (simulated for it alone: a 1 % miss rate is then 25 heavy objects, not 4)."""
    videos_per_class: int = 20
    """Rendered videos per class in the real-world test (the paper filmed 20 + 20)."""
    real_clips: int | None = None
    """Most real clips the real-world test classifies (None: all there are)."""
    render_shadows: bool = True
    """Draw shadows in the rendered videos (slower)."""
    sweep_per_family: int = 20
    """Clips per camera family in the real-world chapter's camera sweep (``study.methods.sweep``; four
    families: 80 clips)."""
    sweep_frame_scale: float = 1.0
    """Factor on the camera sweep's frame sizes (below 1: smaller, faster frames, for tests)."""

    def base_config(self) -> TrainConfig:
        """The config every run starts from, before the grid values are set: the study's protocol, cut to
        this preset's epochs."""
        return dataclasses.replace(_PROTOCOL, dims=self.ablation_dims, length=self.length,
                                   epochs=self.epochs, patience=self.patience, min_epochs=self.min_epochs,
                                   plateau_epochs=self.plateau_epochs, ema_decay=self.ema_decay)

    def cell_config(self, cell: Cell) -> TrainConfig:
        """:meth:`base_config` for ``cell``, with its own epoch cap where it has one (``cell_epochs``)."""
        return dataclasses.replace(self.base_config(), cell=cell, epochs=dict(self.cell_epochs).get(cell, self.epochs))

    def grid_lrs(self, cell: Cell) -> tuple[float, ...]:
        """The learning rates of ``cell``'s grid."""
        return dict(self.cell_lrs).get(cell, self.lrs)

    def n_grid(self, cell: Cell = "peephole") -> int:
        """Number of points in ``cell``'s grid."""
        return len(self.grid_lrs(cell)) * len(self.truncations) * len(self.dropouts) * len(self.batch_sizes)


SWEEP_SIZES: dict[str, dict[str, Any]] = {"smoke": {"sweep_per_family": 1, "sweep_frame_scale": 0.5}}
"""The camera sweep's sizes where a preset differs from the paper's. Kept here, not with the other sizes in
``study.core.presets``: that module is in the key of every data set and render, and the sweep is neither."""

CELL_EPOCHS: dict[str, dict[str, Any]] = {"paper": {"cell_epochs": (("gru", 300),)}}
"""The cells with an epoch cap of their own, per preset: on the paper preset the GRU's best grid point was still
climbing 5-9 points over the last 30 of 150 epochs (the cold build at 16ca2b0). Kept here for the reason above."""

PRESETS: dict[str, Preset] = {name: Preset(name=name, **presets.sizes(name, "runs"), **SWEEP_SIZES.get(name, {}),
                                           **CELL_EPOCHS.get(name, {}))
                              for name in presets.NAMES}
"""Every preset's experiment sizes (their numbers are ``study.core.presets.SIZES``'s)."""


def preset(name: str) -> Preset:
    """The preset called ``name`` (``study.core.presets.NAMES``); :class:`ConfigError` for an unknown one."""
    return PRESETS[presets.check(name)]
