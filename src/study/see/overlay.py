"""A copy of the tracked video with the track drawn on it, to check by eye what the tracker saw."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
from tqdm import tqdm

from study.core.errors import ConfigError
from study.see.trajectory import Trajectory
from study.see.video import atomic_writer, frames, probe


JUMP_DIAMETERS = 2.5
"""Two found frames farther apart than this many of the object's diameters (30 px where it is unknown) are not joined
by a line: a jump the tracker accepted within a piece is drawn as the two points it is."""


def joined(traj: Trajectory, j: int) -> bool:
    """Whether frame ``j`` is drawn joined to frame ``j - 1``: both found (not filled, not lost), in the same piece,
    and no farther apart than :data:`JUMP_DIAMETERS` diameters."""
    if j < 1 or traj.status[j] != 1 or traj.status[j - 1] != 1 or traj.segment[j] != traj.segment[j - 1]:
        return False
    d = np.nanmax([traj.diameter[j], traj.diameter[j - 1]]) if np.isfinite(traj.diameter[[j - 1, j]]).any() else 12.0
    return bool(np.hypot(traj.u[j] - traj.u[j - 1], traj.v[j] - traj.v[j - 1]) <= JUMP_DIAMETERS * d)


def write_overlay(traj: Trajectory, out: str | Path, tail: int = 60, progress: bool = False) -> Path:
    """Re-read ``traj.source`` and write it to ``out`` (mp4) with the track drawn: the last ``tail`` frames of it, found
    points joined by blue lines within a piece (never across a gap or a jump, :func:`joined`), filled frames as
    orange dots; the current position as a ring."""
    if traj.source is None:
        raise ConfigError("the trajectory has no source video to draw on")
    info = probe(traj.source)
    pts = np.stack([traj.u, traj.v], axis=1)
    colours = {1: (255, 120, 0), 2: (0, 160, 255)}  # BGR: blue measured, orange filled
    with atomic_writer(out, info.fps, (info.width, info.height)) as w:
        for i, bgr in enumerate(tqdm(frames(traj.source), total=info.frames or None, desc="overlay", disable=not progress, leave=False)):
            if i < len(pts):
                for j in range(max(0, i - tail), i + 1):
                    if joined(traj, j):
                        a = tuple(int(round(x)) for x in pts[j - 1])
                        b = tuple(int(round(x)) for x in pts[j])
                        cv2.line(bgr, a, b, colours[1], 2, cv2.LINE_AA)
                    elif traj.status[j] == 2:
                        cv2.circle(bgr, tuple(int(round(x)) for x in pts[j]), 2, colours[2], -1, cv2.LINE_AA)
                if traj.status[i] > 0:
                    r = int(max(6, (traj.diameter[i] if np.isfinite(traj.diameter[i]) else 10) * 0.7))
                    cv2.circle(bgr, tuple(int(round(x)) for x in pts[i]), r, colours[int(traj.status[i])], 2, cv2.LINE_AA)
            w.write(bgr)
    return Path(out)
