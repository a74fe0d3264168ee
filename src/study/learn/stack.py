"""Many training runs as one: K classifiers of one shape trained side by side, each exactly as it would train alone.

A training step of one small classifier (batch 32, 64 units) leaves most of a core's time to dispatch: the
autograd graph, the head, the loss, the optimizer, copies. :func:`train` steps K runs (*members*) of the same
shape together: one forward and one backward pass over stacked tensors ``(K, ...)`` for all of them, the
recurrent layers' time loops called once per layer for all members, while every member keeps what makes it its
own run:

- its data (its dataset's training part, and its own observation draws: ``study.learn.train.epoch_inputs``),
  its normalisation, its validation part;
- its seed: its initial weights, batch order and dropout masks come from its own generator, started from the
  seed as a lone run starts (the weights drawn as ``Classifier`` draws them);
- its own parameters, a leaf tensor of its own, with its own Adam (learning rate, moments, step), its own
  learning-rate schedule and its own gradient clipping (the norm of its own gradient);
- its own early stopping and failure detection: a member that stops, or whose loss stops being finite, leaves
  the stack with its best epoch's weights, and the others go on.

**A member's result does not depend on its stack** (tested: a run trained alone, in a stack of 3 and in a stack of
8 gives bitwise-identical weights and history, on either time loop). What could make it depend is anything
computed across members; here each matrix product on the CPU is made member by member (a batched product may
choose its kernel by the batch), reductions and random numbers are per member, and the stacked elementwise
operations treat each element alone. On a GPU the products are batched (``torch.bmm``), which is where batching
pays; there a member's rounding may depend on the stack size (cuBLAS picks kernels by shape).

The compiled time loops (``peephole.cpp``, ``gru.cpp``) run member by member inside one layer call: each
member's per-step product is already at the core's speed (about 85 GFLOP/s at B = 32, H = 64, measured with the
BLAS PyTorch ships), and MKL's batched ``sgemm_batch`` measured no faster (77 GFLOP/s at K = 5), so the gain of a
stack is everything around the loops. ``benchmarks/bench_stack.py`` measures it.

Shapes: K members, B batch, T frames, D position dims, C channels the first layer reads, H hidden units, G gate
rows (4H for the LSTMs, 3H for the GRU). Tensors inside are time-major, ``(K, T, B, .)``.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np
import torch
import torch.nn.functional as F

from study.learn import gru, model, native, peephole
from study.learn.batched import baddbmm
from study.learn.config import DIMS, TrainConfig, select_inputs
from study.learn.inputs import (
    deterministic,
    epoch_inputs,
    normalisation,
    split_train_val,
)
from study.learn.model import Classifier
from study.learn.trained import THREADS, TrainedModel, num_threads
from study.simulate.data import Dataset

STACKABLE = ("peephole", "no-peephole", "gru")
"""Cells with a stacked form; ``'torch-lstm'`` (``nn.LSTM``) trains alone."""


@dataclass(frozen=True)
class Shape:
    """What the members of one stack share: everything that sets a tensor's shape or a step's structure."""

    frames: int
    """T: input frames."""
    dims: int
    """D: position dims (1 for Z, 3 for X, Y, Z)."""
    inputs: str
    """What the first layer reads ('positions' or 'velocity')."""
    fps: float
    """Frame rate (the velocity's scale)."""
    cell: str
    hidden: int
    layers: int
    batch_size: int
    truncation: int
    loss_at: str
    n_train: int
    """Trajectories in the training part: the same steps per epoch, the same last batch."""
    n_val: int
    """Trajectories in the validation part."""


# ---------------------------------------------------------------------------------------------
# The stacked classifier


@dataclass(frozen=True)
class Layout:
    """Where each parameter of one member's classifier lies in its flat vector (P,), P padded to a multiple of
    64 so that the stacked (K, P) rows start at the same place in every vector register whatever K is."""

    names: tuple[str, ...]
    """The classifier's parameter names, in ``named_parameters`` order."""
    shapes: tuple[tuple[int, ...], ...]
    offsets: tuple[int, ...]
    size: int
    """P: floats per member."""

    @classmethod
    def of(cls, net: Classifier) -> Layout:
        names, shapes, offsets, at = [], [], [], 0
        for name, p in net.named_parameters():
            names.append(name)
            shapes.append(tuple(p.shape))
            offsets.append(at)
            at += p.numel()
        return cls(tuple(names), tuple(shapes), tuple(offsets), -(-at // 64) * 64)

    def flat(self, net: Classifier) -> torch.Tensor:
        """The member's parameters as one flat vector (P,), zero-padded."""
        out = torch.zeros(self.size, dtype=net.head.weight.dtype, device=net.head.weight.device)
        for (name, p), at in zip(net.named_parameters(), self.offsets):
            out[at : at + p.numel()] = p.detach().reshape(-1)
        return out

    def load(self, net: Classifier, flat: torch.Tensor) -> None:
        """Copy a flat vector (P,) into ``net``'s parameters."""
        with torch.no_grad():
            for (name, p), at in zip(net.named_parameters(), self.offsets):
                p.copy_(flat[at : at + p.numel()].view_as(p))

    def views(self, stacked: torch.Tensor) -> dict[str, torch.Tensor]:
        """Each parameter of every member, ``(K, *shape)``, from the stacked ``(K, P)`` vectors; their gradients
        land in one ``(K, P)`` gradient (:class:`_Unflatten`), not in a zero-filled one per parameter."""
        return dict(zip(self.names, _Unflatten.apply(stacked, self)))


class _Unflatten(torch.autograd.Function):
    """``(K, P)`` -> each parameter ``(K, *shape)`` (copies, contiguous per member); backward writes every
    parameter's gradient into its place of one ``(K, P)`` tensor. (Slicing the stacked vectors instead would make
    autograd zero-fill a ``(K, P)`` tensor per parameter in every backward pass.)"""

    @staticmethod
    def forward(ctx, stacked, layout):  # type: ignore[override]
        ctx.layout = layout
        K = stacked.shape[0]
        return tuple(stacked[:, at : at + math.prod(shape)].reshape(K, *shape).clone()
                     for shape, at in zip(layout.shapes, layout.offsets))

    @staticmethod
    def backward(ctx, *grads):  # type: ignore[override]
        layout = ctx.layout
        g0 = next(g for g in grads if g is not None)
        K = g0.shape[0]
        out = g0.new_zeros(K, layout.size)
        for g, shape, at in zip(grads, layout.shapes, layout.offsets):
            if g is not None:
                out[:, at : at + math.prod(shape)] = g.reshape(K, -1)
        return out, None



def features(x: torch.Tensor, mean: torch.Tensor, std: torch.Tensor, inputs: str, fps: float) -> torch.Tensor:
    """``study.learn.model.Features`` for every member: positions ``x`` (K, B, T, D) metres -> channels
    (K, B, T, C), each member standardised by its own ``mean``, ``std`` (K, C)."""
    m, s = mean[:, None, None], std[:, None, None]
    if inputs == "positions":
        return x / s
    before = torch.cat([x[:, :, :1], x[:, :, :-1]], dim=2)
    return (model.motion_channels(x, before, inputs, fps) - m) / s  # type: ignore[arg-type]


def encode(views: dict[str, torch.Tensor], shape: Shape, x: torch.Tensor, state: list | None = None
           ) -> tuple[torch.Tensor, list]:
    """The members' recurrent layers over channels ``x`` (K, T, B, C) time-major from ``state`` (per layer: (h, c)
    for the LSTMs, h for the GRU, each (K, B, H); None: zeros) -> last layer's hidden states (K, T, B, H) and the
    new state."""
    K, _, B, _ = x.shape
    H = shape.hidden
    new = []
    for layer in range(shape.layers):
        if shape.cell == "gru":
            h0 = x.new_zeros(K, B, H) if state is None else state[layer]
            x, h = gru.stacked_layer(x, h0, *(views[f"rnn.{n}_l{layer}"] for n in ("weight_ih", "weight_hh", "bias_ih",
                                                                             "bias_hh")))
            new.append(h)
            continue
        h0, c0 = (x.new_zeros(K, B, H), x.new_zeros(K, B, H)) if state is None else state[layer]
        p = f"rnn.layers.{layer}."
        peep = [views.get(p + n, x.new_zeros(K, H)) for n in ("w_ci", "w_cf", "w_co")]  # no-peephole: zeros
        x, h, c = peephole.stacked_layer(x, h0, c0, views[p + "weight_ih"], views[p + "weight_hh"], views[p + "bias"], *peep)
        new.append((h, c))
    return x, new


def _detach(state: list) -> list:
    return [tuple(t.detach() for t in s) if isinstance(s, tuple) else s.detach() for s in state]


def logits(views: dict[str, torch.Tensor], shape: Shape, x: torch.Tensor, mean: torch.Tensor, std: torch.Tensor,
           dropout: Callable[[torch.Tensor], torch.Tensor] | None = None, every: bool = False) -> torch.Tensor:
    """The members' logits for positions ``x`` (K, B, T, D): at the last frame (K, B, 2), gradients truncated to
    the last ``shape.truncation`` frames, or (``every``) at every frame (K, T, B, 2), through the whole input.
    ``dropout``: the members' dropout of a hidden state (training), or None (evaluation)."""
    xs = features(x, mean, std, shape.inputs, shape.fps).transpose(1, 2).contiguous()  # (K, T, B, C)
    T = xs.shape[1]
    k = T if every else min(shape.truncation, T)
    state = None
    if k < T:
        with torch.no_grad():
            _, state = encode(views, shape, xs[:, : T - k].contiguous())  # carries the state; no graph is kept
        state = _detach(state)
    hs, _ = encode(views, shape, xs[:, T - k :].contiguous(), state)  # (K, k, B, H)
    h = hs if every else hs[:, -1]
    if dropout is not None:
        h = dropout(h)
    head_w, head_b = views["head.weight"], views["head.bias"]  # (K, 2, H), (K, 2)
    K, H = h.shape[0], h.shape[-1]
    flat = h.reshape(K, -1, H)
    return baddbmm(head_b.unsqueeze(1), flat, head_w.transpose(1, 2)).view(*h.shape[:-1], 2)


# ---------------------------------------------------------------------------------------------
# Training: every member as it would train alone


@dataclass
class Member:
    """One run of a stack: its data, its parameters and optimizer, and how its training is going."""

    cfg: TrainConfig
    view: Callable[[int], torch.Tensor]
    """The training part's positions (n_train, T, D) for an epoch (its own observation draws)."""
    y_tr: torch.Tensor
    x_va: torch.Tensor
    y_va: torch.Tensor
    net: Classifier
    """Its classifier, as initialised (and, at the end, with its best weights)."""
    flat: torch.Tensor
    """Its parameters, one leaf vector (P,)."""
    gen: torch.Generator
    """Its random numbers after initialisation: batch order and dropout masks."""
    opt: torch.optim.Optimizer
    sched: object | None
    n_val: int
    history: list[dict[str, float]] = field(default_factory=list)
    best_loss: float = math.inf
    best_epoch: int = 0
    best_flat: torch.Tensor | None = None
    """Its weights at its best validation epoch (at first: its initial weights)."""
    ema: torch.Tensor | None = None
    """With ``average='ema'``: the moving average of its weights (P,), which is validated and kept instead."""
    steps: int = 0
    """Optimiser steps it has taken (the average's warm-up counts them)."""
    diverged: int | None = None
    total: float = 0.0
    order: torch.Tensor | None = None
    x_tr: torch.Tensor | None = None
    done: bool = False


def shape(dataset: Dataset, cfg: TrainConfig) -> Shape:
    """The stack shape of training ``cfg`` on ``dataset`` (``study.simulate.data.Dataset``)."""
    tr, va = split_train_val(len(dataset.train.y), cfg.val_fraction, cfg.seed)
    return Shape(cfg.n_frames(dataset.fps), len(DIMS[cfg.dims]), cfg.inputs, float(dataset.fps), cfg.cell, cfg.hidden,
                 cfg.layers, cfg.batch_size, cfg.truncation, cfg.loss_at, len(tr), len(va))


def _member(dataset: Dataset, cfg: TrainConfig, device: torch.device) -> Member:
    """A member ready to train: its data split and observed as a lone run's, its network initialised as a lone
    run's (``study.learn.train.fit``), and its generator where that run's random numbers go on from."""
    cfg.check()
    T = cfg.n_frames(dataset.fps)
    x = select_inputs(dataset.train.x, cfg.dims, T, what="training split")
    y = np.asarray(dataset.train.y, dtype=np.int64)
    tr, va = split_train_val(len(y), cfg.val_fraction, cfg.seed)
    view, x_val = epoch_inputs(dataset.train.x[:, :T], tr, va, cfg, dataset.fps)
    feats = model.Features(x.shape[2], cfg.inputs, dataset.fps)
    mean, std = normalisation(view(0), feats)
    with deterministic(cfg.seed):
        net = Classifier(x.shape[2], cfg.hidden, cfg.layers, cfg.dropout, cfg.cell, forget_bias=cfg.forget_bias,
                         chrono_frames=T if cfg.forget_init == "chrono" else None, inputs=cfg.inputs, fps=dataset.fps)
        net.set_normalisation(torch.from_numpy(mean).float(), torch.from_numpy(std).float())
        gen = torch.Generator()
        gen.set_state(torch.get_rng_state())  # the lone run's stream goes on from here
    net.to(device)
    flat = Layout.of(net).flat(net).requires_grad_(True)
    first = flat.detach().clone()  # what a run that diverges before its first validation keeps
    opt = torch.optim.Adam([flat], lr=cfg.lr, foreach=False)
    sched = (torch.optim.lr_scheduler.ReduceLROnPlateau(opt, factor=0.5, patience=max(1, cfg.patience // 4))
             if cfg.lr_schedule == "plateau" else None)
    dev = lambda t: t.to(device)  # noqa: E731
    return Member(cfg, lambda epoch: dev(view(epoch)), dev(torch.from_numpy(y[tr])), dev(torch.from_numpy(x_val)),
                  dev(torch.from_numpy(y[va])), net, flat, gen, opt, sched, len(va), best_flat=first,
                  ema=first.clone() if cfg.average == "ema" else None)


def _dropout(members: Sequence[Member]) -> Callable[[torch.Tensor], torch.Tensor]:
    """Each member's dropout of the hidden states ``h`` (K, ...): its own mask from its own generator, drawn as
    ``torch.nn.functional.dropout`` draws it on the CPU (Bernoulli(1 - p), divided by 1 - p; nothing drawn at
    p = 0), at its own rate p."""
    def drop(h: torch.Tensor) -> torch.Tensor:
        masks = []
        for m in members:
            p = m.cfg.dropout
            mask = torch.ones(h.shape[1:], dtype=h.dtype)
            masks.append(mask if p == 0 else mask.bernoulli_(1 - p, generator=m.gen).div_(1 - p))
        return h * torch.stack(masks).to(h.device)

    return drop


def _losses(out: torch.Tensor, y: torch.Tensor, every: bool) -> list[torch.Tensor]:
    """Each member's cross-entropy: ``out`` (K, B, 2) at the last frame, or (K, T, B, 2) at every frame; ``y``
    (K, B)."""
    if not every:
        return [F.cross_entropy(o, t) for o, t in zip(out.unbind(0), y.unbind(0))]
    T = out.shape[1]
    return [F.cross_entropy(o.reshape(-1, 2), t.repeat(T)) for o, t in zip(out.unbind(0), y.unbind(0))]


@torch.no_grad()
def _validate(members: Sequence[Member], layout: Layout, sh: Shape, mean: torch.Tensor, std: torch.Tensor,
              batch: int = 1024) -> list[tuple[float, float]]:
    """Each member's validation loss and accuracy (evaluation mode: no dropout), at the last frame, of the weights
    it keeps (:func:`kept`)."""
    stacked = torch.stack([kept(m) for m in members])
    views = layout.views(stacked)
    n = sh.n_val
    out = []
    for i in range(0, n, batch):
        x = torch.stack([m.x_va[i : i + batch] for m in members])
        out.append(logits(views, dataclasses.replace(sh, truncation=sh.frames), x, mean, std))
    lg = torch.cat(out, dim=1)  # (K, n_val, 2)
    return [(F.cross_entropy(l, m.y_va).item(), (l.argmax(1) == m.y_va).double().mean().item())
            for l, m in zip(lg.unbind(0), members)]


def train(runs: Sequence[tuple[Dataset, TrainConfig]], device: str | torch.device = "cpu",
          on_epoch: Callable[[int, TrainConfig], None] | None = None) -> list[TrainedModel]:
    """Train every run of ``runs`` ((dataset, config) pairs of one :class:`Shape`) as one stack; returns their
    ``study.learn.train.TrainedModel``, in order, each what training it alone gives. ``on_epoch(i, cfg)`` is
    called after each epoch of member i (progress)."""
    if not runs:
        return []
    shapes = {shape(ds, cfg) for ds, cfg in runs}
    if len(shapes) != 1:
        raise ValueError(f"stack.train: runs of {len(shapes)} shapes; stack only runs of one shape (stack.shape)")
    sh = shapes.pop()
    if sh.cell not in STACKABLE:
        raise ValueError(f"stack.train: cell {sh.cell!r} has no stacked form; train it alone")
    dev = torch.device(device)
    deterministic = torch.are_deterministic_algorithms_enabled()
    fill = torch.utils.deterministic.fill_uninitialized_memory
    torch.use_deterministic_algorithms(True)
    # Deterministic mode fills every new tensor with NaN, a pass over memory per buffer: the layers write every
    # buffer they allocate before reading it, so it is turned off (it costs a fifth of a stacked step).
    torch.utils.deterministic.fill_uninitialized_memory = False
    try:
        return _train(runs, sh, dev, on_epoch)
    finally:
        torch.use_deterministic_algorithms(deterministic)
        torch.utils.deterministic.fill_uninitialized_memory = fill


def _train(runs: Sequence[tuple[Dataset, TrainConfig]], sh: Shape, dev: torch.device,
           on_epoch: Callable[[int, TrainConfig], None] | None) -> list[TrainedModel]:
    with num_threads(THREADS):
        members = [_member(ds, cfg, dev) for ds, cfg in runs]
        layout = Layout.of(members[0].net)
        stats = {id(m): (m.net.features.mean, m.net.features.std) for m in members}
        for epoch in range(max(m.cfg.epochs for m in members)):
            active = [m for m in members if not m.done and epoch < m.cfg.epochs]  # the stack shrinks
            if not active:
                break
            _epoch(active, layout, sh, stats, epoch)
            alive = [m for m in active if m.diverged is None]
            if alive:
                mean = torch.stack([stats[id(m)][0] for m in alive])
                std = torch.stack([stats[id(m)][1] for m in alive])
                for m, (val_loss, val_acc) in zip(alive, _validate(alive, layout, sh, mean, std)):
                    _end_epoch(m, epoch, val_loss, val_acc)
            for i, m in enumerate(members):
                if m in active and on_epoch is not None:
                    on_epoch(i, m.cfg)
    return [_finish(m, layout, ds) for m, (ds, _) in zip(members, runs)]


def _epoch(active: list[Member], layout: Layout, sh: Shape, stats: dict, epoch: int) -> None:
    """One epoch of training for every active member, in lockstep: the same steps, each on its own batches."""
    for m in active:
        m.x_tr = m.view(epoch)
        m.order = torch.randperm(sh.n_train, generator=m.gen)
        m.total = 0.0
        lr = m.cfg.lr_at(epoch)  # a cosine budget sets each epoch's rate; the others set it as they go
        if lr is not None:
            m.opt.param_groups[0]["lr"] = lr
    going = list(active)
    every = sh.loss_at == "every"
    for i in range(0, sh.n_train, sh.batch_size):
        going = [m for m in going if m.diverged is None]
        for m in going:  # a member whose weights stopped being finite has diverged: its loss could only be NaN
            if not native.all_finite(m.flat.detach()):
                m.diverged, m.done = epoch, True
        going = [m for m in going if m.diverged is None]
        if not going:
            break
        idx = [m.order[i : i + sh.batch_size] for m in going]
        x = torch.stack([m.x_tr[j] for m, j in zip(going, idx)])  # (K, B, T, D)
        y = torch.stack([m.y_tr[j] for m, j in zip(going, idx)])  # (K, B)
        stacked = torch.stack([m.flat for m in going])
        views = layout.views(stacked)
        mean = torch.stack([stats[id(m)][0] for m in going])
        std = torch.stack([stats[id(m)][1] for m in going])
        out = logits(views, sh, x, mean, std, _dropout(going), every)
        losses = _losses(out, y, every)
        finite = []
        values = torch.stack([loss.detach() for loss in losses]).tolist()  # one device sync for the stack
        for m, loss, value in zip(going, losses, values):
            if math.isfinite(value):
                finite.append((m, loss, value))
            else:
                m.diverged, m.done = epoch, True  # stops here, its last good weights kept, and says so
        for m, _, _ in finite:
            m.opt.zero_grad(set_to_none=True)
        if not finite:
            continue
        torch.stack([loss for _, loss, _ in finite]).sum().backward()
        for m, _, value in finite:
            if m.cfg.clip_norm > 0:
                torch.nn.utils.clip_grad_norm_([m.flat], m.cfg.clip_norm, foreach=False)
            m.opt.step()
            if m.ema is not None:
                decay = m.cfg.ema_decay_at(m.steps)
                m.ema.mul_(decay).add_(m.flat.detach(), alpha=1 - decay)
            m.steps += 1
            m.total += value * len(idx[0])


def kept(m: Member) -> torch.Tensor:
    """The weights ``m`` validates and keeps (P,): the moving average with ``average='ema'``, else its own."""
    return m.ema if m.ema is not None else m.flat.detach()


def _end_epoch(m: Member, epoch: int, val_loss: float, val_acc: float) -> None:
    """The member's epoch ends as a lone run's does: its history, its schedule, its best weights, its stop."""
    m.history.append({"epoch": epoch, "train_loss": m.total / len(m.y_tr), "val_loss": val_loss,
                      "val_accuracy": val_acc, "lr": m.opt.param_groups[0]["lr"]})
    if m.sched is not None:
        m.sched.step(val_loss)
    if val_loss < m.best_loss:
        m.best_loss, m.best_epoch, m.best_flat = val_loss, epoch, kept(m).clone()
    elif m.cfg.stops_early and epoch - m.best_epoch >= m.cfg.patience and epoch + 1 >= m.cfg.min_epochs:
        m.done = True


def _finish(m: Member, layout: Layout, dataset: Dataset) -> TrainedModel:
    """The member's ``TrainedModel``: its best epoch's weights in its classifier."""
    if m.diverged is not None:
        m.history.append({"epoch": m.diverged, "train_loss": math.nan, "val_loss": math.nan, "val_accuracy": math.nan})
    layout.load(m.net, m.best_flat)
    m.net.eval()
    return TrainedModel(net=m.net.cpu(), config=m.cfg, fps=dataset.fps, data_key=dataset.key, history=m.history,
                        best_epoch=m.best_epoch, diverged_epoch=m.diverged, n_val=m.n_val)
