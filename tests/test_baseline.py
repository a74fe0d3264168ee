"""The physics baseline: its restitution estimate on an exact bounce, and its logistic regression."""

import model_toys
import numpy as np
import pytest

from study.core.errors import ConfigError, TrajectoryError
from study.learn import baseline


def exact_bounce(e: float, h0: float = 1.0, rest: float = 0.1, fps: float = 240.0, seconds: float = 3.0) -> np.ndarray:
    """(T,) height of a ball dropped from rest h0 above its resting height, restitution e, no drag."""
    g = baseline.G
    t = np.arange(round(seconds * fps)) / fps
    z = np.full_like(t, rest)
    t0, v = 0.0, 0.0  # start of the current flight, upward speed at its start
    t_fall = np.sqrt(2 * h0 / g)
    z[t < t_fall] = rest + h0 - 0.5 * g * t[t < t_fall] ** 2
    t0, v = t_fall, e * g * t_fall
    while v > 0.05:
        flight = 2 * v / g
        m = (t >= t0) & (t < t0 + flight)
        z[m] = rest + v * (t[m] - t0) - 0.5 * g * (t[m] - t0) ** 2
        t0, v = t0 + flight, e * v
    return z


def heights(*z: np.ndarray) -> np.ndarray:
    """Height series (T,) as trajectories (n, T, 3) that do not move horizontally."""
    x = np.zeros((len(z), len(z[0]), 3))
    x[:, :, 2] = np.stack(z)
    return x


@pytest.mark.parametrize("e", [0.3, 0.6, 0.85])
def test_restitution_of_an_exact_bounce(e):
    (restitution, ratio, bounces), = baseline.features(heights(exact_bounce(e)), 240.0, "z")
    assert baseline.FEATURES["z"] == ("restitution", "ratio", "bounces")
    assert restitution == pytest.approx(e, abs=0.03)
    assert ratio == pytest.approx(e, abs=0.03)
    assert bounces >= 1


def test_no_impact_gives_zero_features():
    falling = 1.0 - 0.5 * 9.81 * (np.arange(10) / 30) ** 2
    assert baseline.features(heights(falling), 30.0, "z").tolist() == [[0.0, 0.0, 0.0]]


def test_logistic_regression_recovers_weights():
    rng = np.random.default_rng(0)
    f = rng.normal(size=(20000, 2))
    w_true = np.array([2.0, -1.0, 0.5])
    y = (rng.uniform(size=20000) < baseline.sigmoid(f @ w_true[:2] + w_true[2])).astype(float)
    np.testing.assert_allclose(baseline.logistic_regression(f, y, l2=0.0), w_true, atol=0.1)


@pytest.mark.parametrize("dims", ["z", "xyz"])
def test_separates_the_toy_classes(dims):
    ds = model_toys.dataset(n=60, T=60)
    m = baseline.fit(ds, dims, 2.0)
    assert m.w.shape == (len(baseline.FEATURES[dims]) + 1,)
    res = baseline.evaluate(m, ds.test)
    assert res["accuracy"] >= 0.9 and res["n"] == 60


def test_bad_input():
    ds = model_toys.dataset(n=8, T=20)
    with pytest.raises(ConfigError, match="dims"):
        baseline.fit(ds, "xy", 0.5)
    with pytest.raises(ConfigError, match="length"):
        baseline.fit(ds, "z", 0.0)
    with pytest.raises(TrajectoryError, match="frames"):
        baseline.fit(ds, "z", 2.0)
    m = baseline.fit(ds, "z", 0.5)
    x = ds.test.x.copy()
    x[1, 0, 0] = np.inf
    with pytest.raises(TrajectoryError, match="index 1"):
        m.predict_proba(x)
