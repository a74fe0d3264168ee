"""Training the classifier: the recipe every run follows, written once, and the one loop that runs it.

Read top to bottom: :func:`fit` trains one run; :func:`train_runs` trains many runs of one shape together; below
them, the recipe -- :func:`optimiser` (Adam and the learning-rate schedule), :func:`step` (clipping, the update,
the weights' moving average), :func:`end_epoch` (the history, the best weights, the schedule, the stop) -- and the
loop that calls them. ``study.learn.stack`` holds only what running many runs in one pass needs (the stacked
forward pass, each member's data and random numbers); every cell, ``nn.LSTM`` included, trains through this loop.

``fit(dataset, cfg)`` trains on the dataset's train split only: a seeded permutation carves a validation split off
it for early stopping (``study.learn.inputs``), and the test split is left to :func:`evaluate`.

Truncated back-propagation through time (Williams & Zipser's BPTT(k)): the only loss is the
cross-entropy of the prediction at the last frame T. With ``truncation = k < T`` the first ``T - k``
frames run under ``torch.no_grad()`` and only hand their state on, so the loss back-propagates
through the last ``k`` frames at most; with ``k >= T`` it is full BPTT (``study.learn.stack.logits``).

Early stopping (:func:`end_epoch`): a run keeps the weights of its lowest validation loss and stops ``patience``
epochs after it, but never before ``min_epochs``, and patience starts counting only once the validation loss has
left the initial plateau (:data:`study.learn.metrics.PLATEAU_LOSS`): a run still on it after ``plateau_epochs`` has
failed to train and stops there, a slow starter gets that long to leave it, and a one-epoch blip on the plateau
cannot end a run that was about to leave it. The 'plateau' schedule waits for the same epoch before it halves.

Determinism: a run seeds everything from ``cfg.seed`` (the split permutation with NumPy; the weights, batch order
and dropout masks with torch, from a generator of its own started inside a forked RNG, so the caller's RNG is left
alone), turns on ``torch.use_deterministic_algorithms`` and runs on ``THREADS`` CPU threads, so the same config,
seed and data give bitwise-identical weights on the same machine, alone or in a stack. One thread, because
floating-point reductions may be split differently across thread counts, and because independent runs parallelise
better as separate processes (``study.runs`` runs them so).
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import torch
from tqdm import tqdm

from study.core.errors import TrajectoryError
from study.learn import native, stack
from study.learn.config import DIMS, TrainConfig, select_inputs  # noqa: F401  (re-exported: train.TrainConfig)
from study.learn.inputs import (  # noqa: F401  (re-exported)
    OBSERVED_VIEWS,
    deterministic,
    epoch_inputs,
    normalisation,
    split_train_val,
)
from study.learn.metrics import PLATEAU_LOSS, metrics  # noqa: F401  (re-exported: train.metrics)
from study.learn.model import Classifier  # noqa: F401  (re-exported: train.Classifier)
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
    such runs instead). ``device``: where it trains (``"cuda"`` on a GPU).

    Example::

        model = study.fit(ds, study.TrainConfig(length=1.0, epochs=5))   # one process, no pool
        model.save("my-model")
    """
    cfg.check()
    if len(dataset.train.y) < 2:
        raise TrajectoryError(f"training split has {len(dataset.train.y)} trajectories; need at least 2")
    select_inputs(dataset.train.x, cfg.dims, cfg.n_frames(dataset.fps), what="training split")  # a clear error
    bar = tqdm(total=cfg.epochs, desc=f"train {cfg.cell} {cfg.dims} {cfg.length:g}s", disable=not progress)
    with bar:
        tm = train_runs([(dataset, cfg)], device, on_epoch=lambda i, c: bar.update())[0]
    if warn and tm.training_state != "trained":
        warnings.warn(tm.failure(), TrainingFailedWarning, stacklevel=2)
    return tm


