"""The floor path's error model (study.methods.floor_model): its check against the series it was fitted to, on
series drawn from the model itself and from a per-arc depth error the model cannot hold."""

from __future__ import annotations

import numpy as np
import pytest

from study.core.errors import DataError
from study.methods import floor_model, tracker_model
from study.simulate.observe import TrackerNoise


def _series(errors: list[np.ndarray]) -> list[tracker_model.ErrorSeries]:
    return [tracker_model.ErrorSeries(e, np.zeros(len(e), bool), np.ones(len(e), bool)) for e in errors]


def _ar1(rho: float, n: int, rng: np.random.Generator) -> np.ndarray:
    e = np.empty(n)
    e[0] = rng.normal()
    for t in range(1, n):
        e[t] = rho * e[t - 1] + np.sqrt(1 - rho**2) * rng.normal()
    return 0.01 * e


def test_an_ar1_error_passes_the_check_and_a_per_arc_depth_error_does_not():
    rng = np.random.default_rng(0)
    ar1 = _series([_ar1(0.8, 180, rng) for _ in range(30)])
    fit = tracker_model.fit(ar1, bootstrap=20)
    assert fit.model.rho == pytest.approx(0.8, abs=0.1)
    good = floor_model.check(ar1, fit)
    assert good.lags == floor_model.LAGS and good.worst < 0.1, "the model's rho^k is the series' own"
    # one wrong depth a flight: a constant error over each 30-frame arc, plus a little frame noise
    arcs = _series([np.repeat(rng.normal(0, 0.02, 6), 30) + rng.normal(0, 0.003, 180) for _ in range(30)])
    bad = floor_model.check(arcs, tracker_model.fit(arcs, bootstrap=20))
    assert bad.measured[-1] < bad.model[-1] - 0.1, "20 frames on, a new arc has a depth of its own; AR(1) remembers"
    assert bad.worst > 2 * good.worst


def test_a_check_with_no_varying_error_is_refused():
    flat = _series([np.zeros(10)])
    fit = tracker_model.TrackerFit(TrackerNoise(), 0.0, {}, 1, 10, 0, 0.0, 0.0, 0.0, 0.0)
    with pytest.raises(DataError, match="no varying error"):
        floor_model.check(flat, fit)


def test_no_floor_heights_on_the_development_clips_means_no_floor_model(monkeypatch):
    """The one place a failed fit becomes 'no floor model' (the candidates and the page both ask here)."""
    def no_heights(runner, progress=False):
        raise DataError("floor model: the floor path gave no heights on any of the 4 development clips")

    monkeypatch.setattr(floor_model, "fit", no_heights)
    assert floor_model.fitted(None) is None and floor_model.observation(None) is None
