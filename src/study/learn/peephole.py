"""The peephole LSTM layer's time loops and the autograd Function that runs them: what makes the layer of
``study.learn.model`` as fast as ``nn.LSTM``.

``study.learn.model.PeepholeLSTM`` calls :class:`PeepholeFunction`. Its forward runs the time loop without
building an autograd graph; its backward walks the steps once in reverse. On the CPU both loops are the compiled
ones of ``peephole.cpp`` (:mod:`study.learn.native`: one BLAS call and one fused elementwise pass per step), else
:func:`recurrence` and :func:`backward_loop` in PyTorch operations (few kernels per step, preallocated buffers).
The weight gradients are single matrix products over all time steps. The tests check both paths against the
plain definition, :func:`reference`, and ``torch.autograd.gradcheck``.

Layout: time-major ``(T, B, .)``; gates in the order i, f, g, o (``nn.LSTM``'s).
"""

from __future__ import annotations

import torch
import torch.nn.functional as F

from study.learn import native
from study.learn.batched import baddbmm, bmm


def recurrence(
    xw: torch.Tensor, h0: torch.Tensor, c0: torch.Tensor, weight_hh: torch.Tensor,
    w_cif: torch.Tensor, w_co: torch.Tensor,
) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor, torch.Tensor]:
    """The forward time loop, written for few kernel launches per step (eight, all in preallocated buffers).

    ``xw`` (T, B, 4H): the projected input ``W_ih x_t + b``, time-major; it is overwritten in place with
    the activated gates, so the recurrent matmul adds into it without a copy. ``w_cif`` (2, H): the input and
    forget peepholes stacked. Returns, time-major: the activated gates (T, B, 4H) in order i, f, g, o;
    the cell states (T + 1, B, H) and hidden states (T + 1, B, H), index 0 holding ``c0`` and ``h0``;
    and tanh of the cell states (T, B, H).
    """
    T, B, H4 = xw.shape
    H = H4 // 4
    gates = xw
    cs = xw.new_empty(T + 1, B, H)
    hs = xw.new_empty(T + 1, B, H)
    tcs = xw.new_empty(T, B, H)
    cs[0], hs[0] = c0, h0
    w_hh_t = weight_hh.t().contiguous()  # (H, 4H)
    # Per-step views made once, outside the loop: indexing costs as much as a small kernel here.
    g4 = gates.view(T, B, 4, H)
    steps = zip(gates.unbind(0), g4[:, :, :2].unbind(0), g4[:, :, 0].unbind(0),
                g4[:, :, 1].unbind(0), g4[:, :, 2].unbind(0), g4[:, :, 3].unbind(0),
                cs[:-1].unsqueeze(2).unbind(0), cs[:-1].unbind(0), cs[1:].unbind(0),
                hs[:-1].unbind(0), hs[1:].unbind(0), tcs.unbind(0))
    for gate, if_, i, f, g, o, c_old2, c_old, c_new, h_old, h_new, tc in steps:
        gate.addmm_(h_old, w_hh_t)  # pre-activations (B, 4H)
        if_.addcmul_(c_old2, w_cif).sigmoid_()  # i, f see the old cell
        g.tanh_()
        torch.mul(f, c_old, out=c_new).addcmul_(i, g)  # c = f c + i g
        o.addcmul_(c_new, w_co).sigmoid_()  # o sees the new cell
        torch.mul(o, torch.tanh(c_new, out=tc), out=h_new)  # h = o tanh(c)
    return gates, cs, hs, tcs


