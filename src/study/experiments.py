"""The experiments behind Table 1, the ablation and the accuracy-versus-length figure, cached run by run.

Each trained run's result (metrics, test predictions and training history, not weights) is a JSON file
in ``data_dir/runs/``, named by :func:`study.cache.key` of the dataset key, the :class:`TrainConfig`,
whether the test split was scored, the training code (``study.learn.train.SOURCES``), the torch
version and the time loop that ran (compiled for this CPU, or PyTorch's); it is written atomically.
Re-building the book therefore never retrains a run whose inputs did not change, and editing a preset
only trains the runs it adds; a rebuild on another CPU trains afresh.

The chapters call, in order:

1. :func:`grid` -- the paper's grid search on Z, for one cell: every point of the preset's small grid,
   trained with each of ``p.grid_seeds``, scored on the validation split only; :func:`grid_points`
   summarises each point over its seeds and :func:`best_config` picks the highest mean.
2. :func:`seed_runs` -- Table 1: the peephole LSTM's winner for Z and X, Y, Z with ``p.seeds``, scored on
   the test split (the grid's own runs are among them: their kept models are scored, not retrained).
3. :func:`protocol_runs` -- what each change of the training protocol did, on validation data.
4. :func:`ablation` -- each cell at its own grid winner, the same test seeds.
5. :func:`length_sweep` and :func:`long_memory` -- accuracy against input length (the paper's Figure 4),
   and the long inputs again with a memory that spans them (chrono initialisation, full BPTT).
6. :func:`baseline_runs` -- the physics baseline of :mod:`study.learn.baseline`, same split.

Every function returns a tidy list of dicts (one row per run); :func:`summarise` groups them into a
mean, a spread, a 95 % interval, and the count of runs that failed to train or diverged.
"""

from __future__ import annotations

import dataclasses
import itertools
import json
import multiprocessing
import os
import time
from collections.abc import Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import torch

from study import cache, presets
from study.errors import ModelError
from study.learn import baseline, native, train
from study.learn.metrics import Interval, bootstrap_accuracy, failed_to_train
from study.learn.train import TrainConfig
from study.progress import Progress
from study.simulate.data import Dataset

RUN_FORMAT = "study.run/2"
"""Format 2 added the test split's per-trajectory probabilities, the diverged epoch and the failed flag."""


@dataclass(frozen=True)
class Preset:
    """How much of each experiment to run, and the training protocol every run shares."""

    name: str
    """Its name in ``study.presets.NAMES``."""
    length: float
    """Input length for Table 1, the grid and the ablation, seconds."""
    lrs: tuple[float, ...]
    """Grid: Adam learning rates."""
    truncations: tuple[int, ...]
    """Grid: truncated-BPTT lengths, frames."""
    dropouts: tuple[float, ...]
    """Grid: dropout probabilities (0.2 = the paper's keep-probability 0.8)."""
    batch_sizes: tuple[int, ...]
    """Grid: trajectories per step."""
    grid_seeds: tuple[int, ...]
    """Seeds every grid point is trained with; a point is scored by its mean validation accuracy over them."""
    seeds: tuple[int, ...]
    """Test seeds of Table 1 and the ablation."""
    lengths: tuple[float, ...]
    """Input lengths of the length sweep, seconds."""
    length_seeds: tuple[int, ...]
    """Seeds per point of the length sweep."""
    max_epochs: int
    """Epoch cap of every run."""
    patience: int
    """Early-stopping patience of every run, epochs."""
    min_epochs: int
    """Epochs before early stopping may end a run."""
    cells: tuple[str, ...] = ("peephole", "no-peephole", "gru")
    """Cells compared in the ablation (``study.learn.config.CELLS``), the paper's first."""
    ablation_dims: str = "z"
    """Input dims of the grid and the ablation (Z, as in the paper's search)."""
    long_lengths: tuple[float, ...] = ()
    """Lengths at which the long-memory variant runs (chrono initialisation, full BPTT), seconds."""
    long_seeds: tuple[int, ...] = (0,)
    """Seeds of the long-memory runs."""
    protocol_seeds: tuple[int, ...] = (0,)
    """Seeds of the training-protocol comparison (validation only)."""
    first_patience: int = 10
    """Early-stopping patience of the study's first protocol (the comparison's first row), epochs."""
    first_max_epochs: int = 60
    """Epoch cap of the study's first protocol."""
    shape_train: int = 250
    """Training throws per class and shape in the cue chapter's mixed-shape training set."""
    shape_test: int = 500
    """Test throws per class and shape in the cue chapter."""
    calibration_per_class: int = 2500
    """Throws per class in the decision chapter's calibration split (simulated for it alone: a 1 % miss
    rate is then 25 heavy objects, not 4)."""
    videos_per_class: int = 20
    """Rendered videos per class in the real-world test (the paper filmed 20 + 20)."""
    real_clips: int | None = None
    """Most real clips the real-world test classifies (None: all there are)."""
    render_shadows: bool = True
    """Draw shadows in the rendered videos (slower)."""

    def base_config(self) -> TrainConfig:
        """The config every run starts from, before the grid values are set: the study's protocol."""
        return TrainConfig(dims=self.ablation_dims, length=self.length, max_epochs=self.max_epochs,
                           patience=self.patience, min_epochs=self.min_epochs)

    @property
    def n_grid(self) -> int:
        """Number of grid points."""
        return len(self.lrs) * len(self.truncations) * len(self.dropouts) * len(self.batch_sizes)