def train_runs(runs: Sequence[tuple[Dataset, TrainConfig]], device: str | torch.device = "cpu",
               on_epoch: Callable[[int, TrainConfig], None] | None = None) -> list[TrainedModel]:
    """Train every run of ``runs`` ((dataset, config) pairs of one ``study.learn.stack.Shape``) side by side;
    returns their :class:`TrainedModel`, in order, each bitwise what training it alone gives. ``on_epoch(i,
    cfg)`` is called after each epoch of run i (progress)."""
    if not runs:
        return []
    sh = stack.common_shape(runs)
    dev = torch.device(device)
    with stack.exact():
        members = [Run(stack.member(ds, cfg, dev)) for ds, cfg in runs]
        layout = stack.Layout.of(members[0].m.net)
        for epoch in range(max(r.cfg.epochs for r in members)):
            active = [r for r in members if not r.done and epoch < r.cfg.epochs]  # the stack shrinks
            if not active:
                break
            _train_epoch(active, layout, sh, epoch)
            alive = [r for r in active if r.diverged is None]
            if alive:
                scores = stack.validate([r.m for r in alive], [r.kept for r in alive], layout, sh)
                for r, (val_loss, val_acc) in zip(alive, scores):
                    end_epoch(r, epoch, val_loss, val_acc)
            for i, r in enumerate(members):
                if r in active and on_epoch is not None:
                    on_epoch(i, r.cfg)
    return [_finish(r, layout, ds) for r, (ds, _) in zip(members, runs)]


# ---------------------------------------------------------------------------------------------
# The recipe: one run's optimiser, step, epoch end and stop


@dataclass
class Run:
    """One run in training: its member of the stack (data, parameters, random numbers) and how its training goes."""

    m: stack.Member
    opt: torch.optim.Optimizer = field(init=False)
    sched: Any = field(init=False)
    """Its learning-rate schedule when it reacts to the validation loss ('plateau'), else None."""
    history: list[dict[str, float]] = field(default_factory=list)
    best_loss: float = math.inf
    best_epoch: int = 0
    best: torch.Tensor = field(init=False)
    """Its weights at its best validation epoch (at first: its initial weights) (P,)."""
    ema: torch.Tensor | None = field(init=False)
    """With ``average='ema'``: the moving average of its weights (P,), which is validated and kept instead."""
    left_plateau: int | None = None
    """The first epoch whose validation loss was below ``PLATEAU_LOSS``; None while it has not."""
    steps: int = 0
    """Optimiser steps it has taken (the average's warm-up counts them)."""
    diverged: int | None = None
    total: float = 0.0
    """This epoch's summed training loss."""
    done: bool = False

    def __post_init__(self) -> None:
        self.opt, self.sched = optimiser(self.m.flat, self.cfg)
        self.best = self.m.flat.detach().clone()
        self.ema = self.best.clone() if self.cfg.average == "ema" else None

    @property
    def cfg(self) -> TrainConfig:
        return self.m.cfg

    @property
    def kept(self) -> torch.Tensor:
        """The weights it validates and keeps (P,): the moving average with ``average='ema'``, else its own."""
        return self.ema if self.ema is not None else self.m.flat.detach()


