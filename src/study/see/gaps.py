"""From detections to heights: fill short gaps, split at long ones, set the pixel-to-metre calibration, and
resample to another frame rate.

:func:`fill_gaps` interpolates gaps of at most ``max_gap`` frames (the paper's "simple interpolation")
and splits the trajectory at longer ones, keeping which frames were measured and which were filled.
Pixels to metres, two ways: :func:`set_camera`, from the camera's geometry (its position, tilt and focal length)
and the object's depth, each frame's image position to a height above the ground plane; or, with no camera known,
:func:`set_scale`, image row -> height from a ground row (the lowest position of the object's centre, or given)
and one scale (metres per pixel, from the object's known size or given), which ignores the camera's tilt and
the object's changes of depth.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from study.core.errors import ConfigError, TrackingError, check_range
from study.see.camera import Camera
from study.see.trajectory import Trajectory
from study.simulate.observe import fill_runs


def fill_gaps(traj: Trajectory, max_gap: int) -> Trajectory:
    """Interpolate u, v linearly over runs of at most ``max_gap`` missing frames; split at longer runs.

    Filled rows get status 'filled'; the rows of each piece share a ``segment`` number; gaps at
    the start and end of the video, and long gaps, stay missing (nothing is extrapolated). The filling
    itself is ``study.simulate.observe.fill_runs``, which the observation model shares.
    """
    measured = traj.status == 1
    cols = [traj.u, traj.v] + ([] if traj.z is None else [traj.z])
    uv, seg = fill_runs(np.column_stack(cols), measured, max_gap)
    status = np.where(measured, 1, np.where(seg >= 0, 2, 0)).astype(np.int8)
    return replace(traj, u=uv[:, 0], v=uv[:, 1], status=status, segment=seg, z=None if traj.z is None else uv[:, 2])


def set_scale(
    traj: Trajectory,
    *,
    ground_v: float | None = None,
    object_size: float | None = None,
    metres_per_pixel: float | None = None,
) -> Trajectory:
    """Set the ground row and the scale that turn image rows into :attr:`Trajectory.height`.

    Args:
        ground_v: image row of the object's centre when it rests on the ground, pixels; default the
            lowest centre position seen (largest v among measured frames).
        object_size: the object's real diameter, metres (a tennis ball: 0.067); the scale is this over
            the blob's diameter at rest (:func:`rest_diameter`: its median over the frames the object lies
            still at the end, where it is neither blurred nor turned; over every frame if it never rests).
        metres_per_pixel: the scale, if known from a distance in the scene; overrides ``object_size``.
    With neither, heights stay in pixels.
    """
    m = traj.status > 0
    if not m.any():
        raise TrackingError(f"{traj.source}: no tracked frames to set the scale from")
    g = float(np.nanmax(traj.v[m])) if ground_v is None else float(ground_v)
    if metres_per_pixel is not None:
        check_range("metres_per_pixel", metres_per_pixel, 0.0, 100.0, lo_open=True)
        return replace(traj, ground_v=g, height_per_pixel=float(metres_per_pixel), units="m", z=None)
    if object_size is not None:
        check_range("object_size", object_size, 0.0, 100.0, lo_open=True)
        return replace(traj, ground_v=g, height_per_pixel=object_size / rest_diameter(traj), units="m", z=None)
    return replace(traj, ground_v=g, height_per_pixel=1.0, units="px", z=None)


REST_FRAMES = 3
"""Fewest still frames at the end of a track that count as the object at rest (:func:`rest_diameter`)."""


def rest_diameter(traj: Trajectory, tolerance_px: float = 1.0) -> float:
    """The blob's diameter, pixels, with the object at rest: the median over the last run of measured frames
    whose centre stays within ``tolerance_px`` of its final position (at least :data:`REST_FRAMES` of them), else
    over every measured frame. A moving or tumbling object's blob is blurred and turned; a resting one's is its
    size at the ground, where the scale is wanted."""
    m = np.flatnonzero(traj.status == 1)
    if len(m) == 0:
        raise TrackingError(f"{traj.source}: no measured frames to read the object's size from")
    u, v = traj.u[m], traj.v[m]
    still = np.hypot(u - np.median(u[-REST_FRAMES:]), v - np.median(v[-REST_FRAMES:])) <= tolerance_px
    k = len(m)
    while k > 0 and still[k - 1]:
        k -= 1
    frames = m[k:] if len(m) - k >= REST_FRAMES else m
    return float(np.nanmedian(traj.diameter[frames]))


def set_camera(traj: Trajectory, camera: Camera, depth: float | np.ndarray, rest_height: float) -> Trajectory:
    """Heights from the camera's geometry: each frame's image position (u, v) at the object's ``depth`` (metres
    along the view axis; a number, or (n,) one per frame) is a world point, whose z is :attr:`Trajectory.z`
    (metres above the ground plane); :attr:`Trajectory.height` is then z minus ``rest_height`` (the centre's
    height at rest, metres), as :func:`set_scale`'s is the height above the ground row. Its
    ``height_per_pixel`` becomes a pixel's size at the median depth (for what reads one scale).

    The camera must be the one that filmed the video, at its size (``study.see.render.scene_camera`` for a
    rendered throw); raise :class:`ConfigError` if its image size differs or ``depth`` has another length.
    """
    camera.validate()
    if traj.width and (camera.width, camera.height) != (traj.width, traj.height_px):
        raise ConfigError(f"{traj.source}: the camera is {camera.width} x {camera.height} pixels but the video "
                          f"{traj.width} x {traj.height_px}; give the camera at the video's size")
    d = np.asarray(depth, np.float64)
    if d.ndim > 1 or (d.ndim == 1 and len(d) != len(traj.t)):
        raise ConfigError(f"{traj.source}: depth has shape {d.shape}; give one number or one per frame ({len(traj.t)})")
    if not (np.isfinite(d) & (d > 0)).all():
        raise ConfigError(f"{traj.source}: depth must be finite and positive (metres along the view axis)")
    check_range("rest_height (metres)", rest_height, 0.0, 100.0)
    z = camera.heights(traj.u, traj.v, d)
    # height_per_pixel: a pixel's size at the median depth, for what reads one scale (the heights do not use it)
    return replace(traj, z=z, ground_z=float(rest_height), units="m",
                   height_per_pixel=float(np.median(d)) / camera.focal)


def resample(traj: Trajectory, fps: float) -> Trajectory:
    """The longest piece of ``traj`` resampled to ``fps`` by linear interpolation, starting at its first row.

    A resampled row is 'measured' if its nearer source row was measured, else 'filled'.
    """
    check_range("fps", fps, 0.0, 10_000.0, lo_open=True)
    seg = traj.longest()
    t = seg.t[0] + np.arange(int(math.floor((seg.t[-1] - seg.t[0]) * fps + 1e-9)) + 1) / fps
    nearest = np.clip(np.round((t - seg.t[0]) * seg.fps).astype(int), 0, len(seg.t) - 1)
    return replace(
        seg,
        t=t,
        u=np.interp(t, seg.t, seg.u),
        v=np.interp(t, seg.t, seg.v),
        z=None if seg.z is None else np.interp(t, seg.t, seg.z),
        status=seg.status[nearest],
        segment=np.zeros(len(t), np.int32),
        confidence=seg.confidence[nearest],
        diameter=seg.diameter[nearest],
        fps=float(fps),
    )
