"""Heights from a camera nobody measured (study.see.geometry): a ball thrown, bounced and come to rest, seen
through a tilted camera the code is not told about."""

import math

import numpy as np
import pytest

from study.see import geometry, size
from study.see.camera import Camera

W, H, FPS, D = 640, 480, 30.0, 0.1


def _ball(n: int = 90) -> np.ndarray:
    """(n, 3) metres: a ball of diameter D thrown from 1 m, bouncing (restitution 0.6) along +x, then at rest."""
    dt, p, vel, out = 1 / FPS / 20, np.array([-1.0, 0.0, 1.0]), np.array([1.2, 0.0, 1.0]), []
    for k in range(n * 20):
        if k % 20 == 0:
            out.append(p.copy())
        vel[2] -= 9.81 * dt
        p = p + vel * dt
        if p[2] < D / 2:
            p[2], vel[2] = D / 2, -0.6 * vel[2] if abs(vel[2]) > 0.5 else 0.0
            vel[:2] *= 0.9 if vel[2] else 0.0
    return np.array(out)


def _camera(tilt_deg: float, height: float = 1.2, fov: float = 60.0) -> Camera:
    t = math.radians(tilt_deg)
    fwd = np.array([0.0, math.cos(t), -math.sin(t)])
    right = np.array([1.0, 0.0, 0.0])
    f = 0.5 * H / math.tan(math.radians(fov) / 2)
    return Camera((0.0, -4.0, height), tuple(np.column_stack([right, np.cross(right, fwd), -fwd]).ravel()), f, W, H)


@pytest.mark.parametrize("tilt", [0.0, 15.0, 30.0])
def test_a_tilted_camera_gives_the_heights_back_from_the_image_alone(tilt):
    xyz = _ball()
    cam = _camera(tilt)
    uv = cam.project(xyz)
    diam = cam.focal * D / cam.depth_of(xyz)
    t = np.arange(len(xyz)) / FPS
    z, geom = geometry.recover(t, uv[:, 0], uv[:, 1], diam, W, H, D, D / 2)
    assert np.sqrt(np.mean((z - xyz[:, 2]) ** 2)) < 0.02  # metres
    assert abs(geom.tilt_deg - tilt) < 3 and geom.flights >= 2 and geom.ground_frames > 10
    assert "tilted" in geom.note()


def test_a_clip_without_a_free_flight_or_without_the_ground_says_which():
    xyz = _ball()
    cam = _camera(10.0)
    uv, diam = cam.project(xyz), cam.focal * D / cam.depth_of(xyz)
    t = np.arange(len(xyz)) / FPS
    rest = slice(60, 90)  # the ball lying still
    with pytest.raises(geometry.GeometryError, match="no free flight"):
        geometry.recover(t[rest], uv[rest, 0], uv[rest, 1], diam[rest], W, H, D, D / 2, source="still.mp4")
    fall = slice(0, 14)  # the first flight, cut before the bounce
    with pytest.raises(geometry.GeometryError, match="never on the ground"):
        geometry.recover(t[fall], uv[fall, 0], uv[fall, 1], diam[fall], W, H, D, D / 2)


def test_a_box_is_sized_by_its_mean_silhouette():
    assert size.apparent_size("sphere", (0.067,)) == 0.067
    assert size.apparent_size("box", (0.2, 0.2, 0.2)) == pytest.approx(0.2 * math.sqrt(6 / math.pi))


def test_a_tracker_jump_mid_fall_does_not_split_the_flight_when_a_gap_is_allowed():
    """A fall at 30 frames a second, its image row 4 px off in one frame (a centroid's jump at speed): read as is,
    the curvature breaks and the fall is two flights (a landing in mid-air); with ``gap_s`` it stays one flight,
    and a bounce's kink still ends it."""
    t = np.arange(40) / FPS
    fall = np.minimum(t, 0.8)
    v = 100.0 + 0.5 * 9.81 / 0.01 * fall**2  # rows: g at 1 cm a pixel, until a bounce at 0.8 s
    v[t > 0.8] = v[t <= 0.8][-1] - 300.0 * (t[t > 0.8] - 0.8) + 0.5 * 981.0 * (t[t > 0.8] - 0.8) ** 2
    v[12] -= 4.0
    scale = np.full(len(t), 0.01)
    split, _ = geometry.phases(t, v, scale, most=math.inf)
    whole, _ = geometry.phases(t, v, scale, most=math.inf, gap_s=0.05)
    assert sum(a[-1] <= 22 for a in split) >= 2, "read as is, the jump breaks the fall"
    first = next(a for a in whole if a[0] <= 12 <= a[-1])
    assert first[0] <= 2 and 22 <= first[-1] <= 24, "one flight through the jump, ended at the bounce (frame 24)"
