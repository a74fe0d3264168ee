"""The peephole LSTM against a plain reference and nn.LSTM; streaming equals whole-sequence."""

import contextlib

import numpy as np
import pytest
import torch

from study.core.errors import ConfigError, TrajectoryError
from study.learn import native, peephole
from study.learn.config import INPUTS
from study.learn.model import CELLS, Classifier, PeepholeLSTM
from study.learn.stream import Streamer


@pytest.fixture(params=["native", "torch"])
def backend(request, monkeypatch):
    """Run a test with the compiled time loop (peephole.cpp) and with the PyTorch-operations loop."""
    monkeypatch.setenv("STUDY_NATIVE", "1" if request.param == "native" else "0")
    native.load.cache_clear()
    if request.param == "native" and native.load() is None:
        pytest.skip("the compiled loop is not available here (no C++ compiler)")
    assert native.backend() == request.param
    yield request.param
    native.load.cache_clear()


def _layer(D: int = 3, H: int = 5, seed: int = 0) -> PeepholeLSTM:
    torch.manual_seed(seed)
    return PeepholeLSTM(D, H).double()


def peephole_reference(layer, x, state=None):
    """``layer`` (a ``PeepholeLSTM``) run by the cell's one plain definition, ``study.learn.peephole.reference``
    (K stacked layers, time-major) with one member: ``x`` (B, T, D) -> (B, T, H) and the final (h, c)."""
    h0, c0 = layer.init_state(x.shape[0], x) if state is None else state
    weights = (layer.weight_ih, layer.weight_hh, layer.bias, layer.w_ci, layer.w_cf, layer.w_co)
    hs, h, c = peephole.reference(x.transpose(0, 1).unsqueeze(0), h0.unsqueeze(0), c0.unsqueeze(0),
                                  *(w.unsqueeze(0) for w in weights))
    return hs[0].transpose(0, 1), (h[0], c[0])


def _grads(fn, layer, x, state):
    """Outputs and gradients of a random projection of outputs and final state w.r.t. everything."""
    out, (h, c) = fn(layer, x, state)
    g = torch.Generator().manual_seed(1)
    weights = torch.randn(out.shape, generator=g, dtype=torch.float64).to(out.dtype)  # same draws in any dtype
    loss = (out * weights).sum() + (h * c).sum()
    inputs = [x, *state, *layer.parameters()]
    return out, torch.autograd.grad(loss, inputs)


def test_peephole_layer_equals_plain_reference_outputs_and_gradients(backend):
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


def test_peepholes_matter(backend):
    """Guard against a reference that ignores the peepholes in the same way as the layer."""
    layer = _layer()
    x = torch.randn(2, 6, 3, dtype=torch.float64)
    before, _ = layer(x)
    with torch.no_grad():
        layer.w_co.add_(1.0)
    after, _ = layer(x)
    assert (before - after).abs().max() > 1e-3
    torch.testing.assert_close(after, peephole_reference(layer, x)[0], atol=1e-6, rtol=0)


def test_gradcheck(backend):
    layer = _layer(D=2, H=3)
    x = torch.randn(2, 4, 2, dtype=torch.float64, requires_grad=True)
    assert torch.autograd.gradcheck(lambda x: layer(x)[0], (x,))


def test_zero_peepholes_equal_nn_lstm(backend):
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


def normalised(net: Classifier) -> Classifier:
    """``net`` with a mean and a std per channel that are not 0 and 1 (so a test sees them used)."""
    C = net.features.n_channels
    net.set_normalisation(torch.linspace(-0.3, 0.4, C, dtype=net.features.mean.dtype),
                          torch.linspace(0.5, 2.0, C, dtype=net.features.std.dtype))
    return net


@pytest.mark.parametrize("inputs", INPUTS)
@pytest.mark.parametrize("cell", CELLS)
def test_streaming_equals_whole_sequence(cell, inputs, backend):
    torch.manual_seed(0)
    net = normalised(Classifier(3, hidden=8, layers=2, cell=cell, inputs=inputs, fps=30.0).double().eval())
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
    net.set_normalisation(torch.tensor([0.0]), torch.tensor([4.0]))
    torch.testing.assert_close(net(4.0 * x), plain)  # positions are divided by the stored std
    assert {"features.mean", "features.std"} <= set(net.state_dict()), "the statistics travel with the weights"


