"""The paper's own numbers, quoted in one place, and the configurations of its experiments, as pure functions of
a preset: which runs each one trains.

:class:`study.runs.runner.Runner` trains them; keeping the configurations here, free of any training,
lets a reader see every run of an experiment in a few lines:

1. :func:`grid_configs` -- the paper's grid search on Z for one cell, every point once per grid seed
   (validation only); :func:`grid_points` summarises each point over its seeds and :func:`best_config`
   picks the highest mean.
2. :func:`seed_configs` -- Table 1: a config for Z and X, Y, Z with the preset's test seeds.
3. :func:`protocol_changes` -- what each change of the training protocol did, on validation data.
4. :func:`ablation_configs` -- each cell at its own grid winner, the same test seeds; :func:`schedule_configs`
   -- a grid winner with each learning-rate schedule, and :func:`best_schedule` the one validation prefers.
5. :func:`length_configs` and :func:`long_memory_config` -- accuracy against input length (the paper's
   Figure 4), and the long inputs again with a memory that spans them (chrono initialisation, full BPTT).
"""

from __future__ import annotations

import dataclasses
import itertools
from dataclasses import dataclass
from typing import Any

import numpy as np

from study.learn.config import Cell, Dims, Inputs, Schedule, TrainConfig
from study.learn.protocols import PROTOCOLS, Protocol
from study.runs.presets import Preset
from study.runs.runtable import Runs

TABLE1: dict[Dims, float] = {"xyz": 0.81, "z": 0.78}
"""The paper's Table 1, its "best accuracy" with X, Y, Z and with Z alone: the paper's own numbers, quoted."""
REAL_WORLD: dict[str, float] = {"light": 0.93, "heavy": 1.00}
"""The paper's real-world test by class: a golf ball right in 93 % of its videos, a wooden cube in 100 %."""
REAL_OBJECTS: dict[str, str] = {"light": "golf ball", "heavy": "wooden cube"}
"""What the paper filmed for each class."""
REAL_VIDEOS = 20
"""Videos per object in the paper's real-world test."""
DIMS_NAMES: dict[Dims, str] = {"xyz": "X, Y, Z", "z": "Z only"}
"""Table 1's inputs in the paper's words."""

BOTH: tuple[Dims, Dims] = ("z", "xyz")
"""Table 1's two inputs, in the order the experiments train them."""
GRID_FIELDS = ("cell", "inputs", "lr", "truncation", "dropout", "batch_size")
"""The fields that name a grid point (with the cell and what it reads)."""


def grid_configs(p: Preset, cell: Cell = "peephole", inputs: Inputs = "positions") -> list[TrainConfig]:
    """Every point of the preset's grid for ``cell`` reading ``inputs``, once per grid seed."""
    base = dataclasses.replace(p.cell_config(cell), inputs=inputs)
    return [dataclasses.replace(base, lr=lr, truncation=k, dropout=d, batch_size=b, seed=s)
            for lr, k, d, b in itertools.product(p.grid_lrs(cell), p.truncations, p.dropouts, p.batch_sizes)
            for s in p.grid_seeds]


@dataclass(frozen=True)
class GridPoint:
    """One point of a grid, scored over its seeds on the validation split."""

    config: TrainConfig
    """The point (its first seed's config)."""
    n: int
    """Seeds trained at it."""
    val_mean: float
    """Mean validation accuracy over the seeds."""
    val_std: float
    """Their sample standard deviation (0 for one seed)."""
    val_loss_mean: float
    """Mean validation loss, nats (breaks ties)."""
    failed: int
    """Seeds that failed to train."""
    diverged: int
    """Seeds whose loss became non-finite."""
    epochs_mean: float
    """Mean epochs run."""

    def same_point(self, cfg: TrainConfig) -> bool:
        """Whether ``cfg`` is this point (the same :data:`GRID_FIELDS`)."""
        return all(getattr(self.config, f) == getattr(cfg, f) for f in GRID_FIELDS)


def grid_points(runs: Runs) -> list[GridPoint]:
    """The grid runs (one per point and seed) grouped by point, in the order of the grid's fields: the mean and
    sample std of the validation accuracy over the seeds, the mean validation loss, and how many of the seeds
    failed to train or diverged."""
    groups = runs.groups(*GRID_FIELDS)
    out = []
    for key in sorted(groups):
        g = groups[key]
        acc = g.val_accuracies()
        out.append(GridPoint(g[0].config, len(g), float(acc.mean()), float(acc.std(ddof=1)) if len(g) > 1 else 0.0,
                             float(np.mean(g.values("val_loss"))), g.n_failed,
                             sum(d is not None for d in g.values("diverged_epoch")), float(np.mean(g.values("epochs_run")))))
    return out


def best_config(runs: Runs, p: Preset) -> TrainConfig:
    """The grid point with the highest mean validation accuracy over its seeds (ties: lower mean
    validation loss, then grid order), as the config the later experiments start from."""
    best = min(grid_points(runs), key=lambda r: (-r.val_mean, r.val_loss_mean))
    return dataclasses.replace(p.base_config(), **{f: getattr(best.config, f) for f in GRID_FIELDS})


