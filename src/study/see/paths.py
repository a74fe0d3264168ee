"""A user's paths from a video's pixels to heights in metres, each defined once: its key (in the results and on the
command line), its words in the book, and how it reads the scale. No numerics imported: the command line's
``--help`` reads these.

Every other list of paths is derived from :data:`PATHS`: ``study.see.scale.SCALE_FROM`` and ``study track
--scale-from`` (the one-scale paths), ``study.methods.camera_cost.PATHS`` (what the camera sweep measures on every
clip; the marks found by colour only where they were drawn) and the results' names (:data:`PathKey`, with
``exact``: the renderer's truth, and ``known``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal


@dataclass(frozen=True)
class CameraPath:
    """One way from a clip's pixels to metres without a measured camera."""

    key: str
    """Its name in the results (``usercamera.sweep.all.<key>``) and, for a one-scale path, ``--scale-from KEY``."""
    words: str
    """What the book calls it."""
    one_scale: bool
    """True: one metres-per-pixel scale for the whole clip (``study.see.scale.read_scale(how=key)``); False: the
    camera's geometry fitted frame by frame (``study.see.geometry``), or given by marks on the floor
    (``study.see.floor``, ``--floor``)."""
    floor: bool = False
    """True: the camera from marks on the floor (``--floor FLOOR.csv``)."""
    found: bool = False
    """True: the marks' pixels found in the video by their colour (``study.see.marks``: a ``FLOOR.csv`` of positions
    only), so measured only on clips whose marks were drawn; False for a path that needs no marks or is given their
    pixels."""


PATHS: tuple[CameraPath, ...] = (
    CameraPath("rest", "rest size", one_scale=True),
    CameraPath("mean", "mean silhouette", one_scale=True),
    CameraPath("gravity", "gravity", one_scale=True),
    CameraPath("geometry", "geometry", one_scale=False),
    CameraPath("floor", "floor marks", one_scale=False, floor=True),
    CameraPath("found", "floor marks found", one_scale=False, floor=True, found=True),
)
"""Every path, in the order the tables show them."""

EXACT = "exact"
"""The results' key of the renderer's own heights, beside the paths."""
KNOWN = "known"
"""The results' key of the tracker's pixels through the clip's own camera at each frame's true depth: the limit of
any path that knows the camera (the floor path's), beside the paths; no user has it."""
KNOWN_WORDS = "known camera"
"""What the book calls :data:`KNOWN`."""

SCALE_FROM: tuple[str, ...] = tuple(p.key for p in PATHS if p.one_scale)
"""How one scale can be read (``study track --scale-from``)."""
FLOOR_KEYS: tuple[str, ...] = tuple(p.key for p in PATHS if p.floor)
"""The paths through a camera the floor marks give (``--floor``), the marks clicked or found."""
FOUND: str = next(p.key for p in PATHS if p.found)
"""The floor path with its marks found by colour (``study classify --floor MARKS.csv``, positions only)."""

DEFAULT = "mean"
"""The way a user's path reads the scale unless told otherwise (``study classify``, ``study track``, the real-world
chapter): on the book's renders and on the camera sweep its heights are the closest of the one-scale paths to the
truth, and the paths' accuracies cannot be told apart (the real-world chapter shows both)."""

BY_WORDS: dict[str, CameraPath] = {p.words: p for p in PATHS}

PathKey = Literal[(EXACT, KNOWN, *(p.key for p in PATHS))]  # type: ignore[valid-type]
"""How a clip's heights were had: exactly, through the known camera at the true depth, or by one of :data:`PATHS`."""
