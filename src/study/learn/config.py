"""What a training run is made of, without torch: the input dimensions, the recurrent cells, the training
config, and the selection of a model's inputs from trajectories.

Importing this costs no torch, so the command line can build its options and help from these
definitions, and the NumPy baseline can share them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from functools import cache
from typing import Literal, get_args, get_type_hints

import numpy as np

from study.core.errors import ConfigError, TrajectoryError, check_range

Dims = Literal["z", "xyz"]
"""Input dimensions by name: the height only, or all three coordinates."""
Cell = Literal["peephole", "no-peephole", "torch-lstm", "gru"]
"""Recurrent cells the classifier offers: the paper's peephole LSTM; the same layer with its peepholes fixed
at zero (an LSTM without peepholes on the same compiled loop: the ablation's control); ``nn.LSTM``;
``nn.GRU`` (as :class:`study.learn.gru.GRU`, on a compiled loop too)."""
ForgetInit = Literal["constant", "chrono"]
"""How the forget gates' biases start: all at ``forget_bias``, or chrono (Tallec & Ollivier 2018)."""
Loss = Literal["last", "every"]
"""Where the loss is taken: at the last frame only (the paper's), or at every frame."""
Observe = Literal["exact", "randomised", "fixed", "any-camera"]
"""What a network is trained on: the simulator's positions, positions as a random camera observes them,
positions observed with a fixed tracker error (a fresh draw every epoch), or heights as a user's own camera,
anywhere, and ``study classify``'s one scale give them."""
Inputs = Literal["positions", "velocity", "speed"]
"""What the network reads of the positions it is given: the positions (the paper's); the positions and their
frame-to-frame velocity; or what of them does not depend on the throw's heading, the height, its velocity and the
horizontal speed (``study.learn.model.Features``)."""
Schedule = Literal["constant", "plateau", "cosine"]
"""Learning-rate schedules: fixed; halved when the validation loss, once off the initial plateau, stalls for more
than ``patience // 4`` epochs; or a fixed budget of ``epochs``, a linear warm-up over ``warmup_epochs`` then a
cosine decay to ``lr_floor`` of the rate (no early stopping: a run trains its whole budget and keeps its best
validation epoch)."""
Average = Literal["none", "ema"]
"""Which weights are validated and kept: the optimiser's own, or their exponential moving average over steps."""

DIMS: dict[Dims, tuple[int, ...]] = {"z": (2,), "xyz": (0, 1, 2)}
"""Columns of the (x, y, z) trajectory each input dimension name selects."""
CELLS: tuple[Cell, ...] = get_args(Cell)
"""Every cell, the paper's first."""
INPUTS: tuple[Inputs, ...] = get_args(Inputs)
"""Every input representation, the paper's first."""


@dataclass(frozen=True)
class TrainConfig:
    """Everything that determines a trained model, besides the data. The defaults are the study's protocol,
    Table 1's configuration on the paper preset (the grid's winner there), so a model trained with them
    trains.

    Example::

        cfg = study.TrainConfig(dims="z", inputs="velocity", length=2.0, epochs=40)
        model = study.fit(ds, cfg)
    """

    dims: Dims = "z"
    """Input dimensions: 'z' (the height only: what one camera gives) or 'xyz' (all three coordinates)."""
    length: float = 3.0
    """Input length T in seconds: the model sees the first ``length`` seconds of each trajectory."""
    hidden: int = 64
    """Units per recurrent layer (paper: 64)."""
    layers: int = 2
    """Recurrent layers (paper: 2)."""
    dropout: float = 0.2
    """Probability of dropping a unit of the last hidden state (paper's 'rate 0.8' read as keep-probability)."""
    lr: float = 1e-3
    """Adam learning rate."""
    batch_size: int = 32
    """Trajectories per gradient step."""
    truncation: int = 90
    """Truncated-BPTT length in frames: the loss back-propagates through at most this many last frames."""
    epochs: int = 150
    """Upper bound on passes over the training split."""
    patience: int = 20
    """Stop after this many epochs without a lower validation loss, counted once the loss has left the initial
    plateau (``study.learn.metrics.PLATEAU_LOSS``); the best epoch's weights are kept."""
    min_epochs: int = 30
    """Early stopping cannot stop a run before this many epochs; ``epochs`` still ends any run."""
    plateau_epochs: int = 100
    """A run whose validation loss has not left the initial plateau after this many epochs has failed to train and
    stops there (the slowest starters the study measured left it at epochs 56-110: ``scripts/plateau_allowance.py``)."""
    forget_bias: float = 1.0
    """Added to the forget gates' biases at initialisation (TensorFlow's LSTMCell default, which the paper
    used); the GRU, which has no forget gate, ignores it."""
    forget_init: ForgetInit = "constant"
    """'constant' (every forget bias starts at forget_bias more than the uniform draw) or 'chrono' (biases
    log U(1, T - 1), input gates the negative, T the input frames: memory that spans the input)."""
    clip_norm: float = 1.0
    """Clip the gradient's global norm to this before each step; 0: no clipping."""
    lr_schedule: Schedule = "constant"
    """'constant'; 'plateau': halve the learning rate when the validation loss has not improved for more than a
    quarter of ``patience`` epochs, counted once the loss has left the initial plateau (as patience is); or
    'cosine': ``epochs`` epochs whatever happens (no early stopping), the rate rising linearly over
    ``warmup_epochs`` and then falling along a half cosine to ``lr_floor`` of itself."""
    warmup_epochs: int = 0
    """With 'cosine': epochs of linear warm-up, the rate rising from ``lr`` divided by their number to ``lr`` (at
    most one epoch fewer than ``epochs``: a short budget warms up for less)."""
    lr_floor: float = 0.01
    """With 'cosine': the last epoch's rate over ``lr``."""
    average: Average = "ema"
    """'ema': validate and keep an exponential moving average of the weights (one update per step, ``ema_decay``),
    which does not swing with each step as the weights do (the study's recipe, ``benchmarks/bench_recipe.py``);
    'none': the optimiser's own weights, as the study trained before."""
    ema_decay: float = 0.999
    """With 'ema': the average's decay per step (0.999: about the last thousand steps), reached after a warm-up
    (:meth:`ema_decay_at`)."""
    loss_at: Loss = "last"
    """'last': the loss is the answer's at the last frame (the paper's network); 'every': the mean of the
    answers' at every frame, so the network answers at every frame (back-propagation then runs through
    the whole input; ``truncation`` is not used; early stopping still scores the answer at the last frame)."""
    observe: Observe = "exact"
    """What the network is trained on: 'exact' positions; 'randomised' observations (each epoch sees the
    training split through a camera and tracker drawn at random, ``study.simulate.observe.randomised``); or
    'any-camera' (the training and validation splits filmed by cameras drawn as the camera sweep's and read by one
    scale, ``study.simulate.observe.any_camera``); or
    'fixed', the training split observed with the tracker's error (``observe_noise`` and the fields after it, the
    model ``study.simulate.observe.TrackerNoise``) and ``observe_drop``, drawn afresh every epoch (the validation
    split observed the same way, once)."""
    observe_noise: float = 0.0
    """The tracker's position error in flight, metres: with 'fixed' the training and validation noise; with
    'randomised' the validation split's (and the random white noise spans [0, 3x] it)."""
    observe_drop: float = 0.0
    """The tracker's share of lost frames, for the training split of a 'fixed' run and the validation split of
    an observed one."""
    observe_offset: float = 0.0
    """Standard deviation of the tracker's per-throw height offset, metres (one draw per throw and epoch)."""
    observe_rho: float = 0.0
    """Lag-1 autocorrelation of the tracker's error from frame to frame, in (-1, 1); 0: white."""
    observe_contact_ratio: float = 1.0
    """The tracker's error while the object touches the ground over ``observe_noise`` (in flight); 1: the same."""
    val_fraction: float = 0.2
    """Share of the training split held out for early stopping (and for the grid search)."""
    seed: int = 0
    """Seeds the validation split, the initial weights, the batch order and the dropout masks."""
    cell: Cell = "peephole"
    """Recurrent cell: 'peephole' (the paper's), 'no-peephole' (the same layer, peepholes fixed at 0), 'torch-lstm'
    (nn.LSTM) or 'gru' (nn.GRU)."""
    inputs: Inputs = "positions"
    """What the network reads: 'positions' (each coordinate over its standard deviation, the paper's), 'velocity'
    (each coordinate and its frame-to-frame velocity, both standardised) or 'speed' (the height, its velocity and,
    with X, Y, Z, the horizontal speed, m/s, standardised: nothing that turns with the heading); computed inside
    the model, so every caller still passes positions."""
    rotate: float = 0.0
    """Augmentation, degrees: every epoch turns each training throw about the vertical through the origin by its
    own angle, uniform in [-rotate, rotate] (180: any heading); 0: none. Needs dims 'xyz'."""

    def __post_init__(self) -> None:
        self.check()  # a config that exists is one that trains: refused where it is made, not at fit

    def check(self) -> None:
        """Raise :class:`ConfigError` naming the first field that is out of range or not one of its choices."""
        for name, allowed in choices(TrainConfig).items():
            value = getattr(self, name)
            if value not in allowed:
                near = [a for a in allowed if isinstance(value, str) and a.lower() == value.lower()]
                hint = f"use {near[0]!r} (lower case)" if near else f"use one of {', '.join(map(repr, allowed))}"
                raise ConfigError(f"TrainConfig.{name} = {value!r} is unknown; {hint}")
        check_range("TrainConfig.length (seconds)", self.length, 0, lo_open=True)
        for name in ("hidden", "layers", "batch_size", "truncation", "epochs", "patience", "plateau_epochs"):
            value = getattr(self, name)
            if not isinstance(value, int) or isinstance(value, bool) or value < 1:
                raise ConfigError(f"TrainConfig.{name} = {value!r}; it must be a whole number >= 1")
        if not isinstance(self.min_epochs, int) or isinstance(self.min_epochs, bool) or self.min_epochs < 0:
            raise ConfigError(f"TrainConfig.min_epochs = {self.min_epochs!r}; it must be a whole number >= 0")
        check_range("TrainConfig.observe_noise (metres)", self.observe_noise, 0.0, 1.0)
        check_range("TrainConfig.observe_drop", self.observe_drop, 0.0, 1.0, hi_open=True)
        check_range("TrainConfig.observe_offset (metres)", self.observe_offset, 0.0, 1.0)
        check_range("TrainConfig.observe_rho", self.observe_rho, -1.0, 1.0, lo_open=True, hi_open=True)
        check_range("TrainConfig.observe_contact_ratio", self.observe_contact_ratio, 0.0, 100.0)
        check_range("TrainConfig.forget_bias", self.forget_bias, -10, 10)
        check_range("TrainConfig.clip_norm", self.clip_norm, 0)
        check_range("TrainConfig.dropout", self.dropout, 0, 1, hi_open=True)
        check_range("TrainConfig.lr", self.lr, 0, lo_open=True)
        check_range("TrainConfig.val_fraction", self.val_fraction, 0, 1, lo_open=True, hi_open=True)
        check_range("TrainConfig.rotate (degrees)", self.rotate, 0.0, 180.0)
        if not isinstance(self.warmup_epochs, int) or isinstance(self.warmup_epochs, bool) or self.warmup_epochs < 0:
            raise ConfigError(f"TrainConfig.warmup_epochs = {self.warmup_epochs!r}; it must be a whole number >= 0")
        check_range("TrainConfig.lr_floor", self.lr_floor, 0, 1, lo_open=True)
        check_range("TrainConfig.ema_decay", self.ema_decay, 0, 1, lo_open=True, hi_open=True)
        if self.rotate and self.dims == "z":
            raise ConfigError(f"TrainConfig.rotate = {self.rotate!r} turns the horizontal coordinates, which dims 'z' "
                              "does not read; use rotate 0 or dims 'xyz'")

    @property
    def stops_early(self) -> bool:
        """Whether a run may stop before ``epochs`` (``patience``): not on a cosine budget."""
        return self.lr_schedule != "cosine"

    def lr_at(self, epoch: int) -> float | None:
        """The learning rate of ``epoch`` (0-based) on a cosine budget; None for the schedules that set it as they go
        ('constant', 'plateau')."""
        if self.lr_schedule != "cosine":
            return None
        warm = min(self.warmup_epochs, self.epochs - 1)
        if epoch < warm:
            return self.lr * (epoch + 1) / warm
        span = self.epochs - warm - 1  # epochs after the first of the decay
        progress = 1.0 if span <= 0 else min(1.0, (epoch - warm) / span)
        return self.lr * (self.lr_floor + (1 - self.lr_floor) * 0.5 * (1 + math.cos(math.pi * progress)))

    def ema_decay_at(self, step: int) -> float:
        """The weights' average's decay at ``step`` (0-based, counted over the whole run): ``ema_decay``, but at
        most ``(1 + step) / (10 + step)`` early on (TensorFlow's ``ExponentialMovingAverage`` with
        ``num_updates``), so that a short run is not held near its initial weights."""
        return min(self.ema_decay, (1 + step) / (10 + step))

    def n_frames(self, fps: float) -> int:
        """T in frames at ``fps``: ``round(length * fps)``, at least 1."""
        return max(1, round(self.length * fps))


def select_inputs(x: np.ndarray, dims: str, n_frames: int, what: str = "trajectories") -> np.ndarray:
    """First ``n_frames`` frames and the ``dims`` columns of ``x`` (n, T, 3) -> (n, n_frames, D) float32.

    Raises :class:`TrajectoryError` for a wrong shape, too few frames, or NaN/infinite values.
    """
    x = np.asarray(x)
    if x.ndim != 3 or x.shape[2] != 3:
        raise TrajectoryError(f"{what}: shape {x.shape}; expected (n, T, 3) world x, y, z in metres")
    if x.shape[1] < n_frames:
        raise TrajectoryError(
            f"{what}: {x.shape[1]} frames, but the model needs {n_frames}; use a shorter "
            "length (seconds) or longer trajectories (the paper zero-pads short ones)"
        )
    out = np.ascontiguousarray(x[:, :n_frames, DIMS[dims]], dtype=np.float32)
    bad = ~np.isfinite(out).all(axis=(1, 2))
    if bad.any():
        raise TrajectoryError(
            f"{what}: {int(bad.sum())} trajectories hold NaN or infinite values "
            f"(first: index {int(np.argmax(bad))}); fix or drop them"
        )
    return out


WHITE: dict[str, object] = {"observe_offset": 0.0, "observe_rho": 0.0, "observe_contact_ratio": 1.0}
"""The tracker-model fields at white noise: what every model saved before format 4 was observed with."""

NO_RECIPE: dict[str, object] = {"warmup_epochs": 0, "lr_floor": 0.01, "average": "none", "ema_decay": 0.999}
"""The recipe fields at what every model saved before format 5 was trained with: no warm-up, no averaging."""

RENAMED: dict[str, str] = {"max_epochs": "epochs"}
"""Fields saved under another name before model format 6: old name -> today's."""


def old_plateau_epochs(fields: dict[str, object]) -> dict[str, object]:
    """A config saved before model format 7 with the plateau's allowance it was trained with: a run still on the
    plateau stopped at ``min_epochs + patience`` then (``plateau_epochs`` did not exist)."""
    if "plateau_epochs" in fields or not {"min_epochs", "patience"} <= set(fields):
        return fields
    return {**fields, "plateau_epochs": int(fields["min_epochs"]) + int(fields["patience"])}  # type: ignore[call-overload]

OLD_MEANING: dict[int, dict[str, object]] = {
    1: {"min_epochs": 0, "forget_bias": 0.0, "forget_init": "constant", "clip_norm": 0.0, "lr_schedule": "constant",
        "loss_at": "last", "observe": "exact", "observe_noise": 0.0, "observe_drop": 0.0, "inputs": "positions",
        "rotate": 0.0, **WHITE, **NO_RECIPE},
    2: {"inputs": "positions", "rotate": 0.0, **WHITE, **NO_RECIPE},
    3: {"rotate": 0.0, **WHITE, **NO_RECIPE},
    4: dict(NO_RECIPE),
}
"""What the fields added after each model format meant before they existed: how a model saved in format 1
was trained (no minimum, no forget bias, no clipping, a constant learning rate, positions), that a
format-2 model reads positions, that no model before format 4 was trained on rotated throws, and that none before
format 5 warmed up or averaged its weights."""


@cache
def choices(cls: type) -> dict[str, tuple[str, ...]]:
    """``{field: its allowed values}`` for every field of the dataclass ``cls`` typed with a ``Literal``: the
    one table that both the config's check and the command line's ``choices`` read."""
    hints = get_type_hints(cls)
    return {f.name: get_args(hints[f.name]) for f in fields(cls) if getattr(hints[f.name], "__origin__", None) is Literal}
