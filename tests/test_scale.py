"""Metres per pixel from the object's shape (study.see.scale): sizes, validation, and the blob sizes it reads."""

import math

import numpy as np
import pytest

from study.core.errors import ConfigError, TrackingError
from study.see.geometry import GeometryError
from study.see.scale import ObjectShape, read_scale
from study.see.trajectory import Trajectory


def _traj(diam: np.ndarray, v: np.ndarray | None = None) -> Trajectory:
    n = len(diam)
    v = np.linspace(100, 200, n) if v is None else v
    return Trajectory(t=np.arange(n) / 30, u=np.full(n, 50.0), v=v, status=np.ones(n, np.int8),
                      segment=np.zeros(n, np.int32), confidence=np.ones(n), diameter=diam)


def test_a_cube_is_one_edge_and_its_sizes_are_its_silhouettes():
    cube = ObjectShape("box", (0.2,))
    assert cube.dims == (0.2, 0.2, 0.2)
    assert cube.rest_size() == pytest.approx(0.2 * math.sqrt(4 / math.pi))  # one face, side-on
    assert cube.mean_size() == pytest.approx(0.2 * math.sqrt(6 / math.pi))  # Cauchy: a quarter of its surface
    assert cube.rest_height() == pytest.approx(0.1)
    ball = ObjectShape("sphere", (0.067,))
    assert ball.rest_size() == ball.mean_size() == 0.067


@pytest.mark.parametrize("kind, dims", [("cone", (0.1,)), ("box", (0.1, 0.2)), ("sphere", (-0.1,)), ("cylinder", (0.1,))])
def test_a_shape_that_cannot_be_read_is_refused_by_name(kind, dims):
    with pytest.raises(ConfigError, match=kind if kind == "cone" else "size|must|metres"):
        ObjectShape(kind, dims)


def test_the_mean_scale_reads_the_rms_blob_and_the_rest_scale_the_still_end():
    diam = np.r_[np.full(20, 30.0), np.full(10, 40.0)]
    v = np.r_[np.linspace(100, 200, 20), np.full(10, 200.0)]  # still for the last 10 frames
    cube = ObjectShape("box", (0.2,))
    mean = read_scale(_traj(diam, v), cube, "mean")
    assert mean.blob_px == pytest.approx(math.sqrt((20 * 900 + 10 * 1600) / 30))
    assert mean.metres_per_pixel == pytest.approx(cube.mean_size() / mean.blob_px) and mean.frames == 30
    rest = read_scale(_traj(diam, v), cube, "rest")
    assert rest.blob_px == 40.0 and rest.metres_per_pixel == pytest.approx(cube.rest_size() / 40)
    assert "mm/px" in mean.note() and "at rest" in rest.note()


def test_no_blob_size_and_an_unknown_reading_are_clear_errors():
    with pytest.raises(TrackingError, match="metres-per-pixel"):
        read_scale(_traj(np.full(10, np.nan)), ObjectShape("sphere", (0.067,)))
    with pytest.raises(ConfigError, match="rest, mean"):
        read_scale(_traj(np.full(10, 5.0)), ObjectShape("sphere", (0.067,)), "median")


def _bounces(mpp: float, diam_px: float, fps: float = 60.0) -> Trajectory:
    """A ball dropped from 1 m bouncing twice (restitution 0.6) then resting, filmed square-on at ``mpp`` metres per
    pixel, its blob ``diam_px`` wide: image rows from the true heights."""
    t = np.arange(int(3 * fps)) / fps
    z, h, t0, vz = np.zeros_like(t), 1.0, 0.0, 0.0
    for i, ti in enumerate(t):  # piecewise parabolas from each bounce
        s = ti - t0
        z[i] = h + vz * s - 9.81 * s**2 / 2
        if z[i] < 0:
            vz = 0.6 * math.sqrt(2 * 9.81 * h) if vz == 0 else 0.6 * vz
            h, t0, z[i] = 0.0, ti, 0.0
            if vz < 0.3:
                vz = 0.0
    n = len(t)
    return Trajectory(t=t, u=np.full(n, 50.0), v=400 - np.maximum(z, 0) / mpp, status=np.ones(n, np.int8),
                      segment=np.zeros(n, np.int32), confidence=np.ones(n), diameter=np.full(n, diam_px))


def test_gravity_reads_the_scale_from_the_fall_whatever_the_blob_says():
    ball = ObjectShape("sphere", (0.067,))
    true = 0.004  # m/px
    for blob in (0.067 / true, 0.5 * 0.067 / true):  # the blob read right, and read half its size
        s = read_scale(_bounces(true, blob), ball, "gravity")
        assert s.metres_per_pixel == pytest.approx(true, rel=0.02), blob
        assert s.how == "gravity" and s.flights >= 2 and "gravity" in s.note()
    assert read_scale(_bounces(true, 0.5 * 0.067 / true), ball, "rest").metres_per_pixel == pytest.approx(2 * true)  # the size path is misled


def test_gravity_without_a_free_flight_is_a_clear_error():
    still = _traj(np.full(60, 20.0), np.full(60, 300.0))
    with pytest.raises(GeometryError, match="no free flight.*--scale-from rest"):
        read_scale(still, ObjectShape("sphere", (0.067,)), "gravity")
