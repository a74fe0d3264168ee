"""Heights through a camera the floor calibrates: four or more marks a user measured on the floor give the camera,
and the camera gives each frame's 3-D centre without assuming the throw stays in one vertical plane.

The marks come as a CSV, ``FLOOR.csv`` (:func:`read_floor`): a header ``u,v,x,y``, one row per mark, its pixel in the
video (u right, v down, the centre of the top-left pixel at (0, 0)) and its position on the floor in metres. Their
homography gives the focal length and the camera's pose (``study.see.ground.camera_from_floor``); :func:`calibrate`
checks the marks and says how well the floor fits (their reprojection error through the recovered camera).

With the camera known, a frame's ray fixes the centre up to its depth, and the throw's physics fixes the depth
(:func:`centres`):

- **flights and contacts, fitted together** (:func:`_joint`): which frames fly comes from the image
  (``study.see.geometry.phases``: the track's curvature in metres at each frame's rest-plane depth, the rows first
  smoothed over :data:`SMOOTH_S`); each contact's time and pixel is where the image tracks on either side of it meet
  (:func:`_contact`, a frame that still follows the flight's parabola moved into the flight), a first guess.
  Between two contacts the centre flies a ballistic arc (horizontal motion uniform, drag aside), the throw's first
  flight the arc that ends at the first contact; every contact's 3-D point and time and the first flight's velocity
  are fitted at once to the flights' pixels, each contact's pixel and time, and a prior that a contact's centre is
  near the object's mean height at a contact (:func:`contact_height`: a cube tumbling lands with its centre 1.5
  half-edges up on average; spread :data:`CONTACT_SD`), and sinks below
  ``rest_height`` only as far as the object squashes (:data:`CONTACT_SINK`). The fit gives each flight frame its
  depth; the frame's point is on its own pixel's ray at that depth (:func:`_on_rays`), so what the pixels saw off
  the drag-free arc stays in the heights. Since the arcs' curvature sets their depth at g, a light box's slower
  fall (the drag cue) still reads as g;
- **the apparent size**, a weak extra measurement of a flight frame's depth: the focal length times the object's
  mean-silhouette diameter over the blob's (:data:`SIZE_SD`), up to one bias for the whole clip that the fit finds
  (:data:`SIZE_BIAS`). It holds a flight's depth where its pixels do not: a camera low over the floor, a tracker's
  jump that cuts a fall short;
- **ground frames** (the object lies, rolls, slides or rocks between flights, :data:`BOUNCE_S`): its centre is
  ``rest_height`` up, so the ray meets that plane at the centre itself; but a box rocking onto an edge lifts its
  centre for a fraction of a second, and its ray then meets the plane behind it, so each frame's distance along its
  ray is the near envelope of its ground run's (:func:`_near_envelope`, :data:`GROUND_OPEN_S`), then a 5-frame
  running median.

A flight that never lands, and a centre placed where no throw could be, are left unknown.

How well: the book's camera chapter measures the path on the camera sweep. On development clips of other seeds
(seeds 2000-2002: ``docs/floor-path.md``), it is 20-22 mm RMS with each clip's median removed; the renderer's own
pixels give 19-21 mm. What is left is this fit's, in the first flight (no contact before it) and in a box's tumble
after its first landing.
``docs/floor-path.md`` keeps those measurements, what each setting here was chosen on, and what was tried and not
kept.
"""

from __future__ import annotations

import csv
import itertools
import math
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from study.core.errors import ConfigError, DataError, check_range
from study.see.camera import Camera
from study.see.geometry import G, GeometryError, phases
from study.see.scale import ObjectShape
from study.see.ground import DEFAULT_FOVY, _on_plane, camera_from_floor
from study.see.trajectory import Trajectory

MIN_MARKS = 4
"""Marks a homography needs; five or more are recommended (four fit any camera exactly: nothing checks them)."""


@dataclass(frozen=True)
class Floor:
    """The floor marks a user measured: each one's pixel and its position on the floor."""

    pixels: np.ndarray
    """(k, 2) float64: u, v, pixels (the centre of the top-left pixel at (0, 0))."""
    points: np.ndarray
    """(k, 2) float64: x, y on the floor, metres."""
    source: str = ""
    """Where they were read from (for errors)."""
    found: bool = False
    """True when the pixels were found in the video by their colour (``study.see.marks``), not given."""


def seen(camera: Camera, points: np.ndarray, click_px: float = 0.0, seed: int = 0, source: str = "") -> Floor:
    """The floor ``points`` (k, 2) metres that ``camera`` sees inside its picture, with their pixels as a click gives
    them: the camera's projection plus ``click_px`` pixels of noise (seeded by ``seed``)."""
    px = camera.project(np.column_stack([points, np.zeros(len(points))]))
    px = px + np.random.default_rng(seed).normal(0.0, click_px, px.shape) if click_px else px
    inside = (px[:, 0] >= 0) & (px[:, 0] <= camera.width - 1) & (px[:, 1] >= 0) & (px[:, 1] <= camera.height - 1)
    return Floor(px[inside], np.asarray(points, np.float64)[inside], source)


