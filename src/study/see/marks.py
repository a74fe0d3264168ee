"""Floor marks found by their colour: a user who lays magenta discs on the floor gives only their positions (a CSV
with the header ``x,y``: ``study render``'s ``MARKS.csv``), and the video gives their pixels.

:func:`find` thresholds one picture in HSV (:data:`MARK_HSV`, a magenta no object of the study has and the checker
floor's grey and white edge lines are not) and returns each compact blob's centre; :func:`find_in_video` reads it
from the per-pixel median of a few frames spread over the clip, so an object passing over a mark does not hide it.
:func:`match` pairs the found pixels with the positions: every assignment's homography is fitted, the one whose
pixels it reproduces best is kept, and a layout that another assignment fits about as well (a rectangle's corners
alone: turned half round, it is the same rectangle, seen by a camera on the other side) is refused, since nothing in
the image tells the two apart; an irregular layout (``study.see.marklayout.LAYOUT``) has one answer.
"""

from __future__ import annotations

import itertools
import math
from pathlib import Path

import cv2
import numpy as np

from study.core.errors import ConfigError, DataError
from study.see.floor import MIN_MARKS, Floor, check_spread, read_floor
from study.see.ground import camera_from_floor
from study.see.marklayout import MARK_HSV
from study.see.video import open_video

MIN_AREA = 6
"""Pixels: a smaller blob is noise, not a mark."""
MAX_MARKS = 8
"""Most marks matched by trying every assignment (8! = 40,320 homographies)."""
AMBIGUOUS = 3.0
"""An assignment whose reprojection error is within this factor of the best one's (plus a pixel) makes the match
ambiguous."""
FRAMES = 9
"""Frames whose per-pixel median :func:`find_in_video` reads."""


def find(bgr: np.ndarray, hsv: tuple[tuple[int, int, int], tuple[int, int, int]] = MARK_HSV) -> np.ndarray:
    """(k, 2) pixels (u, v; the top-left pixel's centre at 0, 0) of the compact blobs of colour ``hsv`` in the
    picture ``bgr`` (h, w, 3) uint8, largest first: each blob's centroid, its pixels weighted alike."""
    (h0, s0, v0), (h1, s1, v1) = hsv
    mask = cv2.inRange(cv2.cvtColor(bgr, cv2.COLOR_BGR2HSV), (h0, s0, v0), (h1, s1, v1))
    n, _, stats, centroids = cv2.connectedComponentsWithStats(mask, connectivity=8)
    keep = [i for i in range(1, n) if stats[i, cv2.CC_STAT_AREA] >= MIN_AREA
            and stats[i, cv2.CC_STAT_AREA] >= 0.3 * stats[i, cv2.CC_STAT_WIDTH] * stats[i, cv2.CC_STAT_HEIGHT]]
    keep.sort(key=lambda i: -stats[i, cv2.CC_STAT_AREA])
    return np.array([centroids[i] for i in keep], np.float64).reshape(-1, 2)


def median_frame(path: str | Path, n: int = FRAMES) -> np.ndarray:
    """The per-pixel median of ``n`` frames spread evenly over the video ``path``, (h, w, 3) uint8."""
    cap, info = open_video(path)
    try:
        total = max(1, info.frames)
        picks, frames = set(np.linspace(0, total - 1, min(n, total)).round().astype(int).tolist()), []
        for i in range(total):
            ok, bgr = cap.read()
            if not ok:
                break
            if i in picks:
                frames.append(bgr)
    finally:
        cap.release()
    if not frames:
        raise DataError(f"video {path}: no frame could be read to find the floor marks in")
    return np.median(np.stack(frames), axis=0).astype(np.uint8)


def find_in_video(path: str | Path) -> np.ndarray:
    """(k, 2) pixels of the floor marks in the video ``path`` (:func:`find` on :func:`median_frame`)."""
    return find(median_frame(path))


def _homography_error(points: np.ndarray, pixels: np.ndarray) -> float:
    """RMS pixels by which the floor ``points`` (k, 2), through their best homography, miss ``pixels`` (k, 2)."""
    h, _ = cv2.findHomography(points, pixels, 0)
    if h is None or not np.isfinite(h).all():
        return math.inf
    p = np.column_stack([points, np.ones(len(points))]) @ h.T
    if np.any(np.abs(p[:, 2]) < 1e-12):
        return math.inf
    return float(np.sqrt(np.mean(np.sum((p[:, :2] / p[:, 2:] - pixels) ** 2, axis=1))))