PRESETS: dict[str, Preset] = {
    # The whole book in minutes on the smoke dataset: 2 grid points, 2 seeds, 3 lengths, 3 epochs.
    "smoke": Preset(
        name="smoke", length=1.0, lrs=(3e-3,), truncations=(10, 30), dropouts=(0.2,), batch_sizes=(32,),
        grid_seeds=(0, 1), seeds=(0, 1), lengths=(0.5, 1.0, 1.5), length_seeds=(0, 1), max_epochs=3,
        patience=2, min_epochs=2, long_lengths=(1.5,), protocol_seeds=(0,), first_patience=1, first_max_epochs=2,
        shape_train=4, shape_test=4, calibration_per_class=8, videos_per_class=2, real_clips=2,
        render_shadows=False,
    ),
    # The paper's scale, 74 minutes from an empty data/ on a 2-core CPU (measured at cc15304): a 2 x 2
    # grid (learning rate x truncation) x 3 seeds x 3 cells; Table 1 with 5 seeds; the training protocols
    # with 2; the length sweep with 2 seeds; the long-memory test at 6 s. A run converges in 40-150
    # epochs of about 1.2 s at 3 s of input (batch 32, two runs at a time).
    "paper": Preset(
        name="paper", length=3.0, lrs=(1e-3, 3e-3), truncations=(30, 90), dropouts=(0.2,), batch_sizes=(32,),
        grid_seeds=(0, 1, 2), seeds=(0, 1, 2, 3, 4), lengths=(0.5, 1.0, 2.0, 3.0, 6.0), length_seeds=(0, 1),
        max_epochs=150, patience=20, min_epochs=30, long_lengths=(6.0,), long_seeds=(0, 1),
        protocol_seeds=(0, 1),
    ),
}


def preset(name: str) -> Preset:
    """The preset called ``name`` (``study.presets.NAMES``); :class:`ConfigError` for an unknown one."""
    return PRESETS[presets.check(name)]


