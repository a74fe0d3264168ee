"""The observation model: each function's statistics, its composition, and its bad inputs."""

from __future__ import annotations

import numpy as np
import pytest

from study.core.errors import ConfigError, TrajectoryError
from study.simulate import observe


def parabolas(n: int = 50, T: int = 90, fps: float = 30.0, seed: int = 0) -> np.ndarray:
    """Smooth trajectories (n, T, 3): free flight of random throws, no ground (for exact interpolation tests)."""
    rng = np.random.default_rng(seed)
    t = np.arange(T) / fps
    p0 = rng.uniform(-1, 1, (n, 1, 3)) + np.array([0, 0, 3.0])
    v0 = rng.uniform(-2, 2, (n, 1, 3))
    x = p0 + v0 * t[None, :, None]
    x[:, :, 2] -= 0.5 * 9.81 * t**2 / 4
    return x


def test_noise_has_the_size_asked_for_and_only_on_the_height():
    x = parabolas(200)
    y = observe.noise(x, 0.01, np.random.default_rng(1))
    d = y - x
    assert np.std(d[:, :, 2]) == pytest.approx(0.01, rel=0.02) and abs(np.mean(d[:, :, 2])) < 5e-4
    assert (d[:, :, :2] == 0).all()
    per = observe.noise(x, np.linspace(0, 0.02, 200), np.random.default_rng(1))
    assert np.std((per - x)[:10, :, 2]) < np.std((per - x)[-10:, :, 2])  # one size per trajectory
    assert (observe.noise(x, 0.0, np.random.default_rng(1)) == x).all()


def test_dropped_frames_are_the_share_asked_for_and_filled_linearly():
    rng = np.random.default_rng(2)
    x = parabolas(100)
    y = observe.drop(x, 0.3, rng)
    changed = np.abs(y - x).max(axis=2) > 1e-12
    # On a straight line linear interpolation is exact; on these parabolas it is not: the lost frames
    # are the ones that moved. About 30 % of the frames (the first one is never lost).
    assert changed[:, 0].sum() == 0 and changed.mean() == pytest.approx(0.3 * 89 / 90, abs=0.02)
    line = np.broadcast_to(np.linspace(0, 1, 90)[None, :, None], (5, 90, 3))
    y = observe.drop(line, 0.3, np.random.default_rng(3))
    # Interpolated frames lie on the line; lost frames at the very end cannot be interpolated and hold
    # the last frame the tracker has, so compare all but the last few.
    np.testing.assert_allclose(y[:, :80], line[:, :80], atol=1e-12)


def test_fill_runs_fills_short_gaps_and_splits_at_long_ones():
    v = np.arange(12, dtype=float)[:, None]
    measured = np.ones(12, bool)
    measured[[3, 6, 7, 8, 9]] = False
    filled, seg = observe.fill_runs(v, measured, max_gap=2)
    assert filled[3, 0] == 3.0 and seg.tolist() == [0] * 6 + [-1] * 4 + [1, 1]


def test_camera_rate_resamples_a_smooth_curve_to_tolerance():
    fps = 120.0
    x = parabolas(20, T=361, fps=fps)  # 3 s at 120 fps
    at30 = x[:, ::4]
    for camera in (120.0, 60.0, 30.0):
        y = observe.camera_rate(x, fps, camera, out_fps=30.0)
        assert y.shape == at30.shape
        np.testing.assert_allclose(y, at30, atol=1e-12)  # a frame the camera has is the frame itself
    y15 = observe.camera_rate(x, fps, 15.0, out_fps=30.0)
    # between two 15 fps frames the parabola is interpolated linearly: error g' dt^2 / 8 at most
    assert np.abs(y15 - at30).max() == pytest.approx(9.81 / 4 * (1 / 15) ** 2 / 8, rel=0.05)
    with pytest.raises(ConfigError, match="camera_fps = 45"):
        observe.camera_rate(x, fps, 45.0)


