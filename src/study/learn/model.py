"""The paper's classifier: two layers of peephole LSTM, dropout, and a softmax on the last hidden state.

PyTorch's ``nn.LSTM`` has no peepholes, so :class:`PeepholeLSTM` writes the layer out. Gates follow
Gers et al. (2002) and Sak et al. (2014), with diagonal peephole weights (one vector per gate)::

    i_t = sigmoid(W_xi x_t + W_hi h_{t-1} + w_ci * c_{t-1} + b_i)     input gate sees the old cell
    f_t = sigmoid(W_xf x_t + W_hf h_{t-1} + w_cf * c_{t-1} + b_f)     forget gate sees the old cell
    g_t = tanh   (W_xg x_t + W_hg h_{t-1}                  + b_g)
    c_t = f_t * c_{t-1} + i_t * g_t
    o_t = sigmoid(W_xo x_t + W_ho h_{t-1} + w_co * c_t     + b_o)     output gate sees the new cell
    h_t = o_t * tanh(c_t)

The gate order (i, f, g, o) and weight layout match ``nn.LSTM``, so with zero peepholes and
``bias = bias_ih + bias_hh`` the two compute the same function (tested).

:class:`Classifier` is the paper's network. Its inputs are raw trajectories in metres; a fixed first layer,
:class:`Features`, turns them into what the recurrent layers read: the positions divided by their
standard deviation on the training split (the paper's), or the positions and their frame-to-frame
velocity, each standardised (a network that reads the motion, not only where the object is). The
statistics are buffers, set by :meth:`Classifier.set_normalisation`, so they travel with the weights, and
every caller -- training, ``study classify``, the frame-by-frame streamers -- passes positions alone. The third
representation, ``'speed'``, keeps of the motion only what does not turn with the throw's heading: the height, its
velocity and the horizontal speed (every throw starts at x = y = 0 with its heading uniform on the circle, so the
signed horizontal channels carry the heading, and no class).

Shapes: B batch, T frames, D input dims (1 for Z, 3 for XYZ), C channels the recurrent layers read (D for
positions, 2 D with velocity; 2 with speed, 3 from X, Y, Z), H hidden units, L layers.
"""

from __future__ import annotations

import math

import torch
import torch.nn as nn
import torch.nn.functional as F

from study.core.errors import ConfigError
from study.learn import peephole
from study.learn.config import CELLS, INPUTS, Cell, Inputs
from study.learn.gru import GRU

# A layer's state is (h, c) for the LSTMs, h alone for the GRU; the classifier's state is what its recurrent
# core takes (a list of per-layer (h, c) for the peephole stack, nn.LSTM's or nn.GRU's own) with the last
# input frame, from which the next frame's velocity is taken.
State = object


def n_channels(n_dims: int, inputs: Inputs) -> int:
    """C, the channels per frame that ``inputs`` makes of ``n_dims`` position dims (:class:`Features`)."""
    if inputs == "positions":
        return n_dims
    if inputs == "speed":
        return 2 if n_dims == 1 else 3
    return 2 * n_dims


def motion_channels(x: torch.Tensor, before: torch.Tensor, inputs: Inputs, fps: float) -> torch.Tensor:
    """The channels of positions ``x`` (..., T, D) metres, given the frame before each (``before``, the same shape),
    before standardisation: (..., T, C). ``'velocity'``: ``x`` and ``v = (x - before) fps`` (m/s). ``'speed'``:
    the height, its velocity and, with X, Y, Z (D = 3), the horizontal speed ``|v_h| = sqrt(v_x^2 + v_y^2)``; with
    Z alone it is ``'velocity'``'s, bit for bit. (Positions need no frame before: :meth:`Features.raw`.)"""
    v = (x - before) * fps
    if inputs == "velocity" or x.shape[-1] == 1:
        return torch.cat([x, v], dim=-1)
    speed = torch.sqrt(v[..., 0:1] * v[..., 0:1] + v[..., 1:2] * v[..., 1:2])
    return torch.cat([x[..., 2:3], v[..., 2:3], speed], dim=-1)


