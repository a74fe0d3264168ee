"""Heights through a camera the floor calibrates: four or more marks a user measured on the floor give the camera,
and the camera gives each frame's 3-D centre without assuming the throw stays in one vertical plane.

The marks come as a CSV, ``FLOOR.csv`` (:func:`read_floor`): a header ``u,v,x,y``, one row per mark, its pixel in the
video (u right, v down, the centre of the top-left pixel at (0, 0)) and its position on the floor in metres. Their
homography gives the focal length and the camera's pose (``study.see.ground.camera_from_floor``); :func:`calibrate`
checks the marks and says how well the floor fits (their reprojection error through the recovered camera).

With the camera known, a frame's ray fixes the centre up to its depth, and the throw's physics fixes the depth
(:func:`centres`):

- **ground frames** (the object lies, rolls or slides): its centre is ``rest_height`` up, so the ray meets that plane
  at the centre itself (a 5-frame running median against a box that rocks onto an edge, which lifts it a little);
- **flights** between two contacts: the horizontal motion of a ballistic arc is uniform (drag aside), so the centre's
  horizontal position is interpolated in time between the contacts at the arc's ends, and the height is where the
  ray passes over it;
- a flight with a contact at one end only (the first, from the throw): the arc is fitted to its pixels through the
  camera, a ballistic parabola whose end meets the contact (its three velocities the unknowns).

Which frames are flights comes from the image (``study.see.geometry.phases``: the track's curvature in metres, at
each frame's rest-plane depth, the rows first smoothed over :data:`SMOOTH_S`). A centre placed where no throw could
be is left unknown.

**Measured, and not yet good enough on video.** On inline scenes (``tests/test_floor.py``: a throw that turns at
every bounce, four cameras) the heights are 1-7 mm RMS from exact pixels and under 3 cm with marks clicked a pixel
off. On rendered video (``scripts/floor_sweep.py``, development clips of another seed than the sweep's) the
tracker's pixels and a tumbling box's edges cost far more, most from low and high cameras: the contacts and the
first flight need the weighing the floor-camera issue describes before the path is offered as the study's.
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from study.core.errors import ConfigError, DataError
from study.see.camera import Camera
from study.see.geometry import G, GeometryError, phases
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


def read_floor(path: str | Path) -> Floor:
    """The marks of ``path``, a CSV with the header ``u,v,x,y`` and one row per mark. :class:`DataError` for a
    missing, empty or unreadable file, :class:`ConfigError` for a bad header, a value that is not a number, fewer than
    :data:`MIN_MARKS` marks or marks on one line; each names the file and what to write."""
    p = Path(path)
    if not p.is_file():
        raise DataError(f"floor file {p}: no such file; write a CSV with the header u,v,x,y and one row per floor mark "
                        "(its pixel, then its position on the floor in metres)")
    try:
        rows = list(csv.reader(p.open(newline="")))
    except (OSError, UnicodeDecodeError, csv.Error) as e:
        raise DataError(f"floor file {p}: cannot be read ({type(e).__name__}); write it as a plain CSV") from None
    rows = [r for r in rows if any(c.strip() for c in r)]
    if not rows:
        raise DataError(f"floor file {p}: empty; write the header u,v,x,y and one row per floor mark")
    header = [c.strip().lower() for c in rows[0]]
    if header != ["u", "v", "x", "y"]:
        raise ConfigError(f"floor file {p}: header {','.join(rows[0])!r}; it must be u,v,x,y (pixel right, pixel down, "
                          "then the mark's x and y on the floor, metres)")
    values = []
    for i, r in enumerate(rows[1:], start=2):
        try:
            row = [float(c) for c in r]
        except ValueError:
            raise ConfigError(f"floor file {p}, line {i}: {','.join(r)!r} is not four numbers u,v,x,y") from None
        if len(row) != 4 or not all(math.isfinite(x) for x in row):
            raise ConfigError(f"floor file {p}, line {i}: {','.join(r)!r} is not four finite numbers u,v,x,y")
        values.append(row)
    a = np.array(values, np.float64).reshape(-1, 4)
    floor = Floor(a[:, :2], a[:, 2:], str(p))
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

    def note(self) -> str:
        """What the answer assumed of the camera, in words."""
        fov = 2 * math.degrees(math.atan(0.5 * self.camera.height / self.camera.focal))
        out = (f"camera from {self.n_marks} floor marks ({self.reprojection_px:.1f} px RMS reprojection"
               + ("; four marks fit any camera exactly, so nothing checks them: five or more are recommended"
                  if self.n_marks == MIN_MARKS else "") + f"), {self.camera.position[2]:.2f} m up, "
               f"{fov:.0f}° field of view")
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
                       len(floor.points))


def _over(camera: Camera, u: np.ndarray, v: np.ndarray, xy: np.ndarray) -> np.ndarray:
    """(n, 3) the point of each pixel's ray whose horizontal position is nearest ``xy`` (n, 2): where the ray passes
    over it."""
    d = camera.rays(u, v)
    c = np.asarray(camera.position)
    dh = d[:, :2]
    with np.errstate(divide="ignore", invalid="ignore"):
        s = np.sum((xy - c[:2]) * dh, axis=1) / np.sum(dh * dh, axis=1)
    return c + s[:, None] * d


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


def _first_flight(camera: Camera, t: np.ndarray, u: np.ndarray, v: np.ndarray, anchor: np.ndarray,
                  t_anchor: float) -> np.ndarray:
    """(len(t), 3) the centres of a flight that ends at the contact ``anchor`` (3,) at ``t_anchor`` and has none
    before it: the arc fitted to its pixels (:func:`_fit_arc`) when it is seen in :data:`FIT_FRAMES` frames or more,
    else each frame at the contact's depth (a throw across the view keeps its depth; the pixels' curvature over a
    short hop cannot fix it)."""
    if np.isfinite(u).sum() >= FIT_FRAMES:
        return _fit_arc(camera, t, u, v, anchor, t_anchor)
    return camera.position + camera.depth_of(anchor[None])[0] * camera.rays(u, v)


FIT_FRAMES = 20
"""Frames a flight needs for its pixels alone to fix its depth: the issue that set this path measured a 20-31-frame
arc's depth to 0.03-0.40 m and a 9-11-frame hop's only to 0.1-1 m (360p)."""


MAX_HEIGHT = 5.0
"""Metres: a centre placed higher (or below the floor) is left unknown, not reported."""
MAX_DISTANCE = 30.0
"""Metres from the camera, on the floor: a centre placed farther is left unknown."""
SMOOTH_S = 0.15
"""Seconds of the image rows' running quadratic fit before the flights are found: a tracker's pixel of noise,
twice differentiated over the 5 frames ``phases`` reads, is about half of g at 60 frames a second."""


def _smoothed(t: np.ndarray, v: np.ndarray, seconds: float) -> np.ndarray:
    """``v`` (n,) through a running quadratic fit over ``seconds`` (at least 5 frames; NaN kept); as it is at 30
    frames a second or slower."""
    dt = float(np.median(np.diff(t))) if len(t) > 1 else 1.0
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
    a parabola, meet in the image row (the bounce itself is blurred over the frames between)."""
    tb, ta = t[before][-5:], t[after][:5]
    vb, va = _quad(tb, v[before][-5:]), _quad(ta, v[after][:5])
    lo, hi = t[before][-1], t[after][0]
    roots = np.roots(np.polysub(vb, va)) if np.any(np.polysub(vb, va)) else []
    real = [float(r.real) for r in np.atleast_1d(roots) if abs(r.imag) < 1e-9 and lo - 1e-9 <= r.real <= hi + 1e-9]
    tc = min(real, key=lambda r: abs(r - 0.5 * (lo + hi))) if real else 0.5 * (lo + hi)
    ub, ua = _quad(tb, u[before][-5:]), _quad(ta, u[after][:5])
    return tc, 0.5 * (np.polyval(ub, tc) + np.polyval(ua, tc)), 0.5 * (np.polyval(vb, tc) + np.polyval(va, tc))


