"""Many training runs as one: K classifiers of one shape stepped side by side, each exactly as it would train alone.

This module holds only what training many runs at once needs; the recipe every run follows (its optimiser, its
step, the end of its epoch, its stop) is ``study.learn.train``'s, written once there. A training step of one small
classifier (batch 32, 64 units) leaves most of a core's time to dispatch: the autograd graph, the head, the loss,
the optimizer, copies. Here K runs (*members*) of the same shape take one forward and one backward pass over
stacked tensors ``(K, ...)``, the recurrent layers' time loops called once per layer for all members, while every
member keeps what makes it its own run:

- its data (its dataset's training part, and its own observation draws: ``study.learn.inputs.epoch_inputs``),
  its normalisation, its validation part;
- its seed: its initial weights, batch order and dropout masks come from its own generator, started from the
  seed (the weights drawn as ``Classifier`` draws them);
- its own parameters, a leaf tensor of its own (:class:`Layout`), so that its optimiser, clipping and stop are
  its own.

**A member's result does not depend on its stack** (tested: a run trained alone, in a stack of 3 and in a stack of
8 gives bitwise-identical weights and history, on either time loop). What could make it depend is anything
computed across members; here each matrix product on the CPU is made member by member (a batched product may
choose its kernel by the batch), reductions and random numbers are per member, and the stacked elementwise
operations treat each element alone. On a GPU the products are batched (``torch.bmm``), which is where batching
pays; there a member's rounding may depend on the stack size (cuBLAS picks kernels by shape).

The compiled time loops (``peephole.cpp``, ``gru.cpp``) run member by member inside one layer call: each
member's per-step product is already at the core's speed (about 85 GFLOP/s at B = 32, H = 64, measured with the
BLAS PyTorch ships), and MKL's batched ``sgemm_batch`` measured no faster (77 GFLOP/s at K = 5), so the gain of a
stack is everything around the loops. ``nn.LSTM`` (``'torch-lstm'``) runs member by member through the function
that module calls (``torch.lstm``). ``benchmarks/bench_stack.py`` measures the stack.

Shapes: K members, B batch, T frames, D position dims, C channels the first layer reads, H hidden units, G gate
rows (4H for the LSTMs, 3H for the GRU). Tensors inside are time-major, ``(K, T, B, .)``.
"""

from __future__ import annotations

import contextlib
import dataclasses
import math
from collections.abc import Callable, Iterator, Sequence
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
from study.learn.trained import THREADS, num_threads
from study.simulate.data import Dataset

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
    if shape.cell == "torch-lstm":
        return _torch_lstm(views, shape, x, state)
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


def _torch_lstm(views: dict[str, torch.Tensor], shape: Shape, x: torch.Tensor, state: list | None
                ) -> tuple[torch.Tensor, list]:
    """:func:`encode` for ``nn.LSTM``'s cell, member by member through the function ``nn.LSTM`` calls."""
    K, _, B, _ = x.shape
    L, H = shape.layers, shape.hidden
    names = [f"rnn.{n}_l{layer}" for layer in range(L) for n in ("weight_ih", "weight_hh", "bias_ih", "bias_hh")]
    outs, hs, cs = [], [], []
    for k in range(K):
        if state is None:
            h0 = c0 = x.new_zeros(L, B, H)
        else:
            h0 = torch.stack([state[layer][0][k] for layer in range(L)])  # (L, B, H)
            c0 = torch.stack([state[layer][1][k] for layer in range(L)])
        out, h, c = torch.lstm(x[k], (h0, c0), [views[n][k] for n in names], True, L, 0.0, False, False, False)
        outs.append(out)  # (T, B, H)
        hs.append(h)
        cs.append(c)
    h, c = torch.stack(hs), torch.stack(cs)  # (K, L, B, H)
    return torch.stack(outs), [(h[:, layer], c[:, layer]) for layer in range(L)]


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


def last_logits(net: Classifier, x: torch.Tensor, truncation: int) -> torch.Tensor:
    """What training computes for one classifier: ``net``'s logits (B, 2) at the last frame of ``x`` (B, T, D)
    metres, through the stacked pass as a stack of one, gradients truncated to the last ``truncation`` frames
    (evaluation mode: no dropout). Equal to ``net(x)``; tests hold the two together."""
    layout = Layout.of(net)
    layers = len(net.rnn.layers) if isinstance(net.rnn, model.PeepholeStack) else net.rnn.num_layers
    sh = Shape(x.shape[1], net.n_inputs, net.features.inputs, net.features.fps, net.cell_type, net.head.in_features,
               layers, x.shape[0], truncation, "last", x.shape[0], 0)
    views = layout.views(layout.flat(net)[None])
    f = net.features
    return logits(views, sh, x[None], f.mean[None], f.std[None])[0]


# ---------------------------------------------------------------------------------------------
# The members: what each run brings to the stack (its recipe is ``study.learn.train``'s)