class Features(nn.Module):
    """The classifier's fixed first layer: positions (B, T, D) metres -> channels (B, T, C) the recurrent
    layers read.

    ``'positions'`` (the paper's): ``x_t / std``, C = D. ``'velocity'``: ``(x_t - mean) / std`` and
    ``(v_t - mean_v) / std_v`` with ``v_t = (x_t - x_{t-1}) fps``, C = 2 D. ``'speed'``: the same of the height
    alone, and with X, Y, Z the horizontal speed ``|v_h|`` standardised beside them, C = 3 (2 for Z alone): a
    throw turned about the vertical gives the same channels. The first frame's velocity (and speed) is 0,
    unless the frame before it is given (the carried state of a trajectory fed in pieces). ``mean`` and
    ``std`` (C,) are buffers, set from the training split by ``study.learn.train.fit``.
    """

    def __init__(self, n_dims: int, inputs: Inputs = "positions", fps: float = 30.0) -> None:
        super().__init__()
        if inputs not in INPUTS:
            raise ConfigError(f"inputs = {inputs!r} is unknown; use one of {INPUTS}")
        self.inputs, self.fps, self.n_dims = inputs, float(fps), n_dims
        C = self.n_channels
        self.register_buffer("mean", torch.zeros(C))  # (C,) of the training split; positions: unused
        self.register_buffer("std", torch.ones(C))  # (C,) of the training split

    @property
    def n_channels(self) -> int:
        """C: channels per frame."""
        return n_channels(self.n_dims, self.inputs)

    def raw(self, x: torch.Tensor, prev: torch.Tensor | None = None) -> torch.Tensor:
        """The channels of ``x`` (B, T, D) before standardisation: (B, T, C). ``prev`` (B, D): the frame before
        ``x``'s first (its velocity is then not 0)."""
        if self.inputs == "positions":
            return x
        before = torch.cat([(x[:, :1] if prev is None else prev[:, None]), x[:, :-1]], dim=1)  # (B, T, D)
        return motion_channels(x, before, self.inputs, self.fps)

    def forward(self, x: torch.Tensor, prev: torch.Tensor | None = None) -> torch.Tensor:
        """``x`` (B, T, D) metres -> standardised channels (B, T, C)."""
        if self.inputs == "positions":
            return x / self.std  # the paper's normalisation, bit for bit
        return (self.raw(x, prev) - self.mean) / self.std


