"""MiniRocket (Dempster et al. 2021), from sktime: what a time-series practitioner would try first.

Random convolutional kernels turn each trajectory into about 10 000 features (the proportion of
positive values of each kernel's output); a ridge classifier with cross-validated regularisation
separates the classes. Nothing here re-implements it: :class:`MiniRocket` feeds our trajectories to
sktime's ``MiniRocketMultivariate`` and scikit-learn's ``RidgeClassifierCV``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from study.learn.config import DIMS, select_inputs


@dataclass
class MiniRocket:
    """MiniRocket features and a ridge classifier on the first ``n_frames`` frames of ``dims``."""

    dims: str
    n_frames: int
    seed: int = 0
    """Seeds the random kernels' dilations and biases."""
    parts: dict[str, Any] = field(default_factory=dict, repr=False)

    def _panel(self, x: np.ndarray) -> np.ndarray:
        """(n, T, 3) metres -> sktime's (n, D, n_frames) panel."""
        return np.ascontiguousarray(select_inputs(x, self.dims, self.n_frames).transpose(0, 2, 1), dtype=np.float64)

    def fit(self, x: np.ndarray, y: np.ndarray) -> MiniRocket:
        """Fit the kernels' biases and the ridge classifier on ``x`` (n, T, 3), labels ``y`` (n,)."""
        from sklearn.linear_model import RidgeClassifierCV
        from sklearn.preprocessing import StandardScaler
        from sktime.transformations.panel.rocket import MiniRocketMultivariate

        panel = self._panel(x)
        kernels = MiniRocketMultivariate(random_state=self.seed)
        features = np.asarray(kernels.fit_transform(panel))
        scaler = StandardScaler(with_mean=False).fit(features)
        y = np.asarray(y)
        scaled = scaler.transform(features)
        ridge = RidgeClassifierCV(alphas=np.logspace(-3, 3, 10)).fit(scaled, y)
        self.parts = {"kernels": kernels, "scaler": scaler, "ridge": ridge,
                      "platt": platt(self._held_out(scaled, y, ridge.alpha_), y)}
        return self

    def _held_out(self, scaled: np.ndarray, y: np.ndarray, alpha: float, folds: int = 5) -> np.ndarray:
        """Each training throw's ridge decision (n,) from a fit that did not see it (``folds``-fold, seeded, at the
        chosen ``alpha``): what the logistic is fitted on, so that it is not the training fit's overconfidence."""
        from sklearn.linear_model import RidgeClassifier
        from sklearn.model_selection import StratifiedKFold

        out = np.zeros(len(y))
        k = min(folds, int(np.bincount(y).min())) if len(np.unique(y)) == 2 else 0
        if k < 2:
            return out  # too few of a class to hold any out: p(heavy) stays at 1/2 (the logistic's slope falls to 0)
        for tr, te in StratifiedKFold(k, shuffle=True, random_state=self.seed).split(scaled, y):
            out[te] = RidgeClassifier(alpha=alpha).fit(scaled[tr], y[tr]).decision_function(scaled[te])
        return out

    def decision(self, x: np.ndarray) -> np.ndarray:
        """The ridge's decision (n,) for ``x`` (n, T, 3): heavy above 0."""
        p = self.parts
        features = np.asarray(p["kernels"].transform(self._panel(x)))
        return np.asarray(p["ridge"].decision_function(p["scaler"].transform(features)), dtype=np.float64)

    def predict(self, x: np.ndarray) -> np.ndarray:
        """Labels (n,) for ``x`` (n, T, 3): the ridge's."""
        return (self.decision(x) > 0).astype(np.int64)

    def p_heavy(self, x: np.ndarray) -> np.ndarray:
        """p(heavy) (n,) for ``x`` (n, T, 3): the decision through the logistic fitted on held-out decisions, moved
        so that it crosses 1/2 where the decision crosses 0 (its label is the ridge's: :meth:`predict`)."""
        a = self.parts["platt"]
        return 1.0 / (1.0 + np.exp(-a * self.decision(x)))


def platt(decision: np.ndarray, y: np.ndarray) -> float:
    """The slope ``a`` of p(heavy) = 1 / (1 + exp(-a d)) that best fits labels ``y`` (n,) from decisions ``d`` (n,)
    (maximum likelihood, no intercept, so the label stays the decision's sign): Platt scaling through the origin."""
    from scipy.optimize import minimize_scalar

    d, t = np.asarray(decision, float), np.asarray(y) == 1

    def loss(log_a: float) -> float:
        z = np.exp(log_a) * d
        return float(np.sum(np.logaddexp(0.0, -z) * t + np.logaddexp(0.0, z) * ~t))

    return float(np.exp(minimize_scalar(loss, bounds=(-10.0, 10.0), method="bounded").x))

    @property
    def n_inputs(self) -> int:
        return len(DIMS[self.dims])