def test_velocity_channels_are_the_positions_and_their_differences_times_the_frame_rate():
    from study.learn.model import Features

    f = Features(1, "velocity", fps=30.0)
    x = torch.tensor([[[1.0], [1.5], [1.25]]])  # (1, 3, 1) metres
    torch.testing.assert_close(f.raw(x), torch.tensor([[[1.0, 0.0], [1.5, 15.0], [1.25, -7.5]]]))
    torch.testing.assert_close(f.raw(x[:, 1:], prev=x[:, 0]), f.raw(x)[:, 1:]), "the frame before carries over"
    f.mean.copy_(torch.tensor([1.0, 2.0]))
    f.std.copy_(torch.tensor([0.5, 10.0]))
    torch.testing.assert_close(f(x)[0, 1], torch.tensor([1.0, 1.3]))
    assert Features(3, "positions").n_channels == 3 and Features(3, "velocity").n_channels == 6


def test_speed_channels_are_the_height_its_velocity_and_the_horizontal_speed():
    from study.learn.model import Features

    f = Features(3, "speed", fps=10.0)
    x = torch.tensor([[[0.0, 0.0, 1.0], [0.3, -0.4, 0.8], [0.3, -0.4, 0.8]]])  # (1, 3, 3) metres
    torch.testing.assert_close(f.raw(x), torch.tensor([[[1.0, 0.0, 0.0], [0.8, -2.0, 5.0], [0.8, 0.0, 0.0]]]))
    torch.testing.assert_close(f.raw(x[:, 1:], prev=x[:, 0]), f.raw(x)[:, 1:]), "the frame before carries over"
    assert f.n_channels == 3 and Features(1, "speed").n_channels == 2
    z = torch.randn(2, 7, 1, dtype=torch.float64)
    assert torch.equal(Features(1, "speed").raw(z), Features(1, "velocity").raw(z)), "on Z alone: the velocity's"


def _turned(x: torch.Tensor, degrees: float | np.ndarray) -> torch.Tensor:
    """``x`` (B, T, 3) turned about the vertical through the origin (``study.learn.inputs.rotated``)."""
    from study.learn.inputs import rotated

    a = np.broadcast_to(np.asarray(degrees, dtype=np.float64), (x.shape[0],))
    return torch.from_numpy(rotated(x.numpy(), a))


@pytest.mark.parametrize("cell", CELLS)
def test_a_throw_turned_about_the_vertical_gets_the_same_answer_from_the_speed_input_only(cell):
    """Every throw starts at x = y = 0 with its heading uniform on the circle: the 'speed' network's answer does not
    depend on it; a network on the positions (or their signed velocity) answers otherwise."""
    torch.manual_seed(0)
    x = torch.cumsum(0.1 * torch.randn(4, 15, 3, dtype=torch.float64), dim=1)
    x[:, 0, :2] = 0.0  # launched at the origin
    angles = np.array([37.0, 90.0, -120.0, 179.0])
    for inputs in INPUTS:
        torch.manual_seed(1)
        net = normalised(Classifier(3, hidden=8, cell=cell, inputs=inputs).double().eval())
        with torch.no_grad():
            before, after = net(x), net(_turned(x, angles))
        gap = float((torch.softmax(before, -1) - torch.softmax(after, -1)).abs().max())
        if inputs == "speed":
            assert gap < 1e-12, f"{cell}: turning the throw moved the answer by {gap}"
        else:
            assert gap > 1e-3, f"{cell}, {inputs}: the answer should depend on the heading"


def test_the_numpy_streamer_of_a_speed_network_ignores_the_heading_frame_by_frame():
    torch.manual_seed(0)
    net = normalised(Classifier(3, hidden=8, inputs="speed").double().eval())
    x = torch.cumsum(0.1 * torch.randn(1, 12, 3, dtype=torch.float64), dim=1)
    a, b = Streamer(net, dtype=np.float64), Streamer(net, dtype=np.float64)
    for plain, turned in zip(x[0].numpy(), _turned(x, 63.0)[0].numpy()):
        np.testing.assert_allclose(a.push(plain), b.push(turned), atol=1e-12, rtol=0)


