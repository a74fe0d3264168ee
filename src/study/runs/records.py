"""One trained run, cached, and a stack of them trained at once: the records every experiment reads.

A run's record (metrics, test predictions and training history, not weights) is a JSON file in
``data_dir/runs/``, named by :func:`run_key`: a hash of the dataset's key, the :class:`TrainConfig`,
whether the test split was scored, the code that makes a record (this module's import closure:
``study.core.cache.code_hash("run")``, the training with it), the torch version, the time loop that ran
(compiled for this CPU, or PyTorch's) and the device. It is written atomically, so a rebuild never retrains a
run whose inputs did not change, and a run trained anywhere that shares ``data_dir`` is a hit everywhere. Its
kept model lies in :func:`model_dir`. :func:`train_stack` trains several runs of one shape as one stack
(``study.learn.stack``), each writing the record it would write alone; ``study.runs.schedule`` decides
which runs train where.

"""

from __future__ import annotations

import dataclasses
import json
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import torch

from study.core import cache
from study.core.errors import ModelError
from study.learn import native, stack, train
from study.learn.train import TrainConfig
from study.simulate.data import Dataset

RUN_FORMAT = "study.run/4"
"""Format 2 added the test split's per-trajectory probabilities, the diverged epoch and the failed flag; format 3
what the validation part says of the run (``training``: trained, failed, or too few to tell) and the device; format 4
the data's frame rate (``fps``: with the config's length and truncation, whether back-propagation was truncated)."""


# ---------------------------------------------------------------------------------------------
# One run, cached


def device_name(device: str | torch.device = "cpu") -> str:
    """What a run's key says of where it trained: ``"cpu"``, or the GPU's kind (``"cuda: NVIDIA H200"``), whose
    kernels round otherwise (and may change with the stack's size: cuBLAS chooses them by shape)."""
    d = torch.device(device)
    return "cpu" if d.type == "cpu" else f"{d.type}: {torch.cuda.get_device_name(d)}"


def run_key(dataset: Dataset, cfg: TrainConfig, test: bool, device: str | torch.device = "cpu") -> str:
    """The cache key of one trained run."""
    return cache.key({
        "format": RUN_FORMAT, "data": dataset.key, "config": dataclasses.asdict(cfg), "test": test,
        "code": cache.code_hash("run"), "torch": torch.__version__, "device": device_name(device),
        # the compiled loop is built for this CPU and rounds differently from PyTorch's: either changes a run
        "backend": native.backend(), "build": native.build_id(),
    })


def record_path(data_dir: str | Path, key: str) -> Path:
    """Where the record of the run ``key`` lives."""
    return Path(data_dir) / "runs" / f"{key}.json"


def model_dir(dataset: Dataset, cfg: TrainConfig, data_dir: str | Path, device: str | torch.device = "cpu") -> Path:
    """Where :func:`run` keeps the trained model of ``cfg`` (``study.learn.train.load`` reads it): one folder
    per config, dataset and device, whether or not the run was scored on the test split."""
    return Path(data_dir) / "models" / run_key(dataset, cfg, False, device)


def cached(dataset: Dataset, cfg: TrainConfig, data_dir: str | Path, test: bool = True,
           device: str | torch.device = "cpu") -> dict[str, Any] | None:
    """The cached record of this run, or None if there is none (or it is damaged, or the dataset has no key)."""
    key = run_key(dataset, cfg, test, device)
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


def run(dataset: Dataset, cfg: TrainConfig, data_dir: str | Path, test: bool = True,
        device: str | torch.device = "cpu") -> dict[str, Any]:
    """Train ``cfg`` on ``dataset`` (or read the cached result) and return its record: :func:`train_stack` of one."""
    return train_stack([(dataset, cfg, test)], data_dir, device)[0]


