"""Run records written straight into a runner's cache, so a chapter's computation can be tested on real code
paths without training: ``study.runs.records`` reads them as runs trained earlier.

    runner = Runner.open("smoke", data_dir=tmp_path)
    cache_records(runner, configs, score=lambda cfg: 0.7 if cfg.dims == "z" else 0.8)
    t1 = table1.compute(runner)    # reads every run from the cache: nothing trains
"""

from __future__ import annotations

import dataclasses
import json
from collections.abc import Callable, Iterable
from pathlib import Path

import numpy as np
import torch

from study.core.cache import write_text_atomic
from study.learn import train
from study.learn.config import DIMS, TrainConfig
from study.learn.metrics import failed_to_train, metrics, training_state
from study.learn.model import Classifier
from study.methods import rockets
from study.runs import records
from study.simulate.data import Dataset


def record(dataset: Dataset, cfg: TrainConfig, test: bool, accuracy: float, val_accuracy: float | None = None,
           val_loss: float = 0.45, seed: int = 0) -> dict:
    """A run record of ``cfg`` on ``dataset`` as ``records.run`` writes it: right on ``round(accuracy * n)`` of the n
    test throws (a seeded random subset) and on ``val_accuracy`` (default: ``accuracy``) of the validation split."""
    va = accuracy if val_accuracy is None else val_accuracy
    n_val = max(1, round(len(dataset.train.y) * cfg.val_fraction))
    rec = {
        "key": records.run_key(dataset, cfg, test), "format": records.RUN_FORMAT, "data_key": dataset.key,
        "config": dataclasses.asdict(cfg), "val_accuracy": va, "val_loss": val_loss, "n_val": n_val,
        "training": training_state(va, val_loss, n_val), "failed": failed_to_train(va, val_loss, n_val),
        "diverged_epoch": None, "best_epoch": 1, "epochs_run": 3,
        "history": [{"epoch": e, "val_loss": val_loss, "val_accuracy": va} for e in range(3)],
        "train_seconds": 1.0, "test": None,
    }
    if test:
        y = np.asarray(dataset.test.y)
        rng = np.random.default_rng([seed, cfg.seed, round(1e6 * accuracy)])
        right = np.zeros(len(y), bool)
        right[rng.permutation(len(y))[:round(accuracy * len(y))]] = True
        pred = np.where(right, y, 1 - y)
        p_heavy = np.where(pred == 1, 0.9, 0.1)
        rec["test"] = metrics(y, pred) | {"p_heavy": [float(p) for p in p_heavy]}
    return rec


def cache_records(runner, cfgs: Iterable[TrainConfig], score: Callable[[TrainConfig], float] = lambda c: 0.7,
                  test: bool = True, dataset: Dataset | None = None,
                  val_score: Callable[[TrainConfig], float] | None = None,
                  val_loss: Callable[[TrainConfig], float] | None = None) -> None:
    """Write a record of each of ``cfgs`` (on ``dataset``, default the runner's), scored on the test split if
    ``test``, right on ``score(cfg)`` of the test throws and ``val_score(cfg)`` (default ``score``) of the
    validation throws at a validation loss of ``val_loss(cfg)`` (default 0.45: it trained; 0.69, a coin's, fails),
    into the runner's cache (both the test-scored and the validation-only record, so every experiment reading either
    finds it)."""
    ds = dataset or runner.dataset
    for cfg in cfgs:
        for t in (True, False) if test else (False,):
            rec = record(ds, cfg, t, score(cfg), None if val_score is None else val_score(cfg),
                         0.45 if val_loss is None else val_loss(cfg))
            write_text_atomic(records.record_path(runner.data_dir, rec["key"]), json.dumps(rec) + "\n")


def cache_models(runner, cfgs: Iterable[TrainConfig], dataset: Dataset | None = None) -> None:
    """An untrained model of each of ``cfgs`` (its weights as initialised under ``torch.manual_seed(cfg.seed)``)
    saved where ``runner.trained`` looks for the kept model, so experiments that load models find them."""
    ds = dataset or runner.dataset
    for cfg in cfgs:
        torch.manual_seed(cfg.seed)
        net = Classifier(len(DIMS[cfg.dims]), cfg.hidden, cfg.layers, cfg.dropout, cfg.cell, inputs=cfg.inputs,
                         fps=ds.fps)
        train.TrainedModel(net, cfg, ds.fps, ds.key).save(records.model_dir(ds, cfg, runner.data_dir))


def cache_rocket(runner, dims: str, n_frames: int, seed: int, tests: dict[str, np.ndarray],
                 labels: dict[str, np.ndarray], train_x: np.ndarray | None = None) -> None:
    """A MiniRocket fit's record (``study.methods.rockets``) whose labels on each of ``tests`` are ``labels``,
    so ``runner.rocket(dims, n_frames, seed, tests, train_x)`` reads them instead of fitting."""
    key = rockets.rocket_key(runner.dataset, dims, n_frames, seed, tests, train_x)  # type: ignore[arg-type]
    body = {"key": key, "format": rockets.FORMAT, "predictions": {k: np.asarray(v).tolist() for k, v in labels.items()}}
    write_text_atomic(Path(runner.data_dir) / "rocket" / f"{key}.json", json.dumps(body) + "\n")