def default_workers() -> int:
    """Training processes to run at once: the CPUs this process may use (each run takes one thread)."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # not on Linux
        return max(1, os.cpu_count() or 1)


# ---------------------------------------------------------------------------------------------
# One run, cached


def run_key(dataset: Dataset, cfg: TrainConfig, test: bool) -> str:
    """The cache key of one trained run."""
    return cache.key({
        "format": RUN_FORMAT, "data": dataset.key, "config": dataclasses.asdict(cfg), "test": test,
        "code": cache.source_hash(*train.SOURCES), "torch": torch.__version__,
        # the compiled loop is built for this CPU and rounds differently from PyTorch's: either changes a run
        "backend": native.backend(), "build": native.build_id(),
    })


def _path(dataset: Dataset, cfg: TrainConfig, data_dir: str | Path, test: bool) -> tuple[str, Path]:
    key = run_key(dataset, cfg, test)
    return key, Path(data_dir) / "runs" / f"{key}.json"


def model_dir(dataset: Dataset, cfg: TrainConfig, data_dir: str | Path = "data") -> Path:
    """Where :func:`run` keeps the trained model of ``cfg`` (``study.learn.train.load`` reads it): one folder
    per config and dataset, whether or not the run was scored on the test split."""
    return Path(data_dir) / "models" / run_key(dataset, cfg, test=False)


def cached(dataset: Dataset, cfg: TrainConfig, data_dir: str | Path = "data", test: bool = True) -> dict[str, Any] | None:
    """The cached record of this run, or None if there is none (or it is damaged, or the dataset has no key)."""
    key, path = _path(dataset, cfg, data_dir, test)
    if not dataset.key or not path.is_file():
        return None
    try:
        record = json.loads(path.read_text())
    except (OSError, json.JSONDecodeError, UnicodeDecodeError):
        return None  # a damaged entry is retrained and overwritten
    return record if isinstance(record, dict) and record.get("key") == key else None


def _test_scores(tm: train.TrainedModel, dataset: Dataset) -> dict[str, Any]:
    """The test metrics of ``tm`` and its probability of heavy for every test trajectory (for intervals)."""
    p_heavy = tm.predict_proba(dataset.test.x)[:, 1]
    res = train.metrics(dataset.test.y, (p_heavy > 0.5).astype(np.int64))
    return res | {"p_heavy": [round(float(p), 6) for p in p_heavy]}


def run(dataset: Dataset, cfg: TrainConfig, data_dir: str | Path = "data", test: bool = True) -> dict[str, Any]:
    """Train ``cfg`` on ``dataset`` (or read the cached result) and return its record.

    The record holds the config, the validation accuracy and loss at the kept epoch, whether the run
    failed to train (validation accuracy indistinguishable from chance) or diverged (and when), the
    epochs run, the history, the training time and, if ``test``, the test metrics with every test
    trajectory's probability of heavy. The trained model itself is saved in :func:`model_dir`. A
    dataset without a key is never cached.
    """
    record = cached(dataset, cfg, data_dir, test)
    if record is not None:
        return record
    key, path = _path(dataset, cfg, data_dir, test)
    reused = _score_kept_model(dataset, cfg, data_dir, key) if test else _without_test(dataset, cfg, data_dir, key)
    if reused is not None:
        cache.write_text_atomic(path, json.dumps(reused, indent=1) + "\n")
        return reused
    t0 = time.perf_counter()
    tm = train.fit(dataset, cfg, progress=False)
    seconds = time.perf_counter() - t0
    if dataset.key:
        tm.save(model_dir(dataset, cfg, data_dir))  # so a chapter that needs this very model loads it
    n_val = len(train.split_train_val(len(dataset.train.y), cfg.val_fraction, cfg.seed)[1])
    record = {
        "key": key, "format": RUN_FORMAT, "data_key": dataset.key, "config": dataclasses.asdict(cfg),
        "val_accuracy": tm.val_accuracy, "val_loss": tm.history[tm.best_epoch]["val_loss"], "n_val": n_val,
        "failed": failed_to_train(tm.val_accuracy, tm.history[tm.best_epoch]["val_loss"], n_val),
        "diverged_epoch": tm.diverged_epoch,
        "best_epoch": tm.best_epoch, "epochs_run": len(tm.history), "history": tm.history,
        "train_seconds": seconds, "test": _test_scores(tm, dataset) if test else None,
    }
    if dataset.key:
        cache.write_text_atomic(path, json.dumps(record, indent=1) + "\n")
    return record


def _score_kept_model(dataset: Dataset, cfg: TrainConfig, data_dir: str | Path, key: str) -> dict[str, Any] | None:
    """The test-scored record of ``cfg`` from the same run made without the test split (a grid run is such a
    run), its kept model scored on the test split instead of training it again; None if absent.

    Training is seeded and deterministic, so this is the record a new run would give (its
    ``train_seconds`` are those of the original run).
    """
    base = cached(dataset, cfg, data_dir, test=False)
    if base is None:
        return None
    try:
        tm = train.load(model_dir(dataset, cfg, data_dir))  # the folder's name is the key of (data, cfg)
    except (ModelError, OSError):
        return None
    return {**base, "key": key, "test": _test_scores(tm, dataset)}


def _without_test(dataset: Dataset, cfg: TrainConfig, data_dir: str | Path, key: str) -> dict[str, Any] | None:
    """The validation-only record of ``cfg`` from the same run scored on the test split, if there is one."""
    scored = cached(dataset, cfg, data_dir, test=True)
    return None if scored is None else {**scored, "key": key, "test": None}


def _runs(dataset: Dataset, cfgs: list[TrainConfig], data_dir: str | Path, test: bool, desc: str, progress: bool,
          workers: int | None) -> list[dict]:
    """The records of ``cfgs`` in order: cached ones read, the others trained, in ``workers`` processes
    (``None``: :func:`default_workers`).

    Every run is seeded and single-threaded (see :mod:`study.learn.train`), so running them in parallel
    processes gives the same records as running them one by one (tested).
    """
    workers = default_workers() if workers is None else workers
    records = [cached(dataset, c, data_dir, test) for c in cfgs]
    todo = [i for i, r in enumerate(records) if r is None]
    # Longest inputs first, so the last runs to finish are short ones and no core idles long at the end.
    todo.sort(key=lambda i: -cfgs[i].n_frames(dataset.fps))
    note = f"{len(cfgs) - len(todo)} of {len(cfgs)} cached" if len(todo) < len(cfgs) else ""
    with Progress(desc, total=len(todo), show=progress and bool(todo), note=note, unit="run") as bar:
        if workers > 1 and len(todo) > 1:
            ctx = multiprocessing.get_context("spawn")  # no fork of a process that holds torch threads
            with ProcessPoolExecutor(min(workers, len(todo)), mp_context=ctx) as pool:
                futures = {pool.submit(run, dataset, cfgs[i], data_dir, test): i for i in todo}
                for f in as_completed(futures):
                    records[futures[f]] = f.result()
                    bar.update()
        else:
            for i in todo:
                records[i] = run(dataset, cfgs[i], data_dir, test)
                bar.update()
    return records


def _row(rec: dict[str, Any], dataset: Dataset, *fields: str) -> dict[str, Any]:
    """A tidy row: the named config fields, then the run's headline numbers; with a test score, ``correct``:
    (n,) bool, which test trajectories it got right (for intervals)."""
    row = {f: rec["config"][f] for f in fields}
    row.update(seed=rec["config"]["seed"], val_accuracy=rec["val_accuracy"], val_loss=rec["val_loss"],
               epochs=rec["epochs_run"], best_epoch=rec["best_epoch"], seconds=rec["train_seconds"],
               failed=rec["failed"], diverged_epoch=rec["diverged_epoch"],
               capped=rec["epochs_run"] >= rec["config"]["max_epochs"] and rec["diverged_epoch"] is None)
    if rec["test"] is not None:
        pred = np.asarray(rec["test"]["p_heavy"]) > 0.5
        row.update(accuracy=rec["test"]["accuracy"], correct=pred == (np.asarray(dataset.test.y) == 1),
                   **{f"accuracy_{c}": a for c, a in rec["test"]["per_class_accuracy"].items()})
    return row


# ---------------------------------------------------------------------------------------------
# The experiments


def grid_configs(p: Preset, cell: str = "peephole") -> list[TrainConfig]:
    """Every point of the preset's grid for ``cell``, once per grid seed."""
    base = dataclasses.replace(p.base_config(), cell=cell)
    return [dataclasses.replace(base, lr=lr, truncation=k, dropout=d, batch_size=b, seed=s)
            for lr, k, d, b in itertools.product(p.lrs, p.truncations, p.dropouts, p.batch_sizes)
            for s in p.grid_seeds]