HEADERS = {"u,v,x,y": "a mark's pixel, then its x and y on the floor, metres",
           "x,y": "a mark's x and y on the floor, metres: its pixel found in the video (magenta marks)"}
"""The headers a floor file may have, and what each row holds."""


def read_floor(path: str | Path) -> Floor:
    """The marks of ``path``, a CSV with one row per mark and the header ``u,v,x,y`` (each mark's pixel and
    position) or ``x,y`` (positions only: the pixels NaN, to be found in the video, ``study.see.marks.located``); a
    spreadsheet's byte-order mark is allowed. :class:`DataError` for a missing, empty or unreadable file,
    :class:`ConfigError` for a bad header, a value that is not a number, fewer than :data:`MIN_MARKS` marks or marks
    on one line; each names the file and what to write."""
    p = Path(path)
    if not p.is_file():
        raise DataError(f"floor file {p}: no such file; write a CSV with the header u,v,x,y and one row per floor mark "
                        "(its pixel, then its position on the floor in metres)")
    try:
        rows = list(csv.reader(p.open(newline="", encoding="utf-8-sig")))
    except (OSError, UnicodeDecodeError, csv.Error) as e:
        raise DataError(f"floor file {p}: cannot be read ({type(e).__name__}); write it as a plain CSV") from None
    rows = [r for r in rows if any(c.strip() for c in r)]
    if not rows:
        raise DataError(f"floor file {p}: empty; write the header u,v,x,y and one row per floor mark")
    header = ",".join(c.strip().lower() for c in rows[0])
    if header not in HEADERS:
        raise ConfigError(f"floor file {p}: header {','.join(rows[0])!r}; it must be u,v,x,y (pixel right, pixel down, "
                          "then the mark's x and y on the floor, metres), or x,y for magenta marks found in the video")
    width = header.count(",") + 1
    values = []
    for i, r in enumerate(rows[1:], start=2):
        try:
            row = [float(c) for c in r]
        except ValueError:
            row = []
        if len(row) != width or not all(math.isfinite(x) for x in row):
            raise ConfigError(f"floor file {p}, line {i}: {','.join(r)!r} is not {('two', 'four')[width // 4]} "
                              f"numbers {header} ({HEADERS[header]})")
        values.append(row)
    a = np.array(values, np.float64).reshape(-1, width)
    pixels = a[:, :2] if width == 4 else np.full((len(a), 2), np.nan)
    floor = Floor(pixels, a[:, -2:], str(p))
    check_spread(floor)
    return floor


def check_spread(floor: Floor) -> None:
    """:class:`ConfigError` for fewer than :data:`MIN_MARKS` marks, or marks on one line (on the floor or in the
    image): a homography needs four points, no three of them on a line."""
    where = f"floor marks{' of ' + floor.source if floor.source else ''}"
    if len(floor.points) < MIN_MARKS:
        raise ConfigError(f"{where}: {len(floor.points)} marks; give at least {MIN_MARKS} (five or more are "
                          "recommended: four fit any camera exactly)")
    for what, xy in (("on the floor", floor.points), ("in the image", floor.pixels)):
        if not np.isfinite(xy).all():
            continue  # positions only: the pixels are found later
        centred = xy - xy.mean(axis=0)
        s = np.linalg.svd(centred, compute_uv=False)
        if s[1] <= 1e-3 * max(s[0], 1e-12):
            raise ConfigError(f"{where}: the marks lie on one line {what}; spread them out (the corners of a "
                              "rectangle, say)")


@dataclass(frozen=True)
class Calibration:
    """The camera a floor gives, and how well it fits."""

    camera: Camera
    reprojection_px: float
    """Root-mean-square distance between each mark's pixel and its floor position projected through ``camera``."""
    assumed_fov: bool
    """True when the marks could not fix the focal length and a field of view of ``DEFAULT_FOVY`` was assumed."""
    n_marks: int
    found: bool = False
    """True when the marks' pixels were found in the video by their colour, not given."""

    def note(self) -> str:
        """What the answer assumed of the camera, in words."""
        fov = 2 * math.degrees(math.atan(0.5 * self.camera.height / self.camera.focal))
        out = (f"camera from {self.n_marks} floor marks ({self.reprojection_px:.1f} px RMS reprojection"
               + ("; four marks fit any camera exactly, so nothing checks them: five or more are recommended"
                  if self.n_marks == MIN_MARKS else "") + f"), {self.camera.position[2]:.2f} m up, "
               f"{fov:.0f}° field of view")
        if self.found:
            out += " (the marks found in the video by their magenta)"
        if self.assumed_fov:
            out += f" (assumed: the marks cannot fix the focal length; {DEFAULT_FOVY:g}° taken)"
        return out


