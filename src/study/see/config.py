"""The colour tracker's settings, without OpenCV: named colour ranges, HSV parsing and :class:`TrackConfig`."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from study.core.errors import ConfigError, check_range

COLORS: dict[str, tuple[tuple[int, int, int], tuple[int, int, int]]] = {
    "tennis": ((22, 70, 90), (50, 255, 255)),
    "orange": ((3, 100, 25), (20, 255, 255)),
    "red": ((170, 100, 25), (8, 255, 255)),
    "green": ((50, 100, 25), (80, 255, 255)),
    "blue": ((100, 100, 25), (130, 255, 255)),
}
"""Named HSV ranges (OpenCV scale: H 0-179, S and V 0-255), (low, high); a low hue above the high
one wraps through 0 (red). 'tennis' is a yellow to yellow-green felt ball, 'orange' the colour
``study.see.render`` paints its objects.

'orange' keeps the rendered box's shaded faces: its lower bounds were S 120, V 80 until issue 28, which dropped about
a fifth of the box's pixels (its faces turned from the light) and set the centroid on the lit faces, about 15 mm
high at 4 m. S 100, V 25 were chosen on development renders (render seed 2000, 12 throws at the book's settings,
never the book's): the middle of the range (S 60-140, V 10-40) where the tracker's error is smallest and flat; from
S 180 frames are lost. 'red', 'green' and 'blue' took the same lower bounds (issue 51; they were S 120, 100, 120 and
V 70, 60, 60): under the camera sweep's dimmer lights a box's shaded faces are at V 41-54, and without them the blob
was the lit faces only, its centre up to 18 px high and its diameter 29 % small (``docs/floor-path.md``).

'tennis' is unchanged: on the real clips a lower V bound (60, 40) finds the same frames with the same blob (the ball
is lit against a bright wall), and a lower S bound lets the table of one clip in."""

CENTROIDS = ("weighted", "binary")
"""How a blob's position is measured (:attr:`TrackConfig.centroid`)."""


@dataclass
class TrackConfig:
    """How the colour tracker finds the object.

    Example::

        cfg = study.TrackConfig(color="orange", max_gap=4)
        traj = study.track_video("throw.mp4", cfg)
    """

    color: str = "tennis"
    """The name of a colour preset (:data:`COLORS`, each an HSV range), in any case; ignored when ``hsv`` is given."""
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
    centroid: str = "weighted"
    """'weighted': the blob's centroid with each pixel weighted by its saturation (a pixel the object only partly
    covers, at its edge, is paler and counts less: a sub-pixel position); 'binary': every pixel of the blob alike.
    On the development renders the weighted centroid's error is about a quarter smaller."""
    smooth: int = 0
    """Savitzky-Golay window, frames (odd), fitted to the track between the bounces found in it and never across
    one (``study.see.smooth``); 0: no smoothing."""
    smooth_order: int = 2
    """Polynomial order of that fit (2: a parabola, free flight's shape)."""
    progress: bool = True
    """Show a progress bar while decoding."""

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """(low, high) HSV bounds as uint8 arrays of 3; raise :class:`ConfigError` if malformed."""
        if self.hsv is not None:
            return parse_hsv(self.hsv)
        name = self.color.lower()  # a colour's name in any case
        if name not in COLORS:
            raise ConfigError(f"color = {self.color!r} is not a known colour; choose one of {', '.join(COLORS)} or give --hsv")
        lo, hi = COLORS[name]
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
        if self.centroid not in CENTROIDS:
            raise ConfigError(f"TrackConfig.centroid = {self.centroid!r}; choose one of {', '.join(CENTROIDS)}")
        check_range("TrackConfig.smooth_order", self.smooth_order, 0, 10)
        if self.smooth and (self.smooth % 2 == 0 or self.smooth <= self.smooth_order):
            raise ConfigError(f"TrackConfig.smooth = {self.smooth}: give an odd window above smooth_order "
                              f"({self.smooth_order}), or 0 for no smoothing")
        check_range("TrackConfig.smooth", self.smooth, 0, 10_001)


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