def optimiser(params: torch.Tensor, cfg: TrainConfig) -> tuple[torch.optim.Optimizer, Any]:
    """Adam on ``params`` (one flat leaf (P,)) at ``cfg.lr``, and the schedule that reacts to the validation loss
    ('plateau': halve the rate once more than ``patience // 4`` epochs have passed without a lower loss, counted from
    the epoch the run left the initial plateau: :func:`end_epoch`), or None (a cosine budget sets each epoch's rate
    in :func:`_train_epoch`; 'constant' never changes it)."""
    opt = torch.optim.Adam([params], lr=cfg.lr, foreach=False)
    sched = (torch.optim.lr_scheduler.ReduceLROnPlateau(opt, factor=0.5, patience=max(1, cfg.patience // 4))
             if cfg.lr_schedule == "plateau" else None)
    return opt, sched


def step(r: Run, loss: float, n: int) -> None:
    """One optimiser step of ``r`` after its gradient is in: clip the gradient's norm to ``clip_norm``, update,
    fold the new weights into their moving average; ``loss`` (its batch's mean) over ``n`` items is counted."""
    if r.cfg.clip_norm > 0:
        torch.nn.utils.clip_grad_norm_([r.m.flat], r.cfg.clip_norm, foreach=False)
    r.opt.step()
    if r.ema is not None:
        decay = r.cfg.ema_decay_at(r.steps)
        r.ema.mul_(decay).add_(r.m.flat.detach(), alpha=1 - decay)
    r.steps += 1
    r.total += loss * n


def end_epoch(r: Run, epoch: int, val_loss: float, val_acc: float) -> None:
    """The end of ``r``'s epoch: its history, its best weights, its schedule, and whether it stops.

    It stops ``patience`` epochs after its best one, not before ``min_epochs``, patience counted from the epoch
    its validation loss left the plateau; a run still on the plateau after ``plateau_epochs`` stops there. The
    'plateau' schedule, like patience, starts counting once the run has left the initial plateau: halving the rate
    while it is still there only kept it there (the cold build at 9217b0c: a run halved every 6 epochs, to 1/256 of
    its rate from epoch 49, never left)."""
    r.history.append({"epoch": epoch, "train_loss": r.total / len(r.m.y_tr), "val_loss": val_loss,
                      "val_accuracy": val_acc, "lr": r.opt.param_groups[0]["lr"]})
    if val_loss < r.best_loss:
        r.best_loss, r.best_epoch, r.best = val_loss, epoch, r.kept.clone()
    if r.left_plateau is None and val_loss < PLATEAU_LOSS:
        r.left_plateau = epoch
    if r.sched is not None and r.left_plateau is not None:  # halving on the plateau would only bury it there
        r.sched.step(val_loss)
    if not r.cfg.stops_early:
        return
    if r.left_plateau is None:
        r.done = epoch + 1 >= r.cfg.plateau_epochs
    else:
        r.done = epoch - max(r.best_epoch, r.left_plateau) >= r.cfg.patience and epoch + 1 >= r.cfg.min_epochs


def _train_epoch(active: list[Run], layout: stack.Layout, sh: stack.Shape, epoch: int) -> None:
    """One epoch for every active run, in lockstep: the same steps, each on its own batches."""
    for r in active:
        lr = r.cfg.lr_at(epoch)  # a cosine budget sets each epoch's rate; the others set it as they go
        if lr is not None:
            r.opt.param_groups[0]["lr"] = lr
        r.total = 0.0
    x_tr = {id(r): r.m.view(epoch) for r in active}  # the same positions each epoch, or another observation
    order = {id(r): torch.randperm(sh.n_train, generator=r.m.gen) for r in active}
    going = list(active)
    for i in range(0, sh.n_train, sh.batch_size):
        for r in going:  # weights no longer finite: diverged (its loss could only be NaN); its best weights kept
            if not native.all_finite(r.m.flat.detach()):
                r.diverged, r.done = epoch, True
        going = [r for r in going if r.diverged is None]
        if not going:
            return
        idx = [order[id(r)][i : i + sh.batch_size].to(r.m.y_tr.device) for r in going]
        x = torch.stack([x_tr[id(r)][j] for r, j in zip(going, idx)])  # (K, B, T, D)
        y = torch.stack([r.m.y_tr[j] for r, j in zip(going, idx)])  # (K, B)
        losses = stack.losses([r.m for r in going], x, y, layout, sh)
        values = torch.stack([loss.detach() for loss in losses]).tolist()  # one device sync for the stack
        finite = [(r, loss, v) for r, loss, v in zip(going, losses, values) if math.isfinite(v)]
        for r, v in zip(going, values):
            if not math.isfinite(v):
                r.diverged, r.done = epoch, True  # stops here, its best weights kept, and says so
        for r, _, _ in finite:
            r.opt.zero_grad(set_to_none=True)
        if finite:
            torch.stack([loss for _, loss, _ in finite]).sum().backward()
            for r, _, v in finite:
                step(r, v, len(idx[0]))
        going = [r for r, _, _ in finite]


def _finish(r: Run, layout: stack.Layout, dataset: Dataset) -> TrainedModel:
    """The run's :class:`TrainedModel`: its best epoch's weights in its classifier."""
    if r.diverged is not None:
        r.history.append({"epoch": r.diverged, "train_loss": math.nan, "val_loss": math.nan, "val_accuracy": math.nan})
    layout.load(r.m.net, r.best)
    r.m.net.eval()
    return TrainedModel(net=r.m.net.cpu(), config=r.cfg, fps=dataset.fps, data_key=dataset.key, history=r.history,
                        best_epoch=r.best_epoch, diverged_epoch=r.diverged, n_val=r.m.n_val)


# ---------------------------------------------------------------------------------------------
# Scoring


def evaluate(tm: TrainedModel, split: Split) -> dict[str, Any]:
    """Score ``tm`` on ``split`` (normally the test split): see :func:`metrics`.

    Example::

        res = study.evaluate(model, ds.test)
        print(res["accuracy"], res["per_class_accuracy"])
    """
    pred = (tm.predict_proba(split.x)[:, 1] > 0.5).astype(np.int64)  # heavy above 1/2 (runs.stats.label_of)
    return metrics(split.y, pred)
