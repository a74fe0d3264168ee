"""One-feature rules on a window of the first T seconds, and the drag rule among them: what the cue and length
chapters ask of a window before crediting a network with anything.

    rows = rules(x_train, y_train, x_test, y_test, fps, contact)   # every rule, each with its test interval
    window_cues(dataset, (0.5, 1.0), contact)                     # per T: landed share, drag rule, best other
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from study.learn.metrics import bootstrap_accuracy
from study.simulate import data, measure

DRAG = "fall_acceleration"
"""The drag rule's feature (``study.simulate.measure.FEATURES``)."""


def rules(train_x: np.ndarray, train_y: np.ndarray, test_x: np.ndarray, test_y: np.ndarray, fps: float,
          contact_height: float, names: Sequence[str] | None = None) -> list[dict]:
    """The one-feature rules of ``study.simulate.measure`` on exactly these inputs (the first T seconds),
    each with the bootstrap interval of its test accuracy."""
    rows = measure.simple_rules(train_x, train_y, test_x, test_y, fps, contact_height, tuple(names or measure.FEATURES))
    return [r | {"interval": bootstrap_accuracy(r["correct"])} for r in rows]


def window_cues(dataset: data.Dataset, lengths: Sequence[float], contact_height: float) -> list[dict]:
    """What the first T seconds of each test throw hold, for each T (s) of ``lengths``: the share whose first
    fall has ended inside the window (``landed``), the drag rule's test accuracy on the window (``drag``)
    and the best other one-feature rule's (``other``, named by ``other_feature``), intervals over test throws."""
    rows = []
    for length in lengths:
        n = round(length * dataset.fps)
        xte = dataset.test.x[:, :n]
        ends = [measure.first_contact(z) for z in xte[..., 2]]
        by = {r["feature"]: r for r in rules(dataset.train.x[:, :n], dataset.train.y, xte, dataset.test.y,
                                             dataset.fps, contact_height)}
        drag = by.pop(DRAG)
        other = max(by.values(), key=lambda r: r["test_accuracy"])
        rows.append({"length": float(length), "landed": float(np.mean([e is not None for e in ends])),
                     "drag": drag["interval"], "other": other["interval"], "other_feature": other["feature"]})
    return rows