def test_perspective_of_a_level_camera_recovers_heights_in_the_plane_it_faces():
    t = np.arange(90) / 30.0
    x = np.zeros((10, 90, 3))
    x[:, :, 0] = np.linspace(-1, 1, 10)[:, None] * t  # across the view
    x[:, :, 2] = 0.1 + np.abs(np.sin(3 * t))[None] * np.linspace(0.2, 1.2, 10)[:, None]  # bounces, 0.1-1.3 m
    y = observe.perspective(x, observe.Camera(distance=4.0, elevation=0.0))
    assert (y[:, :, :2] == 0).all()
    np.testing.assert_allclose(y[:, :, 2], x[:, :, 2], atol=0.02)  # the small error: depth varies with x
    towards = x.copy()
    towards[:, :, 0] = np.linspace(0, 1, 90)  # across the view overall, but 1.5 m towards the camera and back
    towards[:, :, 1] = -1.5 * np.sin(np.pi * t / t[-1])
    z = observe.perspective(towards, observe.Camera(distance=4.0, elevation=20.0))[:, :, 2]
    assert np.abs(z - towards[:, :, 2]).max() > 0.1  # a camera from above mistakes depth for height


def test_height_scale_and_composition():
    x = parabolas(10)
    assert np.allclose(observe.height_scale(x, 2.0)[:, :, 2] - 0.1, 2 * (x[:, :, 2] - 0.1))
    ob = observe.Observation(noise=0.005, drop=0.1, camera_fps=15.0, height_factor=1.1)
    a = ob.apply(x, 30.0, np.random.default_rng(5))
    b = ob.apply(x, 30.0, np.random.default_rng(5))
    assert a.shape == x.shape and (a == b).all(), "seeded: the same observation twice"
    assert (observe.Observation().apply(x, 30.0, np.random.default_rng(0)) == x).all(), "the default is exact"
    r = observe.randomised(x, 30.0, np.random.default_rng(6))
    assert r.shape == x.shape and np.isfinite(r).all() and (r[:, :, :2] == 0).all()


@pytest.mark.parametrize("call, match", [
    (lambda x, g: observe.noise(x, -0.01, g), "noise sigma"),
    (lambda x, g: observe.drop(x, 1.0, g), "drop share"),
    (lambda x, g: observe.drop(x, -0.1, g), "drop share"),
    (lambda x, g: observe.perspective(x, observe.Camera(kind="fisheye")), "Camera.kind"),
    (lambda x, g: observe.height_scale(x, 0.0), "height scale"),
    (lambda x, g: observe.Observation(noise=-1.0).apply(x, 30.0, g), "Observation.noise"),
    (lambda x, g: observe.Observation(drop=1.5).apply(x, 30.0, g), "Observation.drop"),
])
def test_bad_parameters_name_themselves(call, match):
    with pytest.raises(ConfigError, match=match):
        call(parabolas(2), np.random.default_rng(0))


def test_bad_trajectories():
    with pytest.raises(TrajectoryError, match="shape"):
        observe.noise(np.zeros((3, 4)), 0.01, np.random.default_rng(0))
    x = parabolas(2)
    x[0, 3, 2] = np.nan
    with pytest.raises(TrajectoryError, match="NaN"):
        observe.drop(x, 0.1, np.random.default_rng(0))


def test_turned_across_view_turns_each_throw_to_cross_the_camera():
    x = parabolas(20)
    turned = observe.turned_across_view(x)
    d = turned[:, -1, :2] - turned[:, 0, :2]
    np.testing.assert_allclose(d[:, 1], 0, atol=1e-12)
    assert (d[:, 0] >= 0).all()
    np.testing.assert_allclose(np.linalg.norm(d, axis=1), np.linalg.norm(x[:, -1, :2] - x[:, 0, :2], axis=1))
    np.testing.assert_allclose(turned[:, :, 2], x[:, :, 2])  # heights untouched