GRID_FIELDS = ("cell", "lr", "truncation", "dropout", "batch_size")
"""The fields that name a grid point (with the cell)."""


def grid(dataset: Dataset, p: Preset, cell: str = "peephole", data_dir: str | Path = "data", progress: bool = True,
         workers: int | None = None) -> list[dict]:
    """The grid search on ``p.ablation_dims`` for ``cell``: one row per (point, seed), validation scores only."""
    recs = _runs(dataset, grid_configs(p, cell), data_dir, False, f"grid ({cell})", progress, workers)
    return [_row(r, dataset, *GRID_FIELDS) for r in recs]


def grid_points(rows: list[dict]) -> list[dict]:
    """The grid rows of :func:`grid` grouped by point: mean and sample std of the validation accuracy over
    the seeds, the mean validation loss, and how many of the seeds failed to train or diverged."""
    out = []
    for key, group in itertools.groupby(sorted(rows, key=lambda r: tuple(r[f] for f in GRID_FIELDS)),
                                        key=lambda r: tuple(r[f] for f in GRID_FIELDS)):
        g = list(group)
        acc = np.array([r["val_accuracy"] for r in g])
        out.append({**dict(zip(GRID_FIELDS, key)), "n": len(g), "val_mean": float(acc.mean()),
                    "val_std": float(acc.std(ddof=1)) if len(g) > 1 else 0.0,
                    "val_loss_mean": float(np.mean([r["val_loss"] for r in g])),
                    "failed": sum(r["failed"] for r in g),
                    "diverged": sum(r["diverged_epoch"] is not None for r in g),
                    "epochs_mean": float(np.mean([r["epochs"] for r in g]))})
    return out


