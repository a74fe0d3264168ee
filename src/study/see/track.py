"""The colour tracker, end to end: a video of a thrown object in, its height series and the classifier's
input out.

:func:`track_video` detects the object in every frame (``study.see.detect``), fills short gaps and
splits at long ones, smooths the track between its bounces if asked (``study.see.smooth``), and turns image
positions into heights (``study.see.gaps``): from the camera's geometry and the object's depth when the camera is
known (``study.see.camera``), else from a ground row and one scale; :func:`to_model_input`
resamples the result to the classifier's frame rate and cuts or zero-pads it to its input length, as
the paper did. The pieces are importable from here too, so ``from study import track`` gives the whole
tracker: :class:`TrackConfig` and the colours it knows (``study.see.config.COLORS``), :class:`Trajectory`
(``study.see.trajectory``), the CSV file (``study.see.trackfile``) and the overlay video
(``study.see.overlay``).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from study.core.errors import TrajectoryError, check_range
from study.see.camera import Camera
from study.see.config import COLORS, TrackConfig, parse_hsv
from study.see.detect import detect_all
from study.see.gaps import fill_gaps, resample, set_camera, set_scale
from study.see.overlay import write_overlay
from study.see.scale import DEFAULT, ObjectShape, read_scale
from study.see.smooth import smooth
from study.see.trackfile import read_csv, write_csv
from study.see.trajectory import STATUS, Trajectory

__all__ = ["COLORS", "STATUS", "Camera", "TrackConfig", "Trajectory", "detect_all", "fill_gaps", "parse_hsv",
           "read_csv", "resample", "set_camera", "set_scale", "smooth", "to_model_input", "track_video", "write_csv",
           "write_overlay"]


def track_video(
    path: str | Path,
    cfg: TrackConfig | None = None,
    *,
    ground_v: float | None = None,
    object_size: float | None = None,
    metres_per_pixel: float | None = None,
    camera: Camera | None = None,
    depth: float | np.ndarray | None = None,
    rest_height: float = 0.0,
    shape: ObjectShape | None = None,
    scale_from: str = DEFAULT,
) -> Trajectory:
    """Track, fill short gaps, split at long ones, smooth between bounces if ``cfg.smooth`` asks, and turn pixels
    into heights: the whole pipeline for one video.

    With a ``camera`` (the one that filmed the video) and the object's ``depth`` along its view axis (metres; a
    number, or one per frame), heights come from the camera's geometry (``study.see.gaps.set_camera``: its tilt
    and the object's depth, no scale assumed), above ``rest_height``; else from one scale
    (``study.see.gaps.set_scale``): ``metres_per_pixel``; or read off the blob of an object of ``shape``
    (``study.see.scale.read_scale``, at rest, as its mean over the video or by gravity, as ``scale_from`` says); or
    ``object_size`` (a ball's diameter, metres) over the blob's size at rest.

    Example::

        from study.answer import shape
        traj = study.track_video("throw.mp4", study.TrackConfig(color="tennis"), shape=shape(0.067))
        print(traj.t[-1], traj.height[:5])  # seconds; metres above the ground
    """
    cfg = cfg or TrackConfig()
    traj = fill_gaps(detect_all(path, cfg), cfg.max_gap)
    if cfg.smooth:
        traj = smooth(traj, cfg.smooth, cfg.smooth_order)
    if camera is not None:
        if depth is None:
            raise TrajectoryError(f"{path}: a camera without the object's depth gives no height; pass depth")
        return set_camera(traj, camera, depth, rest_height)
    if shape is not None and metres_per_pixel is None:
        metres_per_pixel = read_scale(traj, shape, scale_from).metres_per_pixel
    return set_scale(traj, ground_v=ground_v, object_size=object_size, metres_per_pixel=metres_per_pixel)


def to_model_input(
    traj: Trajectory,
    fps: float,
    n_frames: int,
    height_factor: float = 1.0,
    rest_height: float = 0.0,
) -> np.ndarray:
    """The classifier's input for one video: (n_frames, 3) float32, world x, y, z in metres.

    The longest piece of ``traj`` is resampled to ``fps``, its height (in the trajectory's own units, times
    ``height_factor``: a wrong pixel scale, to measure how much a label depends on it) plus
    ``rest_height`` (the centre's height at rest, metres) becomes z; a single camera gives no depth,
    so x and y are zero. Longer pieces are cut to ``n_frames``, shorter ones zero-padded at the end
    (the paper's padding).
    """
    check_range("n_frames", n_frames, 1, 1e7)
    r = resample(traj, fps)
    z = r.height * height_factor + rest_height
    if not np.isfinite(z).all():
        raise TrajectoryError(f"{traj.source}: the height series has NaN after resampling")
    out = np.zeros((n_frames, 3), np.float32)
    k = min(n_frames, len(z))
    out[:k, 2] = z[:k]
    return out
