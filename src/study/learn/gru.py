"""``nn.GRU`` with the compiled time loop of ``gru.cpp`` on CPU: the ablation's GRU at the peephole LSTM's speed.

:class:`GRU` *is* an ``nn.GRU`` (same parameters, initialisation, state dict and state shape), so a
model saved with one loads into the other. Its forward runs each layer through :class:`GRUFunction`:
one BLAS call and one fused elementwise pass per time step in ``gru.cpp`` (:mod:`study.learn.native`), a
hand-written backward, and the weight gradients as single matrix products over all steps. Where the
compiled loop cannot run (CUDA, other dtypes, ``study.learn.native`` disabled or unavailable, inter-layer
dropout, unbatched input, a NaN or infinity in the input, state or weights) it is plain ``nn.GRU``; a
gradient that is not finite goes back through :func:`reference` instead of the compiled loop.

Shapes: B batch, T frames, D input dims, H hidden units, L layers; batch-first like the classifier.
"""

from __future__ import annotations

import torch
import torch.nn as nn
import torch.nn.functional as F

from study.learn import native
from study.learn.batched import baddbmm, bmm


class GRUFunction(torch.autograd.Function):
    """One GRU layer over a batch-first sequence: ``x`` (B, T, D), ``h0`` (B, H) -> all hidden states
    (B, T, H) and the last (B, H); parameters as ``nn.GRU``'s layer (gate rows r, z, n)."""

    @staticmethod
    def forward(ctx, x, h0, weight_ih, weight_hh, bias_ih, bias_hh):  # type: ignore[override]
        lib = native.active()
        T, B, H = x.shape[1], x.shape[0], weight_hh.shape[1]
        # b_hr and b_hz add to the pre-activations like b_ir, b_iz; b_hn sits inside r (W_hn h + b_hn).
        bias = torch.cat((bias_ih[: 2 * H] + bias_hh[: 2 * H], bias_ih[2 * H:]))
        gates = F.linear(x.transpose(0, 1), weight_ih, bias).contiguous()  # (T, B, 3H)
        hs = gates.new_empty(T + 1, B, H)
        hs[0] = h0
        hn = gates.new_empty(T, B, H)
        scratch = gates.new_empty(B, 3 * H)
        w = [t.detach().contiguous() for t in (weight_hh.t(), bias_hh[2 * H:])]
        lib.gru_forward[gates.dtype](T, B, H, native.ptr(gates), *map(native.ptr, w), native.ptr(hs), native.ptr(hn), native.ptr(scratch),
                                     lib.blas[gates.dtype])
        ctx.lib = lib
        ctx.save_for_backward(x, weight_ih, weight_hh, bias_ih, bias_hh, gates, hs, hn)
        return hs[1:].transpose(0, 1), hs[-1].clone()

    @staticmethod
    def backward(ctx, d_out, d_h):  # type: ignore[override]
        x, weight_ih, weight_hh, bias_ih, bias_hh, gates, hs, hn = ctx.saved_tensors
        if not native.all_finite(d_out, d_h):  # the compiled loop assumes finite numbers
            return _backward_reference(ctx.needs_input_grad, d_out, d_h, x, hs[0], weight_ih, weight_hh, bias_ih, bias_hh)
        lib = ctx.lib
        T, B, H3 = gates.shape
        H = H3 // 3
        d_out = native.own(None if d_out is None else d_out.transpose(0, 1), gates, (T, B, H))  # time-major
        dh = native.own(d_h, gates, (B, H))
        d_x, d_s = torch.empty_like(gates), torch.empty_like(gates)  # (T, B, 3H) each
        lib.gru_backward[gates.dtype](T, B, H, native.ptr(gates), native.ptr(hs), native.ptr(hn), native.ptr(weight_hh.detach().contiguous()),
                                      native.ptr(d_out), native.ptr(dh), native.ptr(d_x), native.ptr(d_s), lib.blas[gates.dtype])
        need = ctx.needs_input_grad
        dx = (d_x @ weight_ih).transpose(0, 1) if need[0] else None  # (B, T, D)
        flat_x, flat_s = d_x.reshape(T * B, H3), d_s.reshape(T * B, H3)
        d_w_ih = (x.transpose(0, 1).reshape(T * B, -1).t() @ flat_x).t() if need[2] else None  # (3H, D)
        d_w_hh = (hs[:-1].reshape(T * B, H).t() @ flat_s).t() if need[3] else None  # (3H, H)
        d_b_ih = flat_x.sum(0) if need[4] else None
        d_b_hh = flat_s.sum(0) if need[5] else None
        return dx, dh, d_w_ih, d_w_hh, d_b_ih, d_b_hh