def best_config(rows: list[dict], p: Preset) -> TrainConfig:
    """The grid point with the highest mean validation accuracy over its seeds (ties: lower mean
    validation loss, then grid order), as the config the later experiments start from."""
    best = min(grid_points(rows), key=lambda r: (-r["val_mean"], r["val_loss_mean"]))
    return dataclasses.replace(p.base_config(), **{f: best[f] for f in GRID_FIELDS})


def seed_runs(dataset: Dataset, cfg: TrainConfig, p: Preset, data_dir: str | Path = "data", progress: bool = True,
              workers: int | None = None) -> list[dict]:
    """Table 1: ``cfg`` for Z and X, Y, Z, one row per (dims, seed), with test accuracy."""
    cfgs = [dataclasses.replace(cfg, dims=d, seed=s) for d in ("z", "xyz") for s in p.seeds]
    return [_row(r, dataset, "dims") for r in _runs(dataset, cfgs, data_dir, True, "Table 1", progress, workers)]


PROTOCOLS: tuple[str, ...] = (
    "paper's network, our first protocol",
    "+ forget bias 1 (the paper's TensorFlow default)",
    "+ early stopping after a minimum, higher cap",
    "+ gradient clipping (norm 1): the study's protocol",
    "+ learning rate halved on plateaus",
)
"""The training protocols compared on validation data (:func:`protocol_changes`)."""
STUDY_PROTOCOL = 3
"""Index in :data:`PROTOCOLS` of the protocol every other experiment uses."""


def protocol_changes(p: Preset) -> dict[str, dict[str, Any]]:
    """Each protocol of :data:`PROTOCOLS` as the config fields it changes from the study's protocol: each
    row adds one change to the row above it, up to the study's own (:data:`STUDY_PROTOCOL`); the last
    row adds one more that the study does not keep. The first protocol stopped early as the preset's
    ``first_patience`` and ``first_max_epochs`` say."""
    first = {"min_epochs": 0, "max_epochs": p.first_max_epochs, "patience": p.first_patience}
    changes = [{"forget_bias": 0.0, "clip_norm": 0.0, **first}, {"clip_norm": 0.0, **first}, {"clip_norm": 0.0}, {},
               {"lr_schedule": "plateau"}]
    return dict(zip(PROTOCOLS, changes))


def protocol_runs(dataset: Dataset, cfg: TrainConfig, p: Preset, data_dir: str | Path = "data",
                  progress: bool = True, workers: int | None = None) -> list[dict]:
    """Every protocol of :func:`protocol_changes` at ``cfg``, for Z and X, Y, Z with ``p.protocol_seeds``,
    validation only: one row per (protocol, dims, seed)."""
    plan = [(name, dataclasses.replace(cfg, dims=d, seed=s, **changes))
            for name, changes in protocol_changes(p).items() for d in ("z", "xyz") for s in p.protocol_seeds]
    recs = _runs(dataset, [c for _, c in plan], data_dir, False, "protocols", progress, workers)
    return [_row(r, dataset, "dims") | {"protocol": name} for (name, _), r in zip(plan, recs)]


