"""A trained classifier and its model directory: what it was trained with, how it answers, saving and loading.

:class:`TrainedModel` is what ``study.learn.train.fit`` returns and what a model directory holds (:meth:`save`,
:func:`load`, checked file by file). Its answers run on :data:`THREADS` CPU threads, so the same model gives the
same numbers on any machine of a kind.
"""

from __future__ import annotations

import contextlib
import dataclasses
import json
import math
import os
import shutil
import tempfile
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import torch
import torch.nn.functional as F

from study import CLASSES
from study.core.errors import ConfigError, ModelError, output_error
from study.core.cache import umask_mode
from study.learn import native
from study.learn.config import DIMS, OLD_MEANING, RENAMED, TrainConfig, old_plateau_epochs, select_inputs
from study.learn.metrics import PLATEAU_LOSS, training_state
from study.learn.model import Classifier

THREADS = 1
"""CPU threads used by :func:`fit` (see the module docstring)."""

FORMATS = {"study.model/1": 1, "study.model/2": 2, "study.model/3": 3, "study.model/4": 4, "study.model/5": 5,
           "study.model/6": 6, "study.model/7": 7}
"""Every model format this code reads. Format 2 added the training fields min_epochs, forget_bias,
forget_init, clip_norm, lr_schedule and the record of a diverged run; format 3 the input representation
(``TrainConfig.inputs``: the classifier's first layer, with a mean and a standard deviation per channel);
format 4 the rotation of the training throws (``TrainConfig.rotate``) and the input ``'speed'``, which a
format-3 reader cannot build; format 5 the training recipe's warm-up, cosine budget and weight averaging
(``TrainConfig.warmup_epochs``, ``lr_floor``, ``average``, ``ema_decay``); format 6 names the epoch budget
``epochs`` (``max_epochs`` before, ``RENAMED``); format 7 adds the plateau's allowance
(``TrainConfig.plateau_epochs``: ``min_epochs + patience`` before, ``old_plateau_epochs``). An older directory is read with the
later fields' old meaning (``OLD_MEANING``): positions, divided by their standard deviation; no rotation; no
warm-up or averaging."""
FORMAT = "study.model/7"
FILES = ("weights.pt", "config.json", "normalisation.json", "history.json", "meta.json")
"""What a saved model directory holds."""


@contextlib.contextmanager
def num_threads(n: int) -> Iterator[None]:
    """Run torch's CPU ops on ``n`` threads; restore the previous count after."""
    before = torch.get_num_threads()
    if before == n:
        yield
        return
    torch.set_num_threads(n)
    try:
        yield
    finally:
        torch.set_num_threads(before)


def frame_logits(net: Classifier, x: torch.Tensor) -> torch.Tensor:
    """Logits (B, T, 2) at every frame of ``x`` (B, T, D), gradients through the whole input."""
    hs, _ = net.encode(x)  # (B, T, H)
    return net.logits(hs)


RETRY: dict[str, dict[str, str]] = {
    "python": {"seed": "seed", "lr": "lr", "epochs": "epochs", "clip": "clip_norm=1 (TrainConfig's fields)"},
    "cli": {"seed": "--seed", "lr": "--lr", "epochs": "--epochs", "clip": "--clip-norm 1"},
    "none": {},
}
"""How :meth:`TrainedModel.failure` names the knobs of a retry, by who reads it."""


