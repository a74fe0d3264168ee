"""Frame-by-frame classification of one trajectory in NumPy: what a car would run per camera frame.

:meth:`study.learn.model.Classifier.step` streams in PyTorch, but a PyTorch call costs several
microseconds however small the tensor, and one frame of the paper's network is some forty of
them. :class:`Streamer` copies the weights of a trained peephole (or plain) LSTM classifier into
preallocated NumPy buffers and updates one trajectory's state with about twenty small NumPy calls
per layer, none of which allocates. Its probabilities equal the PyTorch network's (tested); how fast
it is, ``benchmarks/bench_train.py`` measures.

Two rewrites make it cheap, both exact in real arithmetic:

* ``sigmoid(a) = (1 + tanh(a / 2)) / 2``, so the rows of the i, f and o gates (weights, bias and
  peepholes) are halved once, and one ``tanh`` serves the i, f and g gates together;
* the layer's input and its previous hidden state sit side by side in one buffer, so the gate
  pre-activations are one matrix-vector product with the stacked ``[W_ih | W_hh]``.
"""

from __future__ import annotations

import numpy as np
import torch

from study.core.errors import ConfigError, TrajectoryError


class _Layer:
    """Buffers and halved weights of one layer (H units, D inputs)."""

    def __init__(self, w_ih: np.ndarray, w_hh: np.ndarray, bias: np.ndarray, w_ci: np.ndarray,
                 w_cf: np.ndarray, w_co: np.ndarray, dtype: np.dtype) -> None:
        H4, D = w_ih.shape
        H = H4 // 4
        half = np.ones(H4)
        half[: 2 * H] = half[3 * H :] = 0.5  # the sigmoid gates i, f, o
        self.H, self.D = H, D
        self.w = np.ascontiguousarray((np.concatenate([w_ih, w_hh], axis=1) * half[:, None]).T, dtype=dtype)  # (D+H, 4H)
        self.b = (bias * half).astype(dtype)
        self.w_cif = (0.5 * np.stack([w_ci, w_cf])).astype(dtype)  # (2, H)
        self.w_co = (0.5 * w_co).astype(dtype)
        self.z = np.zeros(D + H, dtype)  # [input, h]
        self.c = np.zeros(H, dtype)
        self.pre = np.empty(4 * H, dtype)
        self.pre_if = self.pre[: 2 * H].reshape(2, H)
        self.pre_ifg = self.pre[: 3 * H]
        self.pre_o = self.pre[3 * H :]
        self.t = np.empty(3 * H, dtype)  # tanh of the halved i, f and the g pre-activations
        self.t_i, self.t_f, self.t_g = self.t[:H], self.t[H : 2 * H], self.t[2 * H :]
        self.tmp2 = np.empty((2, H), dtype)
        self.a = np.empty(H, dtype)
        self.o = np.empty(H, dtype)
        self.x = self.z[:D]
        self.h = self.z[D:]

    def reset(self) -> None:
        self.z[:] = 0
        self.c[:] = 0

    def step(self) -> np.ndarray:
        """Advance one frame, reading ``self.x``; returns h (H,), a view of the state buffer."""
        np.dot(self.z, self.w, out=self.pre)
        self.pre += self.b
        np.multiply(self.w_cif, self.c, out=self.tmp2)
        self.pre_if += self.tmp2  # i, f see the old cell
        np.tanh(self.pre_ifg, out=self.t)
        self.t[: 2 * self.H] += 1  # 2 i, 2 f
        np.multiply(self.t_f, self.c, out=self.c)
        np.multiply(self.t_i, self.t_g, out=self.a)
        self.c += self.a
        self.c *= 0.5  # c = f c + i g
        np.multiply(self.w_co, self.c, out=self.o)
        self.o += self.pre_o
        np.tanh(self.o, out=self.o)
        self.o += 1  # 2 o; the output gate sees the new cell
        np.tanh(self.c, out=self.a)
        np.multiply(self.o, self.a, out=self.h)
        self.h *= 0.5  # h = o tanh(c)
        return self.h


