"""Heights from a few points on the floor: the camera a user's video needs, from four or more floor points whose
positions they measured (the corners of a tile, a mat, tape marks), and the throw's heights from it.

The floor points' pixels and their positions on the floor (metres) give the floor's homography; with square pixels
and the principal point at the image centre it gives the focal length and the camera's pose (Zhang's constraints,
:func:`camera_from_floor`). The object moves in one vertical plane (a throw's horizontal path is a line): the frames
in which it touches the ground put its centre on the horizontal plane ``rest_height`` up, so their rays meet that
plane on the path's line, and every other frame's ray meets it farther from the camera (the object is above it).
The line is an edge of those points' convex hull that faces the camera: the one whose heights fall at g in flight
(:func:`path_line`); each frame's height is where its ray crosses the vertical plane through it (:func:`heights`).

**Measured, and not on a user's path.** On throws that stay in their plane it gives the heights to a centimetre
with a pixel's error in the clicks (``tests/test_ground.py``). The study's throws do not stay in it: a tumbling box
bounces and slides sideways, 5-17 cm off the line through its path, and on the camera sweep's clips
(``scripts/ground_points_sweep.py``) the heights are worse than the one scale's (mean silhouette), far worse from
above. So ``study classify`` does not offer it; it is kept, with its measurement, for throws that do keep their
plane (a ball rolled along a lane).
"""

from __future__ import annotations

import math

import cv2
import numpy as np

from study.core.errors import ConfigError
from study.see.camera import Camera
from study.see.geometry import G, GeometryError, _runs

DEFAULT_FOVY = 60.0
"""Vertical field of view assumed, degrees, when the floor points cannot fix the focal length (a camera that looks
straight along the floor's lines)."""


def camera_from_floor(pixels: np.ndarray, floor: np.ndarray, width: int, height: int) -> Camera:
    """The :class:`~study.see.camera.Camera` that sees the floor points ``floor`` (k, 2) metres (x, y on the floor,
    z = 0) at ``pixels`` (k, 2) (u, v), k >= 4, in a ``width`` x ``height`` image. Raises :class:`ConfigError` for
    too few or degenerate points."""
    pixels, floor = np.asarray(pixels, np.float64), np.asarray(floor, np.float64)
    if pixels.shape != floor.shape or pixels.ndim != 2 or pixels.shape[1] != 2 or len(pixels) < 4:
        raise ConfigError(f"floor points: {pixels.shape} pixels and {floor.shape} floor positions; give four or more "
                          "points, each as u, v (pixels) and x, y (metres on the floor)")
    h, _ = cv2.findHomography(floor, pixels, 0)
    if h is None or not np.isfinite(h).all():
        raise ConfigError("floor points: no homography fits them (three on one line?); give four spread points")
    c = np.array([[1.0, 0.0, -(width / 2 - 0.5)], [0.0, 1.0, -(height / 2 - 0.5)], [0.0, 0.0, 1.0]])
    a = c @ h  # the principal point moved to the origin: a = lambda diag(f, f, 1) [r1 r2 t]
    (a11, a12, _), (a21, a22, _), (a31, a32, _) = a
    # Zhang's two constraints are linear in w = 1/f^2 (r1 . r2 = 0, |r1| = |r2|); each is ill-conditioned where its
    # perspective term vanishes (a floor axis along the image rows, or at 45 degrees), so w is their least squares.
    coef = np.array([a11 * a12 + a21 * a22, a11**2 + a21**2 - a12**2 - a22**2])
    rhs = -np.array([a31 * a32, a31**2 - a32**2])
    w = float(coef @ rhs / (coef @ coef)) if coef @ coef > 0 else math.nan
    fixed = math.isfinite(w) and w > 0 and np.abs(rhs).max() > 1e-9 * (np.abs(coef).max() + 1e-300)
    f = 1.0 / math.sqrt(w) if fixed else 0.5 * height / math.tan(math.radians(DEFAULT_FOVY) / 2)
    k_inv = np.diag([1 / f, 1 / f, 1.0])
    m = k_inv @ a
    lam = 1.0 / np.linalg.norm(m[:, 0])
    r1, r2, t = lam * m[:, 0], lam * m[:, 1], lam * m[:, 2]
    if t[2] < 0:  # the floor in front of the camera
        r1, r2, t = -r1, -r2, -t
    u, _, vt = np.linalg.svd(np.column_stack([r1, r2, np.cross(r1, r2)]))
    r = u @ vt  # the nearest rotation: OpenCV's camera axes (right, down, forward) as rows, world -> camera
    centre = -r.T @ t
    if centre[2] <= 0:
        raise ConfigError("floor points: the camera they give is below the floor; check each point's x, y and u, v")
    axes = r.T @ np.diag([1.0, -1.0, -1.0])  # columns: right, up, backwards (study.see.camera.Camera's)
    return Camera(tuple(float(x) for x in centre), tuple(float(x) for x in axes.ravel()), float(f), int(width),
                  int(height))


def _on_plane(camera: Camera, u: np.ndarray, v: np.ndarray, z: float) -> np.ndarray:
    """(n, 3) where each pixel's ray meets the horizontal plane ``z`` metres up in front of the camera (NaN rows
    where it does not)."""
    d = camera.rays(u, v)
    c = np.asarray(camera.position)
    with np.errstate(divide="ignore", invalid="ignore"):
        s = (z - c[2]) / d[:, 2]
    s = np.where(s > 0, s, np.nan)
    return c + s[:, None] * d


