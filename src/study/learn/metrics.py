"""Scores of a classifier, without torch: accuracy, per-class accuracy and the confusion matrix."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from study import CLASSES


def metrics(y_true: np.ndarray, y_pred: np.ndarray) -> dict[str, Any]:
    """Accuracy, per-class accuracy and the confusion matrix (rows true class, columns predicted)."""
    y_true, y_pred = np.asarray(y_true), np.asarray(y_pred)
    cm = np.zeros((len(CLASSES), len(CLASSES)), dtype=np.int64)
    np.add.at(cm, (y_true, y_pred), 1)
    per_class = {c: (float(cm[k, k] / cm[k].sum()) if cm[k].sum() else math.nan) for k, c in enumerate(CLASSES)}
    return {
        "n": int(len(y_true)),
        "accuracy": float((y_true == y_pred).mean()) if len(y_true) else math.nan,
        "per_class_accuracy": per_class,
        "confusion": cm.tolist(),
        "classes": list(CLASSES),
    }
