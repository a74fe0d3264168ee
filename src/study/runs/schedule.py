"""Where and how runs train: which runs share a stack, which worker trains it, and what a build asked for.

:func:`run_many` reads the cached records of a list of runs and trains the others through a
``concurrent.futures`` executor: a local pool of spawned processes, one per CPU, or a Dask ``distributed``
client's executor when given a scheduler (``"local"`` starts a ``LocalCluster`` on the loopback address; anything
else is a scheduler's address, reached with the security settings of the user's Dask configuration). Runs of one
shape (``study.learn.stack.shape``) go to a worker as stacks of up to :func:`stack_size` members (on the CPU one:
measured, ``benchmarks/bench_stack.py``, a stack trains no faster per run there), the longest inputs first, so that
the last to finish are short and no core idles long at the end. The key of every run is computed where it is
submitted and checked again where it trains: a worker whose code, torch or compiled loop differs refuses, rather
than write a record under another key.

:class:`Trainer` is the build's: one pool for the whole build, a chapter's runs submitted when it stops for them,
each run once whichever chapter asked first.

:class:`Plan` notes every run a runner was asked for, so a build knows how many models it trained.
"""

from __future__ import annotations

import contextlib
import dataclasses
import json
import multiprocessing
import os
import sys
from collections.abc import Sequence
from concurrent.futures import Executor, Future, ProcessPoolExecutor, as_completed
from functools import lru_cache
from pathlib import Path
from typing import Any

import torch
from tqdm import tqdm

from study.core import ticket
from study.core.errors import StudyError
from study.core.progress import Progress
from study.learn import native, stack
from study.learn.train import TrainConfig
from study.runs.cluster import default_workers, local_cluster
from study.runs.records import cached, record_path, run_key, train_stack
from study.simulate import data
from study.simulate.data import Dataset

STACK_SIZES = {"cpu": 1, "cuda": 64}
"""Members per stack by device type. On this study's CPUs a stack of K trains no faster per run than K runs one at a
time (``benchmarks/bench_stack.py``: 0.97x at K = 2, 0.93x at K = 5, 0.81x at K = 10 on a 2-core AMD EPYC; the
time loops and the weight gradients are 80 % of a step and already at the core's BLAS speed), so the CPU trains
runs one at a time, one per core; a GPU batches the products of many."""

Job = tuple[Dataset, TrainConfig, bool]
"""One run: its data set, its config, whether it is scored on the test split."""


class WorkerError(StudyError):
    """A worker computes another key for the run it was sent: its code, torch or compiled loop differ."""


def stack_size(device: str | torch.device = "cpu") -> int:
    """How many runs of one shape :func:`run_many` trains as one stack on ``device`` (:data:`STACK_SIZES`)."""
    return STACK_SIZES.get(torch.device(device).type, 1)


@lru_cache(maxsize=4)
def _dataset_at(path: str) -> Dataset:
    """A dataset file read once per worker process (checked against its checksum)."""
    return data.load(path)


def stack_task(members: Sequence[tuple[Dataset | str, TrainConfig, bool, str]], data_dir: str,
               device: str = "cpu") -> list[dict[str, Any]]:
    """What a worker runs: ``study.runs.records.train_stack`` of ``members`` (dataset or its file, config, test
    flag, the submitter's key), after checking that it computes each submitter's key.

    A dataset is the dataset itself (a Dask worker gets it scattered once) or the path of its file (a local pool's
    worker reads it once)."""
    jobs = []
    for dataset, cfg, test, key in members:
        ds = _dataset_at(dataset) if isinstance(dataset, str) else dataset
        mine = run_key(ds, cfg, test, device)
        if mine != key:
            raise WorkerError(
                f"worker {os.uname().nodename} (pid {os.getpid()}) computes run key {mine} where the submitter "
                f"computed {key}: its study code, torch or compiled loop (backend {native.backend()}, build "
                f"{native.build_id() or '-'}) differ; install the same package on every worker, with the same "
                "compiler, on one kind of CPU"
            )
        jobs.append((ds, cfg, test))
    return train_stack(jobs, data_dir, device)


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


def stacks(jobs: Sequence[Job], indices: Sequence[int], size: int) -> list[list[int]]:
    """The ``indices`` of ``jobs`` as stacks: runs of one shape together, at most ``size`` a stack, the longest
    inputs first."""
    groups: dict[object, list[int]] = {}
    for i in indices:
        ds, c, _ = jobs[i]
        groups.setdefault(stack.shape(ds, c), []).append(i)
    out = [g[k : k + size] for g in groups.values() for k in range(0, len(g), size)]
    return sorted(out, key=lambda s: -jobs[s[0]][1].n_frames(jobs[s[0]][0].fps))


