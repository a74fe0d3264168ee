"""Training and evaluating the classifier: ``fit(dataset, cfg)``, and the truncated loss it trains on.

``fit(dataset, cfg)`` trains on the dataset's train split only: a seeded permutation carves a validation split off
it for early stopping (``study.learn.inputs``), and the test split is left to :func:`evaluate`. A cell with a
stacked form (the peephole LSTM, the same without peepholes, the GRU) trains as a stack of one
(``study.learn.stack``: many runs of one shape train together there, each exactly as it trains alone); ``nn.LSTM``
(``'torch-lstm'``) trains alone in :func:`_fit_alone`.

Truncated back-propagation through time (Williams & Zipser's BPTT(k)): the only loss is the
cross-entropy of the prediction at the last frame T. With ``truncation = k < T`` the first ``T - k``
frames run under ``torch.no_grad()`` and only hand their state on, so the loss back-propagates
through the last ``k`` frames at most; with ``k >= T`` it is full BPTT.

Determinism: a run seeds everything from ``cfg.seed`` (the split permutation with NumPy; the weights, batch order
and dropout masks with torch, from a generator of its own started inside a forked RNG, so the caller's RNG is left
alone), turns on ``torch.use_deterministic_algorithms`` and runs on ``THREADS`` CPU threads, so the same config,
seed and data give bitwise-identical weights on the same machine. One thread, because floating-point reductions may
be split differently across thread counts, and because independent runs parallelise better as separate processes
(``study.experiments`` runs them so).
"""

from __future__ import annotations

import contextlib
import copy
import math
import warnings
from collections.abc import Iterator
from typing import Any

import numpy as np
import torch
import torch.nn.functional as F
from tqdm import tqdm

from study.core.errors import TrajectoryError
from study.learn import stack
from study.learn.config import DIMS, TrainConfig, select_inputs  # noqa: F401  (re-exported: train.TrainConfig)
from study.learn.inputs import (  # noqa: F401  (re-exported)
    OBSERVED_VIEWS,
    deterministic,
    epoch_inputs,
    normalisation,
    split_train_val,
)
from study.learn.metrics import metrics  # noqa: F401  (re-exported: train.metrics)
from study.learn.model import Classifier, Features
from study.learn.trained import (  # noqa: F401  (re-exported: train.TrainedModel, train.load)
    FILES,
    FORMAT,
    FORMATS,
    THREADS,
    TrainedModel,
    frame_logits,
    load,
    num_threads,
)
from study.simulate.data import Dataset, Split


class TrainingFailedWarning(UserWarning):
    """A run ended on the initial plateau (``TrainedModel.failed``): its model answers at chance."""


def fit(dataset: Dataset, cfg: TrainConfig, progress: bool = True, warn: bool = True,
        device: str | torch.device = "cpu") -> TrainedModel:
    """Train the classifier on ``dataset.train`` with ``cfg``; early-stop on a held-out part of it.

    A run that failed to train (``TrainedModel.failed``), or whose validation part is too small to tell, says so
    with a :class:`TrainingFailedWarning` naming what to change, unless ``warn`` is False (the experiments count
    such runs instead). ``device``: where a stacked cell trains (``"cuda"`` on a GPU); ``nn.LSTM`` trains on the
    CPU.

    Example::

        model = study.fit(ds, study.TrainConfig(length=1.0, epochs=5))   # one process, no pool
        model.save("my-model")
    """
    cfg.check()
    if len(dataset.train.y) < 2:
        raise TrajectoryError(f"training split has {len(dataset.train.y)} trajectories; need at least 2")
    select_inputs(dataset.train.x, cfg.dims, cfg.n_frames(dataset.fps), what="training split")  # a clear error
    if cfg.cell in stack.STACKABLE:
        bar = tqdm(total=cfg.epochs, desc=f"train {cfg.cell} {cfg.dims} {cfg.length:g}s", disable=not progress)
        with bar:
            tm = stack.train([(dataset, cfg)], device, on_epoch=lambda i, c: bar.update())
        tm = tm[0]
    else:
        tm = _fit_alone(dataset, cfg, progress)
    if warn and tm.training_state != "trained":
        warnings.warn(tm.failure(), TrainingFailedWarning, stacklevel=2)
    return tm


def last_logits(net: Classifier, x: torch.Tensor, truncation: int) -> torch.Tensor:
    """Logits (B, 2) at the last frame of ``x`` (B, T, D), gradients truncated to the last ``truncation`` frames."""
    T = x.shape[1]
    state = None
    if truncation < T:
        with torch.no_grad():
            _, state = net.encode(x[:, : T - truncation])  # carries the state; no graph is kept
    hs, _ = net.encode(x[:, max(0, T - truncation) :], state)  # (B, k, H)
    return net.logits(hs[:, -1])


def _loss(net: Classifier, x: torch.Tensor, y: torch.Tensor, cfg: TrainConfig) -> torch.Tensor:
    """The training loss of a batch: cross-entropy at the last frame, or the mean over every frame."""
    if cfg.loss_at == "every":
        logits = frame_logits(net, x)  # (B, T, 2)
        return F.cross_entropy(logits.reshape(-1, 2), y.repeat_interleave(x.shape[1]))
    return F.cross_entropy(last_logits(net, x, cfg.truncation), y)


@torch.no_grad()
def _loss_and_accuracy(net: Classifier, x: torch.Tensor, y: torch.Tensor, batch: int = 1024) -> tuple[float, float]:
    net.eval()
    logits = torch.cat([net(x[i : i + batch]) for i in range(0, len(x), batch)])
    return F.cross_entropy(logits, y).item(), (logits.argmax(1) == y).double().mean().item()