def calibrate(floor: Floor, width: int, height: int) -> Calibration:
    """The camera of a ``width`` x ``height`` video whose floor marks are ``floor``; :class:`ConfigError` for a mark
    outside the image, too few or lined-up marks, or a camera below the floor."""
    check_spread(floor)
    where = f"floor marks{' of ' + floor.source if floor.source else ''}"
    u, v = floor.pixels[:, 0], floor.pixels[:, 1]
    outside = (u < -0.5) | (u > width - 0.5) | (v < -0.5) | (v > height - 0.5)
    if outside.any():
        i = int(np.argmax(outside))
        raise ConfigError(f"{where}: mark {i + 1} at pixel ({u[i]:g}, {v[i]:g}) is outside the {width} x {height} "
                          "image; give each mark's pixel in this video")
    cam = camera_from_floor(floor.pixels, floor.points, width, height)
    default_f = 0.5 * height / math.tan(math.radians(DEFAULT_FOVY) / 2)
    ground = np.column_stack([floor.points, np.zeros(len(floor.points))])
    err = cam.project(ground) - floor.pixels
    return Calibration(cam, float(np.sqrt(np.mean(np.sum(err**2, axis=1)))), bool(abs(cam.focal - default_f) < 1e-9),
                       len(floor.points), floor.found)


def contact_height(shape: ObjectShape) -> float:
    """The mean height, metres, of ``shape``'s centre above the floor when it touches the floor in a uniformly
    random orientation, as a tumbling object lands: its support function's mean, half its mean width (a sphere's
    radius; a box's edges summed over 4; a cylinder's length plus pi times its radius, over 4). A cube of half-edge
    a: 1.5 a (a face: a; an edge: 1.41 a; a corner: 1.73 a), not the a it rests at.

    >>> round(contact_height(ObjectShape("box", (0.2,))), 6)
    0.15
    """
    if shape.kind == "sphere":
        return shape.dims[0] / 2
    if shape.kind == "box":
        return sum(shape.dims) / 4
    d, length = shape.dims
    return (length + math.pi * d / 2) / 4


def _frame_s(t: np.ndarray) -> float:
    """Seconds between frames of the times ``t`` (n,) s: the median step (1 for a single frame)."""
    return float(np.median(np.diff(t))) if len(t) > 1 else 1.0


def _median5(a: np.ndarray) -> np.ndarray:
    """A centred 5-frame running median of ``a`` (n, k), NaN ignored, shorter at the ends."""
    out = np.full_like(a, np.nan)
    for i in range(len(a)):
        w = a[max(0, i - 2): i + 3]
        w = w[np.isfinite(w).all(axis=1)]
        if len(w):
            out[i] = np.median(w, axis=0)
    return out


def _fit_arc(camera: Camera, t: np.ndarray, u: np.ndarray, v: np.ndarray, anchor: np.ndarray,
             t_anchor: float) -> np.ndarray:
    """(len(t), 3) a ballistic arc through ``anchor`` (3,) at ``t_anchor`` whose projection best fits the pixels
    ``u``, ``v`` (NaN where lost): its horizontal and vertical velocity the unknowns (least squares in pixels)."""
    from scipy.optimize import least_squares

    def path(p: np.ndarray, times: np.ndarray) -> np.ndarray:
        dt = times - t_anchor
        return np.column_stack([anchor[0] + p[0] * dt, anchor[1] + p[1] * dt,
                                anchor[2] + p[2] * dt - 0.5 * G * dt**2])

    ok = np.isfinite(u) & np.isfinite(v)
    if ok.sum() < 3:
        raise GeometryError("a flight seen in fewer than 3 frames cannot be fitted")
    seen = np.column_stack([u[ok], v[ok]])

    def residual(p: np.ndarray) -> np.ndarray:
        return (camera.project(path(p, t[ok])) - seen).ravel()

    span = float(np.mean(t[ok] - t_anchor))
    start = np.array([0.0, 0.0, 0.5 * G * span])  # a vertical arc of the flight's length
    return path(least_squares(residual, start, method="lm").x, t)


MAX_HEIGHT = 5.0
"""Metres: a centre placed higher (or below the floor) is left unknown, not reported."""
MAX_DISTANCE = 30.0
"""Metres from the camera, on the floor: a centre placed farther is left unknown."""
FLIGHT_GAP_S = 0.05
"""Seconds of frames whose curvature does not read as flight between two that do, still one flight: at speed the
tracker's centroid jumps a few pixels, which at 30 frames a second breaks a fall's curvature for a frame or two (a
fall then read as landing early, its frames put on the floor, a metre off). A bounce's kink spans more frames: about
3 of the 5-frame curvature on rows as they are (30 frames a second: this is 2), more on the rows :data:`SMOOTH_S`
smooths (from about 35 frames a second)."""
SMOOTH_S = 0.15
"""Seconds of the image rows' running quadratic fit before the flights are found: a tracker's pixel of noise,
twice differentiated over the 5 frames ``phases`` reads, is about half of g at 60 frames a second."""


def _smoothed(t: np.ndarray, v: np.ndarray, seconds: float) -> np.ndarray:
    """``v`` (n,) through a running quadratic fit over ``seconds`` (at least 5 frames; NaN kept); as it is at 30
    frames a second or slower."""
    dt = _frame_s(t)
    half = max(2, int(round(seconds / dt / 2)))
    if half <= 2:
        return v
    out = np.full_like(v, np.nan)
    for i in range(len(v)):
        w = slice(max(0, i - half), i + half + 1)
        ok = np.isfinite(v[w])
        if ok.sum() >= 5 and np.isfinite(v[i]):
            out[i] = np.polyval(np.polyfit(t[w][ok] - t[i], v[w][ok], 2), 0.0)
    return out


