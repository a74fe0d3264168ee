"""The tracked object's trajectory, one row per frame: image position, status, pieces, and heights."""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from study.core.errors import TrackingError

STATUS = ("missing", "measured", "filled")
"""Per-frame status codes of a :class:`Trajectory` (index = code)."""


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
    height_per_pixel: float = 1.0
    """Units of :attr:`height` per image pixel: metres per pixel with ``units`` 'm', 1.0 with 'px'."""
    units: str = "px"
    """Units of :attr:`height`: 'px' or 'm'."""
    z: np.ndarray | None = field(default=None, repr=False)
    """(n,) float64 heights of the centre in :attr:`units` where they come from more than the image row: the
    camera's geometry and the object's depth (``study.see.gaps.set_camera``: metres above the ground plane), or
    a CSV's own heights; None: from the row, by :attr:`ground_v` and :attr:`height_per_pixel`."""
    ground_z: float = 0.0
    """The value of :attr:`z` with the object's centre at ground level (its rest height), when :attr:`z` is set."""

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
        """(n,) float64, height of the centre above its height at rest (the ground row), up positive, in
        :attr:`units`: from :attr:`z` when it is set, else from the image row."""
        if self.z is not None:
            return self.z - self.ground_z
        return (self.ground_v - self.v) * self.height_per_pixel

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
        return replace(self, **arrays, z=None if self.z is None else self.z[idx])
