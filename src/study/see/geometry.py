"""Heights in metres from a video whose camera nobody measured: gravity is the ruler, the object's apparent size
says how far it is, and the frames where it lies on the ground say where the ground is.

A camera of unknown height, tilt, roll and focal length films an object of known size. In each frame the tracker
gives its image position (u, v) and its apparent diameter, pixels. Three facts pin the camera down:

* **Free flight is a parabola in metres.** Between bounces the object's centre moves as ``P0 + V t - g t^2 / 2``
  along the world's up direction (g = 9.81 m/s^2); its image is that curve seen through a pinhole. How fast the
  image falls, and how the parabola is turned and foreshortened, give the scale, the tilt and the roll.
* **The apparent size gives the distance**, up to the focal length: depth = focal x size / diameter. It is noisy
  (a tumbling box's silhouette changes with its orientation), so it enters as a weak measurement.
* **On the ground the centre is at its rest height**: a resting or sliding object's ray meets the ground plane
  at the camera's height below it, at the depth its size says.

:func:`recover` finds the flights and the ground frames from the image (:func:`phases`), fits the camera and each
flight by least squares (image positions to half a pixel, sizes to 12 %, weak priors on the roll and the field of
view), then turns every frame's image position into a height above the ground: the depth from its flight's fit,
the ground plane, or between them interpolated. :class:`Geometry` reports what was assumed and found; a video
without a free flight or without a frame on the ground raises :class:`GeometryError` saying which.

Object size: the diameter of the disc whose area is the object's *average* silhouette (``study.see.size.apparent_size``): a
ball's diameter; for a box, ``sqrt(surface / pi)`` (Cauchy: a convex body's mean projected area is a quarter of
its surface), 1.38 edges for a cube.

Conventions as ``study.see.camera``: world z up, metres; pixels u right, v down, the centre of the top-left pixel at
(0, 0); camera axes x right, y up, looking along -z; the principal point at the image centre, square pixels.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares

from study.core.errors import TrajectoryError, check_range

G = 9.81
"""Gravity, m/s^2."""
PIXEL_SD = 0.5
"""How far a tracked centre is trusted, pixels (one standard deviation)."""
SIZE_SD = 0.12
"""How far one frame's apparent size is trusted, as a fraction (a tumbling box's silhouette varies so much)."""
SCALE_SD = 0.05
"""How far the given object size is trusted, as a fraction."""
ROLL_SD_DEG = 5.0
"""Prior on the camera's roll, degrees: a hand-held or mounted camera is held about level."""
FOV_PRIOR_DEG = 65.0
"""Prior vertical field of view, degrees (a phone's main camera in landscape: about 50-70)."""
FOV_SD_LOG = 0.4
"""Width of that prior on the log focal length."""
MIN_ARC = 5
"""Fewest frames a free flight needs to count."""


class GeometryError(TrajectoryError):
    """The video does not show what the geometry needs: a free flight, or the object on the ground."""


@dataclass(frozen=True)
class Geometry:
    """The camera and the fit :func:`recover` found for one video."""

    tilt_deg: float
    """The camera's view below the horizon, degrees."""
    roll_deg: float
    """The image's turn about the view axis, degrees (positive: the horizon falls to the right)."""
    fov_deg: float
    """Vertical field of view, degrees."""
    camera_height: float
    """The camera's height above the ground, metres."""
    size_scale: float
    """The fitted apparent size over the given one."""
    flights: int
    """Free flights fitted."""
    flight_frames: int
    """Frames in them."""
    ground_frames: int
    """Frames with the object on the ground."""
    rms_px: float
    """Root mean square of the image positions' residuals, pixels."""

    def note(self) -> str:
        """One line: what the heights assume."""
        return (f"camera {self.camera_height:.2f} m up, tilted {self.tilt_deg:.0f} deg down, roll {self.roll_deg:.0f} deg, "
                f"field of view {self.fov_deg:.0f} deg; from {self.flights} free flight(s) ({self.flight_frames} frames, "
                f"gravity as the ruler) and {self.ground_frames} frames on the ground; fit {self.rms_px:.1f} px rms")