class Trainer:
    """Runs trained as they are asked for, on one pool kept for a whole build: :meth:`submit` hands a chapter's
    runs to the workers at once (in stacks, :func:`stacks`), and the chapter waits for its own runs only -- no
    barrier between chapters, no pool started per batch. A run trained or in training already is not submitted
    again. ``with Trainer(...) as t:``; leaving it waits for the runs in flight."""

    def __init__(self, data_dir: str | Path, *, workers: int | None = None, scheduler: str | None = None,
                 device: str = "cpu", progress: bool = False) -> None:
        self.data_dir, self.device, self.scheduler = Path(data_dir), device, scheduler
        self.workers = default_workers() if workers is None else workers
        self.futures: dict[str, Future] = {}
        """Run key -> the future of the stack that trains it."""
        self._place: dict[str, int] = {}
        """Run key -> its place in its stack's list of records."""
        self._exit = contextlib.ExitStack()
        self._refs: dict[str, Any] = {}
        self._pool: Executor | None = None
        self._open = False
        self._bar = tqdm(total=0, desc="runs", unit="run", disable=not progress, file=sys.stderr)

    def __enter__(self) -> Trainer:
        self._open = True
        return self

    def _executor(self) -> Executor:
        """The pool, started at the first run to train (a build that trains nothing reaches no cluster)."""
        if self._pool is None:
            if self.scheduler:
                self._client = client(self.scheduler, self.workers)
                self._pool = self._client.get_executor()
            else:
                ctx = multiprocessing.get_context("spawn")  # no fork of a process that holds torch threads
                self._pool = self._exit.enter_context(ProcessPoolExecutor(max(1, self.workers), mp_context=ctx))
        return self._pool

    def __exit__(self, kind: type | None, *exc: object) -> None:
        if kind is not None and self._pool is not None:  # the build failed: nothing more to train
            self._pool.shutdown(wait=False, cancel_futures=True)
        self._exit.close()
        self._bar.close()
        self._open = False

    def trained(self) -> set[str]:
        """The keys of the runs this trainer has finished training."""
        return {k for k, f in self.futures.items() if f.done() and not f.exception()}

    def _ref(self, ds: Dataset) -> Any:
        if self.scheduler:  # scattered to every worker once
            if ds.key not in self._refs:
                self._refs[ds.key] = self._client.scatter(ds, broadcast=True, hash=False)
            return self._refs[ds.key]
        return str(ds.path) if ds.path is not None else ds  # a file: each worker reads it once

    def submit(self, jobs: Sequence[Job]) -> list[Future]:
        """The futures of ``jobs``' runs not cached yet (each once), training from now on: the ones submitted
        here and the ones another call submitted first."""
        if not self._open:
            raise StudyError("Trainer.submit outside its 'with' block")
        keys = [run_key(ds, c, t, self.device) for ds, c, t in jobs]
        first: dict[str, int] = {}
        for i, k in enumerate(keys):
            first.setdefault(k, i)  # each run once, in the order asked
        fresh = [i for k, i in first.items()
                 if k not in self.futures and cached(*jobs[i][:2], self.data_dir, jobs[i][2], self.device) is None]
        for unit in stacks(jobs, fresh, stack_size(self.device)):
            pool = self._executor()  # first: a Dask client is what scatters the data sets
            members = [(self._ref(jobs[i][0]), jobs[i][1], jobs[i][2], keys[i]) for i in unit]
            f = pool.submit(stack_task, members, str(self.data_dir), self.device)
            f.add_done_callback(lambda _, n=len(unit): self._bar.update(n))
            for place, i in enumerate(unit):
                self.futures[keys[i]] = f
                self._place[keys[i]] = place
        self._bar.total += len(fresh)
        self._bar.refresh()
        return list(dict.fromkeys(self.futures[k] for k in first if k in self.futures))

    def record(self, key: str) -> dict[str, Any]:
        """The record of the run of ``key`` this trainer trained (waits for it; a worker's error raised here)."""
        return self.futures[key].result()[self._place[key]]


def run_many(jobs: Sequence[Job], data_dir: str | Path, *, desc: str = "runs", progress: bool = False,
             workers: int | None = None, scheduler: str | None = None, device: str = "cpu") -> list[dict]:
    """The records of ``jobs`` (dataset, config, scored on the test split?) in order: cached ones read, the others
    trained in stacks (:func:`stacks`), in ``workers`` local processes (``None``: one per CPU) or on the Dask
    ``scheduler``, on ``device``.

    Every run is seeded and single-threaded, and a member's result does not depend on its stack, so running them in
    parallel processes, in stacks, or on a cluster gives the same records as running them one by one (tested).
    """
    workers = default_workers() if workers is None else workers
    records = [cached(ds, c, data_dir, test, device) for ds, c, test in jobs]
    todo = [i for i, r in enumerate(records) if r is None]
    units = stacks(jobs, todo, stack_size(device))
    note = f"{len(jobs) - len(todo)} of {len(jobs)} cached" if len(todo) < len(jobs) else ""
    with Progress(desc, total=len(todo), show=progress and bool(todo), note=note, unit="run") as bar:
        if scheduler or (workers > 1 and len(units) > 1):
            pool = workers if scheduler else min(workers, len(units))
            with Trainer(data_dir, workers=pool, scheduler=scheduler, device=device) as trainer:
                futures = trainer.submit([jobs[i] for i in todo])
                for f in as_completed(futures):
                    bar.update(len(f.result()))
                for i in todo:
                    records[i] = trainer.record(run_key(*jobs[i], device))
        else:
            for unit in units:
                for i, rec in zip(unit, train_stack([jobs[i] for i in unit], data_dir, device)):
                    records[i] = rec
                bar.update(len(unit))
    return records


