"""MiniRocket from sktime on the toy bounces: it fits, predicts labels, and separates the toy classes."""

import model_toys
import numpy as np
import pytest

from study.learn.rocket import MiniRocket


@pytest.mark.slow  # numba compiles the kernels on first use (about 20 s)
def test_minirocket_separates_the_toy_classes():
    ds = model_toys.dataset(n=60, T=45)
    m = MiniRocket(dims="z", n_frames=45, seed=0).fit(ds.train.x, ds.train.y)
    pred = m.predict(ds.test.x)
    assert pred.shape == (60,) and set(np.unique(pred)) <= {0, 1}
    assert (pred == ds.test.y).mean() >= 0.8
    again = MiniRocket(dims="z", n_frames=45, seed=0).fit(ds.train.x, ds.train.y).predict(ds.test.x)
    assert (again == pred).all(), "seeded"


@pytest.mark.slow  # numba compiles the kernels on first use
def test_minirockets_probability_labels_as_its_ridge_and_is_calibrated_on_held_out_throws():
    """p(heavy) is above 1/2 exactly where the ridge says heavy; fitted on decisions the fit did not see, it is
    less sure on the training throws than a fit on its own decisions would be, and no sure answer is wrong."""
    ds = model_toys.dataset(n=60, T=45)
    m = MiniRocket(dims="z", n_frames=45, seed=0).fit(ds.train.x, ds.train.y)
    p = m.p_heavy(ds.test.x)
    assert p.shape == (60,) and ((p > 0.5) == (m.predict(ds.test.x) == 1)).all()
    assert 0 < m.parts["platt"] < np.inf and ((p > 0.99) <= (ds.test.y == 1)).all()


def test_platt_scaling_through_the_origin_follows_how_well_the_decision_separates():
    from study.learn.rocket import platt

    rng = np.random.default_rng(0)
    y = np.repeat([0, 1], 500)
    sharp, blurred = (np.where(y == 1, 1.0, -1.0) + s * rng.standard_normal(1000) for s in (0.2, 2.0))
    assert platt(sharp, y) > 3 * platt(blurred, y) > 0
