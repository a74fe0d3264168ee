"""A copy of the tracked video with the track drawn on it, to check by eye what the tracker saw."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
from tqdm import tqdm

from study.core.errors import ConfigError
from study.see.trajectory import Trajectory
from study.see.video import atomic_writer, frames, probe


def write_overlay(traj: Trajectory, out: str | Path, tail: int = 60, progress: bool = False) -> Path:
    """Re-read ``traj.source`` and write it to ``out`` (mp4) with the track drawn: measured points blue, filled orange.

    The last ``tail`` frames of the track are drawn as a line; the current position as a ring.
    """
    if traj.source is None:
        raise ConfigError("the trajectory has no source video to draw on")
    info = probe(traj.source)
    pts = np.stack([traj.u, traj.v], axis=1)
    colours = {1: (255, 120, 0), 2: (0, 160, 255)}  # BGR: blue measured, orange filled
    with atomic_writer(out, info.fps, (info.width, info.height)) as w:
        for i, bgr in enumerate(tqdm(frames(traj.source), total=info.frames or None, desc="overlay", disable=not progress, leave=False)):
            if i < len(pts):
                lo = max(0, i - tail)
                for j in range(lo + 1, i + 1):
                    if traj.status[j] > 0 and traj.status[j - 1] > 0 and traj.segment[j] == traj.segment[j - 1]:
                        a = tuple(int(round(x)) for x in pts[j - 1])
                        b = tuple(int(round(x)) for x in pts[j])
                        cv2.line(bgr, a, b, colours[int(traj.status[j])], 2, cv2.LINE_AA)
                if traj.status[i] > 0:
                    r = int(max(6, (traj.diameter[i] if np.isfinite(traj.diameter[i]) else 10) * 0.7))
                    cv2.circle(bgr, tuple(int(round(x)) for x in pts[i]), r, colours[int(traj.status[i])], 2, cv2.LINE_AA)
            w.write(bgr)
    return Path(out)
