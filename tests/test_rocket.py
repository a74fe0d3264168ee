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