def _runs(mask: np.ndarray) -> list[np.ndarray]:
    """The index runs where ``mask`` (n,) bool is true, in order."""
    edges = np.flatnonzero(np.diff(np.concatenate([[0], mask.astype(np.int8), [0]])))
    return [np.arange(a, b) for a, b in zip(edges[::2], edges[1::2])]


def _rays(u: np.ndarray, v: np.ndarray, f: float, width: int, height: int) -> np.ndarray:
    """(n, 3) camera-frame directions through pixels ``u``, ``v``, scaled to unit depth."""
    return np.stack([(u + 0.5 - width / 2) / f, -(v + 0.5 - height / 2) / f, -np.ones_like(u)], axis=-1)


def _running_median(x: np.ndarray, k: int) -> np.ndarray:
    """(n,) the median of each ``k``-frame window of ``x`` (n,), centred, the ends padded with the end values."""
    pad = np.pad(x, k // 2, mode="edge")
    return np.median(np.lib.stride_tricks.sliding_window_view(pad, k), axis=1)


def _up(tilt: float, roll: float) -> np.ndarray:
    """(3,) the world's up direction in camera coordinates for a camera ``tilt`` radians down, ``roll`` radians."""
    return np.array([math.sin(roll) * math.cos(tilt), math.cos(roll) * math.cos(tilt), math.sin(tilt)])


def phases(t: np.ndarray, v: np.ndarray, scale: np.ndarray, most: float = 1.8, gap_s: float = 0.0
           ) -> tuple[list[np.ndarray], np.ndarray]:
    """The free flights and the ground frames, from the image alone.

    ``t`` (n,) seconds, ``v`` (n,) image rows, ``scale`` (n,) metres per pixel at the object (its size over its
    apparent diameter). A frame whose 5-frame image curvature, in metres, is a downward acceleration between 0.35 g
    and 1.8 g is in flight (a camera tilted 70 degrees still sees a third of g); one whose curvature is within
    0.25 g of none is rolling, sliding or resting: on the ground. ``most``: the upper bound, in g (infinite where
    ``scale`` only bounds the true scale from above). ``gap_s``: seconds of other frames between two runs of flight
    frames that make them one flight (a tracker's jump breaks the curvature for a frame or two); keep it under the
    frames a bounce's kink spans, about 3 on rows as they are, more on smoothed rows. Returns the flights (index
    arrays, each a run of flight frames widened by a frame on each side, at least :data:`MIN_ARC` long) and the
    ground mask (n,) bool."""
    n = len(t)
    ratio = np.full(n, np.nan)
    for i in range(2, n - 2):
        w = slice(i - 2, i + 3)
        if np.isfinite(v[w]).all():
            ratio[i] = 2 * np.polyfit(t[w] - t[i], v[w], 2)[0] * scale[i] / G  # image rows grow downwards
    flight = (ratio > 0.35) & (ratio < most)
    gap = int(round(gap_s / float(np.median(np.diff(t))))) if n > 1 and gap_s > 0 else 0
    runs = _runs(flight)
    for before, after in zip(runs, runs[1:]):
        if after[0] - before[-1] - 1 <= gap:
            flight[before[-1] + 1: after[0]] = True
    kink = (ratio < -0.35) & ~flight
    arcs = []
    for run in _runs(flight):
        lo, hi = run[0], run[-1]
        if lo > 0 and not kink[lo - 1]:
            lo -= 1
        if hi < n - 1 and not kink[hi + 1]:
            hi += 1
        if hi - lo + 1 >= MIN_ARC:
            arcs.append(np.arange(lo, hi + 1))
    in_arc = np.zeros(n, bool)
    for a in arcs:
        in_arc[a] = True
    ground = (np.abs(ratio) < 0.25) & ~in_arc
    return arcs, ground


@dataclass
class _Fit:
    tilt: float
    roll: float
    focal: float
    scale: float
    height: float
    states: np.ndarray  # (arcs, 6): each flight's start position and velocity, camera frame, metres and m/s
    cost: float


def _fit(t, u, v, diam, width, height, size, rest, arcs, ground, fov0: float) -> _Fit:
    """Least squares of the camera and the flights from one start (field of view ``fov0`` degrees)."""
    f0 = 0.5 * height / math.tan(math.radians(fov0) / 2)
    fp = 0.5 * height / math.tan(math.radians(FOV_PRIOR_DEG) / 2)
    g_idx = np.flatnonzero(ground)
    starts, curv = [], []
    for idx in arcs:  # each flight from its sizes: positions in the camera frame, a line and a parabola through them
        p = (f0 * size / diam[idx])[:, None] * _rays(u[idx], v[idx], f0, width, height)
        tau = t[idx] - t[idx[0]]
        c = np.polyfit(tau, p, 2)
        starts.append(np.concatenate([c[2], c[1]]))
        curv.append(-c[0])
    q = np.mean(curv, axis=0)
    tilt0 = float(np.clip(math.atan2(q[2], math.hypot(q[0], q[1])), math.radians(-10), math.radians(60)))
    roll0 = float(np.clip(math.atan2(q[0], q[1]), math.radians(-15), math.radians(15)))
    h0 = 1.0
    if len(g_idx):
        d = f0 * size / diam[g_idx]
        h0 = float(np.median(rest - d * (_rays(u[g_idx], v[g_idx], f0, width, height) @ _up(tilt0, roll0))))
    x0 = np.concatenate([[tilt0, roll0, math.log(f0), 0.0, min(max(h0, 0.05), 19.0)], np.ravel(starts)])
    lo = np.full(len(x0), -np.inf)
    hi = np.full(len(x0), np.inf)
    lo[:5] = [math.radians(-15), math.radians(-20), math.log(fp / 3), math.log(0.7), rest + 1e-3]
    hi[:5] = [math.radians(75), math.radians(20), math.log(fp * 3), math.log(1.4), 20.0]
    x0[:5] = np.clip(x0[:5], lo[:5] + 1e-9, hi[:5] - 1e-9)

    def residuals(x: np.ndarray) -> np.ndarray:
        tilt, roll, lf, ls, hc = x[:5]
        f, lam, up = math.exp(lf), math.exp(ls), _up(tilt, roll)
        out = []
        for j, idx in enumerate(arcs):
            tau = (t[idx] - t[idx[0]])[:, None]
            p = x[5 + 6 * j: 8 + 6 * j] + x[8 + 6 * j: 11 + 6 * j] * tau - 0.5 * G * up * tau**2
            d = np.maximum(-p[:, 2], 1e-3)
            out += [(width / 2 + f * p[:, 0] / d - 0.5 - u[idx]) / PIXEL_SD,
                    (height / 2 - f * p[:, 1] / d - 0.5 - v[idx]) / PIXEL_SD,
                    np.log(f * lam * size / d / diam[idx]) / SIZE_SD]
        if len(g_idx):
            down = np.minimum(_rays(u[g_idx], v[g_idx], f, width, height) @ up, -1e-6)
            d = np.maximum((rest - hc) / down, 1e-3)
            out.append(np.log(f * lam * size / d / diam[g_idx]) / SIZE_SD)
        out.append(np.array([roll / math.radians(ROLL_SD_DEG), (lf - math.log(fp)) / FOV_SD_LOG, ls / SCALE_SD]))
        return np.concatenate(out)

    r = least_squares(residuals, x0, bounds=(lo, hi), x_scale="jac", method="trf", loss="soft_l1", f_scale=2.0)
    tilt, roll, lf, ls, hc = r.x[:5]
    return _Fit(float(tilt), float(roll), math.exp(lf), math.exp(ls), float(hc), r.x[5:].reshape(-1, 6), float(r.cost))


def recover(t: np.ndarray, u: np.ndarray, v: np.ndarray, diam: np.ndarray, width: int, height: int,
            object_size: float, rest_height: float, source: object = "trajectory") -> tuple[np.ndarray, Geometry]:
    """Heights of the object's centre above the ground, metres, from its image alone.

    ``t`` (n,) seconds; ``u``, ``v`` (n,) pixels; ``diam`` (n,) the blob's equivalent-disc diameter, pixels (NaN
    where not measured: filled from its neighbours); ``width`` x ``height`` the frame, pixels; ``object_size``
    metres (``study.see.size.apparent_size``); ``rest_height`` the centre's height resting on the ground, metres. Returns
    (n,) float64 heights (NaN where ``u`` or ``v`` is) and the :class:`Geometry`. Raises :class:`GeometryError`
    for a video without a free flight of :data:`MIN_ARC` frames or without a frame on the ground."""
    check_range("object_size (metres)", object_size, 0.0, 10.0, lo_open=True)
    check_range("rest_height (metres)", rest_height, 0.0, 10.0)
    t, u, v, diam = (np.asarray(a, np.float64) for a in (t, u, v, diam))
    ok = np.isfinite(u) & np.isfinite(v)
    if ok.sum() < 2 * MIN_ARC:
        raise GeometryError(f"{source}: {int(ok.sum())} tracked frames; the geometry needs at least {2 * MIN_ARC}")
    good = ok & np.isfinite(diam) & (diam > 0)
    if good.sum() < 2:
        raise GeometryError(f"{source}: the object's size was measured in fewer than 2 frames")
    log_d = np.interp(t, t[good], np.log(diam[good]))
    diam = np.exp(log_d)
    scale = object_size / diam
    arcs, ground = phases(t, np.where(ok, v, np.nan), scale)
    if not arcs:
        raise GeometryError(f"{source}: no free flight of {MIN_ARC} frames or more (nothing falls freely in view); "
                            "gravity is the ruler, so film the throw, not only the landing")
    if not ground.any():
        raise GeometryError(f"{source}: the object is never on the ground in view (no rolling, sliding or resting "
                            "frame); film it until it lands")
    fit = min((_fit(t, u, v, diam, width, height, object_size, rest_height, arcs, ground, fov)
               for fov in (45.0, 65.0, 85.0)), key=lambda r: r.cost)
    up = _up(fit.tilt, fit.roll)
    depth = np.full(len(t), np.nan)
    resid = []
    for j, idx in enumerate(arcs):
        tau = (t[idx] - t[idx[0]])[:, None]
        p = fit.states[j, :3] + fit.states[j, 3:] * tau - 0.5 * G * up * tau**2
        depth[idx] = -p[:, 2]
        resid += list(width / 2 + fit.focal * p[:, 0] / depth[idx] - 0.5 - u[idx])
        resid += list(height / 2 - fit.focal * p[:, 1] / depth[idx] - 0.5 - v[idx])
    g_idx = np.flatnonzero(ground)
    # on the ground: the depth where the ray meets the ground plane, where it meets it steeply enough; where it
    # grazes the floor, the depth its size says (the plane's would blow up)
    down = _rays(u[g_idx], v[g_idx], fit.focal, width, height) @ up
    by_size = fit.focal * fit.scale * object_size / _running_median(diam, 5)[g_idx]
    by_plane = (rest_height - fit.height) / np.minimum(down, -1e-9)
    depth[g_idx] = np.where((by_plane > 0) & (by_plane < 2 * by_size), by_plane, by_size)
    known = np.isfinite(depth)
    depth = np.interp(t, t[known], depth[known])
    z = fit.height + depth * (_rays(u, v, fit.focal, width, height) @ up)
    geom = Geometry(tilt_deg=math.degrees(fit.tilt), roll_deg=math.degrees(fit.roll),
                    fov_deg=2 * math.degrees(math.atan(0.5 * height / fit.focal)), camera_height=fit.height,
                    size_scale=fit.scale, flights=len(arcs), flight_frames=int(sum(len(a) for a in arcs)),
                    ground_frames=int(ground.sum()), rms_px=float(np.sqrt(np.mean(np.square(resid)))))
    return np.where(ok, z, np.nan), geom
