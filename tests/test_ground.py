"""Heights from a few floor points (study.see.ground): a camera recovered from four clicks, a throw's plane found by
its ground frames and gravity, and the errors for what cannot be done."""

from __future__ import annotations

import numpy as np
import pytest

from study.core.errors import ConfigError
from study.methods import sweep
from study.see import ground
from study.see.geometry import GeometryError


def throw(fps: float = 30.0, seconds: float = 3.0, rest: float = 0.1) -> tuple[np.ndarray, np.ndarray]:
    """Times (n,) and centre positions (n, 3) metres of a ball bouncing along a line on the floor under g."""
    t = np.arange(int(fps * seconds)) / fps
    z, vz, zs = rest + 0.9, 0.0, []
    for _ in t:
        zs.append(z)
        for _ in range(20):  # Euler substeps, bouncing at 60 % of the speed
            vz -= ground.G / fps / 20
            z += vz / fps / 20
            if z < rest:
                z, vz = rest, -0.6 * vz
    x = -1.2 + 1.0 * t
    return t, np.column_stack([x, 0.3 + 0.2 * x, zs])  # a line not along an axis


def camera(height: float, tilt: float, yaw: float, path: np.ndarray):
    shot = sweep.Shot(family="test", height=height, tilt=tilt, yaw=yaw, distance=4.0, fov=60.0, width=854,
                      height_px=480, fps=30.0, colour="red", floor=sweep.FLOORS[0], light=0.8)
    return sweep.camera(shot, path)


def clicks(cam, path: np.ndarray, noise: float, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    mid = path.mean(axis=0)
    floor = np.array([[mid[0] + dx, mid[1] + dy] for dx in (-1.0, 1.0) for dy in (-1.0, 1.0)])
    px = cam.project(np.column_stack([floor, np.zeros(4)]))
    return px + np.random.default_rng(seed).normal(0.0, noise, px.shape), floor


@pytest.mark.parametrize("height, tilt, yaw", [(1.0, 5.0, 0.0), (1.7, 30.0, -45.0), (2.0, 40.0, 30.0),
                                               (0.4, 3.0, 55.0)])
def test_four_clicked_floor_points_give_the_heights(height, tilt, yaw):
    t, path = throw()
    cam = camera(height, tilt, yaw, path)
    got = ground.camera_from_floor(*clicks(cam, path, noise=0.0), cam.width, cam.height)
    np.testing.assert_allclose(got.position, cam.position, atol=1e-4)
    if tilt > 10:  # near square-on the floor's lines barely converge: the focal length is loosely fixed
        np.testing.assert_allclose(got.focal, cam.focal, rtol=1e-4)
    uv = cam.project(path)
    z = ground.heights(cam, t, uv[:, 0], uv[:, 1], 0.1)
    assert np.sqrt(np.mean((z - path[:, 2]) ** 2)) < 0.01, "exact clicks and pixels: under a centimetre (the line is refitted"
    # through the frames within 3 cm of the ground, a few of them just off it)
    noisy = ground.camera_from_floor(*clicks(cam, path, noise=1.0), cam.width, cam.height)
    z = ground.heights(noisy, t, uv[:, 0], uv[:, 1], 0.1)
    assert np.sqrt(np.mean((z - path[:, 2]) ** 2)) < 0.03, "a pixel's clicking error: centimetres"


def test_the_throws_plane_is_the_one_that_falls_at_g():
    t, path = throw()
    cam = camera(1.7, 30.0, -45.0, path)
    uv = cam.project(path)
    a, e = ground.path_line(cam, t, uv[:, 0], uv[:, 1], 0.1)
    assert abs(abs(e @ np.array([1.0, 0.2]) / np.hypot(1.0, 0.2)) - 1) < 1e-4 and abs(a[1] - (0.3 + 0.2 * a[0])) < 0.01
    z = ground.heights(cam, t, uv[:, 0], uv[:, 1], 0.1)
    assert ground.gravity_misfit(t, z, 0.1) < 0.02


def test_what_cannot_be_done_says_why():
    t, path = throw()
    cam = camera(1.7, 30.0, -45.0, path)
    px, floor = clicks(cam, path, 0.0)
    with pytest.raises(ConfigError, match="four or more"):
        ground.camera_from_floor(px[:3], floor[:3], cam.width, cam.height)
    with pytest.raises(ConfigError, match="floor points"):
        ground.camera_from_floor(px, np.array([[0.0, 0.0], [1.0, 0.0], [2.0, 0.0], [3.0, 0.0]]), cam.width,
                                 cam.height)
    uv = cam.project(path + np.array([0.0, 0.0, 5.0]))  # always above the camera: no ray meets the rest plane
    with pytest.raises(GeometryError, match="no ground frames"):
        ground.heights(cam, t, uv[:, 0], uv[:, 1], 0.1)
