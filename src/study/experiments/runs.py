"""One trained run, cached; many of them, trained in parallel on a local process pool or a Dask cluster.

A run's record (metrics, test predictions and training history, not weights) is a JSON file in
``data_dir/runs/``, named by :func:`run_key`: a hash of the dataset's key, the :class:`TrainConfig`,
whether the test split was scored, the training code (``study.learn.train.SOURCES``), the torch version and
the time loop that ran (compiled for this CPU, or PyTorch's). It is written atomically, so a rebuild
never retrains a run whose inputs did not change, and a run trained anywhere that shares ``data_dir`` is
a hit everywhere. Its kept model lies in :func:`model_dir`.

:func:`run_all` trains the runs that are not cached through a ``concurrent.futures`` executor: a local
pool of spawned processes, or a Dask ``distributed`` client's executor when given a scheduler
(``"local"`` starts a ``LocalCluster`` on the loopback address; anything else is a scheduler's address,
reached with the security settings of the user's Dask configuration). The key of every run is computed
where it is submitted and checked again where it runs: a worker whose code, torch or compiled loop
differs refuses, rather than write a record under another key.
"""

from __future__ import annotations

import contextlib
import dataclasses
import json
import multiprocessing
import os
import time
from collections.abc import Iterator, Sequence
from concurrent.futures import Executor, ProcessPoolExecutor, as_completed
from functools import lru_cache
from pathlib import Path
from typing import Any

import numpy as np
import torch

from study.core import cache
from study.core.errors import ModelError, StudyError
from study.core.progress import Progress
from study.experiments.cluster import PLAN_ENV, default_workers, local_cluster, plan_totals
from study.learn import native, train
from study.learn.metrics import failed_to_train
from study.learn.train import TrainConfig
from study.simulate import data
from study.simulate.data import Dataset

RUN_FORMAT = "study.run/2"
"""Format 2 added the test split's per-trajectory probabilities, the diverged epoch and the failed flag."""


class WorkerError(StudyError):
    """A worker computes another key for the run it was sent: its code, torch or compiled loop differ."""


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


def record_path(data_dir: str | Path, key: str) -> Path:
    """Where the record of the run ``key`` lives."""
    return Path(data_dir) / "runs" / f"{key}.json"


def model_dir(dataset: Dataset, cfg: TrainConfig, data_dir: str | Path) -> Path:
    """Where :func:`run` keeps the trained model of ``cfg`` (``study.learn.train.load`` reads it): one folder
    per config and dataset, whether or not the run was scored on the test split."""
    return Path(data_dir) / "models" / run_key(dataset, cfg, test=False)


def cached(dataset: Dataset, cfg: TrainConfig, data_dir: str | Path, test: bool = True) -> dict[str, Any] | None:
    """The cached record of this run, or None if there is none (or it is damaged, or the dataset has no key)."""
    key = run_key(dataset, cfg, test)
    path = record_path(data_dir, key)
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


def run(dataset: Dataset, cfg: TrainConfig, data_dir: str | Path, test: bool = True) -> dict[str, Any]:
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
    key = run_key(dataset, cfg, test)
    path = record_path(data_dir, key)
    reused = _score_kept_model(dataset, cfg, data_dir, key) if test else _without_test(dataset, cfg, data_dir, key)
    if reused is not None:
        cache.write_text_atomic(path, json.dumps(reused, indent=1) + "\n")
        return reused
    t0 = time.perf_counter()
    tm = train.fit(dataset, cfg, progress=False, warn=False)  # a failed run is counted, not warned about
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


def trained(dataset: Dataset, cfg: TrainConfig, data_dir: str | Path) -> train.TrainedModel:
    """The kept model of a run :func:`run` trained (``study.learn.train.load``)."""
    return train.load(model_dir(dataset, cfg, data_dir))