def backward_loop(
    d_out: torch.Tensor | None, d_h: torch.Tensor | None, d_c: torch.Tensor | None, gates: torch.Tensor,
    cs: torch.Tensor, hs: torch.Tensor, tcs: torch.Tensor, weight_hh: torch.Tensor,
    w_ci: torch.Tensor, w_cf: torch.Tensor, w_co: torch.Tensor,
) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
    """The backward time loop as PyTorch operations (five kernels per step): returns dL/d(pre-activations)
    (T, B, 4H) and dL/d(h0, c0), each (B, H). Used where the compiled loop is not available."""
    T, B, H4 = gates.shape
    H = H4 // 4
    i, f, g, o = gates.view(T, B, 4, H).unbind(2)  # each (T, B, H)
    c_old, h = cs[:-1], hs[1:]
    # Derivative factors for all steps at once, each written with as few passes over (T, B, H) as
    # possible (sigmoid' = s - s^2, and o * tanh(c) is h itself):
    a_o = torch.addcmul(h, h, o, value=-1)  # o tanh(c) (1 - o):  dL/d(o pre-activation) = dh * a_o
    b_c = torch.addcmul(o, h, tcs, value=-1).addcmul_(a_o, w_co)  # dc_t += dh * b_c (w_co path included)
    k_ifg = gates.new_empty(T, B, 3, H)  # dL/d(i, f, g pre-activations) = dc_t * k_ifg
    k_i, k_f, k_g = k_ifg.unbind(2)
    torch.addcmul(i, i, i, value=-1, out=k_i).mul_(g)  # g i (1 - i)
    torch.addcmul(f, f, f, value=-1, out=k_f).mul_(c_old)  # c_{t-1} f (1 - f)
    torch.addcmul(torch.ones_like(w_ci), g, g, value=-1, out=k_g).mul_(i)  # i (1 - g^2)
    f_c = torch.addcmul(f, k_i, w_ci).addcmul_(k_f, w_cf)  # dL/dc_{t-1} = dc_t * f_c
    d_out = native.own(None if d_out is None else d_out.transpose(0, 1), gates, (T, B, H))  # time-major; the
    # recurrent matmul adds into it in place
    dh = d_out[-1] + d_h if d_h is not None else d_out[-1].clone()
    dc = d_c.clone() if d_c is not None else gates.new_zeros(B, H)
    d_gates = torch.empty_like(gates)  # (T, B, 4H) gradients of the pre-activations
    dg4 = d_gates.view(T, B, 4, H)
    steps = zip(d_gates.unbind(0), dg4[:, :, :3].unbind(0), dg4[:, :, 3].unbind(0),
                a_o.unbind(0), b_c.unbind(0), k_ifg.unbind(0), f_c.unbind(0))
    for t, (dg, dg_ifg, dg_o, a_o_t, b_c_t, k_t, f_c_t) in reversed(list(enumerate(steps))):
        torch.mul(dh, a_o_t, out=dg_o)
        dc.addcmul_(dh, b_c_t)  # total dL/dc_t
        torch.mul(dc.unsqueeze(1), k_t, out=dg_ifg)
        dc.mul_(f_c_t)  # dL/dc_{t-1}
        dh = d_out[t - 1].addmm_(dg, weight_hh) if t else torch.mm(dg, weight_hh)
    return d_gates, dh, dc


def small_grads(d_gates: torch.Tensor, cs: torch.Tensor) -> tuple[torch.Tensor, ...]:
    """Gradients of the peepholes w_ci, w_cf, w_co and of the bias, each summed over time and batch,
    from dL/d(pre-activations) (T, B, 4H) and the cell states (T + 1, B, H)."""
    T, B, H4 = d_gates.shape
    dgi, dgf, _, dgo = d_gates.view(T, B, 4, H4 // 4).unbind(2)
    c_old = cs[:-1]
    return ((dgi * c_old).sum((0, 1)), (dgf * c_old).sum((0, 1)), (dgo * cs[1:]).sum((0, 1)),
            d_gates.sum((0, 1)))


def native_for(xw: torch.Tensor, *others: torch.Tensor | None) -> native.Native | None:
    """The compiled loop if it can run on ``xw`` (CPU, float32 or float64) and every tensor is finite, else ``None``.

    The compiled loop assumes finite numbers (it is built with ``-ffinite-math-only`` and clamps its exp):
    a NaN or infinity goes to the PyTorch loop, which propagates it as PyTorch does, so a diverged run
    looks diverged on either backend.
    """
    if xw.device.type != "cpu" or xw.dtype not in (torch.float32, torch.float64):
        return None
    lib = native.active()
    return lib if lib is not None and native.all_finite(xw, *others) else None


def recurrence_native(
    lib: native.Native, xw: torch.Tensor, h0: torch.Tensor, c0: torch.Tensor, weight_hh: torch.Tensor,
    w_ci: torch.Tensor, w_cf: torch.Tensor, w_co: torch.Tensor,
) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor, torch.Tensor]:
    """:func:`recurrence` in ``peephole.cpp``: one BLAS call and one fused loop per step; same outputs."""
    T, B, H4 = xw.shape
    H = H4 // 4
    cs = xw.new_empty(T + 1, B, H)
    hs = xw.new_empty(T + 1, B, H)
    tcs = xw.new_empty(T, B, H)
    cs[0], hs[0] = c0, h0
    w = [t.detach().contiguous() for t in (weight_hh.t(), w_ci, w_cf, w_co)]  # weight_hh transposed: (H, 4H)
    lib.forward[xw.dtype](T, B, H, native.ptr(xw), *map(native.ptr, w), native.ptr(cs), native.ptr(hs), native.ptr(tcs), lib.blas[xw.dtype])
    return xw, cs, hs, tcs


