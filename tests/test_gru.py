"""The compiled GRU (study.learn.gru) against nn.GRU itself: same initialisation, outputs and gradients."""

import contextlib

import pytest
import torch

from study.learn import native
from study.learn.gru import GRU, GRUFunction
from study.learn.model import Classifier

pytestmark = pytest.mark.skipif(native.load() is None, reason="no compiled loop here (no C++ compiler)")


def _run(net: GRU, x: torch.Tensor, hx: torch.Tensor | None, compiled: bool):
    """Outputs, final states and the gradients of a fixed random projection of both w.r.t. everything."""
    inputs = [x] + ([hx] if hx is not None else []) + list(net.parameters())
    with contextlib.nullcontext() if compiled else native.disabled():
        out, h = net(x, hx)
    g = torch.Generator().manual_seed(1)
    w_out = torch.randn(out.shape, generator=g, dtype=torch.float64).to(out.dtype)
    w_h = torch.randn(h.shape, generator=g, dtype=torch.float64).to(h.dtype)
    loss = (out * w_out).sum() + (h * w_h).sum()
    return out, h, torch.autograd.grad(loss, inputs)


@pytest.mark.parametrize("with_state", [False, True])
def test_compiled_gru_equals_nn_gru_outputs_and_gradients(with_state):
    torch.manual_seed(0)
    net = GRU(3, 5, 2).double()
    x = torch.randn(4, 7, 3, dtype=torch.float64, requires_grad=True)
    hx = torch.randn(2, 4, 5, dtype=torch.float64, requires_grad=True) if with_state else None
    assert net._compiled(x, hx)
    fast = _run(net, x, hx, compiled=True)
    ref = _run(net, x, hx, compiled=False)
    torch.testing.assert_close(fast[0], ref[0], atol=1e-12, rtol=0)
    torch.testing.assert_close(fast[1], ref[1], atol=1e-12, rtol=0)
    for a, b in zip(fast[2], ref[2]):
        torch.testing.assert_close(a, b, atol=1e-10, rtol=0)
    assert all(g.abs().sum() > 0 for g in fast[2]), "the input, the state and every parameter get a gradient"


def test_compiled_gru_float32_within_1e5_of_float64():
    torch.manual_seed(0)
    net = GRU(3, 16, 2)
    x = torch.randn(8, 30, 3)
    out, h, grads = _run(net, x.requires_grad_(), None, compiled=True)
    ref = GRU(3, 16, 2).double()
    ref.load_state_dict(net.state_dict())
    out64, h64, grads64 = _run(ref, x.detach().double().requires_grad_(), None, compiled=False)
    torch.testing.assert_close(out.double(), out64, atol=1e-5, rtol=0)
    for a, b in zip(grads, grads64):
        torch.testing.assert_close(a.double(), b, atol=1e-5, rtol=1e-4)


def test_gru_function_gradcheck():
    torch.manual_seed(0)
    x = torch.randn(2, 4, 2, dtype=torch.float64, requires_grad=True)
    h0 = torch.randn(2, 3, dtype=torch.float64, requires_grad=True)
    params = [torch.randn(s, dtype=torch.float64, requires_grad=True) for s in ((9, 2), (9, 3), (9,), (9,))]
    assert torch.autograd.gradcheck(lambda *a: GRUFunction.apply(*a)[0], (x, h0, *params))


def test_same_initialisation_and_state_dict_as_nn_gru():
    torch.manual_seed(3)
    ours = GRU(3, 8, 2)
    torch.manual_seed(3)
    theirs = torch.nn.GRU(3, 8, 2, batch_first=True)
    assert ours.state_dict().keys() == theirs.state_dict().keys()
    assert all(torch.equal(a, b) for a, b in zip(ours.state_dict().values(), theirs.state_dict().values()))


@pytest.mark.slow
def test_gru_classifier_trains_on_the_compiled_loop_and_falls_back_elsewhere(monkeypatch):
    torch.manual_seed(0)
    net = Classifier(3, hidden=8, cell="gru")
    x = torch.randn(4, 6, 3)
    calls = []
    orig = GRUFunction.apply
    monkeypatch.setattr(GRUFunction, "apply", lambda *a: calls.append(1) or orig(*a))
    net(x).sum().backward()
    assert len(calls) == 2, "both layers ran the compiled loop"
    with native.disabled():
        net(x)
    assert len(calls) == 2, "with study.native disabled the layer is plain nn.GRU"


def test_the_plain_reference_is_nn_grus_equations():
    """``gru.reference`` (K stacked layers, time-major) with one member against ``nn.GRU`` itself, outputs and the
    last state: the one plain definition the stacked compiled loop is held to (``tests/test_stack.py``)."""
    from study.learn import gru

    torch.manual_seed(0)
    net = torch.nn.GRU(3, 5, 1, batch_first=True).double()
    x = torch.randn(4, 7, 3, dtype=torch.float64)
    h0 = torch.randn(1, 4, 5, dtype=torch.float64)
    want, last = net(x, h0)
    hs, h = gru.reference(x.transpose(0, 1)[None], h0, *(p[None] for p in (net.weight_ih_l0, net.weight_hh_l0,
                                                                            net.bias_ih_l0, net.bias_hh_l0)))
    torch.testing.assert_close(hs[0].transpose(0, 1), want, atol=1e-12, rtol=0)
    torch.testing.assert_close(h, last, atol=1e-12, rtol=0)
