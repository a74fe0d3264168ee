"""A physics-informed baseline: hand-made bounce features and a logistic regression, plain NumPy.

What a reviewer would try before an LSTM. From the height series z(t) of each trajectory:

- ``restitution``: the first rebound's apex height over the equivalent drop height before the first
  impact (``h + vz^2 / 2g``, constant in free fall), square-rooted: ``e = sqrt(h_1 / h_0)``;
- ``ratio``: the mean of ``sqrt(h_{k+1} / h_k)`` over successive apexes (the restitution again, from
  later bounces; equals ``restitution`` when there is one rebound);
- ``bounces``: the number of bounces (``study.simulate.measure.bounces``: rises of 2 cm or more);

heights measured above the lowest centre height seen (the resting height). With ``dims = 'xyz'`` also,
from the horizontal speed s(t) = |d(x, y)/dt|:

- ``decel``: the mean horizontal deceleration after the first ground contact, m/s^2;
- ``stop``: the fraction of the input window before the object stops moving horizontally (s < 5 cm/s).

A feature that cannot be measured inside the window (no impact yet) is 0. The features are
standardised with the training split's mean and std and fed to a logistic regression fitted by
Newton's method with a small L2 penalty. It has no hyper-parameters to tune, so it fits on the whole
training split (the LSTM's training plus validation parts) and is scored on the same test split.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from study.core.errors import ConfigError, check_range
from study.learn.config import DIMS, select_inputs
from study.learn.metrics import metrics
from study.simulate import measure
from study.simulate.data import Dataset, Split

G = 9.81
"""Gravity, m/s^2."""
FEATURES = {"z": ("restitution", "ratio", "bounces"), "xyz": ("restitution", "ratio", "bounces", "decel", "stop")}
"""Feature names by input dims."""


def _bounce_features(z: np.ndarray, fps: float) -> tuple[float, float, float]:
    """(restitution, ratio, bounces) of one height series ``z`` (T,) metres."""
    first = measure.first_contact(z)
    if first is None:
        return 0.0, 0.0, 0.0
    h = z - z.min()
    vz = np.gradient(z) * fps  # (T,) m/s, central differences
    pre = slice(0, max(1, first - 1))  # free flight before the first contact (skip the contact frame)
    h0 = float(np.median(h[pre] + vz[pre] ** 2 / (2 * G)))
    b = measure.bounces(z)
    rebounds = h[b.apexes]
    if len(rebounds) == 0 or h0 <= 0:
        return 0.0, 0.0, float(len(b.impacts))
    heights = np.concatenate([[h0], rebounds])
    ratios = np.sqrt(heights[1:] / heights[:-1])
    return float(ratios[0]), float(ratios.mean()), float(len(b.impacts))


def _slide_features(xy: np.ndarray, z: np.ndarray, fps: float) -> tuple[float, float]:
    """(decel, stop) of one trajectory: horizontal ``xy`` (T, 2) and height ``z`` (T,), metres."""
    s = np.linalg.norm(np.diff(xy, axis=0), axis=1) * fps  # (T-1,) horizontal speed, m/s
    after = s[measure.first_contact(z) or 0 :]
    if len(after) < 2:
        return 0.0, 1.0
    decel = (after[0] - after[-1]) / ((len(after) - 1) / fps)
    moving = np.flatnonzero(s > measure.REST_SPEED)
    stop = (moving[-1] + 1) / len(s) if len(moving) else 0.0
    return float(decel), float(stop)


def features(x: np.ndarray, fps: float, dims: str) -> np.ndarray:
    """Physics features of ``x`` (n, T, 3) metres -> (n, k) float64, columns ``FEATURES[dims]``."""
    out = []
    for traj in np.asarray(x, dtype=np.float64):
        row = list(_bounce_features(traj[:, 2], fps))
        if dims == "xyz":
            row += _slide_features(traj[:, :2], traj[:, 2], fps)
        out.append(row)
    return np.asarray(out, dtype=np.float64).reshape(len(out), len(FEATURES[dims]))


@dataclass
class PhysicsBaseline:
    """Logistic regression on standardised physics features."""

    dims: str
    n_frames: int
    fps: float
    mean: np.ndarray
    """(k,) feature means on the training split."""
    std: np.ndarray
    """(k,) feature standard deviations on the training split (1 where constant)."""
    w: np.ndarray
    """(k + 1,) weights, the last one the bias; p_heavy = sigmoid(features @ w)."""

    def predict_proba(self, x: np.ndarray) -> np.ndarray:
        """``x`` (n, T, 3) metres, T >= n_frames -> (n, 2) float64 [p_light, p_heavy]."""
        xs = select_inputs(x, "xyz", self.n_frames)  # validated, all three columns
        f = (features(xs, self.fps, self.dims) - self.mean) / self.std
        p = sigmoid(np.column_stack([f, np.ones(len(f))]) @ self.w)
        return np.column_stack([1 - p, p])

    @property
    def coefficients(self) -> dict[str, float]:
        """Weight of each standardised feature (positive: evidence for heavy)."""
        return dict(zip(FEATURES[self.dims] + ("bias",), map(float, self.w)))


def sigmoid(a: np.ndarray) -> np.ndarray:
    """The logistic function 1 / (1 + exp(-a)), elementwise, written with tanh so it cannot overflow."""
    return 0.5 * (1 + np.tanh(0.5 * a))


def logistic_regression(f: np.ndarray, y: np.ndarray, l2: float = 1e-3, iters: int = 50) -> np.ndarray:
    """Newton's method for L2-penalised logistic regression: ``f`` (n, k), ``y`` (n,) in {0, 1} -> w (k+1,)."""
    A = np.column_stack([f, np.ones(len(f))])  # (n, k+1)
    w = np.zeros(A.shape[1])
    reg = l2 * np.eye(A.shape[1])
    reg[-1, -1] = 0.0  # no penalty on the bias
    for _ in range(iters):
        p = sigmoid(A @ w)
        grad = A.T @ (p - y) / len(y) + reg @ w
        hess = (A * (p * (1 - p))[:, None]).T @ A / len(y) + reg
        step = np.linalg.solve(hess + 1e-9 * np.eye(len(w)), grad)
        w -= step
        if np.abs(step).max() < 1e-10:
            break
    return w


def fit(dataset: Dataset, dims: str, length: float) -> PhysicsBaseline:
    """Fit the baseline on ``dataset.train`` using the first ``length`` seconds."""
    if dims not in DIMS:
        raise ConfigError(f"dims = {dims!r} is unknown; use 'xyz' or 'z'")
    check_range("length (seconds)", length, 0, lo_open=True)
    n_frames = max(1, round(length * dataset.fps))
    xs = select_inputs(dataset.train.x, "xyz", n_frames, what="training split")
    f = features(xs, dataset.fps, dims)
    mean, std = f.mean(axis=0), f.std(axis=0)
    std = np.where(std > 0, std, 1.0)
    w = logistic_regression((f - mean) / std, np.asarray(dataset.train.y, dtype=np.float64))
    return PhysicsBaseline(dims=dims, n_frames=n_frames, fps=dataset.fps, mean=mean, std=std, w=w)


def evaluate(model: PhysicsBaseline, split: Split) -> dict:
    """Accuracy, per-class accuracy and confusion matrix on ``split`` (see :func:`study.learn.metrics.metrics`)."""
    return metrics(split.y, model.predict_proba(split.x).argmax(axis=1))
