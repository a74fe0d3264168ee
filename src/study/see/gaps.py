"""From detections to heights: fill short gaps, split at long ones, set the pixel-to-metre calibration, and
resample to another frame rate.

:func:`fill_gaps` interpolates gaps of at most ``max_gap`` frames (the paper's "simple interpolation")
and splits the trajectory at longer ones, keeping which frames were measured and which were filled.
Pixels to metres: image row -> height, up positive, from a ground row (the lowest position of the
object's centre, or given) and a scale (metres per pixel, from the object's known size or given).
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from study.core.errors import TrackingError, check_range
from study.see.trajectory import Trajectory
from study.simulate.observe import fill_runs


def fill_gaps(traj: Trajectory, max_gap: int) -> Trajectory:
    """Interpolate u, v linearly over runs of at most ``max_gap`` missing frames; split at longer runs.

    Filled rows get status 'filled'; the rows of each piece share a ``segment`` number; gaps at
    the start and end of the video, and long gaps, stay missing (nothing is extrapolated). The filling
    itself is ``study.simulate.observe.fill_runs``, which the observation model shares.
    """
    measured = traj.status == 1
    uv, seg = fill_runs(np.column_stack([traj.u, traj.v]), measured, max_gap)
    status = np.where(measured, 1, np.where(seg >= 0, 2, 0)).astype(np.int8)
    return replace(traj, u=uv[:, 0], v=uv[:, 1], status=status, segment=seg)


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
            the median blob diameter in pixels.
        metres_per_pixel: the scale, if known from a distance in the scene; overrides ``object_size``.
    With neither, heights stay in pixels.
    """
    m = traj.status > 0
    if not m.any():
        raise TrackingError(f"{traj.source}: no tracked frames to set the scale from")
    g = float(np.nanmax(traj.v[m])) if ground_v is None else float(ground_v)
    if metres_per_pixel is not None:
        check_range("metres_per_pixel", metres_per_pixel, 0.0, 100.0, lo_open=True)
        return replace(traj, ground_v=g, height_per_pixel=float(metres_per_pixel), units="m")
    if object_size is not None:
        check_range("object_size", object_size, 0.0, 100.0, lo_open=True)
        d = float(np.nanmedian(traj.diameter[traj.status == 1]))
        return replace(traj, ground_v=g, height_per_pixel=object_size / d, units="m")
    return replace(traj, ground_v=g, height_per_pixel=1.0, units="px")


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
        status=seg.status[nearest],
        segment=np.zeros(len(t), np.int32),
        confidence=seg.confidence[nearest],
        diameter=seg.diameter[nearest],
        fps=float(fps),
    )