def reference(x: torch.Tensor, h0: torch.Tensor, weight_ih: torch.Tensor, weight_hh: torch.Tensor,
                  bias_ih: torch.Tensor, bias_hh: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
    """K GRU layers as plain PyTorch operations, nn.GRU's equations (autograd differentiates them): the
    stacked PyTorch path, on any device, and the definition the compiled loops are tested against. Shapes as
    :class:`StackedGRU`."""
    K, T, B, C = x.shape
    i_all = baddbmm(bias_ih.unsqueeze(1), x.reshape(K, T * B, C), weight_ih.transpose(1, 2)).view(K, T, B, -1)
    w_hh_t = weight_hh.transpose(1, 2)
    h, hs = h0, []
    for t in range(T):
        i_r, i_z, i_n = i_all[:, t].chunk(3, 2)
        h_r, h_z, h_n = baddbmm(bias_hh.unsqueeze(1), h, w_hh_t).chunk(3, 2)
        r, z = torch.sigmoid(i_r + h_r), torch.sigmoid(i_z + h_z)
        h = (1 - z) * torch.tanh(i_n + r * h_n) + z * h
        hs.append(h)
    return torch.stack(hs, 1), h


def _one_layer(x: torch.Tensor, h0: torch.Tensor, weight_ih: torch.Tensor, weight_hh: torch.Tensor,
              bias_ih: torch.Tensor, bias_hh: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
    """One GRU layer, batch-first: ``x`` (B, T, D), ``h0`` (B, H) -> all hidden states (B, T, H) and the last
    (B, H); :func:`reference` with one member."""
    hs, h = reference(x.transpose(0, 1).unsqueeze(0), h0.unsqueeze(0), weight_ih.unsqueeze(0),
                      weight_hh.unsqueeze(0), bias_ih.unsqueeze(0), bias_hh.unsqueeze(0))
    return hs[0].transpose(0, 1), h[0]


def _backward_reference(need: tuple[bool, ...], d_out: torch.Tensor | None, d_h: torch.Tensor | None,
                        *inputs: torch.Tensor) -> tuple[torch.Tensor | None, ...]:
    """:meth:`GRUFunction.backward` through :func:`reference` and autograd: for incoming gradients that
    are not finite (a diverged loss), which it propagates as PyTorch does."""
    with torch.enable_grad():
        leaves = [t.detach().requires_grad_(n) for t, n in zip(inputs, need)]
        out, last = _one_layer(*leaves)
        pairs = [(o, g) for o, g in ((out, d_out), (last, d_h)) if g is not None]
        wanted = [t for t in leaves if t.requires_grad]
        grads = iter(torch.autograd.grad([o for o, _ in pairs], wanted, [g for _, g in pairs], allow_unused=True))
    return tuple(next(grads) if n else None for n in need)


class GRU(nn.GRU):
    """``nn.GRU`` (batch-first) whose forward uses the compiled loop where it can (see the module docstring)."""

    def __init__(self, input_size: int, hidden_size: int, num_layers: int = 1) -> None:
        super().__init__(input_size, hidden_size, num_layers, batch_first=True)

    def _compiled(self, x: torch.Tensor, hx: torch.Tensor | None) -> bool:
        """Whether the compiled loop can run: CPU, float32/64, batched, plain layers, every number finite."""
        return (x.dim() == 3 and x.device.type == "cpu" and x.dtype in (torch.float32, torch.float64)
                and self.dropout == 0 and not self.bidirectional and self.proj_size == 0
                and native.active() is not None and native.all_finite(x, hx, *self.parameters()))

    def forward(self, x: torch.Tensor, hx: torch.Tensor | None = None) -> tuple[torch.Tensor, torch.Tensor]:  # type: ignore[override]
        """``x`` (B, T, D), ``hx`` (L, B, H) or None -> outputs (B, T, H) and the final states (L, B, H)."""
        if not self._compiled(x, hx):
            return super().forward(x, hx)
        h0 = x.new_zeros(self.num_layers, x.shape[0], self.hidden_size) if hx is None else hx
        finals = []
        for k in range(self.num_layers):
            x, h = GRUFunction.apply(x, h0[k], *(getattr(self, f"{n}_l{k}") for n in
                                                  ("weight_ih", "weight_hh", "bias_ih", "bias_hh")))
            finals.append(h)
        return x, torch.stack(finals)


# ---------------------------------------------------------------------------------------------
# K layers at once, one per member of a stack (``study.learn.stack``): (K, T, B, .)


class StackedGRU(torch.autograd.Function):
    """K GRU layers (``nn.GRU``'s equations and parameters), one per member: ``x`` (K, T, B, C) time-major,
    ``h0`` (K, B, H), ``weight_ih`` (K, 3H, C), ``weight_hh`` (K, 3H, H), ``bias_ih``, ``bias_hh`` (K, 3H) ->
    hidden states (K, T, B, H) and the last (K, B, H). The compiled loop of ``gru.cpp`` member by member (the
    trainer hands it finite parameters only); a member whose incoming gradient is not finite goes back through
    the PyTorch reference (:func:`_backward_reference`), which propagates it as PyTorch does."""

    @staticmethod
    def forward(ctx, x, h0, weight_ih, weight_hh, bias_ih, bias_hh):  # type: ignore[override]
        lib = native.active()
        K, T, B, C = x.shape
        H = weight_hh.shape[2]
        bias = torch.cat((bias_ih[:, : 2 * H] + bias_hh[:, : 2 * H], bias_ih[:, 2 * H:]), dim=1)  # (K, 3H)
        gates = baddbmm(bias.unsqueeze(1), x.reshape(K, T * B, C), weight_ih.transpose(1, 2))
        gates = gates.view(K, T, B, 3 * H).contiguous()
        hs = gates.new_empty(K, T + 1, B, H)
        hs[:, 0] = h0
        hn = gates.new_empty(K, T, B, H)
        scratch = gates.new_empty(B, 3 * H)
        for k in range(K):
            w = [t.detach().contiguous() for t in (weight_hh[k].t(), bias_hh[k, 2 * H:])]
            lib.gru_forward[gates.dtype](T, B, H, native.ptr(gates[k]), *map(native.ptr, w), native.ptr(hs[k]),
                                         native.ptr(hn[k]), native.ptr(scratch), lib.blas[gates.dtype])
        ctx.lib = lib
        ctx.save_for_backward(x, h0, weight_ih, weight_hh, bias_ih, bias_hh, gates, hs, hn)
        return hs[:, 1:], hs[:, -1].clone()

    @staticmethod
    def backward(ctx, d_out, d_h):  # type: ignore[override]
        x, h0, weight_ih, weight_hh, bias_ih, bias_hh, gates, hs, hn = ctx.saved_tensors
        lib = ctx.lib
        K, T, B, G = gates.shape
        H = G // 3
        d_x, d_s = torch.zeros_like(gates), torch.zeros_like(gates)  # (K, T, B, 3H) each
        dh0 = gates.new_zeros(K, B, H)
        bad: dict[int, tuple] = {}
        for k in range(K):
            dout_k = None if d_out is None else d_out[k]
            dh_k = None if d_h is None else d_h[k]
            if not native.all_finite(dout_k, dh_k):
                need = (True, True, True, True, True, True)
                bad[k] = _backward_reference(need, None if dout_k is None else dout_k.transpose(0, 1), dh_k,
                                                 x[k].transpose(0, 1), h0[k], weight_ih[k], weight_hh[k], bias_ih[k],
                                                 bias_hh[k])
                continue
            dout = native.own(dout_k, gates[k], (T, B, H))
            dh = native.own(dh_k, gates[k], (B, H))
            lib.gru_backward[gates.dtype](T, B, H, native.ptr(gates[k]), native.ptr(hs[k]), native.ptr(hn[k]),
                                          native.ptr(weight_hh[k].detach().contiguous()), native.ptr(dout),
                                          native.ptr(dh), native.ptr(d_x[k]), native.ptr(d_s[k]), lib.blas[gates.dtype])
            dh0[k] = dh
        flat_x, flat_s = d_x.view(K, T * B, G), d_s.view(K, T * B, G)
        dx = bmm(flat_x, weight_ih).view(K, T, B, -1)
        d_w_ih = bmm(x.reshape(K, T * B, -1).transpose(1, 2), flat_x).transpose(1, 2).contiguous()  # (K, 3H, C)
        d_w_hh = bmm(hs[:, :-1].reshape(K, T * B, H).transpose(1, 2), flat_s).transpose(1, 2).contiguous()
        d_b_ih, d_b_hh = flat_x.sum(1), flat_s.sum(1)
        for k, (gx, gh, gwi, gwh, gbi, gbh) in bad.items():  # the members the reference took back
            dx[k], dh0[k], d_w_ih[k], d_w_hh[k], d_b_ih[k], d_b_hh[k] = gx.transpose(0, 1), gh, gwi, gwh, gbi, gbh
        return dx, dh0, d_w_ih, d_w_hh, d_b_ih, d_b_hh


def _compiled(*tensors: torch.Tensor) -> bool:
    return (tensors[0].device.type == "cpu" and tensors[0].dtype in (torch.float32, torch.float64)
            and native.active() is not None)


def stacked_layer(x, h0, *weights):
    """One stacked GRU layer: the compiled loop on the CPU where there is one (the trainer hands it finite
    parameters only: a member whose parameters stop being finite has diverged and left), else the PyTorch loop."""
    if _compiled(x):
        return StackedGRU.apply(x, h0, *weights)
    return reference(x, h0, *weights)
