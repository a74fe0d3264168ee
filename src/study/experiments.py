"""The experiments behind Table 1 and the accuracy-versus-length figure, cached run by run.

Each trained run's result (metrics and training history, not weights) is a JSON file in
``data_dir/runs/``, named by :func:`study.cache.key` of the dataset key, the :class:`TrainConfig`,
whether the test split was scored, the source of ``study.learn.model`` and ``study.learn.train`` and the torch
version; it is written atomically. Re-building the book therefore never retrains a run whose inputs
did not change, and editing a preset only trains the runs it adds.

The chapters call, in order:

1. :func:`grid` -- the paper's grid search, on Z only, scored on the validation split (the test split
   is not looked at); :func:`best_config` picks the highest validation accuracy.
2. :func:`seed_runs` -- the chosen config for Z and XYZ with several seeds, scored on the test split.
3. :func:`length_sweep` -- accuracy against input length for Z and XYZ (the paper's Figure 4).
4. :func:`ablation` -- peephole LSTM vs the same layer without peepholes vs GRU at the chosen config,
   same seeds.
5. :func:`baseline_runs` -- the physics baseline of :mod:`study.learn.baseline`, same split.

Every function returns a tidy list of dicts (one row per run), ready for ``pandas.DataFrame``.
"""

from __future__ import annotations

import dataclasses
import itertools
import json
import multiprocessing
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import torch

from study import cache, presets
from study.progress import Progress
from study.errors import ConfigError, ModelError
from study.learn import baseline, native, train
from study.learn.train import TrainConfig
from study.simulate.data import Dataset

RUN_FORMAT = "study.run/1"


@dataclass(frozen=True)
class Preset:
    """How much of each experiment to run."""

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
    seeds: tuple[int, ...]
    """Seeds for Table 1 and the ablation."""
    lengths: tuple[float, ...]
    """Input lengths of the length sweep, seconds."""
    length_seeds: tuple[int, ...]
    """Seeds per point of the length sweep."""
    max_epochs: int
    """Epoch cap of every run."""
    patience: int
    """Early-stopping patience of every run, epochs."""
    grid_seed: int = 0
    """The seed of every grid run."""
    cells: tuple[str, ...] = ("peephole", "no-peephole", "gru")
    """Cells compared in the ablation (``study.learn.model.CELLS``)."""
    ablation_dims: str = "z"
    """Input dims of the ablation (the grid's, as in the paper's search)."""
    control_lengths: tuple[float, ...] = ()
    """Lengths at which the length sweep is repeated with full back-propagation (no truncation), seconds."""
    control_seeds: tuple[int, ...] = (0,)
    """Seeds of those full-BPTT control runs."""
    videos_per_class: int = 20
    """Rendered videos per class in the real-world test (the paper filmed 20 + 20)."""
    real_clips: int | None = None
    """Most real clips the real-world test classifies (None: all there are)."""
    render_shadows: bool = True
    """Draw shadows in the rendered videos (slower)."""

    def base_config(self) -> TrainConfig:
        """The config every run starts from, before the grid values are set."""
        return TrainConfig(dims="z", length=self.length, max_epochs=self.max_epochs, patience=self.patience)

    @property
    def n_grid(self) -> int:
        """Number of grid points."""
        return len(self.lrs) * len(self.truncations) * len(self.dropouts) * len(self.batch_sizes)