class Streamer:
    """Classify one trajectory frame by frame: ``push(xyz_or_z)`` -> probabilities (2,) of (light, heavy).

    Built from a :class:`study.learn.model.Classifier` with a ``peephole`` or ``lstm`` core (eval-mode
    behaviour: no dropout). Inputs are raw metres, turned into the network's channels as its first layer
    (``study.learn.model.Features``) does: divided by the training standard deviation, or, for a network that
    reads velocity, standardised beside the velocity from the previous frame (0 at the first frame); for one
    that reads ``'speed'``, the height, its velocity and the horizontal speed, standardised.
    ``reset()`` starts a new trajectory.
    """

    def __init__(self, net: torch.nn.Module, dtype: type = np.float32) -> None:
        features = net.features
        self.n_inputs = features.n_dims
        self.inputs = features.inputs
        self.fps = features.fps
        self.layers: list[_Layer] = []
        get = lambda t: t.detach().double().cpu().numpy()  # noqa: E731
        if net.cell_type in ("peephole", "no-peephole"):  # the latter's peepholes are zero buffers
            for layer in net.rnn.layers:
                self.layers.append(_Layer(get(layer.weight_ih), get(layer.weight_hh), get(layer.bias),
                                          get(layer.w_ci), get(layer.w_cf), get(layer.w_co), dtype))
        elif net.cell_type == "torch-lstm":
            for k in range(net.rnn.num_layers):
                p = {n: get(getattr(net.rnn, f"{n}_l{k}")) for n in ("weight_ih", "weight_hh", "bias_ih", "bias_hh")}
                zero = np.zeros(net.rnn.hidden_size)
                self.layers.append(_Layer(p["weight_ih"], p["weight_hh"], p["bias_ih"] + p["bias_hh"],
                                          zero, zero, zero, dtype))
        else:
            raise ConfigError(
                f"Streamer: cell {net.cell_type!r} is not supported; use Classifier.step for it, or a "
                "'peephole', 'no-peephole' or 'lstm' model"
            )
        self.inv_std = (1.0 / get(features.std)).astype(dtype)  # (C,)
        self.mean = get(features.mean).astype(dtype)  # (C,)
        self.prev = np.zeros(self.n_inputs, dtype)  # the last frame seen, for the velocity
        self.v = np.empty(self.n_inputs, dtype)  # the velocity into this frame, m/s
        self.channels = np.empty(features.n_channels, dtype)
        self.w_out = np.ascontiguousarray(get(net.head.weight).T, dtype=dtype)  # (H, 2)
        self.b_out = get(net.head.bias).astype(dtype)
        self.logits = np.empty(2, dtype)
        self.frames = 0

    def reset(self) -> None:
        """Forget the trajectory: zero every layer's state."""
        for layer in self.layers:
            layer.reset()
        self.frames = 0
        self.prev[:] = 0

    def update(self, x_t: np.ndarray) -> np.ndarray:
        """Consume one frame ``x_t`` (D,) metres and return the last layer's hidden state (H,) (a view)."""
        x_t = np.asarray(x_t)
        if x_t.shape != (self.n_inputs,):
            raise TrajectoryError(f"Streamer.push: frame of shape {x_t.shape}; the model takes ({self.n_inputs},) metres")
        first = self.layers[0]
        if self.inputs == "positions":
            np.multiply(x_t, self.inv_std, out=first.x)
        else:
            self._motion(x_t)
            np.multiply(self.channels, self.inv_std, out=first.x)
        h = first.step()
        for layer in self.layers[1:]:
            layer.x[:] = h
            h = layer.step()
        self.frames += 1
        return h

    def _motion(self, x_t: np.ndarray) -> None:
        """``self.channels`` for the frame ``x_t`` (D,) of a network that reads the motion, less the training mean
        (``study.learn.model.motion_channels``, one frame)."""
        D, c, v = self.n_inputs, self.channels, self.v
        if self.frames:
            np.subtract(x_t, self.prev, out=v)
            v *= self.fps
        else:
            v[:] = 0  # the first frame's velocity
        self.prev[:] = x_t
        if self.inputs == "velocity" or D == 1:
            c[:D] = x_t
            c[D:] = v
        else:  # 'speed' from X, Y, Z: the height, its velocity, the horizontal speed
            c[0], c[1] = x_t[2], v[2]
            c[2] = np.sqrt(v[0] * v[0] + v[1] * v[1])
        c -= self.mean

    def push(self, x_t: np.ndarray) -> np.ndarray:
        """Consume one frame ``x_t`` (D,) metres; return the class probabilities (2,) after it."""
        h = self.update(x_t)
        np.dot(h, self.w_out, out=self.logits)
        self.logits += self.b_out
        p_heavy = 1.0 / (1.0 + np.exp(self.logits[0] - self.logits[1]))
        return np.array([1.0 - p_heavy, p_heavy])