@dataclass
class TrainedModel:
    """A trained classifier with everything needed to use it and to know where it came from.

    Example::

        model = study.fit(ds, study.TrainConfig(length=1.0, epochs=5))
        print(model.best_epoch, model.failed, model.predict_proba(ds.test.x[:3]))
    """

    net: Classifier
    config: TrainConfig
    fps: float
    """Frames per second of the data it was trained on."""
    data_key: str = ""
    """Key of the dataset it was trained on ('' if unknown)."""
    history: list[dict[str, float]] = field(default_factory=list)
    """One entry per epoch: epoch, train_loss, val_loss, val_accuracy."""
    best_epoch: int = 0
    """The epoch whose weights were kept (lowest validation loss)."""
    diverged_epoch: int | None = None
    """The epoch in which the training loss stopped being finite, if it did (the run then stopped there)."""
    n_val: int = 0
    """Trajectories in the validation part it was early-stopped on (0 if unknown)."""

    @property
    def training_state(self) -> str:
        """What its validation part says (``study.learn.metrics.training_state``): ``"trained"``, ``"failed"`` or
        ``"too few to tell"``; ``"trained"`` where the validation part's size is unknown (a model saved before
        it was recorded)."""
        if not self.history or not self.n_val:
            return "trained"
        best = self.history[self.best_epoch]
        return training_state(float(best["val_accuracy"]), float(best["val_loss"]), self.n_val)

    @property
    def failed(self) -> bool:
        """Whether the run failed to train by the book's criterion: its validation loss never left the plateau of
        a coin (or stopped being finite), or its accuracy cannot be told from guessing on enough validation
        trajectories to tell."""
        return self.training_state == "failed"

    def failure(self, advice: str = "python") -> str:
        """What went wrong and what to change, in one sentence ('' for a run that trained); for a validation part
        too small to judge, that it is too small. ``advice`` names the knobs as the caller takes them: 'python'
        (``TrainConfig``'s fields), 'cli' (``study train``'s options) or 'none' (no advice: the caller gives its
        own)."""
        if advice not in RETRY:
            raise ValueError(f"failure: advice = {advice!r}; use one of {', '.join(RETRY)}")
        state = self.training_state
        if state == "trained":
            return ""
        best = self.history[self.best_epoch]
        acc, loss = float(best["val_accuracy"]), float(best["val_loss"])
        if state == "too few to tell":
            return (f"its validation part is too small to tell whether it trained: {round(acc * self.n_val)} of "
                    f"{self.n_val} right is within a coin's reach, though its loss ({loss:.3f}, a coin's "
                    f"{math.log(2):.3f}) left the plateau" + ("" if advice == "none" else "; train on more data to judge it"))
        knob = RETRY[advice]
        if not math.isfinite(loss):
            return (f"the run diverged in epoch {self.diverged_epoch} (its loss stopped being finite) before it "
                    "learned anything" + ("" if advice == "none" else
                                          f"; train again with a lower {knob['lr']} (the protocol's is "
                                          f"{TrainConfig().lr:g}) or {knob['clip']}"))
        if loss >= PLATEAU_LOSS:
            why = (f"its validation loss at its best epoch ({self.best_epoch}) is {loss:.3f}, a coin's is "
                   f"{math.log(2):.3f}: it never left the initial plateau")
        else:
            why = (f"at its best epoch ({self.best_epoch}) its validation accuracy, {100 * acc:.1f} % of "
                   f"{self.n_val}, cannot be told from guessing (its loss {loss:.3f})")
        if advice == "none":
            return f"the run failed to train: {why}"
        return (f"the run failed to train: {why}. Train again with another {knob['seed']}, a lower {knob['lr']} (the "
                f"protocol's is {TrainConfig().lr:g}), more {knob['epochs']}, or more data")

    @property
    def dims(self) -> str:
        """'z' or 'xyz'."""
        return self.config.dims

    @property
    def n_frames(self) -> int:
        """Input length T in frames."""
        return self.config.n_frames(self.fps)

    @property
    def val_accuracy(self) -> float:
        """Validation accuracy at the kept epoch."""
        return float(self.history[self.best_epoch]["val_accuracy"]) if self.history else math.nan

    @torch.no_grad()
    def predict_proba_frames(self, x: np.ndarray, batch: int = 512) -> np.ndarray:
        """``x`` (n, T, 3) metres -> (n, n_frames, 2) float64: the answer after every frame of the input (the
        network's state then; trained to answer there only when ``config.loss_at == 'every'``)."""
        xs = torch.from_numpy(select_inputs(x, self.dims, self.n_frames))
        self.net.eval()
        with num_threads(THREADS):
            out = [F.softmax(frame_logits(self.net, xs[i : i + batch]), dim=-1) for i in range(0, len(xs), batch)]
        return torch.cat(out).double().numpy() if out else np.zeros((0, self.n_frames, 2))

    @torch.no_grad()
    def predict_proba(self, x: np.ndarray, batch: int = 1024) -> np.ndarray:
        """``x`` (n, T, 3) float32 metres, world (x, y, z), T >= ``n_frames`` -> (n, 2) float64 [p_light, p_heavy].

        Only the first ``n_frames`` frames and the model's own dims are used; normalisation is inside.
        """
        xs = torch.from_numpy(select_inputs(x, self.dims, self.n_frames))
        self.net.eval()
        with num_threads(THREADS):  # same numbers whatever the machine; no thread-pool churn after fit
            out = [F.softmax(self.net(xs[i : i + batch]), dim=-1) for i in range(0, len(xs), batch)]
        return torch.cat(out).double().numpy() if out else np.zeros((0, 2))

    def save(self, out_dir: str | Path) -> Path:
        """Write the model directory atomically (a temporary directory renamed into place).

        Raises :class:`study.core.errors.OutputError` if ``out_dir`` cannot be written.
        """
        out = Path(out_dir)
        try:
            out.parent.mkdir(parents=True, exist_ok=True)
            tmp = Path(tempfile.mkdtemp(prefix=f".{out.name}.", dir=out.parent))
        except OSError as e:
            raise output_error(out, e, "model directory") from None
        try:
            torch.save(self.net.state_dict(), tmp / "weights.pt")
            texts = {
                "config.json": dataclasses.asdict(self.config),
                "normalisation.json": {"dims": self.dims, "inputs": self.config.inputs,
                                       "mean": self.net.features.mean.tolist(), "std": self.net.features.std.tolist()},
                "history.json": {"best_epoch": self.best_epoch, "diverged_epoch": self.diverged_epoch,
                                 "epochs": self.history},
                "meta.json": {"format": FORMAT, "fps": self.fps, "data_key": self.data_key,
                              "n_frames": self.n_frames, "classes": list(CLASSES), "torch": torch.__version__,
                              "backend": native.backend(), "n_val": self.n_val, "failed": self.failed},
            }
            for name, obj in texts.items():
                (tmp / name).write_text(json.dumps(obj, indent=1) + "\n")
            os.chmod(tmp, umask_mode(directory=True))
            if out.exists():
                old = Path(tempfile.mkdtemp(prefix=f".{out.name}.old.", dir=out.parent))
                os.replace(out, old / "m")
                os.replace(tmp, out)
                shutil.rmtree(old)
            else:
                os.replace(tmp, out)
        finally:
            shutil.rmtree(tmp, ignore_errors=True)
        return out