def backward_native(
    lib: native.Native, d_out: torch.Tensor | None, d_h: torch.Tensor | None, d_c: torch.Tensor | None,
    gates: torch.Tensor, cs: torch.Tensor, tcs: torch.Tensor, weight_hh: torch.Tensor,
    w_ci: torch.Tensor, w_cf: torch.Tensor, w_co: torch.Tensor,
) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor, tuple[torch.Tensor, ...]]:
    """:func:`backward_loop` in ``peephole.cpp`` (derivative factors computed inside the fused loop); also
    returns the peephole and bias gradients (w_ci, w_cf, w_co, bias), summed inside the loop."""
    T, B, H4 = gates.shape
    H = H4 // 4
    d_out = native.own(None if d_out is None else d_out.transpose(0, 1), gates, (T, B, H))  # time-major
    dh, dc = native.own(d_h, gates, (B, H)), native.own(d_c, gates, (B, H))
    d_gates = torch.empty_like(gates)
    d_small = gates.new_empty(7 * H)
    w = [t.detach().contiguous() for t in (weight_hh, w_ci, w_cf, w_co)]
    lib.backward[gates.dtype](T, B, H, native.ptr(gates), native.ptr(cs), native.ptr(tcs), *map(native.ptr, w), native.ptr(d_out), native.ptr(dh),
                              native.ptr(dc), native.ptr(d_gates), native.ptr(d_small), lib.blas[gates.dtype])
    d_w_ci, d_w_cf, d_w_co, d_bias = d_small.split((H, H, H, 4 * H))
    return d_gates, dh, dc, (d_w_ci, d_w_cf, d_w_co, d_bias)


class PeepholeFunction(torch.autograd.Function):
    """The peephole LSTM layer with a hand-written backward pass (what makes it as fast as ``nn.LSTM``).

    Forward runs the time loop without building an autograd graph; backward walks the steps once in
    reverse. On CPU both loops are the compiled ones of ``peephole.cpp`` (:mod:`study.learn.native`: one BLAS
    call and one fused elementwise pass per step), else :func:`recurrence` and :func:`backward_loop`
    in PyTorch operations. The weight gradients are then single matrix products over all time steps.
    Both paths are checked against :func:`reference` and ``torch.autograd.gradcheck`` in the tests.
    """

    @staticmethod
    def forward(ctx, x, h0, c0, weight_ih, weight_hh, bias, w_ci, w_cf, w_co):  # type: ignore[override]
        xw = F.linear(x.transpose(0, 1), weight_ih, bias).contiguous()  # (T, B, 4H), one matmul for all t
        lib = native_for(xw, h0, c0, weight_hh, w_ci, w_cf, w_co)
        if lib is not None:
            gates, cs, hs, tcs = recurrence_native(lib, xw, h0, c0, weight_hh, w_ci, w_cf, w_co)
        else:
            gates, cs, hs, tcs = recurrence(xw, h0, c0, weight_hh, torch.stack((w_ci, w_cf)), w_co)
        ctx.native = lib
        ctx.save_for_backward(x, weight_ih, weight_hh, w_ci, w_cf, w_co, gates, cs, hs, tcs)
        out = hs[1:].transpose(0, 1)  # (B, T, H)
        return out, hs[-1].clone(), cs[-1].clone()

    @staticmethod
    def backward(ctx, d_out, d_h, d_c):  # type: ignore[override]
        x, weight_ih, weight_hh, w_ci, w_cf, w_co, gates, cs, hs, tcs = ctx.saved_tensors
        T, B, H4 = gates.shape
        H = H4 // 4
        if ctx.native is not None and native.all_finite(d_out, d_h, d_c):
            d_gates, dh, dc, small = backward_native(ctx.native, d_out, d_h, d_c, gates, cs, tcs, weight_hh,
                                                      w_ci, w_cf, w_co)
        else:
            d_gates, dh, dc = backward_loop(d_out, d_h, d_c, gates, cs, hs, tcs, weight_hh, w_ci, w_cf, w_co)
            small = small_grads(d_gates, cs)
        d_w_ci, d_w_cf, d_w_co, d_bias = small
        flat = d_gates.reshape(T * B, H4)
        need = ctx.needs_input_grad
        dx = (d_gates @ weight_ih).transpose(0, 1) if need[0] else None  # (B, T, D)
        # Both weight gradients in one matrix product over all time steps: [x_t, h_{t-1}] (T B, D + H).
        xh = torch.cat((x.transpose(0, 1).reshape(T * B, -1), hs[:-1].reshape(T * B, H)), dim=1)
        d_w = (xh.t() @ flat).t()  # (4H, D + H); this operand order is the faster one for BLAS here
        D = x.shape[2]
        d_w_ih = d_w[:, :D].contiguous() if need[3] else None
        d_w_hh = d_w[:, D:].contiguous() if need[4] else None
        return dx, dh, dc, d_w_ih, d_w_hh, d_bias if need[5] else None, d_w_ci, d_w_cf, d_w_co