def centres(camera: Camera, t: np.ndarray, u: np.ndarray, v: np.ndarray, rest_height: float
            ) -> tuple[np.ndarray, np.ndarray]:
    """Each frame's 3-D centre (n, 3) metres, world (x, y on the floor, z up), from the tracked centre ``u``, ``v``
    (n,) pixels (NaN where lost) at times ``t`` (n,) s, seen by ``camera``; and the ground mask (n,) bool (frames
    after the last contact, or with no flight seen). NaN rows where the centre was lost or cannot be placed. Raises
    :class:`GeometryError` when no frame's ray meets the rest plane in front of the camera."""
    t, u, v = (np.asarray(a, np.float64) for a in (t, u, v))
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
    arcs, _ = phases(t, _smoothed(t, v, SMOOTH_S), depth / camera.focal, most=math.inf)
    arcs = [a[1:-1] for a in arcs if len(a) > 4]  # the flight frames proper (an arc's ends straddle a contact)
    if arcs and arcs[0][0] <= 3:  # a track that starts (or ends) in the air: its first frames' curvature is unknown
        arcs[0] = np.arange(0, arcs[0][-1] + 1)
    if arcs and arcs[-1][-1] >= n - 4:
        arcs[-1] = np.arange(arcs[-1][0], n)
    out = np.full((n, 3), np.nan)
    ground = on_plane.copy()
    if arcs:
        # Each contact: after an arc, before the next one (or before the slide that follows the last).
        rest = np.arange(arcs[-1][-1] + 1, n)
        ends = [(arcs[k], arcs[k + 1]) for k in range(len(arcs) - 1)] + ([(arcs[-1], rest)] if len(rest) >= 2 else [])
        contacts = []
        for before, after in ends:
            tc, uc, vc = _contact(t, u, v, before, after)
            point = _on_plane(camera, np.array([uc]), np.array([vc]), rest_height)[0]
            if np.isfinite(point).all():
                contacts.append((tc, point))
        if not contacts:  # flights, but no contact seen: the flights cannot be placed, the rest is on the ground
            in_arc = np.zeros(n, bool)
            in_arc[np.concatenate(arcs)] = True
            ground = on_plane & ~in_arc
        else:
            ground = on_plane & (t > contacts[-1][0])  # the slide after the last contact
        for k in range(len(contacts) + 1 if contacts else 0):  # the flights: before the first contact, then between
            lo = contacts[k - 1][0] if k > 0 else -math.inf
            hi = contacts[k][0] if k < len(contacts) else math.inf
            inside = np.flatnonzero((t > lo) & (t <= hi) & ~ground)
            if not len(inside) or (k == len(contacts) and k > 0):
                continue
            if k == 0:  # the throw's first flight, with no contact before it
                out[inside] = _first_flight(camera, t[inside], u[inside], v[inside], contacts[0][1], contacts[0][0])
                continue
            (ta, pa), (tb, pb) = contacts[k - 1], contacts[k]
            w = ((t[inside] - ta) / (tb - ta))[:, None]  # uniform horizontal motion between two contacts
            out[inside] = _over(camera, u[inside], v[inside], (1 - w) * pa[:2] + w * pb[:2])
    smoothed = _median5(np.where(ground[:, None], plane, np.nan)[:, :2])
    out[ground] = np.column_stack([smoothed[ground], np.full(ground.sum(), rest_height)])
    lost = ~(np.isfinite(u) & np.isfinite(v))
    far = np.linalg.norm(out[:, :2] - np.asarray(camera.position[:2]), axis=1) > MAX_DISTANCE
    out[lost | far | (out[:, 2] < 0.0) | (out[:, 2] > MAX_HEIGHT)] = np.nan  # not a place a throw could be: unknown
    return out, ground