@pytest.mark.parametrize("inputs", INPUTS)
def test_the_stacked_first_layer_equals_the_classifier_s(inputs):
    from study.learn import stack
    from study.learn.model import Features

    f = Features(3, inputs, fps=30.0).double()
    C = f.n_channels
    f.mean.copy_(torch.linspace(-0.3, 0.4, C, dtype=torch.float64))
    f.std.copy_(torch.linspace(0.5, 2.0, C, dtype=torch.float64))
    x = torch.randn(2, 4, 9, 3, dtype=torch.float64)  # (K, B, T, D)
    got = stack.features(x, f.mean.expand(2, C), f.std.expand(2, C), inputs, 30.0)
    torch.testing.assert_close(got, torch.stack([f(x[k]) for k in range(2)]), atol=0, rtol=0)


@pytest.mark.parametrize("inputs, D", [("velocity", 1), ("speed", 3)])
@pytest.mark.parametrize("cell", ["peephole", "gru"])
def test_the_split_forward_pass_equals_the_whole_one_with_velocity(cell, inputs, D, backend):
    """Truncated BPTT runs the first frames without a graph and hands the state on: the velocity of the first
    frame after the split must come from the frame before it, so the two passes give the unsplit answer."""
    from study.learn.stack import last_logits

    torch.manual_seed(0)
    net = normalised(Classifier(D, hidden=8, cell=cell, inputs=inputs, fps=30.0).double().eval())
    x = torch.randn(3, 20, D, dtype=torch.float64)
    torch.testing.assert_close(last_logits(net, x, truncation=7), net(x), atol=1e-12, rtol=0)


@pytest.mark.parametrize("inputs", INPUTS)
def test_a_nan_in_one_trajectory_reaches_its_output_only(inputs, backend):
    torch.manual_seed(0)
    net = normalised(Classifier(1, hidden=8, inputs=inputs).eval())
    x = torch.randn(4, 10, 1)
    x[2, 5, 0] = float("nan")
    with torch.no_grad():
        out = net(x)
    assert torch.isnan(out[2]).all() and torch.isfinite(out[[0, 1, 3]]).all()
    torch.testing.assert_close(out[[0, 1, 3]], net(x[[0, 1, 3]]), atol=1e-6, rtol=0)


def test_dropout_only_in_training_mode():
    torch.manual_seed(0)
    net = Classifier(3, hidden=8, dropout=0.5)
    x = torch.randn(4, 5, 3)
    net.train()
    assert not torch.equal(net(x), net(x))
    net.eval()
    assert torch.equal(net(x), net(x))


def test_no_peephole_cell_keeps_its_peepholes_at_zero_and_equals_nn_lstm(backend):
    torch.manual_seed(0)
    net = Classifier(3, hidden=8, layers=2, cell="no-peephole").double()
    names = {n for n, _ in net.named_parameters()}
    assert not any(n.endswith(("w_ci", "w_cf", "w_co")) for n in names), "peepholes are not trained"
    opt = torch.optim.Adam(net.parameters(), lr=0.1)
    x = torch.randn(4, 6, 3, dtype=torch.float64)
    torch.nn.functional.cross_entropy(net(x), torch.tensor([0, 1, 0, 1])).backward()
    opt.step()
    for layer in net.rnn.layers:
        assert all(torch.equal(w, torch.zeros_like(w)) for w in (layer.w_ci, layer.w_cf, layer.w_co))
    # Its function is nn.LSTM's: copy the weights (one bias = nn.LSTM's two summed) and compare.
    ref = torch.nn.LSTM(3, 8, 2, batch_first=True).double()
    with torch.no_grad():
        for k, layer in enumerate(net.rnn.layers):
            getattr(ref, f"weight_ih_l{k}").copy_(layer.weight_ih)
            getattr(ref, f"weight_hh_l{k}").copy_(layer.weight_hh)
            getattr(ref, f"bias_ih_l{k}").copy_(layer.bias)
            getattr(ref, f"bias_hh_l{k}").zero_()
        torch.testing.assert_close(net.rnn(x)[0], ref(x)[0], atol=1e-12, rtol=0)


