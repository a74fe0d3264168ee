"""Training, saving, loading and evaluating the classifier.

``fit(dataset, cfg)`` trains on the dataset's train split only: a seeded permutation carves a
validation split off it for early stopping, and the test split is left to :func:`evaluate`.

Truncated back-propagation through time (Williams & Zipser's BPTT(k)): the only loss is the
cross-entropy of the prediction at the last frame T. With ``truncation = k < T`` the first ``T - k``
frames run under ``torch.no_grad()`` and only hand their state on, so the loss back-propagates
through the last ``k`` frames at most; with ``k >= T`` it is full BPTT.

Determinism: :func:`fit` seeds everything from ``cfg.seed`` (the split permutation with NumPy; the
weights, batch order and dropout masks with torch, inside a forked RNG so the caller's RNG is left
alone), turns on ``torch.use_deterministic_algorithms`` and runs on ``THREADS`` CPU threads, so the
same config, seed and data give bitwise-identical weights on the same machine. One thread, because
floating-point reductions may be split differently across thread counts, and because independent runs
parallelise better as separate processes (``study.experiments`` runs them so).
"""

from __future__ import annotations

import contextlib
import copy
import dataclasses
import json
import math
import os
import shutil
import tempfile
import warnings
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import torch
import torch.nn.functional as F
from tqdm import tqdm

from study import CLASSES
from study.core.errors import ConfigError, ModelError, TrajectoryError, output_error
from study.learn import native
from study.learn.config import (  # re-exported: train.TrainConfig
    DIMS,
    OLD_MEANING,
    TrainConfig,
    select_inputs,
)
from study.learn.metrics import failed_to_train, metrics
from study.learn.model import Classifier, Features
from study.simulate import observe
from study.simulate.data import Dataset, Split

SOURCES = ("learn.config", "learn.model", "learn.gru", "learn.native", "learn.train",
           *(f.relative_to(native.PACKAGE).as_posix() for f in native.FILES))
"""The code that determines a trained model (``study.core.cache.source_hash`` names): part of every run's cache key."""
THREADS = 1
"""CPU threads used by :func:`fit` (see the module docstring)."""

FORMATS = {"study.model/1": 1, "study.model/2": 2, "study.model/3": 3}
"""Every model format this code reads. Format 2 added the training fields min_epochs, forget_bias,
forget_init, clip_norm, lr_schedule and the record of a diverged run; format 3 the input representation
(``TrainConfig.inputs``: the classifier's first layer, with a mean and a standard deviation per channel).
An older directory is read with the later fields' old meaning (``OLD_MEANING``): positions, divided by
their standard deviation."""
FORMAT = "study.model/3"
FILES = ("weights.pt", "config.json", "normalisation.json", "history.json", "meta.json")
"""What a saved model directory holds."""


@dataclass
class TrainedModel:
    """A trained classifier with everything needed to use it and to know where it came from."""

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
    def failed(self) -> bool:
        """Whether the run failed to train by the book's criterion (``study.learn.metrics.failed_to_train``): its
        validation accuracy cannot be told from guessing, or its validation loss never left the plateau of a
        coin. False where the validation part's size is unknown (a model saved before it was recorded)."""
        if not self.history or not self.n_val:
            return False
        acc, loss = (float(self.history[self.best_epoch][k]) for k in ("val_accuracy", "val_loss"))
        return not (math.isfinite(acc) and math.isfinite(loss)) or failed_to_train(acc, loss, self.n_val)

    def failure(self) -> str:
        """What went wrong and what to change, in one sentence ('' for a run that trained)."""
        if not self.failed:
            return ""
        best = self.history[self.best_epoch]
        if not math.isfinite(float(best["val_loss"])):
            return (f"the run diverged in epoch {self.diverged_epoch} (its loss stopped being finite) before it "
                    f"learned anything; train again with a lower --lr (the protocol's is {TrainConfig().lr:g}) or "
                    "--clip-norm 1")
        return (f"the run failed to train: at its best epoch ({self.best_epoch}) the validation accuracy is "
                f"{100 * float(best['val_accuracy']):.1f} % of {self.n_val} and the loss {float(best['val_loss']):.3f} "
                f"(a coin's is {math.log(2):.3f}); it never left the initial plateau. Train again with another "
                f"--seed, a lower --lr (the protocol's is {TrainConfig().lr:g}), more --epochs, or more data")

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


def _read_json(path: Path) -> Any:
    try:
        return json.loads(path.read_text())
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as e:
        raise ModelError(f"model file {path} cannot be read ({type(e).__name__}); retrain with `study train`") from None


def load(model_dir: str | Path) -> TrainedModel:
    """Read a directory written by :meth:`TrainedModel.save`, checking that every file is there and agrees."""
    d = Path(model_dir)
    hint = "retrain it with `study train ... --out DIR`"
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
    if version in OLD_MEANING and isinstance(fields, dict):
        fields = {**OLD_MEANING[version], **fields}  # trained before these fields existed: what it was trained with
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