@dataclass(frozen=True)
class Ensemble:
    """Several trained models of one input (seeds of one config) used as one classifier: the mean of their
    probabilities. A number it gives does not hang on which seed's weights one happened to keep.

    Example::

        seeds = [study.load(d) for d in ("m0", "m1", "m2")]
        p = study.Ensemble(tuple(seeds)).predict_proba(ds.test.x)
    """

    members: tuple[TrainedModel, ...]
    """The models, every one reading the same dims, frames and frame rate."""

    def __post_init__(self) -> None:
        if not self.members:
            raise ConfigError("Ensemble.members is empty; give it at least one trained model")
        first = self.members[0]
        if any((m.dims, m.n_frames, m.fps) != (first.dims, first.n_frames, first.fps) for m in self.members):
            raise ConfigError("Ensemble.members read different inputs (dims, frames or fps); ensemble seeds of one "
                              "config only")

    @property
    def dims(self) -> str:
        """The coordinates its members read ('xyz' or 'z')."""
        return self.members[0].dims

    @property
    def fps(self) -> float:
        """Frames per second of the data its members were trained on."""
        return self.members[0].fps

    @property
    def n_frames(self) -> int:
        """Frames of input its members read."""
        return self.members[0].n_frames

    def predict_proba(self, x: np.ndarray) -> np.ndarray:
        """``x`` (n, T, 3) float32 metres -> (n, 2) float64: the members' mean [p_light, p_heavy]."""
        return np.mean([m.predict_proba(x) for m in self.members], axis=0)


