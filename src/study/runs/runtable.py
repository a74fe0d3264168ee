"""Trained runs as a typed table: one :class:`Run` per record, and :class:`Runs`, the few filters chapters need.

The runner returns :class:`Runs` for every experiment (``Runner.seed_runs``, ``Runner.grid``, ...); a chapter
asks it questions instead of filtering dicts::

    rows = runner.seed_runs(cfg)
    rows.where(dims="z").correct()        # (S, n) bool: seed s got test throw i right
    rows.where(dims="z").accuracies()     # (S,) test accuracy per seed
    rows.groups("dims")                   # {("z",): Runs, ("xyz",): Runs}

A field is looked up in the run's labels first (what an experiment adds: a protocol's name, a cell of a 2 x 2),
then its training config (``dims``, ``cell``, ``length``, ``seed``, ...), then the run itself
(``val_accuracy``, ``failed``, ...).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from study.core.errors import ConfigError
from study.learn.config import TrainConfig


@dataclass(frozen=True, eq=False)
class Run:
    """One trained run: its configuration, how it trained, and, if scored on the test split, how it did there."""

    config: TrainConfig
    """What was trained."""
    val_accuracy: float
    """Validation accuracy at the kept epoch."""
    val_loss: float
    """Validation loss at the kept epoch, nats."""
    epochs_run: int
    """Epochs run (at most ``config.epochs``)."""
    best_epoch: int
    """The kept epoch (0-based)."""
    seconds: float
    """Training time, seconds of one CPU."""
    failed: bool
    """Failed to train (``study.learn.metrics.failed_to_train``): it counts, at chance, wherever it is averaged."""
    diverged_epoch: int | None = None
    """The epoch its loss became non-finite, or None."""
    accuracy: float | None = None
    """Test accuracy; None for a run scored on validation only."""
    correct: np.ndarray | None = None
    """(n,) bool: which test throws it got right; None without a test score."""
    per_class: Mapping[str, float] = field(default_factory=dict)
    """Test accuracy per class name."""
    labels: Mapping[str, Any] = field(default_factory=dict)
    """What the experiment calls this run (``protocol``, ``truncated``, ``forget``, ``frames``, ...)."""

    @classmethod
    def from_record(cls, rec: Mapping[str, Any], test_y: np.ndarray, **labels: Any) -> Run:
        """The run of a record of ``study.runs.records.run``; ``test_y`` (n,) the test labels it was scored on."""
        test = rec.get("test")
        correct = accuracy = None
        per_class: dict[str, float] = {}
        if test is not None:
            correct = (np.asarray(test["p_heavy"]) > 0.5) == (np.asarray(test_y) == 1)
            accuracy = float(test["accuracy"])
            per_class = {str(k): float(v) for k, v in test["per_class_accuracy"].items()}
        return cls(TrainConfig(**rec["config"]), float(rec["val_accuracy"]), float(rec["val_loss"]),
                   int(rec["epochs_run"]), int(rec["best_epoch"]), float(rec["train_seconds"]), bool(rec["failed"]),
                   rec["diverged_epoch"], accuracy, correct, per_class, dict(labels))

    @property
    def seed(self) -> int:
        return self.config.seed

    @property
    def capped(self) -> bool:
        """Stopped by the epoch cap, not by early stopping (nor by diverging)."""
        return self.epochs_run >= self.config.epochs and self.diverged_epoch is None

    def get(self, name: str) -> Any:
        """A field by name: a label, else a config field, else the run's own."""
        if name in self.labels:
            return self.labels[name]
        if name in _CONFIG_FIELDS:
            return getattr(self.config, name)
        if name in _RUN_FIELDS or name in ("seed", "capped"):
            return getattr(self, name)
        raise ConfigError(f"run field {name!r}: neither a label ({', '.join(self.labels) or 'none'}), a TrainConfig "
                          "field nor a run field")

    def labelled(self, **labels: Any) -> Run:
        """The same run with more labels."""
        return dataclasses.replace(self, labels={**self.labels, **labels})