def test_unknown_cell():
    with pytest.raises(ConfigError, match="cell"):
        Classifier(3, cell="transformer")


def test_float32_layer_matches_float64_reference_within_1e_5(backend):
    """The fused layer in single precision (training's dtype) against the plain reference in double."""
    torch.manual_seed(3)
    layer = PeepholeLSTM(3, 16)
    x = torch.randn(4, 50, 3)
    state = (torch.randn(4, 16), torch.randn(4, 16))
    out, grads = _grads(lambda m, x, s: m(x, s), layer, x.requires_grad_(), [s.requires_grad_() for s in state])
    ref = PeepholeLSTM(3, 16).double()
    ref.load_state_dict({k: v.double() for k, v in layer.state_dict().items()})
    x64 = x.detach().double().requires_grad_()
    s64 = [s.detach().double().requires_grad_() for s in state]
    ref_out, ref_grads = _grads(peephole_reference, ref, x64, s64)
    torch.testing.assert_close(out.double(), ref_out, atol=1e-5, rtol=0)
    for a, b in zip(grads, ref_grads):
        torch.testing.assert_close(a.double(), b, atol=1e-5, rtol=1e-5)


def test_layer_without_grad_equals_layer_with_grad(backend):
    layer = _layer()
    x = torch.randn(2, 8, 3, dtype=torch.float64)
    with_grad, _ = layer(x)
    with torch.no_grad():
        without, _ = layer(x)
    assert torch.equal(with_grad.detach(), without)


@pytest.mark.parametrize("inputs", INPUTS)
@pytest.mark.parametrize("cell", ["peephole", "no-peephole", "torch-lstm"])
def test_numpy_streamer_equals_whole_sequence(cell, inputs):
    torch.manual_seed(0)
    net = normalised(Classifier(3, hidden=8, layers=2, cell=cell, inputs=inputs, fps=30.0).double().eval())
    x = torch.randn(1, 12, 3, dtype=torch.float64)
    s = Streamer(net, dtype=np.float64)
    for t in range(x.shape[1]):
        probs = s.push(x[0, t].numpy())
        with torch.no_grad():
            whole = torch.softmax(net(x[:, : t + 1]), dim=-1)[0].numpy()
        np.testing.assert_allclose(probs, whole, atol=1e-12, rtol=0)
    s.reset()
    np.testing.assert_allclose(s.push(x[0, 0].numpy()),
                               torch.softmax(net(x[:, :1]), dim=-1)[0].detach().numpy(), atol=1e-12, rtol=0)


def test_streamer_rejects_gru_and_wrong_frames():
    with pytest.raises(ConfigError, match="gru"):
        Streamer(Classifier(1, hidden=4, cell="gru"))
    s = Streamer(Classifier(1, hidden=4))
    with pytest.raises(TrajectoryError, match=r"\(1,\)"):
        s.push(np.zeros(3))


def test_native_and_torch_loops_agree_in_float32():
    """The two implementations of the time loop compute the same numbers up to float32 rounding."""
    if native.load() is None:
        pytest.skip("the compiled loop is not available here (no C++ compiler)")
    torch.manual_seed(4)
    net = Classifier(3, hidden=32).eval()  # no dropout: the same function on both runs
    x = torch.randn(8, 40, 3)
    results = []
    for loop in (contextlib.nullcontext(), native.disabled()):
        with loop:
            net.zero_grad()
            out = net(x)
            out.square().sum().backward()
        results.append((out.detach(), [p.grad.clone() for p in net.parameters()]))
    (a, ga), (b, gb) = results
    torch.testing.assert_close(a, b, atol=1e-5, rtol=0)
    for u, v in zip(ga, gb):
        torch.testing.assert_close(u, v, atol=1e-5, rtol=1e-4)