def ablation(dataset: Dataset, winners: dict[str, TrainConfig], p: Preset, data_dir: str | Path = "data",
             progress: bool = True, workers: int | None = None) -> list[dict]:
    """Each cell of ``winners`` (cell -> its own grid winner) on ``p.ablation_dims`` with the test seeds
    ``p.seeds``: one row per (cell, seed)."""
    cfgs = [dataclasses.replace(winners[c], cell=c, seed=s) for c in p.cells for s in p.seeds]
    return [_row(r, dataset, "cell") for r in _runs(dataset, cfgs, data_dir, True, "ablation", progress, workers)]


def length_sweep(dataset: Dataset, cfg: TrainConfig, p: Preset, data_dir: str | Path = "data", progress: bool = True,
                 workers: int | None = None) -> list[dict]:
    """Accuracy against input length: one row per (dims, length, seed) at ``cfg``."""
    cfgs = [dataclasses.replace(cfg, dims=d, length=L, seed=s)
            for d in ("z", "xyz") for L in p.lengths for s in p.length_seeds]
    recs = _runs(dataset, cfgs, data_dir, True, "lengths", progress, workers)
    return [_row(r, dataset, "dims", "length") | {"frames": c.n_frames(dataset.fps)} for r, c in zip(recs, cfgs)]


def long_memory_config(cfg: TrainConfig, fps: float) -> TrainConfig:
    """``cfg`` with a memory that spans its input: chrono-initialised forget gates and full
    back-propagation through time (the truncation covers every frame)."""
    return dataclasses.replace(cfg, forget_init="chrono", truncation=max(cfg.truncation, cfg.n_frames(fps)))


def long_memory(dataset: Dataset, cfg: TrainConfig, p: Preset, data_dir: str | Path = "data",
                progress: bool = True, workers: int | None = None) -> list[dict]:
    """The length sweep at ``p.long_lengths`` with :func:`long_memory_config`: one row per (dims, length, seed)."""
    cfgs = [long_memory_config(dataclasses.replace(cfg, dims=d, length=L, seed=s), dataset.fps)
            for d in ("z", "xyz") for L in p.long_lengths for s in p.long_seeds]
    recs = _runs(dataset, cfgs, data_dir, True, "long memory", progress, workers)
    return [_row(r, dataset, "dims", "length", "truncation") | {"frames": c.n_frames(dataset.fps)}
            for r, c in zip(recs, cfgs)]


def baseline_runs(dataset: Dataset, p: Preset) -> list[dict]:
    """The physics baseline for Z and XYZ at ``p.length``: one row per dims (it has no seed)."""
    rows = []
    for d in ("z", "xyz"):
        m = baseline.fit(dataset, d, p.length)
        pred = m.predict_proba(dataset.test.x).argmax(axis=1)
        res = train.metrics(dataset.test.y, pred)
        rows.append({"dims": d, "accuracy": res["accuracy"], "correct": pred == np.asarray(dataset.test.y),
                     **{f"accuracy_{c}": a for c, a in res["per_class_accuracy"].items()},
                     "coefficients": m.coefficients})
    return rows


def train_runs(dataset: Dataset, cfg: TrainConfig, dims: Sequence[str], seeds: Sequence[int],
               data_dir: str | Path = "data", desc: str = "runs", progress: bool = False,
               workers: int | None = None, **changes: Any) -> list[dict]:
    """``cfg`` (with ``changes``) for each of ``dims`` and ``seeds`` on ``dataset``, scored on its test split:
    one row per (dims, seed), as ``study.experiments.seed_runs`` gives them."""
    cfgs = [dataclasses.replace(cfg, dims=d, seed=s, **changes) for d in dims for s in seeds]
    recs = _runs(dataset, cfgs, data_dir, True, desc, progress, workers)
    return [_row(r, dataset, "dims") for r in recs]


def trained(dataset: Dataset, cfg: TrainConfig, data_dir: str | Path = "data"):
    """The kept model of a run :func:`train_runs` (or any experiment) trained: ``study.learn.train.load``."""
    return train.load(model_dir(dataset, cfg, data_dir))


