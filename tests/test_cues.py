"""What a window of each trajectory holds: the rules of study.experiments.cues on a toy set whose only cue is drag."""

from __future__ import annotations

import numpy as np

from study.experiments import cues
from study.simulate import data


def drag_only(n: int, seed: int, fps: float = 30.0, frames: int = 60) -> data.Split:
    """Falls from 1.5-2 m that stop dead at 0.1 m; light objects fall at 9.3 m/s^2, heavy at 9.8: drag is the
    only difference. (n, frames, 3) metres, labels alternate light, heavy."""
    rng = np.random.default_rng(seed)
    y = (np.arange(n) % 2).astype(np.int64)
    g = np.where(y == 1, 9.8, 9.3)
    t = np.arange(frames) / fps
    z = rng.uniform(1.5, 2.0, n)[:, None] + rng.uniform(0, 1, n)[:, None] * t - g[:, None] / 2 * t**2
    x = np.zeros((n, frames, 3))
    x[..., 2] = np.maximum(z, 0.1)
    return data.Split(x.astype(np.float32), y)


def test_window_cues_finds_the_drag_cue_before_any_landing():
    ds = data.Dataset(train=drag_only(200, 0), test=drag_only(200, 1), fps=30.0)
    short, long = cues.window_cues(ds, (0.3, 2.0), contact_height=0.15)
    assert short["length"] == 0.3 and short["landed"] == 0.0  # nothing reaches the ground in 9 frames
    assert long["landed"] == 1.0
    assert short["drag"].value > 0.9 and short["drag"].lo <= short["drag"].value <= short["drag"].hi
    assert short["other_feature"] != "fall_acceleration"
    assert short["other"].value < short["drag"].value


def with_params(split: data.Split, **params: np.ndarray) -> data.Split:
    return data.Split(split.x, split.y, params)


def test_the_fitted_ceiling_reads_the_true_parameters():
    """A class that the restitution alone separates gives a ceiling near 100 %; telling the classifier a mass
    that the classes share adds nothing, one they do not share makes it perfect."""
    rng = np.random.default_rng(0)

    def split(n: int) -> data.Split:
        y = (np.arange(n) % 2).astype(np.int64)
        e = np.where(y == 0, rng.uniform(0.6, 0.8, n), rng.uniform(0.2, 0.4, n))
        shared = rng.uniform(0.3, 0.7, n)
        return with_params(data.Split(np.zeros((n, 2, 3), np.float32), y), restitution=e, friction=shared,
                           mass=np.where(y == 0, 0.2, 5.0) * rng.uniform(0.9, 1.1, n))

    ds = data.Dataset(train=split(400), test=split(400), fps=30.0)
    iv = cues.ceiling(ds)
    assert iv.value > 0.97 and iv.lo <= iv.value <= iv.hi
    assert cues.ceiling(ds, with_mass=True).value == 1.0
    noisy = data.Dataset(train=split(400), test=split(400), fps=30.0)
    for s in (noisy.train, noisy.test):
        s.params["restitution"] = rng.permutation(s.params["restitution"])  # no longer tied to the class
    assert cues.ceiling(noisy).hi < 0.6


def test_mixed_shapes_pool_the_training_splits_and_name_their_parts():
    a = data.Dataset(train=drag_only(10, 0), test=drag_only(6, 1), fps=30.0, meta={"key": "a"})
    b = data.Dataset(train=drag_only(8, 2), test=drag_only(6, 3), fps=30.0, meta={"key": "b"})
    mixed = cues.mixed_shapes({"cube": a, "ball": b}, names=("cube", "ball"))
    assert len(mixed.train) == 18 and mixed.test is a.test and mixed.fps == 30.0
    np.testing.assert_array_equal(mixed.train.x[10:], b.train.x)
    other = cues.mixed_shapes({"cube": a, "ball": b}, names=("ball", "cube"))
    assert mixed.key and other.key and mixed.key != other.key, "the key names its parts, in order"