@contextlib.contextmanager
def deterministic(seed: int) -> Iterator[None]:
    """Seed torch inside a forked RNG, with deterministic algorithms and ``THREADS`` threads; restore after."""
    det = torch.are_deterministic_algorithms_enabled()
    with torch.random.fork_rng(devices=[]), num_threads(THREADS):
        torch.manual_seed(seed)
        torch.use_deterministic_algorithms(True)
        try:
            yield
        finally:
            torch.use_deterministic_algorithms(det)


def last_logits(net: Classifier, x: torch.Tensor, truncation: int) -> torch.Tensor:
    """Logits (B, 2) at the last frame of ``x`` (B, T, D), gradients truncated to the last ``truncation`` frames."""
    T = x.shape[1]
    state = None
    if truncation < T:
        with torch.no_grad():
            _, state = net.encode(x[:, : T - truncation])  # carries the state; no graph is kept
    hs, _ = net.encode(x[:, max(0, T - truncation) :], state)  # (B, k, H)
    return net.logits(hs[:, -1])


def frame_logits(net: Classifier, x: torch.Tensor) -> torch.Tensor:
    """Logits (B, T, 2) at every frame of ``x`` (B, T, D), gradients through the whole input."""
    hs, _ = net.encode(x)  # (B, T, H)
    return net.logits(hs)


def _loss(net: Classifier, x: torch.Tensor, y: torch.Tensor, cfg: TrainConfig) -> torch.Tensor:
    """The training loss of a batch: cross-entropy at the last frame, or the mean over every frame."""
    if cfg.loss_at == "every":
        logits = frame_logits(net, x)  # (B, T, 2)
        return F.cross_entropy(logits.reshape(-1, 2), y.repeat_interleave(x.shape[1]))
    return F.cross_entropy(last_logits(net, x, cfg.truncation), y)