class PeepholeLSTM(nn.Module):
    """One peephole LSTM layer over a batch-first sequence (see the module docstring for the gates).

    With ``peepholes=False`` the peephole weights are zero buffers, not parameters: the layer is then a
    plain LSTM (the function of ``nn.LSTM``) that runs on the same loop.
    """

    def __init__(self, input_size: int, hidden_size: int, peepholes: bool = True) -> None:
        super().__init__()
        H = hidden_size
        self.input_size, self.hidden_size = input_size, hidden_size
        self.weight_ih = nn.Parameter(torch.empty(4 * H, input_size))  # rows: i, f, g, o
        self.weight_hh = nn.Parameter(torch.empty(4 * H, H))
        self.bias = nn.Parameter(torch.empty(4 * H))
        for name in ("w_ci", "w_cf", "w_co"):  # peepholes: diagonal, one weight per unit
            if peepholes:
                setattr(self, name, nn.Parameter(torch.empty(H)))
            else:
                self.register_buffer(name, torch.zeros(H))
        self.reset_parameters()

    def reset_parameters(self) -> None:
        """Uniform(-1/sqrt(H), 1/sqrt(H)) for every weight, as ``nn.LSTM`` initialises."""
        bound = 1.0 / math.sqrt(self.hidden_size)
        for p in self.parameters():
            nn.init.uniform_(p, -bound, bound)

    def init_state(self, batch: int, like: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        """Zero (h, c), each (B, H), with ``like``'s dtype and device."""
        z = like.new_zeros(batch, self.hidden_size)
        return z, z.clone()

    def forward(
        self, x: torch.Tensor, state: tuple[torch.Tensor, torch.Tensor] | None = None
    ) -> tuple[torch.Tensor, tuple[torch.Tensor, torch.Tensor]]:
        """Run the layer over ``x`` (B, T, D); return all hidden states (B, T, H) and the final (h, c)."""
        h0, c0 = self.init_state(x.shape[0], x) if state is None else state
        hs, h, c = peephole.PeepholeFunction.apply(
            x, h0, c0, self.weight_ih, self.weight_hh, self.bias, self.w_ci, self.w_cf, self.w_co
        )
        return hs, (h, c)


class PeepholeStack(nn.Module):
    """``layers`` peephole LSTM layers, each feeding the next; state is a list of per-layer (h, c)."""

    def __init__(self, input_size: int, hidden_size: int, layers: int, peepholes: bool = True) -> None:
        super().__init__()
        sizes = [input_size] + [hidden_size] * (layers - 1)
        self.layers = nn.ModuleList(PeepholeLSTM(d, hidden_size, peepholes) for d in sizes)

    def forward(self, x: torch.Tensor, state: list | None = None) -> tuple[torch.Tensor, list]:
        """``x`` (B, T, D) -> last layer's hidden states (B, T, H) and the new per-layer states."""
        new_state = []
        for k, layer in enumerate(self.layers):
            x, s = layer(x, None if state is None else state[k])  # (B, T, H)
            new_state.append(s)
        return x, new_state


class Classifier(nn.Module):
    """Trajectory -> P(light), P(heavy): recurrent layers, dropout, linear + softmax on the last step.

    ``dropout`` is the probability of *dropping* a unit of the last hidden state. The paper says
    "dropout ... with rate 0.8"; its TensorFlow code (``tf.nn.dropout(x, keep_prob)``) most likely meant
    keep-probability 0.8, i.e. ``dropout = 0.2``, the default here.
    """

    def __init__(
        self, n_inputs: int, hidden: int = 64, layers: int = 2, dropout: float = 0.2, cell: Cell = "peephole",
        forget_bias: float = 1.0, chrono_frames: int | None = None, inputs: Inputs = "positions", fps: float = 30.0,
    ) -> None:
        """A new classifier of ``n_inputs`` position dims (D), reading them as ``inputs`` (:class:`Features`; the
        velocity at ``fps`` frames per second), its forget gates started as the paper's TensorFlow cell starts
        them (+1, or chrono over ``chrono_frames`` frames; :meth:`init_forget_gates`): a training loop of one's
        own starts off the plateau that a zero forget bias leaves it on."""
        super().__init__()
        if cell not in CELLS:
            raise ConfigError(f"cell = {cell!r} is not a known cell; use one of {CELLS}")
        self.cell_type = cell
        self.features = Features(n_inputs, inputs, fps)
        C = self.features.n_channels
        if cell in ("peephole", "no-peephole"):
            self.rnn = PeepholeStack(C, hidden, layers, peepholes=cell == "peephole")
        elif cell == "torch-lstm":
            self.rnn = nn.LSTM(C, hidden, layers, batch_first=True)
        else:
            self.rnn = GRU(C, hidden, layers)  # nn.GRU, on the compiled loop where it can
        self.drop = nn.Dropout(dropout)
        self.head = nn.Linear(hidden, 2)
        self.init_forget_gates(forget_bias, chrono_frames)

    def init_forget_gates(self, bias: float, chrono_frames: int | None = None) -> None:
        """Start the LSTMs' forget gates open: add ``bias`` to every forget-gate bias, or, with
        ``chrono_frames`` T, draw it as log U(1, T - 1) and set the input gate's to its negative (chrono
        initialisation, Tallec & Ollivier 2018: memory timescales up to the input's length). The GRU has
        no forget gate and is left as it is. Uses torch's RNG (seeded by ``study.learn.train.fit``). Called
        once by the constructor; calling it again adds ``bias`` again."""
        if self.cell_type == "gru":
            return
        H = self.head.in_features
        if isinstance(self.rnn, PeepholeStack):
            biases = [layer.bias for layer in self.rnn.layers]
            zeroed = [None] * len(biases)
        else:  # nn.LSTM: two bias vectors per layer; their sum is what counts
            biases = [getattr(self.rnn, f"bias_ih_l{k}") for k in range(self.rnn.num_layers)]
            zeroed = [getattr(self.rnn, f"bias_hh_l{k}") for k in range(self.rnn.num_layers)]
        with torch.no_grad():
            for b, other in zip(biases, zeroed):
                if chrono_frames is None:
                    b[H : 2 * H] += bias
                    continue
                b_f = torch.log(torch.empty(H).uniform_(1.0, max(chrono_frames - 1.0, 1.0 + 1e-6)))
                b[H : 2 * H] = b_f
                b[:H] = -b_f
                if other is not None:
                    other[: 2 * H] = 0.0

    @property
    def n_inputs(self) -> int:
        """D: the position dims the classifier takes."""
        return self.features.n_dims

    def set_normalisation(self, mean: torch.Tensor, std: torch.Tensor) -> None:
        """Store the training split's mean and standard deviation of each channel (C,) (:class:`Features`)."""
        self.features.mean.copy_(mean)
        self.features.std.copy_(std)

    def encode(self, x: torch.Tensor, state: State | None = None) -> tuple[torch.Tensor, State]:
        """Raw ``x`` (B, T, D) metres -> last layer's hidden states (B, T, H) and the carried state (the
        recurrent core's, and the last frame of ``x``)."""
        core, prev = (None, None) if state is None else state
        hs, core = self.rnn(self.features(x, prev), core)
        return hs, (core, x[:, -1])

    def logits(self, h_last: torch.Tensor) -> torch.Tensor:
        """Last hidden state (B, H) -> class logits (B, 2), with dropout in training mode."""
        return self.head(self.drop(h_last))

    def forward(self, x: torch.Tensor, state: State | None = None) -> torch.Tensor:
        """``x`` (B, T, D) metres -> logits (B, 2) from the hidden state at the last frame."""
        hs, _ = self.encode(x, state)
        return self.logits(hs[:, -1])  # (B, 2)

    def init_state(self, batch: int) -> State:
        """The zero state for streaming ``batch`` trajectories with :meth:`step` (no frame seen yet)."""
        w = self.head.weight
        if isinstance(self.rnn, PeepholeStack):
            return [layer.init_state(batch, w) for layer in self.rnn.layers], None
        h = w.new_zeros(self.rnn.num_layers, batch, self.rnn.hidden_size)
        return ((h, h.clone()) if self.cell_type == "torch-lstm" else h), None

    def step(self, x_t: torch.Tensor, state: State) -> tuple[torch.Tensor, State]:
        """Consume one frame ``x_t`` (B, D) metres; return class probabilities (B, 2) and the new state.

        Feeding a trajectory frame by frame gives, after frame t, the same probabilities as the whole
        sequence cut at t (in eval mode).
        """
        hs, state = self.encode(x_t[:, None, :], state)  # (B, 1, H)
        return F.softmax(self.logits(hs[:, -1]), dim=-1), state
