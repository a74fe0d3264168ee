"""Products of K stacked members, ``(K, ...)``: member by member on the CPU, so that each member's product is
bitwise the one a lone run makes (a batched product may choose its kernel by the batch), one batched product
elsewhere (a GPU, where batching pays). Used by the stacked layers of ``study.learn.peephole`` and
``study.learn.gru`` and by the stacked trainer, ``study.learn.stack``.
"""

from __future__ import annotations

import torch


def bmm(a: torch.Tensor, b: torch.Tensor, out: torch.Tensor | None = None) -> torch.Tensor:
    """``a`` (K, n, m) @ ``b`` (K, m, p) -> (K, n, p): member by member on the CPU (each the product a lone run
    makes, written into its slice of ``out``), one batched product elsewhere."""
    if a.device.type != "cpu":
        return torch.bmm(a, b, out=out)
    out = a.new_empty(a.shape[0], a.shape[1], b.shape[2]) if out is None else out
    for k in range(a.shape[0]):
        torch.mm(a[k], b[k], out=out[k])
    return out


def baddbmm(c: torch.Tensor, a: torch.Tensor, b: torch.Tensor) -> torch.Tensor:
    """``c`` (K, 1 or n, p) + ``a`` (K, n, m) @ ``b`` (K, m, p), as :func:`bmm` (differentiable: autograd may
    track its inputs; the layers' own functions write in place instead)."""
    if a.device.type != "cpu":
        return torch.baddbmm(c, a, b)
    if torch.is_grad_enabled() and any(t.requires_grad for t in (a, b, c)):
        return torch.stack([torch.addmm(z, x, y) for z, x, y in zip(c.unbind(0), a.unbind(0), b.unbind(0))])
    out = a.new_empty(a.shape[0], a.shape[1], b.shape[2])
    for k in range(a.shape[0]):
        torch.addmm(c[k], a[k], b[k], out=out[k])
    return out
