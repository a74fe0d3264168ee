"""A colour tracker: a video of a thrown object in, its image trajectory and height series out.

Per frame (streamed, one frame in memory): threshold the frame in HSV, clean the mask with a
morphological closing, keep the connected component most plausibly the object (big enough, and near
where the object was predicted to be), and record its centroid and a confidence. Frames where no
component passes are *missing*; :func:`fill_gaps` interpolates gaps of at most ``max_gap`` frames
(the paper's "simple interpolation") and splits the trajectory at longer ones, keeping which frames
were measured and which were filled.

Speed: while the object is tracked only a window around its predicted position is searched at full
resolution; a full-frame search (on a frame subsampled to at most ``search_width`` pixels wide)
runs only to find it again.

Pixels to metres: image row -> height, up positive, from a ground row (the lowest position of the
object's centre, or given) and a scale (metres per pixel, from the object's known size or given).
:func:`to_model_input` resamples a trajectory to the classifier's frame rate and cuts or zero-pads it
to its input length, as the paper did.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from pathlib import Path

import cv2
import numpy as np
from tqdm import tqdm

from study.cache import write_text_atomic
from study.errors import ConfigError, TrackingError, TrajectoryError, check_range
from study.video import atomic_writer, frames, probe, stream

PRESETS: dict[str, tuple[tuple[int, int, int], tuple[int, int, int]]] = {
    "tennis": ((22, 70, 90), (50, 255, 255)),
    "orange": ((3, 120, 80), (20, 255, 255)),
    "red": ((170, 120, 70), (8, 255, 255)),
    "green": ((50, 100, 60), (80, 255, 255)),
    "blue": ((100, 120, 60), (130, 255, 255)),
}
"""Named HSV ranges (OpenCV scale: H 0-179, S and V 0-255), (low, high); a low hue above the high
one wraps through 0 (red). 'tennis' is a yellow to yellow-green felt ball, 'orange' the colour
``study.render`` paints its objects."""

STATUS = ("missing", "measured", "filled")
"""Per-frame status codes of a :class:`Trajectory` (index = code)."""


@dataclass
class TrackConfig:
    """How the colour tracker finds the object."""

    color: str = "tennis"
    """Name of an HSV preset in :data:`PRESETS` (ignored when ``hsv`` is given)."""
    hsv: tuple[int, int, int, int, int, int] | None = None
    """Explicit HSV bounds (H, S, V low, then H, S, V high), OpenCV scale; overrides ``color``."""
    min_area: int = 4
    """Smallest component accepted as the object, pixels (at full resolution)."""
    min_width: int = 3
    """Narrowest component accepted (its bounding box's smaller side), pixels: rejects edges and strips."""
    max_area_frac: float = 0.1
    """Largest component accepted, as a fraction of the frame's area."""
    max_jump: float = 0.2
    """Largest distance from the predicted position accepted while tracking, fraction of the frame diagonal."""
    max_gap: int = 6
    """Longest run of missing frames filled by interpolation; longer gaps split the trajectory."""
    min_found: int = 8
    """Fewest frames the object must be found in, else :class:`TrackingError`."""
    search_width: int = 160
    """Full-frame (re)acquisition runs on the frame subsampled to at most this width, pixels."""
    static_time: float = 0.5
    """A blob that stays put (within a pixel or two) this long, seconds, is scenery: it is ignored from then on."""
    progress: bool = True
    """Show a progress bar while decoding."""

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """(low, high) HSV bounds as uint8 arrays of 3; raise :class:`ConfigError` if malformed."""
        if self.hsv is not None:
            return parse_hsv(self.hsv)
        if self.color not in PRESETS:
            raise ConfigError(f"color = {self.color!r} is not a preset; choose one of {', '.join(PRESETS)} or give --hsv")
        lo, hi = PRESETS[self.color]
        return parse_hsv((*lo, *hi))

    def validate(self) -> None:
        """Raise :class:`ConfigError` for an out-of-range field."""
        self.bounds()
        check_range("TrackConfig.min_area", self.min_area, 1, 1e7)
        check_range("TrackConfig.min_width", self.min_width, 1, 1e5)
        check_range("TrackConfig.max_area_frac", self.max_area_frac, 0.0, 1.0, lo_open=True)
        check_range("TrackConfig.max_jump", self.max_jump, 0.0, 2.0, lo_open=True)
        check_range("TrackConfig.max_gap", self.max_gap, 0, 10_000)
        check_range("TrackConfig.min_found", self.min_found, 2, 1e9)
        check_range("TrackConfig.search_width", self.search_width, 32, 10_000)
        check_range("TrackConfig.static_time", self.static_time, 0.0, 1e6, lo_open=True)


def parse_hsv(values) -> tuple[np.ndarray, np.ndarray]:
    """Check six HSV numbers (H, S, V low, H, S, V high; H 0-179, S and V 0-255) and return (low, high) uint8.

    A low hue above the high hue wraps through 0 (for red); saturation and value must not.
    """
    try:
        v = [float(x) for x in values]
    except (TypeError, ValueError):
        raise ConfigError(f"hsv = {values!r}: give six numbers H S V (low) H S V (high)") from None
    if len(v) != 6 or not all(math.isfinite(x) and x == int(x) for x in v):
        raise ConfigError(f"hsv = {values!r}: give six whole numbers H S V (low) H S V (high)")
    hl, sl, vl, hh, sh, vh = (int(x) for x in v)
    for name, x, top in (("H low", hl, 179), ("S low", sl, 255), ("V low", vl, 255),
                         ("H high", hh, 179), ("S high", sh, 255), ("V high", vh, 255)):
        if not 0 <= x <= top:
            raise ConfigError(f"hsv {name} = {x} is out of range; allowed [0, {top}] (OpenCV's HSV scale)")
    if sl > sh or vl > vh:
        raise ConfigError(f"hsv = {values!r}: the low S and V must not exceed the high ones")
    return np.array([hl, sl, vl], np.uint8), np.array([hh, sh, vh], np.uint8)


@dataclass
class Trajectory:
    """The tracked object, one row per video frame (or per resampled frame).

    ``status`` says for each row whether it was measured, filled by interpolation, or missing
    (then u, v and height are NaN); ``segment`` numbers the pieces split at long gaps (-1 if missing).
    """

    t: np.ndarray = field(repr=False)
    """(n,) float64 seconds since the first frame of the video."""
    u: np.ndarray = field(repr=False)
    """(n,) float64 pixels, centroid column (right positive)."""
    v: np.ndarray = field(repr=False)
    """(n,) float64 pixels, centroid row (down positive)."""
    status: np.ndarray = field(repr=False)
    """(n,) int8, index into :data:`STATUS`: 0 missing, 1 measured, 2 filled."""
    segment: np.ndarray = field(repr=False)
    """(n,) int32, piece number after splitting at long gaps; -1 where missing."""
    confidence: np.ndarray = field(repr=False)
    """(n,) float64 in [0, 1]: how disc-like and how close to the prediction the blob was; 0 if not measured."""
    diameter: np.ndarray = field(repr=False)
    """(n,) float64 pixels, the blob's equivalent-disc diameter; NaN if not measured."""
    fps: float = 30.0
    """Frames per second of the rows."""
    source: Path | None = None
    """The video the trajectory came from."""
    width: int = 0
    """Frame width of the source, pixels."""
    height_px: int = 0
    """Frame height of the source, pixels."""
    ground_v: float = math.nan
    """Image row of the object's centre at ground level, pixels."""
    scale: float = 1.0
    """Metres per pixel of :attr:`height` (1.0 with ``units`` 'px': height in pixels)."""
    units: str = "px"
    """Units of :attr:`height`: 'px' or 'm'."""

    @property
    def measured(self) -> np.ndarray:
        """(n,) bool, frames where the tracker found the object."""
        return self.status == 1

    @property
    def filled(self) -> np.ndarray:
        """(n,) bool, frames filled by interpolation."""
        return self.status == 2

    @property
    def found_fraction(self) -> float:
        """Fraction of frames measured."""
        return float(self.measured.mean()) if len(self.t) else 0.0

    @property
    def height(self) -> np.ndarray:
        """(n,) float64, height of the centre above the ground row, up positive, in :attr:`units`."""
        return (self.ground_v - self.v) * self.scale

    def segments(self) -> list[Trajectory]:
        """The pieces between long gaps, each a :class:`Trajectory` without missing rows, in time order."""
        out = []
        for s in np.unique(self.segment[self.segment >= 0]):
            idx = np.nonzero(self.segment == s)[0]
            out.append(self.take(slice(idx[0], idx[-1] + 1)))
        return out

    def longest(self) -> Trajectory:
        """The longest piece (the earliest on a tie); raise :class:`TrackingError` if there is none."""
        segs = self.segments()
        if not segs:
            raise TrackingError(f"{self.source}: the trajectory has no measured frames")
        return max(segs, key=lambda s: (len(s.t), -s.t[0]))

    def take(self, idx) -> Trajectory:
        """The rows ``idx`` (a slice or index array) as a new trajectory."""
        arrays = {k: getattr(self, k)[idx] for k in ("t", "u", "v", "status", "segment", "confidence", "diameter")}
        return replace(self, **arrays)


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
        return float(u), float(v), float(conf), self.size


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


def fill_gaps(traj: Trajectory, max_gap: int) -> Trajectory:
    """Interpolate u, v linearly over runs of at most ``max_gap`` missing frames; split at longer runs.

    Filled rows get status 'filled'; the rows of each piece share a ``segment`` number; gaps at
    the start and end of the video, and long gaps, stay missing (nothing is extrapolated).
    """
    check_range("max_gap", max_gap, 0, 10_000)
    u, v = traj.u.copy(), traj.v.copy()
    status = np.where(traj.status == 1, 1, 0).astype(np.int8)
    seg = np.full(len(u), -1, np.int32)
    idx = np.nonzero(status == 1)[0]
    if len(idx) == 0:
        return replace(traj, status=status, segment=seg)
    s = 0
    seg[idx[0]] = 0
    for a, b in zip(idx[:-1], idx[1:]):
        gap = b - a - 1
        if gap > max_gap:
            s += 1
        elif gap > 0:
            w = (np.arange(a + 1, b) - a) / (b - a)
            u[a + 1 : b] = u[a] + w * (u[b] - u[a])
            v[a + 1 : b] = v[a] + w * (v[b] - v[a])
            status[a + 1 : b] = 2
            seg[a + 1 : b] = s
        seg[b] = s
    return replace(traj, u=u, v=v, status=status, segment=seg)


def calibrate(
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
        raise TrackingError(f"{traj.source}: no tracked frames to calibrate")
    g = float(np.nanmax(traj.v[m])) if ground_v is None else float(ground_v)
    if metres_per_pixel is not None:
        check_range("metres_per_pixel", metres_per_pixel, 0.0, 100.0, lo_open=True)
        return replace(traj, ground_v=g, scale=float(metres_per_pixel), units="m")
    if object_size is not None:
        check_range("object_size", object_size, 0.0, 100.0, lo_open=True)
        d = float(np.nanmedian(traj.diameter[traj.status == 1]))
        return replace(traj, ground_v=g, scale=object_size / d, units="m")
    return replace(traj, ground_v=g, scale=1.0, units="px")


def track_video(
    path: str | Path,
    cfg: TrackConfig | None = None,
    *,
    ground_v: float | None = None,
    object_size: float | None = None,
    metres_per_pixel: float | None = None,
) -> Trajectory:
    """Track, fill short gaps, split at long ones and calibrate: the whole pipeline for one video."""
    cfg = cfg or TrackConfig()
    traj = fill_gaps(detect_all(path, cfg), cfg.max_gap)
    return calibrate(traj, ground_v=ground_v, object_size=object_size, metres_per_pixel=metres_per_pixel)


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


def to_model_input(
    traj: Trajectory,
    fps: float,
    n_frames: int,
    scale: float | None = None,
    rest_height: float = 0.0,
) -> np.ndarray:
    """The classifier's input for one video: (n_frames, 3) float32, world x, y, z in metres.

    The longest piece of ``traj`` is resampled to ``fps``, its height (times ``scale``, metres per
    unit of :attr:`Trajectory.height`; default 1, i.e. the trajectory's own units) plus
    ``rest_height`` (the centre's height at rest, metres) becomes z; a single camera gives no depth,
    so x and y are zero. Longer pieces are cut to ``n_frames``, shorter ones zero-padded at the end
    (the paper's padding).
    """
    check_range("n_frames", n_frames, 1, 1e7)
    r = resample(traj, fps)
    z = r.height * (1.0 if scale is None else scale) + rest_height
    if not np.isfinite(z).all():
        raise TrajectoryError(f"{traj.source}: the height series has NaN after resampling")
    out = np.zeros((n_frames, 3), np.float32)
    k = min(n_frames, len(z))
    out[:k, 2] = z[:k]
    return out


def write_csv(traj: Trajectory, path: str | Path) -> Path:
    """Write one row per frame: frame, t_s, u_px, v_px, height_<units>, status, segment, confidence (atomically)."""
    lines = [f"frame,t_s,u_px,v_px,height_{traj.units},status,segment,confidence"]
    h = traj.height
    for i in range(len(traj.t)):
        lines.append(
            f"{i},{traj.t[i]:.9f},{traj.u[i]:.3f},{traj.v[i]:.3f},{h[i]:.6g},{STATUS[traj.status[i]]},"
            f"{traj.segment[i]},{traj.confidence[i]:.3f}"
        )
    write_text_atomic(path, "\n".join(lines) + "\n")
    return Path(path)


def read_csv(path: str | Path) -> Trajectory:
    """Read a trajectory written by :func:`write_csv` (heights keep their units); raise :class:`TrajectoryError` if malformed."""
    from study.errors import check_file

    p = check_file(path, "trajectory CSV", "write one with 'study track VIDEO --out FILE.csv'")
    lines = p.read_text().splitlines()
    head = lines[0].split(",") if lines else []
    if len(head) != 8 or head[0] != "frame" or not head[4].startswith("height_"):
        raise TrajectoryError(f"trajectory CSV {p}: the header is not that of 'study track --out'")
    units = head[4][len("height_"):]
    try:
        rows = [ln.split(",") for ln in lines[1:] if ln]
        t = np.array([float(r[1]) for r in rows])
        u = np.array([float(r[2]) for r in rows])
        v = np.array([float(r[3]) for r in rows])
        h = np.array([float(r[4]) for r in rows])
        status = np.array([STATUS.index(r[5]) for r in rows], np.int8)
        seg = np.array([int(r[6]) for r in rows], np.int32)
        conf = np.array([float(r[7]) for r in rows])
    except (ValueError, IndexError) as e:
        raise TrajectoryError(f"trajectory CSV {p}: a row is malformed ({e})") from None
    if len(t) < 2:
        raise TrajectoryError(f"trajectory CSV {p}: fewer than two rows")
    fps = 1.0 / float(np.median(np.diff(t)))
    # height = (ground - v) * scale: recover ground and scale from two rows with different v.
    ok = np.isfinite(v) & np.isfinite(h)
    if ok.sum() >= 2 and np.ptp(v[ok]) > 0:
        scale, ground = _fit_height(v[ok], h[ok])
    else:
        scale, ground = 1.0, float(np.nanmax(v)) if ok.any() else math.nan
    return Trajectory(t=t, u=u, v=v, status=status, segment=seg, confidence=conf,
                      diameter=np.full(len(t), np.nan), fps=fps, source=p, ground_v=ground, scale=scale, units=units)


def _fit_height(v: np.ndarray, h: np.ndarray) -> tuple[float, float]:
    """(scale, ground_v) with h = (ground_v - v) * scale, least squares."""
    A = np.stack([-v, np.ones_like(v)], axis=1)
    (s, c), *_ = np.linalg.lstsq(A, h, rcond=None)
    return float(s), float(c / s)


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


def bounces(traj: Trajectory, min_rise: float | None = None) -> np.ndarray:
    """Row indices of the bounces in ``traj``: lowest points between a fall and a rise of at least ``min_rise``.

    Looks within each piece (measured and filled rows); ``min_rise`` is in the units of
    :attr:`Trajectory.height`, by default a tenth of the piece's height range. A final rest is not a
    bounce (nothing rises after it).
    """
    out: list[int] = []
    h_all = traj.height
    for s in np.unique(traj.segment[traj.segment >= 0]):
        idx = np.nonzero(traj.segment == s)[0]
        h = h_all[idx]
        if len(h) < 3:
            continue
        rise = 0.1 * float(np.ptp(h)) if min_rise is None else float(min_rise)
        if rise <= 0:
            continue
        mode, hi, lo = 0, 0, 0  # mode 0/1: following a rise (tracking its top); -1: following a fall
        for i in range(1, len(h)):
            if mode >= 0:
                if h[i] > h[hi]:
                    hi = i
                if h[i] < h[hi] - rise:
                    mode, lo = -1, i
            if mode == -1:
                if h[i] < h[lo]:
                    lo = i
                if h[i] > h[lo] + rise:
                    out.append(int(idx[lo]))
                    mode, hi = 1, i
    return np.asarray(out, int)
