"""The colour tracker's settings, without OpenCV: named colour ranges, HSV parsing and :class:`TrackConfig`."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from study.core.errors import ConfigError, check_range

PRESETS: dict[str, tuple[tuple[int, int, int], tuple[int, int, int]]] = {
    "tennis": ((22, 70, 90), (50, 255, 255)),
    "orange": ((3, 120, 80), (20, 255, 255)),
    "red": ((170, 120, 70), (8, 255, 255)),
    "green": ((50, 100, 60), (80, 255, 255)),
    "blue": ((100, 120, 60), (130, 255, 255)),
}
"""Named HSV ranges (OpenCV scale: H 0-179, S and V 0-255), (low, high); a low hue above the high
one wraps through 0 (red). 'tennis' is a yellow to yellow-green felt ball, 'orange' the colour
``study.see.render`` paints its objects."""


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