def _candidates(camera: Camera, u: np.ndarray, v: np.ndarray, rest_height: float,
                tol: float) -> list[tuple[int, np.ndarray, np.ndarray]]:
    """The lines on the floor the throw's path may follow, most ground frames first: (frames within ``tol`` of it, a
    point (2,), a unit direction (2,)) for each edge of the rest-plane points' convex hull that faces the camera."""
    p = _on_plane(camera, u, v, rest_height)[:, :2]
    p = p[np.isfinite(p).all(axis=1)]
    if len(p) < 3:
        raise GeometryError("the object's centre meets the rest plane in front of the camera in fewer than 3 frames: "
                            "no ground frames to place the throw by")
    cam = np.asarray(camera.position[:2])
    hull = cv2.convexHull(p.astype(np.float32), returnPoints=False)[:, 0]
    out = []
    for i, j in zip(hull, np.roll(hull, -1)):
        e = p[j] - p[i]
        if np.linalg.norm(e) < 1e-6:
            continue
        e = e / np.linalg.norm(e)
        n = np.array([-e[1], e[0]])
        side = (p - p[i]) @ n
        outward = -n if np.median(side) > 0 else n  # the side no point lies on
        if outward @ (cam - p[i]) <= 0:
            continue  # an edge facing away from the camera
        inliers = np.abs(side) <= tol
        q = p[inliers]
        w = np.linalg.svd(q - q.mean(axis=0))[2][0] if len(q) > 2 and np.ptp(q, axis=0).max() > 0.2 else e
        out.append((int(inliers.sum()), q.mean(axis=0), w / np.linalg.norm(w)))
    if not out:
        raise GeometryError("no edge of the ground points faces the camera: the throw does not seem to move in one "
                            "vertical plane in front of it")
    return sorted(out, key=lambda c: -c[0])


def _in_plane(camera: Camera, u: np.ndarray, v: np.ndarray, a: np.ndarray, e: np.ndarray) -> np.ndarray:
    """(n,) heights where each pixel's ray crosses the vertical plane through the floor line ``a`` + s ``e``."""
    n = np.array([-e[1], e[0], 0.0])
    c = np.asarray(camera.position)
    d = camera.rays(u, v)
    with np.errstate(divide="ignore", invalid="ignore"):
        s = (np.array([a[0], a[1], 0.0]) - c) @ n / (d @ n)
        z = c[2] + s * d[:, 2]
    return np.where(np.isfinite(z) & (s > 0), z, np.nan)


def gravity_misfit(t: np.ndarray, z: np.ndarray, rest_height: float, min_frames: int = 6) -> float:
    """How far the free flights of heights ``z`` (n,) metres at times ``t`` (n,) s fall from g: the frame-weighted
    mean of |fitted vertical acceleration + g| / g over every run of ``min_frames`` or more frames 3 cm above
    ``rest_height``; NaN without one."""
    up = np.isfinite(z) & (z > rest_height + 0.03)
    runs = [r for r in _runs(up) if len(r) >= min_frames]
    if not runs:
        return math.nan
    acc = [2 * np.polyfit(t[r] - t[r].mean(), z[r], 2)[0] for r in runs]
    return float(np.average([abs(a + G) / G for a in acc], weights=[len(r) for r in runs]))


def path_line(camera: Camera, t: np.ndarray, u: np.ndarray, v: np.ndarray, rest_height: float,
              tol: float = 0.03, candidates: int = 8) -> tuple[np.ndarray, np.ndarray]:
    """The throw's horizontal path: a point (2,) and a unit direction (2,) on the floor, metres, from the tracked
    centre ``u``, ``v`` (n,) pixels (NaN where lost) at times ``t`` (n,) s. Every frame's ray meets the rest plane on
    the path's line (the object on the ground) or beyond it (in the air), so the line is an edge of those points'
    convex hull that faces the camera; of the ``candidates`` with the most ground frames, the one whose heights fall
    at g in flight (:func:`gravity_misfit`), or, without a flight, the one with the most ground frames. Raises
    :class:`GeometryError` when the object never seems to touch the ground."""
    found = _candidates(camera, u, v, rest_height, tol)[:candidates]
    misfit = [gravity_misfit(t, _in_plane(camera, u, v, a, e), rest_height) for _, a, e in found]
    if all(math.isnan(m) for m in misfit):
        return found[0][1], found[0][2]
    k = int(np.nanargmin(misfit))
    return found[k][1], found[k][2]


def heights(camera: Camera, t: np.ndarray, u: np.ndarray, v: np.ndarray, rest_height: float) -> np.ndarray:
    """(n,) the object's centre height above the floor, metres, in each frame of the tracked centre ``u``, ``v``
    (n,) pixels at times ``t`` (n,) s: where each frame's ray crosses the vertical plane of the throw's path
    (:func:`path_line`); NaN where the centre was lost or the ray runs along the plane."""
    a, e = path_line(camera, t, u, v, rest_height)
    return _in_plane(camera, u, v, a, e)