def row(rec: dict[str, Any], dataset: Dataset, *fields: str) -> dict[str, Any]:
    """A tidy row of one record: the named config fields, then the run's headline numbers; with a test score,
    ``correct``: (n,) bool, which test trajectories it got right (for intervals)."""
    out = {f: rec["config"][f] for f in fields}
    out.update(seed=rec["config"]["seed"], val_accuracy=rec["val_accuracy"], val_loss=rec["val_loss"],
               epochs=rec["epochs_run"], best_epoch=rec["best_epoch"], seconds=rec["train_seconds"],
               failed=rec["failed"], diverged_epoch=rec["diverged_epoch"],
               capped=rec["epochs_run"] >= rec["config"]["max_epochs"] and rec["diverged_epoch"] is None)
    if rec["test"] is not None:
        pred = np.asarray(rec["test"]["p_heavy"]) > 0.5
        out.update(accuracy=rec["test"]["accuracy"], correct=pred == (np.asarray(dataset.test.y) == 1),
                   **{f"accuracy_{c}": a for c, a in rec["test"]["per_class_accuracy"].items()})
    return out


# ---------------------------------------------------------------------------------------------
# Where runs are trained


@lru_cache(maxsize=4)
def _dataset_at(path: str) -> Dataset:
    """A dataset file read once per worker process (checked against its checksum)."""
    return data.load(path)


def train_task(dataset: Dataset | str, cfg: TrainConfig, data_dir: str, test: bool, key: str) -> dict[str, Any]:
    """What a worker runs: :func:`run`, after checking that it computes the submitter's ``key`` for it.

    ``dataset`` is the dataset itself (a Dask worker gets it scattered once) or the path of its file (a
    local pool's worker reads it once).
    """
    ds = _dataset_at(dataset) if isinstance(dataset, str) else dataset
    mine = run_key(ds, cfg, test)
    if mine != key:
        raise WorkerError(
            f"worker {os.uname().nodename} (pid {os.getpid()}) computes run key {mine} where the submitter computed "
            f"{key}: its study code, torch or compiled loop (backend {native.backend()}, build {native.build_id() or '-'}) "
            "differ; install the same package on every worker, with the same compiler, on one kind of CPU"
        )
    return run(ds, cfg, data_dir, test)


_CLUSTERS: list = []
"""The LocalClusters this process started, kept alive as long as it runs."""


@lru_cache(maxsize=1)
def _local_cluster(workers: int) -> str:
    """The address of a ``LocalCluster`` started once per process: one single-threaded worker process per
    core, listening on the loopback address only (a Dask scheduler runs whatever code reaches it)."""
    cluster = local_cluster(workers)
    _CLUSTERS.append(cluster)
    return cluster.scheduler_address


@lru_cache(maxsize=4)
def client(scheduler: str, workers: int = 0):
    """A Dask client for ``scheduler`` (``"local"``: :func:`_local_cluster`), connected once per process, with
    the TLS and authentication settings of the user's Dask configuration."""
    from distributed import Client
    from distributed.security import Security

    address = _local_cluster(workers or default_workers()) if scheduler == "local" else scheduler
    return Client(address, security=Security(), set_as_default=False)


@contextlib.contextmanager
def _executor(datasets: Sequence[Dataset], n: int, workers: int, scheduler: str | None) -> Iterator[tuple[Executor, list]]:
    """An executor for ``n`` runs on ``datasets`` and what to send its workers for each dataset: its path for a
    local pool (each worker reads the file once), or a Dask future of it scattered to every worker once."""
    if scheduler:
        c = client(scheduler, workers)
        yield c.get_executor(), [c.scatter(ds, broadcast=True, hash=False) for ds in datasets]
        return
    refs: list = [str(ds.path) if ds.path is not None else ds for ds in datasets]
    ctx = multiprocessing.get_context("spawn")  # no fork of a process that holds torch threads
    with ProcessPoolExecutor(min(workers, n), mp_context=ctx) as pool:
        yield pool, refs