def test_native_falls_back_with_a_warning_when_it_cannot_compile(monkeypatch, tmp_path):
    monkeypatch.setenv("STUDY_NATIVE_DIR", str(tmp_path))
    monkeypatch.setenv("CXX", "no-such-compiler-xyz")
    native.load.cache_clear()
    with pytest.warns(RuntimeWarning, match="no C\\+\\+ compiler"):
        assert native.load() is None
    monkeypatch.setenv("CXX", "false")  # found, but every invocation fails
    native.load.cache_clear()
    with pytest.warns(RuntimeWarning, match="compiling peephole.cpp, gru.cpp failed"):
        assert native.load() is None
    assert list(tmp_path.iterdir()) == [], "a failed build leaves nothing behind"
    native.load.cache_clear()
    torch.manual_seed(0)
    layer = PeepholeLSTM(3, 4)
    with pytest.warns(RuntimeWarning):
        out, _ = layer(torch.randn(2, 5, 3))  # still runs, on the PyTorch loop
    assert out.shape == (2, 5, 4)
    native.load.cache_clear()  # later tests load the real kernel again


def test_every_native_entry_point_checks_its_arguments():
    """argtypes/restype are declared: a wrong call raises in Python instead of crashing in C."""
    import ctypes

    lib = native.load()
    if lib is None:
        pytest.skip("the compiled loop is not available here (no C++ compiler)")
    for name, n_pointers in native.SIGNATURES.items():
        fn = getattr(lib.lib, name)
        assert fn.restype is None and len(fn.argtypes) == 3 + n_pointers, name
        with pytest.raises(TypeError):
            fn(1, 1, 1)  # too few arguments
        with pytest.raises(ctypes.ArgumentError):
            fn(1, 1, 1, *([torch.zeros(4)] * n_pointers))  # a tensor, not its address


def test_native_build_goes_to_the_platform_cache(monkeypatch, tmp_path):
    monkeypatch.delenv("STUDY_NATIVE_DIR", raising=False)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    assert native.cache_dir() == tmp_path / "study" / "native"
    monkeypatch.setenv("STUDY_NATIVE_DIR", str(tmp_path / "elsewhere"))
    assert native.cache_dir() == tmp_path / "elsewhere"


def _poison(net: Classifier, x: torch.Tensor, case: str) -> torch.Tensor:
    """Put a NaN or an infinity into one sample's input, or into one recurrent weight (in place)."""
    bad = float("nan") if "nan" in case else float("inf")
    x = x.clone()
    if case.endswith("input"):
        x[1, 5, 0] = bad
    else:
        w = next(p for name, p in net.named_parameters() if "weight_hh" in name)
        with torch.no_grad():
            w.view(-1)[3] = bad
    return x


@pytest.mark.parametrize("cell", ["peephole", "gru"])
@pytest.mark.parametrize("case", ["nan-input", "inf-input", "nan-weight", "inf-weight"])
def test_non_finite_numbers_propagate_as_in_pytorch(cell, case):
    """float32, compiled loop against PyTorch's own: NaN and infinities give the same outputs and gradients,
    NaN where PyTorch has NaN (the compiled loop alone would have clamped them into finite numbers)."""
    if native.load() is None:
        pytest.skip("the compiled loop is not available here (no C++ compiler)")
    torch.manual_seed(5)
    net = Classifier(3, hidden=16, cell=cell).eval()
    x = _poison(net, torch.randn(4, 20, 3), case)
    results = []
    for loop in (contextlib.nullcontext(), native.disabled()):
        with loop:
            net.zero_grad()
            out = net(x)
            out.sum().backward()
        results.append((out.detach(), [p.grad.clone() for p in net.parameters()]))
    (a, ga), (b, gb) = results
    if case != "inf-input":  # an infinite input saturates the gates, in PyTorch too: finite logits
        assert not torch.isfinite(a).all()  # the poison reached the logits
    torch.testing.assert_close(a, b, equal_nan=True, atol=1e-5, rtol=0)
    for u, v in zip(ga, gb):
        torch.testing.assert_close(u, v, equal_nan=True, atol=1e-5, rtol=1e-4)
    if case == "nan-input":
        assert torch.isfinite(a[[0, 2, 3]]).all() and not torch.isfinite(a[1]).any()  # one sample only