# ---------------------------------------------------------------------------------------------
# K layers at once, one per member of a stack (``study.learn.stack``): (K, T, B, .)


def reference(x: torch.Tensor, h0: torch.Tensor, c0: torch.Tensor, weight_ih: torch.Tensor,
                       weight_hh: torch.Tensor, bias: torch.Tensor, w_ci: torch.Tensor, w_cf: torch.Tensor,
                       w_co: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
    """K peephole LSTM layers as plain PyTorch operations, one batched product per time step for all members
    (autograd differentiates them): the stacked PyTorch path, on any device. Shapes as :class:`StackedPeephole`; one layer alone is K = 1. The definition the compiled loops are
    tested against."""
    K, T, B, C = x.shape
    xw = baddbmm(bias.unsqueeze(1), x.reshape(K, T * B, C), weight_ih.transpose(1, 2)).view(K, T, B, -1)
    w_hh_t = weight_hh.transpose(1, 2)
    ci, cf, co = (w.unsqueeze(1) for w in (w_ci, w_cf, w_co))  # (K, 1, H)
    h, c, hs = h0, c0, []
    for t in range(T):
        a_i, a_f, a_g, a_o = baddbmm(xw[:, t], h, w_hh_t).chunk(4, 2)  # each (K, B, H)
        i = torch.sigmoid(a_i + ci * c)
        f = torch.sigmoid(a_f + cf * c)
        c = f * c + i * torch.tanh(a_g)
        h = torch.sigmoid(a_o + co * c) * torch.tanh(c)
        hs.append(h)
    return torch.stack(hs, 1), h, c


class StackedPeephole(torch.autograd.Function):
    """K peephole LSTM layers (or LSTMs without peepholes), one per member: ``x`` (K, T, B, C) time-major,
    ``h0``, ``c0`` (K, B, H); weights ``weight_ih`` (K, 4H, C), ``weight_hh`` (K, 4H, H), ``bias`` (K, 4H),
    peepholes ``w_ci``, ``w_cf``, ``w_co`` (K, H) -> hidden states (K, T, B, H), last h and c (K, B, H).

    The compiled loop of ``peephole.cpp``, member by member, each writing into its slice of the stacked buffers
    (the trainer hands it finite parameters only; a member whose incoming gradient is not finite goes back
    through the PyTorch loop of :func:`backward_loop`, which propagates it as PyTorch does)."""

    @staticmethod
    def forward(ctx, x, h0, c0, weight_ih, weight_hh, bias, w_ci, w_cf, w_co):  # type: ignore[override]
        lib = native.active()
        K, T, B, C = x.shape
        H = weight_hh.shape[2]
        gates = baddbmm(bias.unsqueeze(1), x.reshape(K, T * B, C), weight_ih.transpose(1, 2)).view(K, T, B, 4 * H)
        cs, hs = gates.new_empty(K, T + 1, B, H), gates.new_empty(K, T + 1, B, H)
        tcs = gates.new_empty(K, T, B, H)
        cs[:, 0], hs[:, 0] = c0, h0
        run = lib.forward[gates.dtype]
        for k in range(K):
            w = [t.detach().contiguous() for t in (weight_hh[k].t(), w_ci[k], w_cf[k], w_co[k])]
            run(T, B, H, native.ptr(gates[k]), *map(native.ptr, w), native.ptr(cs[k]), native.ptr(hs[k]),
                native.ptr(tcs[k]), lib.blas[gates.dtype])
        ctx.lib = lib
        ctx.save_for_backward(x, weight_ih, weight_hh, w_ci, w_cf, w_co, gates, cs, hs, tcs)
        return hs[:, 1:], hs[:, -1].clone(), cs[:, -1].clone()

    @staticmethod
    def backward(ctx, d_out, d_h, d_c):  # type: ignore[override]
        x, weight_ih, weight_hh, w_ci, w_cf, w_co, gates, cs, hs, tcs = ctx.saved_tensors
        lib = ctx.lib
        K, T, B, G = gates.shape
        H = G // 4
        d_gates = torch.empty_like(gates)  # (K, T, B, 4H)
        dh0, dc0 = gates.new_empty(K, B, H), gates.new_empty(K, B, H)
        small = gates.new_empty(K, 7 * H)  # peepholes (3H) and bias (4H), summed over time and batch
        run = lib.backward[gates.dtype]
        for k in range(K):
            dout_k = None if d_out is None else d_out[k]
            dh_k = None if d_h is None else d_h[k]
            dc_k = None if d_c is None else d_c[k]
            if not native.all_finite(dout_k, dh_k, dc_k):
                dg, dh, dc = backward_loop(None if dout_k is None else dout_k.transpose(0, 1), dh_k, dc_k,
                                           gates[k], cs[k], hs[k], tcs[k], weight_hh[k], w_ci[k], w_cf[k], w_co[k])
                d_gates[k], dh0[k], dc0[k] = dg, dh, dc
                small[k] = torch.cat(small_grads(dg, cs[k]))
                continue
            dout = native.own(dout_k, gates[k], (T, B, H))  # time-major; the loop writes into it
            dh0[k] = native.own(dh_k, gates[k], (B, H))
            dc0[k] = native.own(dc_k, gates[k], (B, H))
            w = [t.detach().contiguous() for t in (weight_hh[k], w_ci[k], w_cf[k], w_co[k])]
            run(T, B, H, native.ptr(gates[k]), native.ptr(cs[k]), native.ptr(tcs[k]), *map(native.ptr, w),
                native.ptr(dout), native.ptr(dh0[k]), native.ptr(dc0[k]), native.ptr(d_gates[k]), native.ptr(small[k]),
                lib.blas[gates.dtype])
        flat = d_gates.view(K, T * B, G)
        dx = bmm(flat, weight_ih).view(K, T, B, -1)  # (K, T, B, C)
        C = x.shape[3]
        xh = torch.cat((x.reshape(K, T * B, C), hs[:, :-1].reshape(K, T * B, H)), dim=2)  # (K, T B, C + H)
        d_w = bmm(xh.transpose(1, 2), flat).transpose(1, 2)  # (K, 4H, C + H)
        d_ci, d_cf, d_co, d_b = small.split((H, H, H, 4 * H), dim=1)
        return (dx, dh0, dc0, d_w[:, :, :C].contiguous(), d_w[:, :, C:].contiguous(), d_b, d_ci, d_cf, d_co)


def _compiled(*tensors: torch.Tensor) -> bool:
    return (tensors[0].device.type == "cpu" and tensors[0].dtype in (torch.float32, torch.float64)
            and native.active() is not None)


def stacked_layer(x, h0, c0, *weights):
    """One stacked peephole layer: the compiled loop on the CPU where there is one (the trainer hands it finite
    parameters only: a member whose parameters stop being finite has diverged and left), else the PyTorch loop."""
    if _compiled(x):
        return StackedPeephole.apply(x, h0, c0, *weights)
    return reference(x, h0, c0, *weights)