def split_train_val(n: int, val_fraction: float, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Indices (train, val) of a seeded permutation of ``range(n)``; at least one in each."""
    perm = np.random.default_rng(seed).permutation(n)
    n_val = min(max(1, round(val_fraction * n)), n - 1)
    return np.sort(perm[n_val:]), np.sort(perm[:n_val])


@torch.no_grad()
def _loss_and_accuracy(net: Classifier, x: torch.Tensor, y: torch.Tensor, batch: int = 1024) -> tuple[float, float]:
    net.eval()
    logits = torch.cat([net(x[i : i + batch]) for i in range(0, len(x), batch)])
    return F.cross_entropy(logits, y).item(), (logits.argmax(1) == y).double().mean().item()


OBSERVED_VIEWS = 8
"""Randomised observations of the training split made once per 'randomised' run and cycled through, epoch by
epoch (drawing a new one every epoch would cost more than the epoch)."""


def _inputs(x: np.ndarray, tr: np.ndarray, va: np.ndarray, cfg: TrainConfig,
            fps: float) -> tuple[Callable[[int], torch.Tensor], np.ndarray]:
    """The training part's positions for each epoch (a function of the epoch) and the validation part's, from
    the first frames ``x`` (n, T, 3): exact positions; (``'randomised'``) observed by a random camera, eight
    views cycled; or (``'fixed'``) observed with the config's tracker error, drawn afresh every epoch."""
    def inputs(a: np.ndarray) -> np.ndarray:
        return select_inputs(a, cfg.dims, a.shape[1], what="training split")

    if cfg.observe == "exact":
        exact = torch.from_numpy(inputs(x[tr]))
        return lambda epoch: exact, inputs(x[va])
    calibrated = observe.Observation(noise=cfg.observe_noise, drop=cfg.observe_drop)
    if cfg.observe == "fixed":
        rng = np.random.default_rng([cfg.seed, 2017])  # a stream of its own: never the test split's draw
        x_val = inputs(calibrated.apply(x[va], fps, rng))
        drawn: dict[int, torch.Tensor] = {}

        def view(epoch: int) -> torch.Tensor:  # epochs come in order: each draws once from the same stream
            if epoch not in drawn:
                drawn.clear()
                drawn[epoch] = torch.from_numpy(inputs(calibrated.apply(x[tr], fps, rng)))
            return drawn[epoch]

        return view, x_val
    rng = np.random.default_rng([cfg.seed, 2016])
    ranges = observe.Randomisation(noise=(0.0, 3 * cfg.observe_noise))
    views = [torch.from_numpy(inputs(observe.randomised(x[tr], fps, rng, ranges))) for _ in range(OBSERVED_VIEWS)]
    return lambda epoch: views[epoch % len(views)], inputs(calibrated.apply(x[va], fps, rng))


def normalisation(x: torch.Tensor, features: Features) -> tuple[np.ndarray, np.ndarray]:
    """The mean and standard deviation (C,) of every channel ``features`` makes of the positions ``x`` (n, T, D),
    float64, a constant channel's std set to 1: what :meth:`Classifier.set_normalisation` stores."""
    raw = features.raw(x.double()).reshape(-1, features.n_channels).numpy()  # (n T, C)
    mean, std = raw.mean(axis=0), raw.std(axis=0)
    return mean, np.where(std > 0, std, 1.0)


class TrainingFailedWarning(UserWarning):
    """A run ended on the initial plateau (``TrainedModel.failed``): its model answers at chance."""


def fit(dataset: Dataset, cfg: TrainConfig, progress: bool = True, warn: bool = True) -> TrainedModel:
    """Train the classifier on ``dataset.train`` with ``cfg``; early-stop on a held-out part of it.

    A run that failed to train (``TrainedModel.failed``) says so with a :class:`TrainingFailedWarning` naming
    what to change, unless ``warn`` is False (the experiments count such runs instead)."""
    cfg.check()
    T = cfg.n_frames(dataset.fps)
    x = select_inputs(dataset.train.x, cfg.dims, T, what="training split")  # (n, T, D)
    y = np.asarray(dataset.train.y, dtype=np.int64)
    if len(y) < 2:
        raise TrajectoryError(f"training split has {len(y)} trajectories; need at least 2")
    tr, va = split_train_val(len(y), cfg.val_fraction, cfg.seed)
    view, x_val = _inputs(dataset.train.x[:, :T], tr, va, cfg, dataset.fps)
    y_tr = torch.from_numpy(y[tr])
    x_va, y_va = torch.from_numpy(x_val), torch.from_numpy(y[va])
    features = Features(x.shape[2], cfg.inputs, dataset.fps)
    mean, std = normalisation(view(0), features)  # (C,) the training part's first view only

    with deterministic(cfg.seed):
        net = Classifier(x.shape[2], cfg.hidden, cfg.layers, cfg.dropout, cfg.cell, forget_bias=cfg.forget_bias,
                         chrono_frames=T if cfg.forget_init == "chrono" else None, inputs=cfg.inputs, fps=dataset.fps)
        net.set_normalisation(torch.from_numpy(mean).float(), torch.from_numpy(std).float())
        opt = torch.optim.Adam(net.parameters(), lr=cfg.lr, foreach=True)  # one kernel per update op for all tensors
        sched = (torch.optim.lr_scheduler.ReduceLROnPlateau(opt, factor=0.5, patience=max(1, cfg.patience // 4))
                 if cfg.lr_schedule == "plateau" else None)
        history: list[dict[str, float]] = []
        best_loss, best_epoch, best_state = math.inf, 0, copy.deepcopy(net.state_dict())
        diverged: int | None = None
        bar = tqdm(range(cfg.max_epochs), desc=f"train {cfg.cell} {cfg.dims} {cfg.length:g}s", disable=not progress)
        for epoch in bar:
            net.train()
            x_tr = view(epoch)  # the same positions each epoch, or another observation of them
            order = torch.randperm(len(y_tr))
            total = 0.0
            for i in range(0, len(order), cfg.batch_size):
                idx = order[i : i + cfg.batch_size]
                loss = _loss(net, x_tr[idx], y_tr[idx], cfg)
                if not math.isfinite(loss.item()):
                    diverged = epoch  # a diverged run stops here, its last good weights kept, and says so
                    break
                opt.zero_grad(set_to_none=True)
                loss.backward()
                if cfg.clip_norm > 0:
                    torch.nn.utils.clip_grad_norm_(net.parameters(), cfg.clip_norm, foreach=True)
                opt.step()
                total += loss.item() * len(idx)
            if diverged is not None:
                history.append({"epoch": epoch, "train_loss": math.nan, "val_loss": math.nan, "val_accuracy": math.nan})
                break
            val_loss, val_acc = _loss_and_accuracy(net, x_va, y_va)
            history.append({"epoch": epoch, "train_loss": total / len(y_tr), "val_loss": val_loss, "val_accuracy": val_acc,
                            "lr": opt.param_groups[0]["lr"]})
            bar.set_postfix(val_loss=f"{val_loss:.3f}", val_acc=f"{val_acc:.3f}")
            if sched is not None:
                sched.step(val_loss)
            if val_loss < best_loss:
                best_loss, best_epoch, best_state = val_loss, epoch, copy.deepcopy(net.state_dict())
            elif epoch - best_epoch >= cfg.patience and epoch + 1 >= cfg.min_epochs:
                break
        net.load_state_dict(best_state)
        net.eval()
    tm = TrainedModel(net=net, config=cfg, fps=dataset.fps, data_key=dataset.key, history=history,
                      best_epoch=best_epoch, diverged_epoch=diverged, n_val=len(va))
    if warn and tm.failed:
        warnings.warn(tm.failure(), TrainingFailedWarning, stacklevel=2)
    return tm


def evaluate(tm: TrainedModel, split: Split) -> dict[str, Any]:
    """Score ``tm`` on ``split`` (normally the test split): see :func:`metrics`."""
    pred = tm.predict_proba(split.x).argmax(axis=1)
    return metrics(split.y, pred)