def match(pixels: np.ndarray, points: np.ndarray, width: int, height: int, source: str = "") -> Floor:
    """The floor marks with each found pixel (k, 2) paired with its position on the floor (k, 2) metres: the
    assignment whose homography reproduces the pixels best and gives a camera above the floor.

    :class:`ConfigError` naming what to do when the counts differ, when there are fewer than five marks (four fit
    any assignment exactly), more than :data:`MAX_MARKS`, or when another assignment fits nearly as well (a
    symmetric layout)."""
    pixels, points = np.asarray(pixels, np.float64), np.asarray(points, np.float64)
    where = f"floor marks{' of ' + source if source else ''}"
    if not len(pixels):
        raise ConfigError(f"{where}: no magenta mark found in the video; check that the marks are in view and magenta "
                          "(study.see.marklayout.MARK_HSV), or give their pixels (header u,v,x,y)")
    if len(pixels) != len(points):
        why = ("a mark seen at a grazing angle (a camera low or level) is too thin to find: tilt the camera down onto "
               "the floor or use bigger marks" if len(pixels) < len(points) else "nothing else in view may be magenta")
        raise ConfigError(f"{where}: {len(pixels)} marks found in the video but {len(points)} positions given; give "
                          f"one position per mark in view, or their pixels (header u,v,x,y); {why}")
    check_pairable(len(points), where)
    check_spread(Floor(pixels, points, source))
    scored = []
    for order in itertools.permutations(range(len(points))):
        err = _homography_error(points[list(order)], pixels)
        if math.isfinite(err):
            scored.append((err, order))
    scored.sort()
    best = None
    for err, order in scored:
        try:
            camera_from_floor(pixels, points[list(order)], width, height)
        except ConfigError:
            continue  # a mirror image: the camera it gives is below the floor
        if best is None:
            best = (err, order)
        elif err <= AMBIGUOUS * best[0] + 1.0:
            raise ConfigError(f"{where}: two pairings of the marks with their positions fit the image alike "
                              f"({best[0]:.1f} and {err:.1f} px): the layout looks the same turned; move one mark "
                              "off the layout's symmetry, or give the pixels (header u,v,x,y)")
        else:
            break
    if best is None:
        raise ConfigError(f"{where}: no pairing of the marks found with the positions gives a camera above the "
                          "floor; check the positions")
    return Floor(pixels, points[list(best[1])], source, found=True)


def read(path: str | Path) -> Floor:
    """The floor marks of ``path`` (``study.see.floor.read_floor``: the header ``u,v,x,y``, or ``x,y`` for positions
    only, their pixels to be found in the video by :func:`located`), with as many positions as finding them by colour
    can pair (five to :data:`MAX_MARKS`); :class:`ConfigError` naming the file and what to write."""
    floor = read_floor(path)
    if needs_finding(floor):
        check_pairable(len(floor.points), f"floor file {path}")
    return floor


def check_pairable(n: int, where: str) -> None:
    """:class:`ConfigError` (``where`` names the file or clip) unless ``n`` positions can be paired with marks found
    by colour: five to :data:`MAX_MARKS`."""
    if n <= MIN_MARKS:
        raise ConfigError(f"{where}: {n} positions; marks found by their colour need five or more (four fit any "
                          "pairing with the pixels), or give their pixels (header u,v,x,y)")
    if n > MAX_MARKS:
        raise ConfigError(f"{where}: {n} positions; marks found by their colour are paired {MAX_MARKS} at most; "
                          "give their pixels (header u,v,x,y)")


def needs_finding(floor: Floor) -> bool:
    """Whether ``floor`` holds positions only (:func:`read` of an ``x,y`` file): its marks are found in the video."""
    return not np.isfinite(floor.pixels).all()


def located(floor: Floor, video: str | Path) -> Floor:
    """``floor`` with each mark's pixel: as given, or found by colour in ``video`` and paired with the positions
    (:func:`find_in_video`, :func:`match`)."""
    if not needs_finding(floor):
        return floor
    from study.see.video import probe

    info = probe(video)
    return match(find_in_video(video), floor.points, info.width, info.height,
                 f"{floor.source} in {Path(video).name}" if floor.source else Path(video).name)
