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
        ridge = RidgeClassifierCV(alphas=np.logspace(-3, 3, 10)).fit(scaler.transform(features), np.asarray(y))
        self.parts = {"kernels": kernels, "scaler": scaler, "ridge": ridge}
        return self

    def predict(self, x: np.ndarray) -> np.ndarray:
        """Labels (n,) for ``x`` (n, T, 3)."""
        p = self.parts
        features = np.asarray(p["kernels"].transform(self._panel(x)))
        return p["ridge"].predict(p["scaler"].transform(features)).astype(np.int64)

    @property
    def n_inputs(self) -> int:
        return len(DIMS[self.dims])