def _quad(t: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Coefficients of the parabola through ``y`` (k,) at ``t`` (k,), least squares (a line for two points)."""
    ok = np.isfinite(y)
    deg = min(2, int(ok.sum()) - 1)
    return np.polyfit(t[ok], y[ok], deg) if deg >= 1 else np.array([float(np.nanmean(y))])


def _contact(t: np.ndarray, u: np.ndarray, v: np.ndarray, before: np.ndarray, after: np.ndarray
             ) -> tuple[float, float, float]:
    """When and where (t, u, v) the object touched the ground between the frames ``before`` (the end of a flight)
    and ``after`` (the start of the next, or of the slide): where the image tracks of the two, each extrapolated as
    a parabola, meet in the image row (the bounce itself is blurred over the frames between). Frames of ``after``
    that come before that meeting still fly: they move to ``before`` and the two are met again."""
    before, after = np.asarray(before), np.asarray(after)
    tc = uc = vc = math.nan
    for _ in range(4):  # at most a few frames late
        tb, ta = t[before][-5:], t[after][:5]
        vb, va = _quad(tb, v[before][-5:]), _quad(ta, v[after][:5])
        lo, hi = t[before][-1], t[after][0]
        diff = np.polysub(vb, va)
        roots = np.roots(diff) if np.any(diff) else []
        real = [float(r.real) for r in np.atleast_1d(roots) if abs(r.imag) < 1e-9 and lo - 1e-9 <= r.real <= hi + 1e-9]
        tc = min(real, key=lambda r: abs(r - 0.5 * (lo + hi))) if real else 0.5 * (lo + hi)
        ub, ua = _quad(tb, u[before][-5:]), _quad(ta, u[after][:5])
        uc, vc = 0.5 * (np.polyval(ub, tc) + np.polyval(ua, tc)), 0.5 * (np.polyval(vb, tc) + np.polyval(va, tc))
        # the first frame of `after` has not landed yet if its row follows the flight's parabola more closely than
        # the parabola of the frames after it
        if len(after) <= 6 or not np.isfinite(v[after[0]]):
            break
        rest = _quad(t[after][1:6], v[after][1:6])
        off_flight = abs(np.polyval(vb, t[after[0]]) - v[after[0]])
        if off_flight > EXTEND_PX or off_flight >= abs(np.polyval(rest, t[after[0]]) - v[after[0]]):
            break
        before, after = np.append(before, after[0]), after[1:]
    return tc, uc, vc


EXTEND_PX = 3.0
"""A frame after a flight still flies while its image row lies within this many pixels of the flight's parabola
(the phases' curvature blurs a flight's last frames into the bounce). A tumbling box's centroid jitters by a pixel
or two, which the parabola through a flight's last 5 frames carries further: at 1.5 px a fall at 30 frames a
second was cut three frames early and a metre's drop read as landed (seed 2001's oblique_007). Chosen with
:data:`SIZE_SD` on seed 2000's development clips, with the shaded faces tracked: 1.5 and 3.0 px gave 22.5 and 22.2
mm."""
CONTACT_SD = 0.5
"""A contact's centre height prior: the object's mean height at a contact (:func:`contact_height`: a box lands on an
edge or a corner more often than on a face) with a spread of this share of its rest height. A cube's orientations
spread its contact height by 0.15 of its half-edge; the tracker's contact pixel and time add to it. On the 18
development clips of seed 2000 (the module's measurements) spreads of 0.15, 0.25 and 0.5 gave 27.0, 26.3 and 25.6
mm; with the shaded faces tracked (issue 51), 0.3, 0.5 and 0.8 gave 22.9, 22.2 and 22.0."""
CONTACT_SINK = 0.15
"""The prior's spread below ``rest_height``, a share of it: a centre sinks below its resting height only as far as
the object gives (a ball's squash), so a contact placed lower is held back more than one placed higher."""
FIT_EVALUATIONS = 200
"""The joint fit's budget of residual evaluations per start; it stops where it is after them. A clip's fit
converges in far fewer, but with the contact prior centred above the rest height one development clip's fit (a box
rocking under a low camera) wandered for minutes; capped, the 18 clips' heights were unchanged (33.4 mm)."""
GROUND_OPEN_S = 0.4
"""Seconds: on the ground, a rise of the ray's distance (to where it meets the rest plane) that lasts less than twice
this is a box rocking onto an edge, not a move away from the camera (:func:`_near_envelope`)."""
CONTACT_S = 0.03
"""Seconds: the spread of a contact's time about where the image tracks on either side meet (:func:`_contact`). The
fit moves it: a flight's height between two contacts is ``g/2 (t - t_a)(t_b - t)`` on top of theirs, so a frame's
error in one contact's time is centimetres at the flight's top."""
CONTACT_PX = 3.0
"""The spread of a contact's pixel where the image tracks of the flights on either side meet, pixels (the bounce
itself is blurred over the frames between)."""
TRACK_PX = 2.0
"""Beyond this many pixels a flight frame's misfit counts linearly, not squared (a tracker's jump)."""
SIZE_SD = 0.3
"""The spread of a flight frame's depth from its apparent size (the focal length times the object's mean-silhouette
diameter over the blob's, :func:`on_floor`) about the true depth times the clip's own bias, as a share: a tumbling
box shows more or less than its mean silhouette (7.5 % in a median frame), a blob of 15-60 pixels gains or loses
an edge pixel from frame to frame, and a small blob at 480p loses more. A weak measurement: on seed 2000's
development clips, with the shaded faces tracked and :data:`EXTEND_PX` 3, spreads of 0.1, 0.2, 0.3 and 0.4 gave 24.0,
22.4, 22.2 and 22.4 mm, and no size 23.6 (``docs/floor-path.md``)."""
SIZE_BIAS = 0.3
"""The prior spread of a clip's bias in depth from apparent size, as a share (log): the blob's edge moves with the
lighting, the floor behind and the video's resolution, -9 % to +14 % on 18 development clips (seed 2000), so the
apparent size says how a flight's depth changes more than what it is. Loose: a prior as tight as the biases seen
(0.1) pulls a clip's bias towards none, and with it the flights whose depth only the size holds (on an inline scene
from a low camera, a size 10 % off put the first flight 23 mm off on average over 12 draws, against 20 mm without
the size and 18 mm with this prior; on the development clips both priors give 33 and 48 mm)."""
BOUNCE_S = 0.25
"""Seconds between two flights' frames for one bounce to join them; a longer stretch between is on the ground (a
slide, a box rocking on its edges), with a landing before it and a take-off after."""

Flight = tuple[int | None, int, np.ndarray]
"""A flight: the index of the contact it starts from (None: the throw's, no contact before it), of the contact that
ends it, and its frames."""


def _merged(t: np.ndarray, u: np.ndarray, v: np.ndarray, arcs: list[np.ndarray], gap_max: int) -> list[np.ndarray]:
    """``arcs`` with two that a bounce would join made one where the image tracks on either side meet in the upper
    half of the rows next to them: a contact is the lowest point of the track near it (its largest row); a flight
    split at its apex is one flight."""
    out = [np.asarray(arcs[0])] if arcs else []
    for nxt in arcs[1:]:
        arc = out[-1]
        if nxt[0] - arc[-1] - 1 <= gap_max:
            _, _, vc = _contact(t, u, v, arc, nxt)
            near = np.concatenate([v[arc[-3:]], v[nxt[:3]]])
            if np.isfinite(near).any() and vc < 0.5 * (np.nanmin(near) + np.nanmax(near)):
                out[-1] = np.arange(arc[0], nxt[-1] + 1)
                continue
        out.append(np.asarray(nxt))
    return out


def _contacts(camera: Camera, t: np.ndarray, u: np.ndarray, v: np.ndarray, arcs: list[np.ndarray],
              contact_height: float) -> tuple[list[tuple[float, np.ndarray]], list[Flight]]:
    """The contacts (time, where the contact's ray meets the plane ``contact_height`` up, metres) and the flights
    between them, from the image's flights ``arcs``: two flights a bounce apart (:data:`BOUNCE_S`) share a contact;
    with longer on the ground between, the first lands and the next takes off. A flight that never lands is left out
    (unknown)."""
    dt = _frame_s(t)
    gap_max = max(2, int(round(BOUNCE_S / dt)))
    contacts: list[tuple[float, np.ndarray]] = []

    def contact(before: np.ndarray, after: np.ndarray) -> int | None:
        if len(before) < 2 or len(after) < 2:
            return None
        tc, uc, vc = _contact(t, u, v, before, after)
        point = _on_plane(camera, np.array([uc]), np.array([vc]), contact_height)[0]
        if not np.isfinite(point).all():
            return None
        contacts.append((tc, point))
        return len(contacts) - 1

    arcs = _merged(t, u, v, arcs, gap_max)
    flights: list[Flight] = []
    start: int | None = None
    for k, arc in enumerate(arcs):
        nxt = arcs[k + 1] if k + 1 < len(arcs) else None
        between = np.arange(arc[-1] + 1, nxt[0] if nxt is not None else len(t))
        if nxt is not None and len(between) <= gap_max:  # a bounce
            end = contact(arc, nxt)
            after_start = end
        else:  # a landing, then (if another flight follows) a take-off
            end = contact(arc, between)
            after_start = contact(between, nxt) if nxt is not None else None
        if end is not None:
            lo = contacts[start][0] if start is not None else -math.inf
            frames = np.flatnonzero((t > lo) & (t <= contacts[end][0]))
            if len(frames):
                flights.append((start, end, frames))
        start = after_start
    return contacts, flights


def _joint(camera: Camera, t: np.ndarray, u: np.ndarray, v: np.ndarray, flights: list[Flight],
           contacts: list[tuple[float, np.ndarray]], rest_height: float, contact_height: float,
           sized: np.ndarray | None = None) -> list[np.ndarray]:
    """Each flight's centres (len(frames), 3), every flight and contact fitted at once through the camera: the
    unknowns are each contact's 3-D point and time, the velocity of each flight with no contact before it and the
    apparent size's bias for the clip; a flight between two contacts is the ballistic arc through both (its
    horizontal motion uniform, its height a parabola in g), one without the arc that ends at its contact. Least squares on the flights' pixels (robust
    beyond :data:`TRACK_PX`), each contact's pixel (:data:`CONTACT_PX`), its time (:data:`CONTACT_S`) and its
    centre's height (``contact_height``, spread :data:`CONTACT_SD` of ``rest_height``; below ``rest_height``
    :data:`CONTACT_SINK` more), and,
    given ``sized`` (n,) each frame's depth from its apparent size, metres (NaN where unknown), each flight frame's
    depth against it (:data:`SIZE_SD`) up to one bias for the clip (an unknown, :data:`SIZE_BIAS`): the contacts,
    the arcs' curvature, the apparent size and the continuity between them weighed together."""
    from scipy.optimize import least_squares

    seen_t = np.array([c[0] for c in contacts])  # (K,) s, where the image tracks on either side meet
    start = np.array([c[1] for c in contacts], np.float64)  # (K, 3) where each contact's ray meets the rest plane
    seen_c = camera.project(start)
    sized = np.full(len(t), np.nan) if sized is None else np.asarray(sized, np.float64)
    K = len(contacts)
    free = [i for i, (a, _, _) in enumerate(flights) if a is None]  # flights with a velocity of their own
    ok = [np.isfinite(u[f]) & np.isfinite(v[f]) for _, _, f in flights]
    seen_px = [np.column_stack([u[f][o], v[f][o]]) for (_, _, f), o in zip(flights, ok)]  # each (k, 2) pixels
    with np.errstate(invalid="ignore", divide="ignore"):
        log_sized = [np.log(sized[f][o]) for (_, _, f), o in zip(flights, ok)]  # each (k,), NaN where unknown
    down = np.array([0.0, 0.0, -0.5 * G])

    def arc(i: int, p: np.ndarray, vel: np.ndarray, tc: np.ndarray, times: np.ndarray) -> np.ndarray:
        a, b, _ = flights[i]
        # a frame the fit moved a contact past is at that contact, not on this parabola extended past it (below
        # the floor); placing it on the next flight instead was exact on inline hops but unstable on video
        times = np.clip(times, -math.inf if a is None else tc[a], tc[b])
        if a is None:
            dt = (times - tc[b])[:, None]
            return p[b] + vel[free.index(i)] * dt + down * dt**2
        w = ((times - tc[a]) / (tc[b] - tc[a]))[:, None]
        sag = 0.5 * G * (times - tc[a]) * (tc[b] - times)
        return (1 - w) * p[a] + w * p[b] + np.column_stack([0 * sag, 0 * sag, sag])

    def unpack(x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
        """(K, 3) contact points, (len(free), 3) velocities, (K,) contact times, the apparent size's log bias."""
        m = 3 * K + 3 * len(free)
        return x[: 3 * K].reshape(K, 3), x[3 * K: m].reshape(len(free), 3), x[m: m + K], float(x[m + K])

    def residual(x: np.ndarray) -> np.ndarray:
        p, vel, tc, bias = unpack(x)
        parts = []
        for i, ((_, _, f), o) in enumerate(zip(flights, ok)):
            if not o.any():
                continue
            xyz = arc(i, p, vel, tc, t[f][o])  # (k, 3) the flight's seen frames, once for pixels and size
            parts.append((camera.project(xyz) - seen_px[i]).ravel())
            s = np.isfinite(log_sized[i])
            if s.any():
                depth = np.maximum(camera.depth_of(xyz[s]), 1e-3)
                parts.append((np.log(depth) - log_sized[i][s] - bias) / SIZE_SD * TRACK_PX)
        parts.append(((camera.project(p) - seen_c) / CONTACT_PX * TRACK_PX).ravel())
        parts.append((p[:, 2] - contact_height) / (CONTACT_SD * rest_height) * TRACK_PX)
        parts.append(np.minimum(p[:, 2] - rest_height, 0.0) / (CONTACT_SINK * rest_height) * TRACK_PX)
        parts.append((tc - seen_t) / CONTACT_S * TRACK_PX)
        parts.append(np.array([bias / SIZE_BIAS * TRACK_PX]))
        return np.concatenate(parts)

    # Each free flight's velocity, guessed two or three ways: fitted alone at its contact, at that contact's depth,
    # and at the depth its apparent size gives.
    options = []
    for i in free:
        _, b, f = flights[i]
        seen = f[ok[i]]
        guesses = [np.zeros(3)]
        if len(seen) >= 3:
            guesses = []
            tries = [_fit_arc(camera, t[seen], u[seen], v[seen], start[b], seen_t[b]),
                     camera.position + camera.depth_of(start[b:b + 1])[0] * camera.rays(u[seen], v[seen])]
            if np.isfinite(sized[seen]).sum() >= 3:
                tries.append(camera.position + np.nanmedian(sized[seen]) * camera.rays(u[seen], v[seen]))
            for alone in tries:
                dt = t[seen] - seen_t[b]
                drop = alone - start[b] - down * dt[:, None] ** 2
                guesses.append(np.linalg.lstsq(dt[:, None], drop, rcond=None)[0][0])
        options.append(guesses)
    starts = [np.concatenate([start.ravel(), *g, seen_t, [0.0]]) for g in itertools.product(*options)]
    best = min((least_squares(residual, x0, loss="huber", f_scale=TRACK_PX, x_scale="jac", max_nfev=FIT_EVALUATIONS)
                for x0 in starts),
               key=lambda f: f.cost)
    p, vel, tc, _ = unpack(best.x)
    return [arc(i, p, vel, tc, t[f]) for i, (_, _, f) in enumerate(flights)]


def centres(camera: Camera, t: np.ndarray, u: np.ndarray, v: np.ndarray, rest_height: float,
            sized: np.ndarray | None = None, contact_height: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Each frame's 3-D centre (n, 3) metres, world (x, y on the floor, z up), from the tracked centre ``u``, ``v``
    (n,) pixels (NaN where lost) at times ``t`` (n,) s, seen by ``camera``, and optionally ``sized`` (n,) each
    frame's depth from its apparent size, metres (NaN where unknown), and ``contact_height`` the centre's mean height
    at a contact, metres (None: ``rest_height``, a ball's); and the ground mask (n,) bool (frames
    after the last contact, or with no flight seen). NaN rows where the centre was lost or cannot be placed. Raises
    :class:`GeometryError` when no frame's ray meets the rest plane in front of the camera."""
    t, u, v = (np.asarray(a, np.float64) for a in (t, u, v))
    contact_height = rest_height if contact_height is None else contact_height
    n = len(t)
    plane = _on_plane(camera, u, v, rest_height)  # (n, 3): a ground frame's centre; a flight's is nearer the camera
    on_plane = np.isfinite(plane).all(axis=1)
    if on_plane.sum() < 3:
        raise GeometryError("the tracked centre meets the floor in front of the camera in fewer than 3 frames: the "
                            "camera the floor marks give does not see this throw from above the floor")
    depth = camera.depth_of(np.where(on_plane[:, None], plane, camera.position))
    depth = np.where(on_plane, depth, np.max(depth[on_plane]))  # above the camera: the farthest, for the scale
    # Metres per pixel at each frame's rest-plane depth bound the true scale from above (a flying object is nearer
    # than where its ray meets the plane), so a flight's curvature may read above g: no upper bound.
    arcs, _ = phases(t, _smoothed(t, v, SMOOTH_S), depth / camera.focal, most=math.inf, gap_s=FLIGHT_GAP_S)
    arcs = [a[1:-1] for a in arcs if len(a) > 4]  # the flight frames proper (an arc's ends straddle a contact)
    if arcs and arcs[0][0] <= 3:  # a track that starts (or ends) in the air: its first frames' curvature is unknown
        arcs[0] = np.arange(0, arcs[0][-1] + 1)
    if arcs and arcs[-1][-1] >= n - 4:
        arcs[-1] = np.arange(arcs[-1][0], n)
    out = np.full((n, 3), np.nan)
    contacts, flights = _contacts(camera, t, u, v, arcs, contact_height)
    in_flight = np.zeros(n, bool)  # a flight's frames, placed by the fit; an arc's that never lands stay unknown
    for frames in [*arcs, *(f for _, _, f in flights)]:
        in_flight[frames] = True
    ground = on_plane & ~in_flight  # lying, sliding or rocking on the floor: on the rest plane
    if flights:
        for (_, _, frames), xyz in zip(flights, _joint(camera, t, u, v, flights, contacts, rest_height, contact_height,
                                                             sized)):
            out[frames] = _on_rays(camera, u[frames], v[frames], xyz)
    near = _near_envelope(camera, t, plane, ground)
    out[ground] = _median5(np.where(ground[:, None], near, np.nan))[ground]
    lost = ~(np.isfinite(u) & np.isfinite(v))
    far = np.linalg.norm(out[:, :2] - np.asarray(camera.position[:2]), axis=1) > MAX_DISTANCE
    out[lost | far | (out[:, 2] < 0.0) | (out[:, 2] > MAX_HEIGHT)] = np.nan  # not a place a throw could be: unknown
    return out, ground


def _on_rays(camera: Camera, u: np.ndarray, v: np.ndarray, fitted: np.ndarray) -> np.ndarray:
    """(n, 3) metres: each frame's point on its own pixel's ray (``u``, ``v`` (n,) pixels) at the depth of its
    ``fitted`` (n, 3) arc point; NaN where the pixel is unknown (:func:`centres` leaves those frames unknown). The
    arc is drag-free at g, so its own points would replace what the pixels saw between contacts (a tumbling box's
    centroid off its arc) with the model; taken at the arc's depth, the pixels keep their shape."""
    return np.asarray(camera.position) + camera.depth_of(fitted)[:, None] * camera.rays(u, v)


def _near_envelope(camera: Camera, t: np.ndarray, plane: np.ndarray, ground: np.ndarray) -> np.ndarray:
    """The ground frames' centres (n, 3) metres (NaN elsewhere): each ground frame's ray (to ``plane`` (n, 3), where
    it meets the rest plane) cut at its distance's morphological opening over each run of ``ground`` (n,) bool
    frames, :data:`GROUND_OPEN_S` each side. A box rocking onto an edge lifts its centre off the rest plane for a
    fraction of a second, so its ray meets that plane behind it: a short rise of the distance, which the opening
    removes, placing the centre on the ray where the box is."""
    dt = _frame_s(t)
    w = max(1, int(round(GROUND_OPEN_S / dt)))
    ray = plane - np.asarray(camera.position)  # (n, 3)
    dist = np.linalg.norm(ray, axis=1)  # (n,) metres, NaN where the ray misses the plane
    opened = np.full_like(dist, np.nan)
    edges = np.flatnonzero(np.diff(np.r_[0, ground.astype(np.int8), 0]))
    for a, b in zip(edges[::2], edges[1::2]):
        opened[a:b] = _opening(dist[a:b], w)
    return np.asarray(camera.position) + ray / dist[:, None] * opened[:, None]


def _opening(a: np.ndarray, w: int) -> np.ndarray:
    """The grey opening of ``a`` (n,) finite: the running minimum over ``w`` frames each side, then the running
    maximum of that, each window cut short at the ends; it removes rises narrower than ``2 w + 1`` frames and keeps
    a steady trend, but over a run's last (and first) ``w`` frames a trend away from the camera is held at its value
    ``w`` frames in (a slide that ends in a take-off is pulled towards the camera there). A run shorter than ``w``
    frames is held at its nearest."""
    from scipy.ndimage import maximum_filter1d, minimum_filter1d

    eroded = minimum_filter1d(a, 2 * w + 1, mode="constant", cval=np.inf)  # a window past an end: cut short
    return maximum_filter1d(eroded, 2 * w + 1, mode="constant", cval=-np.inf)


def heights(camera: Camera, t: np.ndarray, u: np.ndarray, v: np.ndarray, rest_height: float) -> np.ndarray:
    """(n,) the centre's height above the floor, metres, in each frame (:func:`centres`); NaN where unknown."""
    return centres(camera, t, u, v, rest_height)[0][:, 2]


def on_floor(traj: Trajectory, floor: Floor, rest_height: float, size: float | None = None,
             contact_height: float | None = None) -> tuple[Trajectory, Calibration]:
    """``traj`` (a track in pixels of a video of ``traj.width`` x ``traj.height_px``) with each frame's centre height
    in metres through the camera ``floor`` calibrates (:func:`centres`), and that calibration. ``rest_height``: the
    centre's height when the object lies on the floor, metres; ``size``: the diameter of the disc with the object's
    mean silhouette area, metres (``ObjectShape.mean_size``), for each frame's depth from the blob's diameter (None:
    the apparent size unused); ``contact_height``: the centre's mean height when it touches the floor tumbling,
    metres (:func:`contact_height`; None: ``rest_height``)."""
    if not traj.width or not traj.height_px:
        raise ConfigError(f"{traj.source}: the track does not say its video's size; track the video itself with "
                          "--floor (a trajectory CSV keeps no frame size)")
    cal = calibrate(floor, traj.width, traj.height_px)
    sized = None
    if size is not None:
        check_range("size (metres)", size, 0.0, 10.0, lo_open=True)
        usable = np.isfinite(traj.diameter) & (traj.diameter > 0)
        sized = cal.camera.focal * size / np.where(usable, traj.diameter, np.nan)
    if contact_height is not None:
        check_range("contact height (metres)", contact_height, rest_height, 10.0)
    xyz, _ = centres(cal.camera, traj.t, traj.u, traj.v, rest_height, sized, contact_height)
    seen = np.isfinite(xyz).all(axis=1)
    if seen.sum() < 3:
        raise GeometryError(f"{traj.source}: fewer than 3 frames could be placed through the floor's camera")
    scale = float(np.median(cal.camera.depth_of(xyz[seen]) / cal.camera.focal))
    status, segment = _unknown_split(traj.status, traj.segment, seen)
    return replace(traj, z=xyz[:, 2], ground_z=rest_height, units="m", height_per_pixel=scale, status=status,
                   segment=segment), cal


def _unknown_split(status: np.ndarray, segment: np.ndarray, placed: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The track's status (n,) and pieces (n,) with the frames the floor's camera could not place (``placed``
    False) lost: each such run of frames splits its piece, so a piece holds only frames with a height."""
    lost = ~placed | (segment < 0)
    piece = np.cumsum(np.r_[True, lost[:-1] & ~lost[1:]] | np.r_[True, segment[1:] != segment[:-1]])
    out = np.where(lost, -1, piece)
    kept = np.unique(out[out >= 0])
    renumbered = np.where(out >= 0, np.searchsorted(kept, out), -1).astype(segment.dtype)
    return np.where(lost, 0, status).astype(status.dtype), renumbered