PRESETS: dict[str, Preset] = {
    # Whole chapter in seconds on the smoke dataset: 2 grid points, 2 seeds, 3 lengths, 3 epochs.
    "smoke": Preset(
        name="smoke", length=1.0, lrs=(3e-3,), truncations=(10, 30), dropouts=(0.2,), batch_sizes=(32,),
        seeds=(0, 1), lengths=(0.5, 1.0, 1.5), length_seeds=(0, 1), max_epochs=3, patience=2,
        control_lengths=(1.5,), videos_per_class=2, real_clips=2, render_shadows=False,
    ),
    # The real thing: a 2x2x2x2 grid on Z at 3 s (90 frames); 5 seeds for Z and XYZ; 8 lengths x 3
    # seeds x 2 dims; the ablation's 2 other cells x 5 seeds; 4 full-BPTT controls: 81 trained models
    # (n_models). Measured on a 2-core CPU (two runs at a time, one thread each, 1600 + 400 sequences
    # of 90 frames), all on the compiled loops: 1.0-1.6 s per epoch
    # for the peephole LSTM (and without peepholes), 1.15 for the GRU (nn.GRU itself: 3.4 at batch 32);
    # Z converges in 15-40 epochs, X, Y, Z needs up to
    # 60 at the same settings, hence the 60-epoch cap (a 30-epoch cap left X, Y, Z at ~65 %).
    "paper": Preset(
        name="paper", length=3.0, lrs=(1e-3, 3e-3), truncations=(30, 90), dropouts=(0.2, 0.5),
        batch_sizes=(32, 128), seeds=(0, 1, 2, 3, 4), lengths=(0.5, 1.0, 1.5, 2.0, 3.0, 4.0, 6.0, 8.0),
        length_seeds=(0, 1, 2), max_epochs=60, patience=10,
        # The length sweep's long inputs, again with full BPTT, X, Y, Z and Z, one seed: 4 more models.
        control_lengths=(6.0, 8.0),
    ),
}


def preset(name: str) -> Preset:
    """The preset called ``name`` (``study.presets.NAMES``); :class:`ConfigError` for an unknown one."""
    return PRESETS[presets.check(name)]