def differs_from_defaults(cfg: TrainConfig, p: Preset) -> dict[str, tuple[Any, Any]]:
    """The grid fields in which ``cfg`` differs from the preset's base config (TrainConfig's defaults, the
    study's protocol): ``{field: (default, cfg's)}``; empty when the grid chose the defaults."""
    base = p.base_config()
    return {f: (getattr(base, f), getattr(cfg, f)) for f in GRID_FIELDS if getattr(base, f) != getattr(cfg, f)}


def seed_configs(cfg: TrainConfig, seeds: tuple[int, ...], dims: tuple[Dims, ...] = BOTH, **changes: Any) -> list[TrainConfig]:
    """``cfg`` (with ``changes``) for each of ``dims`` and ``seeds``: one config per (dims, seed)."""
    return [dataclasses.replace(cfg, dims=d, seed=s, **changes) for d in dims for s in seeds]


def protocol_plan(cfg: TrainConfig, p: Preset) -> list[tuple[Protocol, TrainConfig]]:
    """Every protocol of ``study.learn.protocols.PROTOCOLS`` at ``cfg``, for Z and X, Y, Z with
    ``p.protocol_seeds``."""
    return [(q, c) for q in PROTOCOLS for c in seed_configs(cfg, p.protocol_seeds, **q.fields(p.first_patience,
                                                                                                p.first_epochs))]


def ablation_configs(winners: dict[Cell, TrainConfig], p: Preset) -> list[TrainConfig]:
    """Each cell of ``p.cells`` at its own grid winner, on ``p.ablation_dims``, with the test seeds."""
    return [dataclasses.replace(winners[c], cell=c, seed=s) for c in p.cells for s in p.seeds]


SCHEDULES: tuple[Schedule, ...] = ("constant", "plateau")
"""The learning-rate schedules Table 1's chapter compares on its grid's winner (``TrainConfig.lr_schedule``), the
study's protocol first; the fixed cosine budgets are compared by ``benchmarks/bench_recipe.py``."""


def schedule_configs(cfg: TrainConfig, p: Preset) -> list[TrainConfig]:
    """``cfg`` (a grid's winner) with each of :data:`SCHEDULES`, on the grid's dims and seeds, for validation only:
    the first schedule's runs are the grid's own at that point."""
    return [dataclasses.replace(cfg, dims=p.ablation_dims, seed=s, lr_schedule=k) for k in SCHEDULES
            for s in p.grid_seeds]


def best_schedule(runs: Runs) -> Schedule:
    """The schedule of ``runs`` (:func:`schedule_configs`) with the highest mean validation accuracy over its seeds,
    ties to the lower mean validation loss, then to the study's protocol: the grid's rule, one field further."""
    groups = runs.groups("lr_schedule")

    def score(k: Schedule) -> tuple[float, float, int]:
        g = groups[(k,)]
        return -float(g.val_accuracies().mean()), float(np.mean(g.values("val_loss"))), SCHEDULES.index(k)

    return min((k for k in SCHEDULES if (k,) in groups), key=score)


def length_configs(cfg: TrainConfig, p: Preset) -> list[TrainConfig]:
    """The length sweep: ``cfg`` for each (dims, length, seed)."""
    return [dataclasses.replace(cfg, dims=d, length=L, seed=s) for d in BOTH for L in p.lengths for s in p.length_seeds]


def long_memory_config(cfg: TrainConfig, fps: float) -> TrainConfig:
    """``cfg`` with a memory that spans its input: chrono-initialised forget gates and full
    back-propagation through time (the truncation covers every frame)."""
    return dataclasses.replace(cfg, forget_init="chrono", truncation=max(cfg.truncation, cfg.n_frames(fps)))


def long_memory_configs(cfg: TrainConfig, p: Preset, fps: float) -> list[TrainConfig]:
    """The length sweep at ``p.long_lengths`` with :func:`long_memory_config`, one per (dims, length, seed)."""
    return [long_memory_config(dataclasses.replace(cfg, dims=d, length=L, seed=s), fps)
            for d in BOTH for L in p.long_lengths for s in p.long_seeds]


def factorial_configs(cfg: TrainConfig, p: Preset, fps: float) -> list[tuple[str, str, TrainConfig]]:
    """The paper's explanation of Figure 4, one factor at a time: at the longest input, truncation (``cfg``'s
    frames, or the whole input) x the forget gates' start (``cfg``'s constant bias, or chrono), for Z and
    X, Y, Z with ``p.long_seeds``: ``(truncation, forget start, config)`` per run. Two cells are runs the
    length sweep and the long-memory test already have."""
    L = max(p.long_lengths)
    out = []
    for d in BOTH:
        for s in p.long_seeds:
            base = dataclasses.replace(cfg, dims=d, length=L, seed=s)
            whole = base.n_frames(fps)
            for trunc, k in ((f"{cfg.truncation} frames", cfg.truncation), ("the whole input", max(cfg.truncation, whole))):
                for forget in ("constant", "chrono"):
                    out.append((trunc, forget, dataclasses.replace(base, truncation=k, forget_init=forget)))
    return out