def evaluate(tm: TrainedModel, split: Split) -> dict[str, Any]:
    """Score ``tm`` on ``split`` (normally the test split): see :func:`metrics`.

    Example::

        res = study.evaluate(model, ds.test)
        print(res["accuracy"], res["per_class_accuracy"])
    """
    pred = tm.predict_proba(split.x).argmax(axis=1)
    return metrics(split.y, pred)


@contextlib.contextmanager
def _weights(params: list[torch.Tensor], values: list[torch.Tensor] | None) -> Iterator[None]:
    """``params`` holding ``values`` for the block (None: as they are), restored after."""
    if values is None:
        yield
        return
    saved = [p.detach().clone() for p in params]
    with torch.no_grad():
        torch._foreach_copy_(params, values)
    try:
        yield
    finally:
        with torch.no_grad():
            torch._foreach_copy_(params, saved)


def _fit_alone(dataset: Dataset, cfg: TrainConfig, progress: bool) -> TrainedModel:
    """The training loop of a cell without a stacked form (``'torch-lstm'``, ``nn.LSTM``): one run alone, its random
    numbers from torch's generator inside a fork seeded by ``cfg.seed``."""
    T = cfg.n_frames(dataset.fps)
    x = select_inputs(dataset.train.x, cfg.dims, T, what="training split")  # (n, T, D)
    y = np.asarray(dataset.train.y, dtype=np.int64)
    if len(y) < 2:
        raise TrajectoryError(f"training split has {len(y)} trajectories; need at least 2")
    tr, va = split_train_val(len(y), cfg.val_fraction, cfg.seed)
    view, x_val = epoch_inputs(dataset.train.x[:, :T], tr, va, cfg, dataset.fps)
    y_tr = torch.from_numpy(y[tr])
    x_va, y_va = torch.from_numpy(x_val), torch.from_numpy(y[va])
    features = Features(x.shape[2], cfg.inputs, dataset.fps)
    mean, std = normalisation(view(0), features)  # (C,) the training part's first view only

    with deterministic(cfg.seed):
        net = Classifier(x.shape[2], cfg.hidden, cfg.layers, cfg.dropout, cfg.cell, forget_bias=cfg.forget_bias,
                         chrono_frames=T if cfg.forget_init == "chrono" else None, inputs=cfg.inputs, fps=dataset.fps)
        net.set_normalisation(torch.from_numpy(mean).float(), torch.from_numpy(std).float())
        opt = torch.optim.Adam(net.parameters(), lr=cfg.lr, foreach=True)  # one kernel per update op for all tensors
        sched = (torch.optim.lr_scheduler.ReduceLROnPlateau(opt, factor=0.5, patience=max(1, cfg.patience // 4))
                 if cfg.lr_schedule == "plateau" else None)
        history: list[dict[str, float]] = []
        best_loss, best_epoch, best_state = math.inf, 0, copy.deepcopy(net.state_dict())
        diverged: int | None = None
        bar = tqdm(range(cfg.epochs), desc=f"train {cfg.cell} {cfg.dims} {cfg.length:g}s", disable=not progress)
        params = list(net.parameters())
        ema = [p.detach().clone() for p in params] if cfg.average == "ema" else None
        steps = 0  # optimiser steps so far
        for epoch in bar:
            lr = cfg.lr_at(epoch)  # a cosine budget sets each epoch's rate; the others set it as they go
            if lr is not None:
                opt.param_groups[0]["lr"] = lr
            net.train()
            x_tr = view(epoch)  # the same positions each epoch, or another observation of them
            order = torch.randperm(len(y_tr))
            total = 0.0
            for i in range(0, len(order), cfg.batch_size):
                idx = order[i : i + cfg.batch_size]
                loss = _loss(net, x_tr[idx], y_tr[idx], cfg)
                if not math.isfinite(loss.item()):
                    diverged = epoch  # a diverged run stops here, its last good weights kept, and says so
                    break
                opt.zero_grad(set_to_none=True)
                loss.backward()
                if cfg.clip_norm > 0:
                    torch.nn.utils.clip_grad_norm_(net.parameters(), cfg.clip_norm, foreach=True)
                opt.step()
                if ema is not None:
                    decay = cfg.ema_decay_at(steps)
                    torch._foreach_mul_(ema, decay)
                    torch._foreach_add_(ema, [p.detach() for p in params], alpha=1 - decay)
                steps += 1
                total += loss.item() * len(idx)
            if diverged is not None:
                history.append({"epoch": epoch, "train_loss": math.nan, "val_loss": math.nan, "val_accuracy": math.nan})
                break
            with _weights(params, ema):  # the averaged weights, where they are the ones kept
                val_loss, val_acc = _loss_and_accuracy(net, x_va, y_va)
                if val_loss < best_loss:
                    best_loss, best_epoch, best_state = val_loss, epoch, copy.deepcopy(net.state_dict())
            history.append({"epoch": epoch, "train_loss": total / len(y_tr), "val_loss": val_loss, "val_accuracy": val_acc,
                            "lr": opt.param_groups[0]["lr"]})
            bar.set_postfix(val_loss=f"{val_loss:.3f}", val_acc=f"{val_acc:.3f}")
            if sched is not None:
                sched.step(val_loss)
            if cfg.stops_early and epoch - best_epoch >= cfg.patience and epoch + 1 >= cfg.min_epochs:
                break
        net.load_state_dict(best_state)
        net.eval()
    return TrainedModel(net=net, config=cfg, fps=dataset.fps, data_key=dataset.key, history=history,
                        best_epoch=best_epoch, diverged_epoch=diverged, n_val=len(va))
