"""Metres per pixel without a camera: the object's known shape and size over the size of its blob.

A user knows what they threw (a ball of 6.7 cm, a 20 cm cube), not their camera. The tracker measures the blob's
equivalent-disc diameter in pixels, frame by frame; the scale is a real size over a blob size, read one of two ways:

- ``rest``: the blob at rest at the end of the video (``study.see.gaps.rest_diameter``) against the disc of the
  silhouette the object shows lying still, side-on (:meth:`ObjectShape.rest_size`): a ball's diameter; a box's
  face on its two longest edges; a cylinder's side.
- ``mean``: the blob's root-mean-square diameter over every measured frame against the disc of the object's *mean*
  silhouette (:meth:`ObjectShape.mean_size`, ``study.see.size.apparent_size``): a tumbling object shows every side,
  and a box resting turned to the camera shows more than one face.

- ``gravity``: no size at all. Between bounces the object falls at 9.81 m/s^2; the image rows of each free flight
  (``study.see.geometry.phases``) are fitted with a parabola, and metres per pixel is g over twice its curvature
  (the median over the flights, each weighted by its frames). A camera tilted down foreshortens the fall and the
  heights alike, so the ruler carries the tilt; a blob whose size is misread (blur, a tumbling box, a few pixels
  across) does not move it. The size only helps find the flights.

Each is one scale for the whole video: the object's changes of distance are ignored, and the note (:class:`Scale`)
says so.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from study.core.errors import ConfigError, TrackingError, check_range
from study.see.gaps import rest_diameter
from study.see.geometry import G, GeometryError, phases
from study.see.paths import DEFAULT, SCALE_FROM  # noqa: F401  (re-exported: how the scale is read)
from study.see.size import apparent_size
from study.see.trajectory import Trajectory

KINDS = ("sphere", "box", "cylinder")
"""Object shapes a scale can be read from."""
GUESS_FACTORS = (1.0, 0.5, 2.0, 1 / 3, 3.0)
"""Multiples of the blob's scale ``gravity`` tries when finding the flights."""


@dataclass(frozen=True)
class ObjectShape:
    """What was thrown: a kind and its dimensions, metres."""

    kind: str
    """'sphere', 'box' or 'cylinder'."""
    dims: tuple[float, ...]
    """A sphere's diameter; a box's three edges (one number: a cube); a cylinder's diameter and length."""

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise ConfigError(f"object shape {self.kind!r} is unknown; use one of {', '.join(KINDS)}")
        need = {"sphere": (1,), "box": (1, 3), "cylinder": (2,)}[self.kind]
        if len(self.dims) not in need:
            raise ConfigError(f"a {self.kind} takes {' or '.join(map(str, need))} size(s) in metres, got "
                              f"{len(self.dims)}: {self.dims}")
        for d in self.dims:
            check_range(f"{self.kind} size (metres)", d, 0.0, 100.0, lo_open=True)
        if self.kind == "box" and len(self.dims) == 1:
            object.__setattr__(self, "dims", (self.dims[0],) * 3)

    def rest_size(self) -> float:
        """The diameter, metres, of the disc with the area of the silhouette it shows lying still, side-on."""
        if self.kind == "box":
            a, b = sorted(self.dims)[1:]
            return math.sqrt(4 * a * b / math.pi)
        if self.kind == "cylinder":
            return math.sqrt(4 * self.dims[0] * self.dims[1] / math.pi)
        return float(self.dims[0])

    def mean_size(self) -> float:
        """The diameter, metres, of the disc with its mean silhouette area (``study.see.size.apparent_size``)."""
        return apparent_size(self.kind, self.dims)

    def rest_height(self) -> float:
        """The centre's height lying still on the floor, metres (a box on its two longest edges, a cylinder on its
        side)."""
        return (min(self.dims) if self.kind == "box" else self.dims[0]) / 2