def scored(models: Sequence[Any], x: np.ndarray, y: np.ndarray) -> Interval:
    """The mean accuracy of ``models`` on trajectories ``x`` (n, T, 3) with labels ``y``, and its bootstrap
    interval over the trajectories and the models (seeds)."""
    correct = np.stack([m.predict_proba(x).argmax(axis=1) == np.asarray(y) for m in models])
    return bootstrap_accuracy(correct)


# ---------------------------------------------------------------------------------------------
# Summaries


def summarise(rows: list[dict], by: tuple[str, ...], value: str = "accuracy") -> list[dict]:
    """Group ``rows`` by the ``by`` fields: n, mean, sample std (ddof=1; 0 for one run), min and best of
    ``value``; the runs that failed to train, diverged, or stopped at the epoch cap; and, where rows carry
    ``correct``, ``interval``:
    the 95 % bootstrap interval of the mean over test trajectories and seeds."""
    groups: dict[tuple, list[dict]] = {}
    for r in rows:
        groups.setdefault(tuple(r[b] for b in by), []).append(r)
    out = []
    for k, g in groups.items():
        a = np.asarray([float(r[value]) for r in g])
        s = {**dict(zip(by, k)), "n": len(a), "mean": float(a.mean()),
             "std": float(a.std(ddof=1)) if len(a) > 1 else 0.0, "min": float(a.min()), "best": float(a.max()),
             "failed": sum(bool(r.get("failed")) for r in g),
             "diverged": sum(r.get("diverged_epoch") is not None for r in g),
             "capped": sum(bool(r.get("capped")) for r in g)}
        if value == "accuracy" and all("correct" in r for r in g):
            s["interval"] = bootstrap_accuracy(np.stack([r["correct"] for r in g]))
        out.append(s)
    return out


def best_run_interval(rows: list[dict]) -> tuple[dict, Interval]:
    """The row with the highest test accuracy and the bootstrap interval of that one run (the paper's
    number is a best run: compare it with ours)."""
    best = max(rows, key=lambda r: r["accuracy"])
    return best, bootstrap_accuracy(best["correct"])


def n_models(p: Preset) -> int:
    """How many models a full run of the preset trains (grid runs at a test seed are scored, not retrained;
    the length sweep's runs at ``p.length`` with a seed of ``p.seeds`` are Table 1's)."""
    per_cell_grid = p.n_grid * len(p.grid_seeds)
    grid_all = len(p.cells) * per_cell_grid
    shared = len(set(p.seeds) & set(p.grid_seeds))
    table1 = (len(p.seeds) - shared) + len(p.seeds)  # Z beyond the grid's seeds, X, Y, Z all
    ablation = (len(p.cells) - 1) * (len(p.seeds) - shared)
    protocols = (len(PROTOCOLS) - 1) * 2 * len(p.protocol_seeds)  # the study's own row is Table 1's runs
    sweep_shared = 2 * len(set(p.length_seeds) & set(p.seeds)) if p.length in p.lengths else 0
    sweep = 2 * len(p.lengths) * len(p.length_seeds) - sweep_shared
    long = 2 * len(p.long_lengths) * len(p.long_seeds)
    return grid_all + table1 + ablation + protocols + sweep + long


def long_input_effect(summary: list[dict], dims: str) -> dict[str, Any]:
    """Does accuracy fall at the longest inputs? From :func:`summarise` rows grouped by (dims, length).

    Compares the best mean accuracy over lengths with the mean at the longest length; ``hurts`` when
    their 95 % intervals do not overlap and the longest is below.
    """
    rows = sorted((r for r in summary if r["dims"] == dims), key=lambda r: r["length"])
    best = max(rows, key=lambda r: r["mean"])
    last = rows[-1]
    drop = best["mean"] - last["mean"]
    hurts = best is not last and drop > 0 and not best["interval"].overlaps(last["interval"])
    return {"dims": dims, "best_length": best["length"], "best_mean": best["mean"], "last_length": last["length"],
            "last_mean": last["mean"], "drop": drop, "hurts": bool(hurts)}