@dataclass
class Member:
    """One run of a stack: its data, its classifier and parameters, its random numbers."""

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

    @property
    def n_val(self) -> int:
        return len(self.y_va)


def shape(dataset: Dataset, cfg: TrainConfig) -> Shape:
    """The stack shape of training ``cfg`` on ``dataset`` (``study.simulate.data.Dataset``)."""
    tr, va = split_train_val(len(dataset.train.y), cfg.val_fraction, cfg.seed)
    return Shape(cfg.n_frames(dataset.fps), len(DIMS[cfg.dims]), cfg.inputs, float(dataset.fps), cfg.cell, cfg.hidden,
                 cfg.layers, cfg.batch_size, cfg.truncation, cfg.loss_at, len(tr), len(va))


def common_shape(runs: Sequence[tuple[Dataset, TrainConfig]]) -> Shape:
    """The one :class:`Shape` of ``runs`` ((dataset, config) pairs); ValueError if they have several."""
    shapes = {shape(ds, cfg) for ds, cfg in runs}
    if len(shapes) != 1:
        raise ValueError(f"train_runs: runs of {len(shapes)} shapes; stack only runs of one shape (stack.shape)")
    return shapes.pop()


def member(dataset: Dataset, cfg: TrainConfig, device: torch.device) -> Member:
    """A member ready to train: its data split and observed, its network initialised from its seed (weights drawn
    as ``Classifier`` draws them, inside a forked RNG), and its generator where its random numbers go on from."""
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
        gen.set_state(torch.get_rng_state())  # the run's stream goes on from here
    net.to(device)
    flat = Layout.of(net).flat(net).requires_grad_(True)
    dev = lambda t: t.to(device)  # noqa: E731
    return Member(cfg, lambda epoch: dev(view(epoch)), dev(torch.from_numpy(y[tr])), dev(torch.from_numpy(x_val)),
                  dev(torch.from_numpy(y[va])), net, flat, gen)


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


def _normalisation(members: Sequence[Member]) -> tuple[torch.Tensor, torch.Tensor]:
    """The members' channel means and standard deviations, (K, C) each."""
    return (torch.stack([m.net.features.mean for m in members]), torch.stack([m.net.features.std for m in members]))


def losses(members: Sequence[Member], x: torch.Tensor, y: torch.Tensor, layout: Layout, sh: Shape
           ) -> list[torch.Tensor]:
    """Each member's training loss on its batch, positions ``x`` (K, B, T, D) metres and labels ``y`` (K, B), in one
    stacked forward pass (its own dropout masks): the cross-entropy at the last frame, or (``loss_at='every'``)
    the mean over every frame."""
    views = layout.views(torch.stack([m.flat for m in members]))
    every = sh.loss_at == "every"
    out = logits(views, sh, x, *_normalisation(members), _dropout(members), every)
    if not every:  # out (K, B, 2)
        return [F.cross_entropy(o, t) for o, t in zip(out.unbind(0), y.unbind(0))]
    T = out.shape[1]  # out (K, T, B, 2)
    return [F.cross_entropy(o.reshape(-1, 2), t.repeat(T)) for o, t in zip(out.unbind(0), y.unbind(0))]


@torch.no_grad()
def validate(members: Sequence[Member], weights: Sequence[torch.Tensor], layout: Layout, sh: Shape,
             batch: int = 1024) -> list[tuple[float, float]]:
    """Each member's validation loss and accuracy with ``weights`` (its (P,) vector each), in evaluation mode (no
    dropout), at the last frame."""
    views = layout.views(torch.stack(list(weights)))
    mean, std = _normalisation(members)
    whole = dataclasses.replace(sh, truncation=sh.frames)
    out = []
    for i in range(0, sh.n_val, batch):
        x = torch.stack([m.x_va[i : i + batch] for m in members])
        out.append(logits(views, whole, x, mean, std))
    lg = torch.cat(out, dim=1)  # (K, n_val, 2)
    return [(F.cross_entropy(l, m.y_va).item(), (l.argmax(1) == m.y_va).double().mean().item())
            for l, m in zip(lg.unbind(0), members)]


@contextlib.contextmanager
def exact() -> Iterator[None]:
    """Deterministic algorithms for the block, and :data:`THREADS` CPU threads (restored after).

    Deterministic mode fills every new tensor with NaN, a pass over memory per buffer: the layers write every
    buffer they allocate before reading it, so that fill is turned off (it costs a fifth of a stacked step)."""
    was = torch.are_deterministic_algorithms_enabled()
    fill = torch.utils.deterministic.fill_uninitialized_memory
    torch.use_deterministic_algorithms(True)
    torch.utils.deterministic.fill_uninitialized_memory = False
    try:
        with num_threads(THREADS):
            yield
    finally:
        torch.use_deterministic_algorithms(was)
        torch.utils.deterministic.fill_uninitialized_memory = fill
