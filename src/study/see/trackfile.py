"""A trajectory as a CSV file (one row per frame), written atomically and read back with clear errors."""

from __future__ import annotations

import csv
import io
import math
from pathlib import Path

import numpy as np

from study.core.cache import write_text_atomic
from study.core.errors import TrajectoryError, check_file
from study.see.trajectory import STATUS, Trajectory

COLUMNS = ("frame", "t_s", "u_px", "v_px", "height", "status", "segment", "confidence", "diameter_px")
"""The file's columns; the height's header names its units (``height_m`` or ``height_px``). The blob's diameter
lets a track in pixels be scaled later (``study classify TRACK.csv --object-size D``); files written before it
was kept have the first eight columns and are read without it."""


def write_csv(traj: Trajectory, path: str | Path) -> Path:
    """Write one row per frame: frame, t_s, u_px, v_px, height_<units>, status, segment, confidence, diameter_px
    (atomically)."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow([*COLUMNS[:4], f"height_{traj.units}", *COLUMNS[5:]])
    for i, h in enumerate(traj.height):
        w.writerow([i, f"{traj.t[i]:.9f}", f"{traj.u[i]:.3f}", f"{traj.v[i]:.3f}", f"{h:.6g}", STATUS[traj.status[i]],
                    int(traj.segment[i]), f"{traj.confidence[i]:.3f}", f"{traj.diameter[i]:.3f}"])
    write_text_atomic(path, buf.getvalue())
    return Path(path)


def read_csv(path: str | Path) -> Trajectory:
    """Read a trajectory written by :func:`write_csv` (heights keep their units); raise :class:`TrajectoryError` if malformed.

    Example::

        traj = study.read_csv("throw.csv")         # written by `study track --out`
        print(traj.units, len(traj.t))
    """
    p = check_file(path, "trajectory CSV", "write one with 'study track VIDEO --out FILE.csv'")
    try:
        with p.open(newline="") as f:
            rows = list(csv.reader(f))
    except (OSError, UnicodeDecodeError, csv.Error) as e:
        raise TrajectoryError(f"trajectory CSV {p}: cannot be read ({type(e).__name__}: {e})") from None
    head = rows[0] if rows else []
    if len(head) not in (len(COLUMNS) - 1, len(COLUMNS)) or head[0] != "frame" or not head[4].startswith("height_"):
        raise TrajectoryError(f"trajectory CSV {p}: the header is not that of 'study track --out'")
    units = head[4][len("height_"):]
    body = [r for r in rows[1:] if r]
    try:
        t, u, v, h = (np.array([float(r[k]) for r in body]) for k in range(1, 5))
        status = np.array([STATUS.index(r[5]) for r in body], np.int8)
        seg = np.array([int(r[6]) for r in body], np.int32)
        conf = np.array([float(r[7]) for r in body])
        diam = np.array([float(r[8]) for r in body]) if len(head) == len(COLUMNS) else np.full(len(body), np.nan)
    except (ValueError, IndexError) as e:
        raise TrajectoryError(f"trajectory CSV {p}: a row is malformed ({e})") from None
    if len(t) < 2:
        raise TrajectoryError(f"trajectory CSV {p}: fewer than two rows")
    fps = 1.0 / float(np.median(np.diff(t)))
    # height = (ground - v) * per_pixel: recover both from two rows with different v.
    ok = np.isfinite(v) & np.isfinite(h)
    if ok.sum() >= 2 and np.ptp(v[ok]) > 0:
        per_pixel, ground = _fit_height(v[ok], h[ok])
    else:
        per_pixel, ground = 1.0, float(np.nanmax(v)) if ok.any() else math.nan
    return Trajectory(t=t, u=u, v=v, status=status, segment=seg, confidence=conf,
                      diameter=diam, fps=fps, source=p, ground_v=ground, height_per_pixel=per_pixel, units=units)


def _fit_height(v: np.ndarray, h: np.ndarray) -> tuple[float, float]:
    """(per_pixel, ground_v) with h = (ground_v - v) * per_pixel, least squares."""
    A = np.stack([-v, np.ones_like(v)], axis=1)
    (s, c), *_ = np.linalg.lstsq(A, h, rcond=None)
    return float(s), float(c / s)
