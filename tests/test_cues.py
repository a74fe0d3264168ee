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