def run_many(jobs: Sequence[tuple[Dataset, TrainConfig, bool]], data_dir: str | Path, *, desc: str = "runs",
             progress: bool = False, workers: int | None = None, scheduler: str | None = None) -> list[dict]:
    """The records of ``jobs`` (dataset, config, scored on the test split?) in order: cached ones read, the others
    trained together, in ``workers`` local processes (``None``: :func:`default_workers`) or on the Dask
    ``scheduler``, longest inputs first, so that no core idles while another run could start.

    Every run is seeded and single-threaded (see :mod:`study.learn.train`), so running them in parallel
    processes, or on a cluster, gives the same records as running them one by one (tested).
    """
    workers = default_workers() if workers is None else workers
    records = [cached(ds, c, data_dir, test) for ds, c, test in jobs]
    todo = [i for i, r in enumerate(records) if r is None]
    # Longest inputs first, so the last runs to finish are short ones and no core idles long at the end.
    todo.sort(key=lambda i: -jobs[i][1].n_frames(jobs[i][0].fps))
    note = f"{len(jobs) - len(todo)} of {len(jobs)} cached" if len(todo) < len(jobs) else ""
    with Progress(desc, total=len(todo), show=progress and bool(todo), note=note, unit="run") as bar:
        if scheduler or (workers > 1 and len(todo) > 1):
            datasets = list({id(jobs[i][0]): jobs[i][0] for i in todo}.values())
            index = {id(ds): k for k, ds in enumerate(datasets)}
            with _executor(datasets, len(todo), workers, scheduler) as (pool, refs):
                futures = {}
                for i in todo:
                    ds, c, test = jobs[i]
                    futures[pool.submit(train_task, refs[index[id(ds)]], c, str(data_dir), test, run_key(ds, c, test))] = i
                for f in as_completed(futures):
                    records[futures[f]] = f.result()
                    bar.update()
        else:
            for i in todo:
                ds, c, test = jobs[i]
                records[i] = run(ds, c, data_dir, test)
                bar.update()
    return records


def run_all(dataset: Dataset, cfgs: Sequence[TrainConfig], data_dir: str | Path, test: bool, *, desc: str = "runs",
            progress: bool = False, workers: int | None = None, scheduler: str | None = None) -> list[dict]:
    """:func:`run_many` of ``cfgs`` on one ``dataset``."""
    return run_many([(dataset, c, test) for c in cfgs], data_dir, desc=desc, progress=progress, workers=workers,
                    scheduler=scheduler)


# ---------------------------------------------------------------------------------------------
# What a build trains


class Plan:
    """The runs a runner was asked for: their models (one per dataset and config, whether scored on the test
    split or not) and the records that hold their training times.

    Where :data:`PLAN_ENV` names a file (``study book`` sets one per chapter), each run is also appended to it
    as a JSON line, so the builder can count the distinct models of the whole book and sum their CPU time.
    """

    def __init__(self, path: str | Path | None = None) -> None:
        self.models: dict[str, str] = {}
        """Model key -> the path of a record of that run."""
        self.path = Path(path) if path else None

    @classmethod
    def from_env(cls) -> Plan:
        return cls(os.environ.get(PLAN_ENV) or None)

    def add(self, dataset: Dataset, cfg: TrainConfig, data_dir: str | Path, test: bool) -> None:
        """Record that the run of ``cfg`` on ``dataset`` is part of this plan."""
        model = run_key(dataset, cfg, test=False)
        record = str(record_path(Path(data_dir).resolve(), run_key(dataset, cfg, test)))
        if model in self.models:
            return
        self.models[model] = record
        if self.path is not None:
            with contextlib.suppress(OSError), open(self.path, "a") as f:
                f.write(json.dumps({"model": model, "record": record}) + "\n")

    @property
    def n_models(self) -> int:
        """Distinct models: what a build from an empty cache trains."""
        return len(self.models)