def _read_json(path: Path) -> Any:
    try:
        return json.loads(path.read_text())
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as e:
        raise ModelError(f"model file {path} cannot be read ({type(e).__name__}); retrain with `study train`") from None


def load(model_dir: str | Path) -> TrainedModel:
    """Read a directory written by :meth:`TrainedModel.save`, checking that every file is there and agrees.

    Example::

        model = study.load("my-model")
        p = model.predict_proba(ds.test.x)      # (n, 2): p_light, p_heavy
    """
    d = Path(model_dir)
    hint = "retrain it with `study train ... --out DIR`"
    if d.is_file():
        raise ModelError(f"model {d} is a file; give the model's directory (the folder `study train --out DIR` "
                         "wrote, with weights.pt and config.json inside)")
    if not d.is_dir():
        raise ModelError(f"model directory {d}: no such directory; {hint}")
    for name in FILES:
        if not (d / name).is_file():
            raise ModelError(f"model directory {d} is missing {name}; {hint}")
    meta = _read_json(d / "meta.json")
    version = FORMATS.get(meta.get("format"))
    if version is None:
        raise ModelError(f"model directory {d}: format {meta.get('format')!r}, expected {FORMAT!r}; {hint}")
    fields = _read_json(d / "config.json")
    if version < 6 and isinstance(fields, dict):
        fields = {RENAMED.get(k, k): v for k, v in fields.items()}
    if version in OLD_MEANING and isinstance(fields, dict):
        fields = {**OLD_MEANING[version], **fields}  # trained before these fields existed: what it was trained with
    if version < 7 and isinstance(fields, dict):
        fields = old_plateau_epochs(fields)
    missing = {f.name for f in dataclasses.fields(TrainConfig)} - set(fields if isinstance(fields, dict) else ())
    if missing:  # never fill a saved model's training with today's defaults
        raise ModelError(f"model file {d / 'config.json'} lacks {', '.join(sorted(missing))}; {hint}")
    try:
        cfg = TrainConfig(**fields)
        cfg.check()
    except (TypeError, ConfigError) as e:
        raise ModelError(f"model file {d / 'config.json'} is not a valid TrainConfig ({e}); {hint}") from None
    try:
        state = torch.load(d / "weights.pt", weights_only=True)
    except Exception as e:  # torch raises several types for a corrupt file
        raise ModelError(f"model file {d / 'weights.pt'} cannot be loaded ({type(e).__name__}); {hint}") from None
    net = Classifier(len(DIMS[cfg.dims]), cfg.hidden, cfg.layers, cfg.dropout, cfg.cell, inputs=cfg.inputs,
                     fps=float(meta["fps"]))
    if version < 3 and isinstance(state, dict) and "scale" in state:  # the positions' std, before the first layer
        state = {**{k: v for k, v in state.items() if k != "scale"}, "features.std": state["scale"],
                 "features.mean": torch.zeros_like(state["scale"])}
    try:
        net.load_state_dict(state)
    except (RuntimeError, TypeError) as e:
        raise ModelError(f"model file {d / 'weights.pt'} does not match config.json ({str(e)[:200]}); {hint}") from None
    norm = _read_json(d / "normalisation.json")
    if norm.get("dims") != cfg.dims or norm.get("inputs", "positions") != cfg.inputs \
            or not np.allclose(norm.get("std", []), net.features.std.numpy(), rtol=1e-6):
        raise ModelError(f"model file {d / 'normalisation.json'} disagrees with the weights; {hint}")
    hist = _read_json(d / "history.json")
    net.eval()
    diverged = hist.get("diverged_epoch")
    return TrainedModel(net=net, config=cfg, fps=float(meta["fps"]), data_key=str(meta.get("data_key", "")),
                        history=list(hist.get("epochs", [])), best_epoch=int(hist.get("best_epoch", 0)),
                        diverged_epoch=None if diverged is None else int(diverged), n_val=int(meta.get("n_val", 0)))