def heights(camera: Camera, t: np.ndarray, u: np.ndarray, v: np.ndarray, rest_height: float) -> np.ndarray:
    """(n,) the centre's height above the floor, metres, in each frame (:func:`centres`); NaN where unknown."""
    return centres(camera, t, u, v, rest_height)[0][:, 2]


def on_floor(traj: Trajectory, floor: Floor, rest_height: float) -> tuple[Trajectory, Calibration]:
    """``traj`` (a track in pixels of a video of ``traj.width`` x ``traj.height_px``) with each frame's centre height
    in metres through the camera ``floor`` calibrates (:func:`centres`), and that calibration. ``rest_height``: the
    centre's height when the object lies on the floor, metres."""
    if not traj.width or not traj.height_px:
        raise ConfigError(f"{traj.source}: the track does not say its video's size; track the video itself with "
                          "--floor (a trajectory CSV keeps no frame size)")
    cal = calibrate(floor, traj.width, traj.height_px)
    xyz, _ = centres(cal.camera, traj.t, traj.u, traj.v, rest_height)
    seen = np.isfinite(xyz).all(axis=1)
    if seen.sum() < 3:
        raise GeometryError(f"{traj.source}: fewer than 3 frames could be placed through the floor's camera")
    scale = float(np.median(cal.camera.depth_of(xyz[seen]) / cal.camera.focal))
    return replace(traj, z=xyz[:, 2], ground_z=rest_height, units="m", height_per_pixel=scale), cal