def run_key(dataset: Dataset, cfg: TrainConfig, test: bool) -> str:
    """The cache key of one trained run."""
    return cache.key({
        "format": RUN_FORMAT, "data": dataset.key, "config": dataclasses.asdict(cfg), "test": test,
        "code": cache.source_hash(*train.SOURCES),
        "torch": torch.__version__,
        "backend": native.backend(),  # the compiled and the PyTorch time loop round differently
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


def run(dataset: Dataset, cfg: TrainConfig, data_dir: str | Path = "data", test: bool = True) -> dict[str, Any]:
    """Train ``cfg`` on ``dataset`` (or read the cached result) and return its record.

    The record holds the config, the validation accuracy and loss at the kept epoch, the epochs run,
    the history, the training time and, if ``test``, the test metrics of :func:`study.learn.train.evaluate`.
    The trained model itself is saved in :func:`model_dir`. A dataset without a key is never cached.
    """
    record = cached(dataset, cfg, data_dir, test)
    if record is not None:
        return record
    key, path = _path(dataset, cfg, data_dir, test)
    if test:
        scored = _score_kept_model(dataset, cfg, data_dir, key)
        if scored is not None:
            cache.write_text_atomic(path, json.dumps(scored, indent=1) + "\n")
            return scored
    t0 = time.perf_counter()
    tm = train.fit(dataset, cfg, progress=False)
    if dataset.key:
        tm.save(model_dir(dataset, cfg, data_dir))  # so a chapter that needs this very model loads it
    record = {
        "key": key, "format": RUN_FORMAT, "data_key": dataset.key, "config": dataclasses.asdict(cfg),
        "val_accuracy": tm.val_accuracy, "val_loss": tm.history[tm.best_epoch]["val_loss"],
        "best_epoch": tm.best_epoch, "epochs_run": len(tm.history), "history": tm.history,
        "train_seconds": time.perf_counter() - t0,
        "test": train.evaluate(tm, dataset.test) if test else None,
    }
    if dataset.key:
        cache.write_text_atomic(path, json.dumps(record, indent=1) + "\n")
    return record


def _score_kept_model(dataset: Dataset, cfg: TrainConfig, data_dir: str | Path, key: str) -> dict[str, Any] | None:
    """The test-scored record of ``cfg`` from the same run made without the test split (the grid's winner
    is such a run), its kept model scored on the test split instead of training it again; None if absent.

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
    return {**base, "key": key, "test": train.evaluate(tm, dataset.test)}


def _runs(dataset: Dataset, cfgs: list[TrainConfig], data_dir: str | Path, test: bool, desc: str, progress: bool,
          workers: int) -> list[dict]:
    """The records of ``cfgs`` in order: cached ones read, the others trained, in ``workers`` processes if > 1.

    Every run is seeded and single-threaded (see :mod:`study.learn.train`), so running them in parallel
    processes gives the same records as running them one by one (tested).
    """
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


def _row(rec: dict[str, Any], *fields: str) -> dict[str, Any]:
    """A tidy row: the named config fields, then the run's headline numbers."""
    row = {f: rec["config"][f] for f in fields}
    row.update(val_accuracy=rec["val_accuracy"], val_loss=rec["val_loss"], epochs=rec["epochs_run"],
               seconds=rec["train_seconds"])
    if rec["test"] is not None:
        row.update(accuracy=rec["test"]["accuracy"],
                   **{f"accuracy_{c}": a for c, a in rec["test"]["per_class_accuracy"].items()})
    return row


def grid(dataset: Dataset, p: Preset, data_dir: str | Path = "data", progress: bool = True,
         workers: int = 1) -> list[dict]:
    """The grid search on Z: one row per (lr, truncation, dropout, batch_size), validation scores only."""
    base = p.base_config()
    cfgs = [
        dataclasses.replace(base, lr=lr, truncation=k, dropout=d, batch_size=b, seed=p.grid_seed)
        for lr, k, d, b in itertools.product(p.lrs, p.truncations, p.dropouts, p.batch_sizes)
    ]
    recs = _runs(dataset, cfgs, data_dir, False, "grid (Z)", progress, workers)
    return [_row(r, "lr", "truncation", "dropout", "batch_size") for r in recs]


def best_config(rows: list[dict], p: Preset) -> TrainConfig:
    """The grid point with the highest validation accuracy (ties: lower validation loss, then grid order)."""
    best = min(rows, key=lambda r: (-r["val_accuracy"], r["val_loss"]))
    return dataclasses.replace(p.base_config(), lr=best["lr"], truncation=best["truncation"],
                               dropout=best["dropout"], batch_size=best["batch_size"])


def seed_runs(dataset: Dataset, cfg: TrainConfig, p: Preset, data_dir: str | Path = "data", progress: bool = True,
              workers: int = 1) -> list[dict]:
    """The chosen config for Z and XYZ, one row per (dims, seed), with test accuracy."""
    cfgs = [dataclasses.replace(cfg, dims=d, seed=s) for d in ("z", "xyz") for s in p.seeds]
    return [_row(r, "dims", "seed") for r in _runs(dataset, cfgs, data_dir, True, "seeds", progress, workers)]


def length_sweep(dataset: Dataset, cfg: TrainConfig, p: Preset, data_dir: str | Path = "data", progress: bool = True,
                 workers: int = 1) -> list[dict]:
    """Accuracy against input length: one row per (dims, length, seed) at the chosen config."""
    cfgs = [dataclasses.replace(cfg, dims=d, length=L, seed=s)
            for d in ("z", "xyz") for L in p.lengths for s in p.length_seeds]
    recs = _runs(dataset, cfgs, data_dir, True, "lengths", progress, workers)
    return [_row(r, "dims", "length", "seed") | {"frames": c.n_frames(dataset.fps)} for r, c in zip(recs, cfgs)]


def full_bptt_control(dataset: Dataset, cfg: TrainConfig, p: Preset, data_dir: str | Path = "data",
                      progress: bool = True, workers: int = 1) -> list[dict]:
    """The length sweep at ``p.control_lengths`` with full back-propagation through time.

    With truncation k, the gradient of the loss at frame T reaches frames T - k .. T only; when those
    frames show an object at rest, nothing tells the network what the earlier, informative frames should
    leave in its state. These runs set the truncation to the whole input, so the gradient reaches every
    frame: one row per (dims, length, seed), with the truncation used.
    """
    swept = [dataclasses.replace(cfg, dims=d, length=L, seed=s)
             for d in ("z", "xyz") for L in p.control_lengths for s in p.control_seeds]
    cfgs = [dataclasses.replace(c, truncation=max(c.truncation, c.n_frames(dataset.fps))) for c in swept]
    recs = _runs(dataset, cfgs, data_dir, True, "full BPTT", progress, workers)
    return [_row(r, "dims", "length", "seed", "truncation") | {"frames": c.n_frames(dataset.fps)}
            for r, c in zip(recs, cfgs)]


def ablation(dataset: Dataset, cfg: TrainConfig, p: Preset, data_dir: str | Path = "data", progress: bool = True,
             workers: int = 1) -> list[dict]:
    """The cells ``p.cells`` (peephole LSTM, the same without peepholes, GRU) at the chosen config on
    ``p.ablation_dims``, same seeds."""
    cfgs = [dataclasses.replace(cfg, dims=p.ablation_dims, cell=c, seed=s) for c in p.cells for s in p.seeds]
    return [_row(r, "cell", "dims", "seed") for r in _runs(dataset, cfgs, data_dir, True, "ablation", progress, workers)]


def baseline_runs(dataset: Dataset, p: Preset) -> list[dict]:
    """The physics baseline for Z and XYZ at ``p.length``: one row per dims (it has no seed)."""
    rows = []
    for d in ("z", "xyz"):
        m = baseline.fit(dataset, d, p.length)
        res = baseline.evaluate(m, dataset.test)
        rows.append({"dims": d, "accuracy": res["accuracy"],
                     **{f"accuracy_{c}": a for c, a in res["per_class_accuracy"].items()},
                     "coefficients": m.coefficients})
    return rows


def summarise(rows: list[dict], by: tuple[str, ...], value: str = "accuracy") -> list[dict]:
    """Group ``rows`` by the ``by`` fields: n, mean, sample std (ddof=1; 0 for one run), min, best of ``value``."""
    groups: dict[tuple, list[float]] = {}
    for r in rows:
        groups.setdefault(tuple(r[b] for b in by), []).append(float(r[value]))
    out = []
    for k, v in groups.items():
        a = np.asarray(v)
        out.append({**dict(zip(by, k)), "n": len(a), "mean": float(a.mean()),
                    "std": float(a.std(ddof=1)) if len(a) > 1 else 0.0,
                    "min": float(a.min()), "best": float(a.max())})
    return out


def n_models(p: Preset) -> int:
    """How many models a full run of the preset trains: the length sweep's runs at ``p.length`` with a
    seed of ``p.seeds`` are the seed runs' (the same config, so the same cache entry), and the Z seed run
    at ``p.grid_seed`` is the grid's winner (its kept model is scored, not trained again)."""
    shared = 2 * len(set(p.length_seeds) & set(p.seeds)) if p.length in p.lengths else 0
    sweep = 2 * len(p.lengths) * len(p.length_seeds) - shared
    control = 2 * len(p.control_lengths) * len(p.control_seeds)
    seeds = 2 * len(p.seeds) - (p.grid_seed in p.seeds)
    return p.n_grid + seeds + sweep + (len(p.cells) - 1) * len(p.seeds) + control


def long_input_effect(summary: list[dict], dims: str) -> dict[str, Any]:
    """Does accuracy fall at the longest inputs? From :func:`summarise` rows grouped by (dims, length).

    Compares the best mean accuracy over lengths with the mean at the longest length; ``hurts`` when
    the drop exceeds twice the larger of the two standard deviations and one percentage point.
    """
    rows = sorted((r for r in summary if r["dims"] == dims), key=lambda r: r["length"])
    best = max(rows, key=lambda r: r["mean"])
    last = rows[-1]
    drop = best["mean"] - last["mean"]
    return {"dims": dims, "best_length": best["length"], "best_mean": best["mean"], "last_length": last["length"],
            "last_mean": last["mean"], "drop": drop,
            "hurts": bool(drop > max(0.01, 2 * max(best["std"], last["std"]))) and best is not last}
