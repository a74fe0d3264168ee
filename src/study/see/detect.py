"""Finding the object in each frame of a video: the colour detector and :func:`detect_all`.

Per frame (streamed, one frame in memory): threshold the frame in HSV, clean the mask with a
morphological closing, keep the connected component most plausibly the object (big enough, and near
where the object was predicted to be), and record its centroid and a confidence. The centroid weights
each of the component's pixels by its saturation (``TrackConfig.centroid``, :meth:`_Detector.weighted`):
a pixel the object covers only in part, at its edge, mixes in the pale background and counts less, so
the position is measured to a fraction of a pixel (only the position reported: which blob is found, and
followed, is decided on the plain centroid). Frames where no component passes are *missing*
(``study.see.gaps`` fills the short gaps).

Speed: while the object is tracked only a window around its predicted position is searched at full
resolution; a full-frame search (on a frame subsampled to at most ``search_width`` pixels wide)
runs only to find it again.
"""

from __future__ import annotations

import math
from pathlib import Path

import cv2
import numpy as np
from tqdm import tqdm

from study.core.errors import TrackingError
from study.see.config import TrackConfig
from study.see.trajectory import Trajectory
from study.see.video import stream


class _Detector:
    """Finds the object in one frame, remembering where it was to search near there first."""

    KERNEL = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (3, 3))

    def __init__(self, cfg: TrackConfig, width: int, height: int, fps: float):
        self.cfg = cfg
        self.lo, self.hi = cfg.bounds()
        self.wrap = int(self.lo[0]) > int(self.hi[0])
        if self.wrap:  # two ranges: [lo_h, 179] and [0, hi_h]
            self.ranges = [(self.lo, np.array([179, self.hi[1], self.hi[2]], np.uint8)),
                           (np.array([0, self.lo[1], self.lo[2]], np.uint8), self.hi)]
        else:
            self.ranges = [(self.lo, self.hi)]
        self.W, self.H = width, height
        self.gate = cfg.max_jump * math.hypot(width, height)
        self.max_area = cfg.max_area_frac * width * height
        self.step = max(1, math.ceil(width / cfg.search_width))
        self.prev: list[tuple[float, float]] = []  # last two found centroids (for a constant-velocity guess)
        self.size = 0.0  # last equivalent-disc diameter, pixels
        self.still = max(5, round(cfg.static_time * fps))  # frames a blob must stay put to count as scenery
        self.recent: list[tuple[float, float]] = []  # centroids of the current run of found frames
        self.moved = False  # whether the current run has moved since its first frame
        self.static: list[tuple[float, float, float]] = []  # u, v, radius of blobs judged to be scenery

    def mask(self, bgr: np.ndarray, close: bool = True) -> np.ndarray:
        """(h, w) uint8 mask of the pixels in the HSV range, closed with a 3x3 disc unless ``close`` is False."""
        hsv = cv2.cvtColor(bgr, cv2.COLOR_BGR2HSV)
        m = cv2.inRange(hsv, *self.ranges[0])
        if self.wrap:
            m |= cv2.inRange(hsv, *self.ranges[1])
        return cv2.morphologyEx(m, cv2.MORPH_CLOSE, self.KERNEL) if close else m

    def predict(self) -> tuple[float, float] | None:
        """Where the object should be now (constant velocity from the last two centroids), or None."""
        if not self.prev:
            return None
        if len(self.prev) == 1:
            return self.prev[-1]
        (u0, v0), (u1, v1) = self.prev[-2], self.prev[-1]
        return 2 * u1 - u0, 2 * v1 - v0

    def _search(self, bgr: np.ndarray, box: tuple[int, int, int, int], k: int, pred):
        """The best component in ``bgr[box]`` (x0, y0, x1, y1) subsampled by ``k``: (conf, (u, v), area) or None."""
        x0, y0, x1, y1 = max(0, box[0]), max(0, box[1]), min(self.W, box[2]), min(self.H, box[3])
        if x1 - x0 < 2 or y1 - y0 < 2:
            return None
        if k > 1:  # every k-th pixel; cv2.resize (nearest) does it far faster than a strided numpy copy
            x1, y1 = x0 + max(1, (x1 - x0) // k) * k, y0 + max(1, (y1 - y0) // k) * k
            crop = cv2.resize(bgr[y0:y1, x0:x1], ((x1 - x0) // k, (y1 - y0) // k), interpolation=cv2.INTER_NEAREST)
        else:
            crop = bgr[y0:y1, x0:x1]
        m = self.mask(crop, close=False)
        if not cv2.countNonZero(m):
            return None
        cands = None
        if pred is not None and self.size > 0:
            # Fast path: if everything in range fits in a box the object's size, it is one blob, and
            # its moments give area and centroid without labelling components.
            x, y, w, h = cv2.boundingRect(m)
            if max(w, h) * k <= 1.5 * self.size + 3 * k:
                xa, ya = max(0, x - 1), max(0, y - 1)
                sub = cv2.morphologyEx(m[ya : y + h + 1, xa : x + w + 1], cv2.MORPH_CLOSE, self.KERNEL)
                M = cv2.moments(sub, True)
                if M["m00"] > 0:
                    cands = [((x, y, w, h, M["m00"]), (xa + M["m10"] / M["m00"], ya + M["m01"] / M["m00"]))]
        if cands is None:
            m = cv2.morphologyEx(m, cv2.MORPH_CLOSE, self.KERNEL)
            n, _, stats, cents = cv2.connectedComponentsWithStats(m, connectivity=8, ltype=cv2.CV_32S)
            cands = zip(stats.tolist()[1:], cents.tolist()[1:])
        best, best_score = None, math.inf
        k2, min_area, max_area, min_w = k * k, self.cfg.min_area, self.max_area, self.cfg.min_width
        # Plain Python over plain lists: one to a few components, where numpy's per-call cost dominates.
        for (x, y, w, h, area), (cu, cv) in cands:
            area *= k2
            if area < min_area or area > max_area or min(w, h) * k < min_w:
                continue
            u, v = x0 + k * cu, y0 + k * cv
            if self.static and any(math.hypot(u - su, v - sv) <= sr for su, sv, sr in self.static):
                continue
            fill = min(1.0, area / (math.pi * (max(w, h) * k / 2) ** 2))  # 1 for a disc, small for a line
            if pred is None:
                score, close = -area * fill, 1.0  # nothing to be near: the biggest compact blob
            else:
                d = math.hypot(u - pred[0], v - pred[1])
                if d > self.gate:
                    continue
                score, close = d - 0.25 * math.sqrt(area), math.exp(-((d / self.gate) ** 2))  # near first
            if score < best_score:
                best, best_score = (fill * close, (u, v), float(area)), score
        return best

    def _refine(self, bgr: np.ndarray, hit, k: int):
        """Re-measure a hit found at subsampling ``k`` at full resolution in a tight box around it."""
        if k == 1:
            return hit
        (u, v), r = hit[1], math.sqrt(hit[2] / math.pi) + 2 * k
        fine = self._search(bgr, (int(u - r), int(v - r), int(u + r) + 2, int(v + r) + 2), 1, (u, v))
        return fine or hit

    def weighted(self, bgr: np.ndarray, u: float, v: float, area: float) -> tuple[float, float]:
        """The centroid of the blob found at (u, v) with ``area`` pixels, each of its pixels weighted by its
        saturation; (u, v) unchanged if the blob cannot be found again at full resolution."""
        r = math.sqrt(area / math.pi) + 4  # the blob's radius and a margin (motion blur stretches it)
        r = max(r, 0.75 * self.size + 4)
        x0, y0 = max(0, int(u - r)), max(0, int(v - r))
        x1, y1 = min(self.W, int(u + r) + 2), min(self.H, int(v + r) + 2)
        if x1 - x0 < 2 or y1 - y0 < 2:
            return u, v
        crop = bgr[y0:y1, x0:x1]
        hsv = cv2.cvtColor(crop, cv2.COLOR_BGR2HSV)
        m = cv2.inRange(hsv, *self.ranges[0])
        if self.wrap:
            m |= cv2.inRange(hsv, *self.ranges[1])
        m = cv2.morphologyEx(m, cv2.MORPH_CLOSE, self.KERNEL)
        n, labels, _, cents = cv2.connectedComponentsWithStats(m, connectivity=8, ltype=cv2.CV_32S)
        if n < 2:
            return u, v
        k = 1 + int(np.argmin(np.hypot(cents[1:, 0] + x0 - u, cents[1:, 1] + y0 - v)))  # the blob found before
        w = np.where(labels == k, hsv[:, :, 1], 0).astype(np.float32)
        M = cv2.moments(w, False)
        if M["m00"] <= 0:
            return u, v
        return x0 + M["m10"] / M["m00"], y0 + M["m01"] / M["m00"]

    def __call__(self, bgr: np.ndarray) -> tuple[float, float, float, float] | None:
        """(u, v, confidence, diameter) of the object in ``bgr`` (H, W, 3) uint8, or None if not found."""
        pred = self.predict()
        hit, jumped = None, False
        if pred is not None:  # fast path: a window around the prediction
            speed = math.dist(*self.prev[-2:]) if len(self.prev) > 1 else 0.0
            k = max(1, int(self.size // 12))  # keep the object about 12 samples across
            # A small window first (constant velocity predicts free flight to a pixel), a wider one
            # for bounces and throws, where the velocity flips or jumps.
            for half in (self.size + 0.5 * speed + 6, 1.5 * self.size + 2.5 * speed + 12):
                box = (int(pred[0] - half), int(pred[1] - half), int(pred[0] + half) + 1, int(pred[1] + half) + 1)
                hit = self._search(bgr, box, k, pred)
                if hit is not None:
                    hit = self._refine(bgr, hit, k)
                    break
        if hit is None:  # reacquire: the whole frame, subsampled
            box = (0, 0, self.W, self.H)
            hit = self._search(bgr, box, self.step, pred)
            if hit is None and pred is not None:
                hit = self._search(bgr, box, self.step, None)
            if hit is None:
                self.prev.clear()
                self.recent.clear()
                return None
            hit = self._refine(bgr, hit, self.step)
            if pred is not None:
                hit, jumped = (hit[0] * 0.5, hit[1], hit[2]), True  # a jump: less sure
        conf, (u, v), area = hit
        # What is found, the prediction and the scenery test all follow the blob's plain centroid, so the
        # weighted one changes only the position reported, never which blob is tracked.
        at = self.weighted(bgr, u, v, area) if self.cfg.centroid == "weighted" else (u, v)
        self.size = 2 * math.sqrt(area / math.pi)
        self.prev = (self.prev + [(u, v)])[-2:]
        if jumped or not self.recent:  # a new run of found frames starts here
            self.recent, self.moved = [], False
        self.recent.append((u, v))
        tol = max(3.0, 0.5 * self.size)  # compression jitters a still blob's centroid by a pixel or two
        if not self.moved and math.dist(self.recent[0], self.recent[-1]) > tol:
            self.moved = True
        if not self.moved and len(self.recent) >= self.still:
            # found where it was first seen and never moved since: scenery. (An object that came to
            # rest after moving is kept.)
            r = np.asarray(self.recent)
            cu, cv = r.mean(axis=0)
            self.static.append((float(cu), float(cv), max(3.0, 0.75 * self.size)))
            self.prev.clear()
            self.recent.clear()
        self.recent = self.recent[-self.still :]
        return float(at[0]), float(at[1]), float(conf), self.size


def detect_all(path: str | Path, cfg: TrackConfig | None = None) -> Trajectory:
    """Track the object through every frame of ``path``; rows not found are missing (no filling yet).

    Streams the video (one frame in memory). Raises :class:`VideoError` for a missing, empty,
    undecodable or truncated file and :class:`TrackingError` if the object is found in fewer than
    ``cfg.min_found`` frames.
    """
    cfg = cfg or TrackConfig()
    cfg.validate()
    info, decoded = stream(path)
    det = _Detector(cfg, info.width, info.height, info.fps)
    rows: list[tuple[float, float, float, float]] = []
    nan4 = (math.nan, math.nan, 0.0, math.nan)
    total = info.frames or None
    for bgr in tqdm(decoded, total=total, desc=f"track {info.path.name}", unit="frame", disable=not cfg.progress, leave=False):
        found = det(bgr)
        rows.append(found if found is not None else nan4)
    a = np.array(rows, float).reshape(-1, 4)
    n_found = int(np.isfinite(a[:, 0]).sum())
    if n_found == 0:
        raise TrackingError(
            f"video {info.path}: the object was never found in {len(a)} frames with HSV range "
            f"{_describe(cfg)}; check --color/--hsv against the object's colour"
        )
    if n_found < cfg.min_found:
        raise TrackingError(
            f"video {info.path}: the object was found in only {n_found} of {len(a)} frames "
            f"(need {cfg.min_found}); check --color/--hsv or lower min_found"
        )
    status = np.where(np.isfinite(a[:, 0]), 1, 0).astype(np.int8)
    return Trajectory(
        t=np.arange(len(a)) / info.fps,
        u=a[:, 0],
        v=a[:, 1],
        status=status,
        segment=np.where(status > 0, 0, -1).astype(np.int32),
        confidence=a[:, 2],
        diameter=a[:, 3],
        fps=info.fps,
        source=info.path,
        width=info.width,
        height_px=info.height,
    )


def _describe(cfg: TrackConfig) -> str:
    lo, hi = cfg.bounds()
    name = "" if cfg.hsv is not None else f"'{cfg.color}' "
    return f"{name}{tuple(int(x) for x in lo)}-{tuple(int(x) for x in hi)}"