def train_stack(jobs: Sequence[tuple[Dataset, TrainConfig, bool]], data_dir: str | Path,
                device: str | torch.device = "cpu") -> list[dict[str, Any]]:
    """The records of ``jobs`` (dataset, config, scored on the test split?), each read from the cache, made from a
    kept model, or trained: those left train side by side (``study.learn.train.train_runs``), one stack per shape
    (``study.learn.stack.shape``).

    A record holds the config, the validation accuracy and loss at the kept epoch, what the validation part says
    of the run (``training``; ``failed`` when it failed to train), whether it diverged (and when), the epochs run,
    the history, the training time, wall and process CPU (a stack's shared evenly by its members) and, if ``test``,
    the test metrics
    with every test trajectory's probability of heavy. A member's record is the one it would have alone. The
    trained model itself is saved in :func:`model_dir`. A dataset without a key is never cached.
    """
    records: list[dict[str, Any] | None] = [cached(ds, c, data_dir, t, device) for ds, c, t in jobs]
    todo = []
    for i, (ds, c, t) in enumerate(jobs):
        if records[i] is not None:
            continue
        key = run_key(ds, c, t, device)
        reused = (_score_kept_model(ds, c, data_dir, key, device) if t else _without_test(ds, c, data_dir, key, device))
        if reused is not None:
            cache.write_text_atomic(record_path(data_dir, key), json.dumps(reused, indent=1) + "\n")
            records[i] = reused
        else:
            todo.append(i)
    groups: dict[object, list[int]] = {}
    for i in todo:  # one stack per shape
        ds, c, _ = jobs[i]
        groups.setdefault(stack.shape(ds, c), []).append(i)
    for group in groups.values():
        t0, c0 = time.perf_counter(), time.process_time()
        models = train.train_runs([(jobs[i][0], jobs[i][1]) for i in group], device)
        seconds = (time.perf_counter() - t0) / len(group)
        cpu = (time.process_time() - c0) / len(group)
        for i, tm in zip(group, models):
            records[i] = _record(jobs[i][0], jobs[i][1], jobs[i][2], tm, seconds, cpu, data_dir, device)
    return records  # type: ignore[return-value]


def _record(dataset: Dataset, cfg: TrainConfig, test: bool, tm: train.TrainedModel, seconds: float, cpu: float,
            data_dir: str | Path, device: str | torch.device) -> dict[str, Any]:
    """The record of a run just trained, written to the cache with its model."""
    key = run_key(dataset, cfg, test, device)
    if dataset.key:
        tm.save(model_dir(dataset, cfg, data_dir, device))  # so a chapter that needs this very model loads it
    best = tm.history[tm.best_epoch]
    record = {
        "key": key, "format": RUN_FORMAT, "data_key": dataset.key, "fps": dataset.fps, "config": dataclasses.asdict(cfg),
        "device": device_name(device), "val_accuracy": tm.val_accuracy, "val_loss": best["val_loss"],
        "n_val": tm.n_val, "training": tm.training_state, "failed": tm.failed, "diverged_epoch": tm.diverged_epoch,
        "best_epoch": tm.best_epoch, "epochs_run": len(tm.history), "history": tm.history,
        "train_seconds": seconds, "cpu_seconds": cpu, "test": _test_scores(tm, dataset) if test else None,
    }
    if dataset.key:
        cache.write_text_atomic(record_path(data_dir, key), json.dumps(record, indent=1) + "\n")
    return record


def _score_kept_model(dataset: Dataset, cfg: TrainConfig, data_dir: str | Path, key: str,
                      device: str | torch.device) -> dict[str, Any] | None:
    """The test-scored record of ``cfg`` from the same run made without the test split (a grid run is such a
    run), its kept model scored on the test split instead of training it again; None if absent.

    Training is seeded and deterministic, so this is the record a new run would give (its
    ``train_seconds`` are those of the original run).
    """
    base = cached(dataset, cfg, data_dir, False, device)
    if base is None:
        return None
    try:
        tm = train.load(model_dir(dataset, cfg, data_dir, device))  # the folder's name is the key of (data, cfg)
    except (ModelError, OSError):
        return None
    return {**base, "key": key, "test": _test_scores(tm, dataset)}


def _without_test(dataset: Dataset, cfg: TrainConfig, data_dir: str | Path, key: str,
                  device: str | torch.device) -> dict[str, Any] | None:
    """The validation-only record of ``cfg`` from the same run scored on the test split, if there is one."""
    scored = cached(dataset, cfg, data_dir, True, device)
    return None if scored is None else {**scored, "key": key, "test": None}


def trained(dataset: Dataset, cfg: TrainConfig, data_dir: str | Path,
            device: str | torch.device = "cpu") -> train.TrainedModel:
    """The kept model of a run :func:`run` trained (``study.learn.train.load``)."""
    return train.load(model_dir(dataset, cfg, data_dir, device))
