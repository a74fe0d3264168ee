"""The peephole LSTM against a plain reference and nn.LSTM; streaming equals whole-sequence."""

import pytest
import torch

from study.errors import ConfigError
from study.model import CELLS, Classifier, PeepholeLSTM, peephole_reference


def _layer(D: int = 3, H: int = 5, seed: int = 0) -> PeepholeLSTM:
    torch.manual_seed(seed)
    return PeepholeLSTM(D, H).double()


def _grads(fn, layer, x, state):
    """Outputs and gradients of a random projection of outputs and final state w.r.t. everything."""
    out, (h, c) = fn(layer, x, state)
    g = torch.Generator().manual_seed(1)
    loss = (out * torch.randn(out.shape, generator=g, dtype=out.dtype)).sum() + (h * c).sum()
    inputs = [x, *state, *layer.parameters()]
    return out, torch.autograd.grad(loss, inputs)


def test_peephole_layer_equals_plain_reference_outputs_and_gradients():
    layer = _layer()
    x = torch.randn(3, 7, 3, dtype=torch.float64, requires_grad=True)
    state = (torch.randn(3, 5, dtype=torch.float64, requires_grad=True),
             torch.randn(3, 5, dtype=torch.float64, requires_grad=True))
    fast_out, fast_g = _grads(lambda m, x, s: m(x, s), layer, x, state)
    ref_out, ref_g = _grads(peephole_reference, layer, x, state)
    torch.testing.assert_close(fast_out, ref_out, atol=1e-6, rtol=0)
    for a, b in zip(fast_g, ref_g):
        torch.testing.assert_close(a, b, atol=1e-6, rtol=0)
    assert all(g.abs().sum() > 0 for g in fast_g), "every parameter, the input and the state get a gradient"


def test_peepholes_matter():
    """Guard against a reference that ignores the peepholes in the same way as the layer."""
    layer = _layer()
    x = torch.randn(2, 6, 3, dtype=torch.float64)
    before, _ = layer(x)
    with torch.no_grad():
        layer.w_co.add_(1.0)
    after, _ = layer(x)
    assert (before - after).abs().max() > 1e-3
    torch.testing.assert_close(after, peephole_reference(layer, x)[0], atol=1e-6, rtol=0)


def test_gradcheck():
    layer = _layer(D=2, H=3)
    x = torch.randn(2, 4, 2, dtype=torch.float64, requires_grad=True)
    assert torch.autograd.gradcheck(lambda x: layer(x)[0], (x,))


def test_zero_peepholes_equal_nn_lstm():
    layer = _layer(D=3, H=6)
    torch.manual_seed(2)
    ref = torch.nn.LSTM(3, 6, batch_first=True).double()
    with torch.no_grad():
        layer.weight_ih.copy_(ref.weight_ih_l0)
        layer.weight_hh.copy_(ref.weight_hh_l0)
        layer.bias.copy_(ref.bias_ih_l0 + ref.bias_hh_l0)
        for w in (layer.w_ci, layer.w_cf, layer.w_co):
            w.zero_()
    x = torch.randn(4, 9, 3, dtype=torch.float64)
    out, (h, c) = layer(x)
    ref_out, (ref_h, ref_c) = ref(x)
    torch.testing.assert_close(out, ref_out, atol=1e-12, rtol=0)
    torch.testing.assert_close(h, ref_h[0], atol=1e-12, rtol=0)
    torch.testing.assert_close(c, ref_c[0], atol=1e-12, rtol=0)


@pytest.mark.parametrize("cell", CELLS)
def test_streaming_equals_whole_sequence(cell):
    torch.manual_seed(0)
    net = Classifier(3, hidden=8, layers=2, cell=cell).double().eval()
    net.set_scale(torch.tensor([0.5, 2.0, 0.3]))
    x = torch.randn(2, 6, 3, dtype=torch.float64)
    state = net.init_state(2)
    for t in range(x.shape[1]):
        probs, state = net.step(x[:, t], state)
        whole = torch.softmax(net(x[:, : t + 1]), dim=-1)
        torch.testing.assert_close(probs, whole, atol=1e-12, rtol=0)


@pytest.mark.parametrize("cell", CELLS)
def test_classifier_shapes_and_normalisation(cell):
    torch.manual_seed(0)
    net = Classifier(1, hidden=4, cell=cell).eval()
    x = torch.randn(5, 7, 1)
    plain = net(x)
    assert plain.shape == (5, 2)
    net.set_scale(torch.tensor([4.0]))
    torch.testing.assert_close(net(4.0 * x), plain)  # inputs are divided by the stored std
    assert "scale" in net.state_dict(), "the statistics travel with the weights"


def test_dropout_only_in_training_mode():
    torch.manual_seed(0)
    net = Classifier(3, hidden=8, dropout=0.5)
    x = torch.randn(4, 5, 3)
    net.train()
    assert not torch.equal(net(x), net(x))
    net.eval()
    assert torch.equal(net(x), net(x))


def test_unknown_cell():
    with pytest.raises(ConfigError, match="cell"):
        Classifier(3, cell="transformer")