def run_all(dataset: Dataset, cfgs: Sequence[TrainConfig], data_dir: str | Path, test: bool, *, desc: str = "runs",
            progress: bool = False, workers: int | None = None, scheduler: str | None = None,
            device: str = "cpu") -> list[dict]:
    """:func:`run_many` of ``cfgs`` on one ``dataset``."""
    return run_many([(dataset, c, test) for c in cfgs], data_dir, desc=desc, progress=progress, workers=workers,
                    scheduler=scheduler, device=device)


# ---------------------------------------------------------------------------------------------
# What a build trains


class Plan:
    """The runs a runner was asked for: their models (one per dataset and config, whether scored on the test
    split or not) and the records that hold their training times.

    Where the chapter's ticket names a plan file (``study book`` gives one per chapter), each run is also appended to it
    as a JSON line, so the builder can count the distinct models of the whole book and sum their CPU time.
    """

    def __init__(self, path: str | Path | None = None) -> None:
        self.models: dict[str, str] = {}
        """Model key -> the path of a record of that run."""
        self.path = Path(path) if path else None

    @classmethod
    def from_env(cls) -> Plan:
        return cls(ticket.current().plan or None)

    def add(self, dataset: Dataset, cfg: TrainConfig, data_dir: str | Path, test: bool, device: str = "cpu") -> None:
        """Record that the run of ``cfg`` on ``dataset`` is part of this plan."""
        model = run_key(dataset, cfg, False, device)
        record = str(record_path(Path(data_dir).resolve(), run_key(dataset, cfg, test, device)))
        if model in self.models:
            return
        self.models[model] = record
        if self.path is not None:
            with contextlib.suppress(OSError), open(self.path, "a") as f:
                f.write(json.dumps({"model": model, "record": record}) + "\n")

    def reject(self, dataset: Dataset, cfg: TrainConfig, device: str = "cpu") -> None:
        """Record that the run of ``cfg`` on ``dataset``, trained as a candidate, was not chosen (a rate its
        chapter's validation turned down): the build's list of failed runs gives it that reason. A line with no
        record, so the plan's totals count the run once, where it was added."""
        if self.path is not None:
            with contextlib.suppress(OSError), open(self.path, "a") as f:
                f.write(json.dumps({"model": run_key(dataset, cfg, False, device), "rejected": True}) + "\n")

    @property
    def n_models(self) -> int:
        """Distinct models: what a build from an empty cache trains."""
        return len(self.models)


# ---------------------------------------------------------------------------------------------
# One plan per build: chapters ask, the builder trains

class Pending(StudyError):
    """A chapter asked for runs that are not trained yet, in a build that trains every chapter's runs together: it
    stops here, and the builder (which reads the runs from the chapter's ticket, not this exception) trains them
    with every other chapter's before executing it again."""


def planning() -> Path | None:
    """The file of runs still to train when a build plans its runs (the ticket's ``pending``), else None."""
    path = ticket.current().pending
    return Path(path) if path else None


def ask(jobs: Sequence[Job], data_dir: str | Path, device: str = "cpu") -> None:
    """In a planned build (:func:`planning`), stop with :class:`Pending` if any of ``jobs`` has no cached record,
    after writing them where the builder reads them; else do nothing."""
    path = planning()
    if path is None:
        return
    missing = [(ds, c, t) for ds, c, t in jobs if cached(ds, c, data_dir, t, device) is None]
    if not missing:
        return
    with open(path, "a") as f:
        for ds, c, t in missing:
            if ds.path is None:
                raise StudyError(f"a planned build needs the data set of key {ds.key} as a file; save it first "
                                 "(study.chapters.cues.saved) so the builder can train its runs")
            f.write(json.dumps({"dataset": str(ds.path), "config": dataclasses.asdict(c), "test": t}) + "\n")
    raise Pending(f"{len(missing)} runs are not trained yet; the build trains them with every chapter's, then "
                  "executes this chapter again")


def pending(path: Path) -> list[Job]:
    """The runs a planned build's chapters asked for (:func:`ask`), each once, in the order asked."""
    seen, out = set(), []
    for line in path.read_text().splitlines() if path.is_file() else []:
        entry = json.loads(line)
        ident = json.dumps(entry, sort_keys=True)
        if ident in seen:
            continue
        seen.add(ident)
        out.append((_dataset_at(entry["dataset"]), TrainConfig(**entry["config"]), bool(entry["test"])))
    return out