@dataclass(frozen=True)
class Scale:
    """A scale read from the blob, and what it assumed."""

    metres_per_pixel: float
    """The scale."""
    blob_px: float
    """The blob diameter it read, pixels."""
    size_m: float
    """The real size it read it against, metres."""
    how: str
    """'rest', 'mean' or 'gravity' (:data:`SCALE_FROM`)."""
    frames: int | None
    """Frames it read (None for the frames at rest: ``study.see.gaps.rest_diameter`` chooses them)."""
    flights: int = 0
    """Free flights it fitted ('gravity' only)."""

    def note(self) -> str:
        """One line: the scale and what it read."""
        if self.how == "gravity":
            return (f"scale {1000 * self.metres_per_pixel:.2f} mm/px (gravity: {self.flights} free flight(s), "
                    f"{self.frames} frames, fitted as parabolas)")
        what = "at rest" if self.how == "rest" else f"its RMS over {self.frames} frames"
        return f"scale {1000 * self.metres_per_pixel:.2f} mm/px ({self.size_m:.3f} m over a {self.blob_px:.1f}-px blob, {what})"


def read_scale(traj: Trajectory, shape: ObjectShape, how: str = DEFAULT) -> Scale:
    """Metres per pixel of ``traj`` (pixels, from the tracker) for an object of ``shape``, read ``how``
    (:data:`SCALE_FROM`). Raise :class:`TrackingError` when no blob size was measured."""
    if how not in SCALE_FROM:
        raise ConfigError(f"scale from {how!r}: use one of {', '.join(SCALE_FROM)}")
    d = traj.diameter[traj.measured]
    d = d[np.isfinite(d) & (d > 0)]
    if len(d) == 0:
        raise TrackingError(f"{traj.source}: the object's size was measured in no frame; give --metres-per-pixel")
    if how == "rest":
        blob, size, n = rest_diameter(traj), shape.rest_size(), None
    else:
        blob, size, n = float(np.sqrt(np.mean(d**2))), shape.mean_size(), len(d)
    if how == "gravity":
        return gravity_scale(traj, size / blob, blob, size)
    return Scale(size / blob, blob, size, how, n)


def gravity_scale(traj: Trajectory, guess: float, blob_px: float = math.nan, size_m: float = math.nan) -> Scale:
    """Metres per pixel with gravity as the ruler: g over twice the image curvature (rows/s^2) of the free flights,
    the median over the flights weighted by their frames. ``guess`` (metres per pixel, e.g. from the blob's size)
    only finds the flights (``study.see.geometry.phases``). Raise :class:`~study.see.geometry.GeometryError` when no
    free flight is found."""
    v = np.where(traj.measured, traj.v, np.nan)
    # A blob misread by 2x would hide every flight from phases' 0.35-1.8 g window: try the guess and its multiples,
    # keep the reading that finds the most flight frames.
    arcs = max((phases(traj.t, v, np.full(len(v), guess * f))[0] for f in GUESS_FACTORS),
               key=lambda found: sum(len(a) for a in found))
    curv, weight = [], []
    for a in arcs:
        a = a[1:-1] if len(a) >= 7 else a  # the widened ends may hold the bounce
        a = a[np.isfinite(v[a])]
        if len(a) >= 5:
            curv.append(2 * np.polyfit(traj.t[a] - traj.t[a].mean(), v[a], 2)[0])  # rows grow downwards
            weight.append(len(a))
    if not curv:
        raise GeometryError(f"{traj.source}: no free flight found to measure gravity by (the object must be seen in "
                            "the air for at least 5 frames between bounces); read the scale from its size instead "
                            "(--scale-from rest)")
    order = np.argsort(curv)
    cum = np.cumsum(np.asarray(weight)[order])
    c = float(np.asarray(curv)[order][np.searchsorted(cum, cum[-1] / 2)])
    if c <= 0:
        raise GeometryError(f"{traj.source}: its flights curve upwards in the image; is the video upside down?")
    return Scale(G / c, blob_px, size_m, "gravity", int(sum(weight)), len(curv))