_CONFIG_FIELDS = frozenset(f.name for f in dataclasses.fields(TrainConfig))
_RUN_FIELDS = frozenset(f.name for f in dataclasses.fields(Run))


class Runs(tuple):
    """An ordered table of :class:`Run`: the filters and columns the chapters need."""

    def __new__(cls, runs: Iterable[Run] = ()) -> Runs:
        return super().__new__(cls, tuple(runs))

    def where(self, **equal: Any) -> Runs:
        """The runs whose fields equal ``equal`` (``where(dims="z", cell="gru")``)."""
        return Runs(r for r in self if all(r.get(k) == v for k, v in equal.items()))

    def one(self, **equal: Any) -> Run:
        """The one run whose fields equal ``equal``; :class:`ConfigError` if none or several."""
        found = self.where(**equal)
        if len(found) != 1:
            raise ConfigError(f"runs where {equal}: {len(found)} runs, expected one")
        return found[0]

    def values(self, name: str) -> list[Any]:
        """The field ``name`` of every run, in order."""
        return [r.get(name) for r in self]

    def distinct(self, name: str) -> list[Any]:
        """The distinct values of ``name``, in order of first appearance."""
        out: list[Any] = []
        for v in self.values(name):
            if v not in out:
                out.append(v)
        return out

    def groups(self, *names: str) -> dict[tuple, Runs]:
        """The runs grouped by the fields ``names``, groups in order of first appearance."""
        out: dict[tuple, list[Run]] = {}
        for r in self:
            out.setdefault(tuple(r.get(n) for n in names), []).append(r)
        return {k: Runs(v) for k, v in out.items()}

    def correct(self) -> np.ndarray:
        """(S, n) bool: run s got test throw i right (every run scored on the same test split)."""
        if not self:
            raise ConfigError("runs.correct(): no runs")
        missing = [r.seed for r in self if r.correct is None]
        if missing:
            raise ConfigError(f"runs.correct(): runs of seeds {missing} were scored on validation only")
        return np.stack([r.correct for r in self])

    def accuracies(self) -> np.ndarray:
        """(S,) test accuracy per run."""
        return np.asarray([r.accuracy for r in self], dtype=np.float64)

    def val_accuracies(self) -> np.ndarray:
        """(S,) validation accuracy per run."""
        return np.asarray([r.val_accuracy for r in self], dtype=np.float64)

    @property
    def seeds(self) -> list[int]:
        return [r.seed for r in self]

    @property
    def n_failed(self) -> int:
        """Runs that failed to train."""
        return sum(r.failed for r in self)

    def picked_by_validation(self) -> Run:
        """The run with the highest validation accuracy (ties: the first): what the paper's "best accuracy" is
        fairly compared with, since it never looks at the test split."""
        if not self:
            raise ConfigError("runs.picked_by_validation(): no runs")
        return max(self, key=lambda r: r.val_accuracy)

    def labelled(self, labels: Iterable[Mapping[str, Any]]) -> Runs:
        """Each run with the labels of its place in ``labels``."""
        return Runs(r.labelled(**lab) for r, lab in zip(self, labels, strict=True))

    def __add__(self, other: Iterable[Run]) -> Runs:  # type: ignore[override]
        return Runs(tuple(self) + tuple(other))


@dataclass(frozen=True, eq=False)
class Fitted:
    """A classifier without seeds (the physics baseline), fitted once on the training split and scored on the test
    split."""

    dims: str
    """Its input."""
    accuracy: float
    """Test accuracy."""
    correct: np.ndarray
    """(n,) bool: which test throws it got right."""
    per_class: Mapping[str, float]
    """Test accuracy per class name."""
    coefficients: Mapping[str, float]
    """Its fitted weights by feature (standardised features; + means heavy)."""
