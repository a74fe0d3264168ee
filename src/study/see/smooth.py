"""Smoothing a tracked trajectory between the bounces found in it, never across one.

Between two contacts with the ground a thrown object flies freely: its image position changes smoothly (its height
is a parabola in time), so a Savitzky-Golay fit (a polynomial of low order over a sliding window of frames) removes
frame-to-frame jitter without bending the motion. At a bounce the velocity reverses within a frame, and a window
that straddles it would round the corner off: the trajectory is therefore cut at every *kick* (a frame whose image
row accelerates upwards far beyond what the frame-to-frame jitter explains, :func:`kicks`) and each piece between
kicks is smoothed on its own; the kick frames themselves, and pieces shorter than the window, are kept as tracked.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from scipy.signal import savgol_filter

from study.core.errors import ConfigError, check_range
from study.see.trajectory import Trajectory

KICK_SIGMAS = 6.0
"""A frame is a kick when its image row's upward acceleration exceeds this many robust standard deviations of the
row's second differences (their median absolute deviation, scaled to a standard deviation)."""
MIN_KICK = 1.0
"""...and at least this much, pixels per frame squared (a still object's jitter can be tiny)."""


def kicks(v: np.ndarray, sigmas: float = KICK_SIGMAS, floor: float = MIN_KICK) -> np.ndarray:
    """(n,) bool: the frames of the image row ``v`` (n,) pixels, down positive, no NaN, where it accelerates upwards
    by more than ``sigmas`` robust standard deviations of its second difference (and by ``floor`` px/frame² at
    least): the ground pushing the object back up at a bounce, or stopping it at the landing. The first and last
    frames are never kicks."""
    v = np.asarray(v, np.float64)
    out = np.zeros(len(v), bool)
    if len(v) < 3:
        return out
    a = v[2:] - 2 * v[1:-1] + v[:-2]  # second difference at frames 1 .. n-2
    spread = 1.4826 * np.median(np.abs(a - np.median(a)))
    out[1:-1] = a < np.median(a) - max(sigmas * spread, floor)
    return out


def pieces(n: int, cut: np.ndarray) -> list[slice]:
    """The runs of frames 0 .. n-1 between the frames where ``cut`` (n,) bool is True, the cut frames excluded."""
    edges = np.flatnonzero(cut)
    starts, stops = np.r_[0, edges + 1], np.r_[edges, n]
    return [slice(int(a), int(b)) for a, b in zip(starts, stops) if b > a]


def smooth_series(x: np.ndarray, cut: np.ndarray, window: int, order: int) -> np.ndarray:
    """``x`` (n,) with each run between the ``cut`` frames (n,) bool fitted by a Savitzky-Golay filter of ``window``
    frames (odd) and polynomial ``order``; cut frames and runs shorter than the window unchanged."""
    out = np.array(x, np.float64, copy=True)
    for s in pieces(len(out), cut):
        if s.stop - s.start >= window:
            out[s] = savgol_filter(out[s], window, order, mode="interp")
    return out


def smooth(traj: Trajectory, window: int, order: int = 2) -> Trajectory:
    """``traj`` with u and v smoothed between the bounces found in it (:func:`kicks` on each piece between long
    gaps; :func:`smooth_series`), status and everything else kept. ``window``: frames, odd, above ``order``."""
    check_range("smooth window (frames)", window, order + 1, 10_001, lo_open=True)
    check_range("smooth order", order, 0, 10)
    if window % 2 == 0:
        raise ConfigError(f"smooth window = {window} frames; it must be odd (a window centred on each frame)")
    u, v = traj.u.copy(), traj.v.copy()
    for seg in np.unique(traj.segment[traj.segment >= 0]):
        idx = np.flatnonzero(traj.segment == seg)
        s = slice(idx[0], idx[-1] + 1)
        cut = kicks(v[s])
        u[s], v[s] = smooth_series(u[s], cut, window, order), smooth_series(v[s], cut, window, order)
    return replace(traj, u=u, v=v)
