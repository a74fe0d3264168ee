"""What a camera and a tracker deliver instead of the simulator's exact positions: an observation model.

The simulator records the object's centre to the micrometre at exactly 30 frames a second. A car's
camera and a colour tracker do not (``study.see`` measures how far they do not). Each function here
takes trajectories ``x`` (n, T, 3) metres sampled at ``fps`` and returns what the classifier would be
given instead, in the same shape and units, seeded by the ``rng`` it is handed:

- :func:`noise`: white Gaussian position error of a given size;
- :func:`tracker_noise`: the tracker's error as :class:`TrackerNoise` models it (fitted on rendered video,
  ``study.methods.tracker_model``): a per-throw offset plus noise correlated from frame to frame, of one size in
  flight and another while the object touches the ground (:func:`in_contact`); white noise is its special case;
- :func:`drop`: frames the tracker loses (motion blur, occlusion), filled as the tracker fills them
  (:func:`fill_runs`: linear interpolation over short gaps);
- :func:`camera_rate`: another camera frame rate, resampled to the model's by linear interpolation, as
  the tracking path (``study.see.gaps.resample``) does;
- :func:`perspective`: the height a single camera at a distance and an angle recovers from the image
  row, with the pixel scale taken from the object's apparent size (as ``study.see.track`` does);
- :func:`height_scale`: an unknown error in that scale.

:class:`Observation` composes them; :func:`randomised` draws one per trajectory (for training a
classifier that expects observed positions). :func:`any_camera` draws what a user's own camera gives instead: a
camera anywhere (:class:`AnyCamera`) and heights read from the image by one scale, the object's mean apparent size
(:func:`filmed`), as ``study classify VIDEO --object-size D`` reads them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from study.core.errors import ConfigError, TrajectoryError, check_range

Z = 2
"""Column of the height in a trajectory."""


def height_only(x: np.ndarray) -> np.ndarray:
    """What one camera's height leaves of trajectories ``x`` (..., 3) metres: X and Y set to 0, Z kept (for a
    classifier that reads all three channels)."""
    x = np.asarray(x)
    return np.concatenate([np.zeros_like(x[..., :2]), x[..., 2:]], axis=-1)


def _check(x: np.ndarray, what: str = "trajectories") -> np.ndarray:
    x = np.asarray(x, dtype=np.float64)
    if x.ndim != 3 or x.shape[2] != 3:
        raise TrajectoryError(f"{what}: shape {x.shape}; expected (n, T, 3) world x, y, z in metres")
    if not np.isfinite(x).all():
        raise TrajectoryError(f"{what}: NaN or infinite positions; an observation needs finite ones")
    return x


def noise(x: np.ndarray, sigma: float | np.ndarray, rng: np.random.Generator, dims: tuple[int, ...] = (Z,)) -> np.ndarray:
    """``x`` plus independent Gaussian errors of standard deviation ``sigma`` (metres; a scalar, or (n,) one
    per trajectory) on the columns ``dims`` (the height only, by default: one camera sees a height)."""
    x = _check(x).copy()
    s = np.broadcast_to(np.asarray(sigma, dtype=np.float64), (len(x),))
    if not np.isfinite(s).all() or (s < 0).any():
        raise ConfigError(f"noise sigma = {sigma!r} m; it must be >= 0 (the tracker's error, in metres)")
    for d in dims:
        x[:, :, d] += rng.standard_normal(x.shape[:2]) * s[:, None]
    return x


REST_HEIGHT = 0.1
"""The study's object's centre height at rest, metres: the 20 cm cube on a face (``study.simulate.scene.Shape``)."""
CONTACT_BAND = 0.005
"""A frame is in contact when the exact centre is at most this far above its rest height, metres: the object lies
or slides on a face (a tumbling box touching the ground on an edge or a corner only, for a frame, does not count)."""


def in_contact(z: np.ndarray, rest_height: float = REST_HEIGHT, band: float = CONTACT_BAND) -> np.ndarray:
    """Frames in which the object touches the ground: the exact centre heights ``z`` (any shape, metres) at most
    ``band`` above ``rest_height``; bool, the shape of ``z``."""
    return np.asarray(z, dtype=np.float64) <= rest_height + band


@dataclass(frozen=True)
class TrackerNoise:
    """The tracker's height error, one throw at a time: ``e_t = o + s_t u_t``, where

    - ``o`` is the throw's offset, one draw per throw, Gaussian with standard deviation :attr:`offset`;
    - ``u`` is a stationary Gaussian AR(1) series of unit variance, ``u_t = rho u_{t-1} + sqrt(1 - rho^2) w_t``
      (``w`` white), so the error keeps its sign and size from one frame to the next with autocorrelation
      :attr:`rho`;
    - ``s_t`` is :attr:`flight` while the object is in the air and :attr:`contact` while it touches the ground
      (:func:`in_contact` on the exact heights).

    So the position error's standard deviation is ``sqrt(offset^2 + s^2)`` and the frame-to-frame error's (what a
    velocity reads) ``s sqrt(2 (1 - rho))`` within either state. White noise of ``sigma`` is the special case
    ``offset = 0``, ``rho = 0``, ``flight = contact = sigma`` (:meth:`white`), and draws exactly what
    :func:`noise` draws from the same generator.
    """

    flight: float = 0.0
    """Standard deviation of the error about its offset while the object is in the air, metres."""
    contact: float = 0.0
    """The same while the object touches the ground, metres."""
    offset: float = 0.0
    """Standard deviation of the per-throw offset, metres (one draw per throw, the same in every frame)."""
    rho: float = 0.0
    """Lag-1 autocorrelation of the varying error, in (-1, 1) (0: white from frame to frame)."""
    band: float = CONTACT_BAND
    """How far above its rest height the exact centre counts as touching the ground, metres (:func:`in_contact`)."""

    @classmethod
    def white(cls, sigma: float) -> TrackerNoise:
        """White noise of standard deviation ``sigma`` metres in every frame: no offset, no correlation."""
        return cls(flight=sigma, contact=sigma)

    def validate(self, where: str = "TrackerNoise") -> None:
        """Raise :class:`ConfigError` naming the first field out of range (``where.field``)."""
        for name in ("flight", "contact", "offset"):
            check_range(f"{where}.{name} (metres)", getattr(self, name), 0.0, 10.0)
        check_range(f"{where}.rho", self.rho, -1.0, 1.0, lo_open=True, hi_open=True)
        check_range(f"{where}.band (metres)", self.band, 0.0, 10.0)

    @property
    def exact(self) -> bool:
        """No error at all."""
        return self.flight == 0 and self.contact == 0 and self.offset == 0

    def position_sd(self, in_contact: bool = False) -> float:
        """Standard deviation of the position error in flight (or in contact), offset included, metres."""
        return math.hypot(self.offset, self.contact if in_contact else self.flight)

    def describe(self) -> str:
        """The model in words, millimetres: ``offset 8.0 mm, 23.0 mm in flight, 8.0 mm in contact, lag-1
        autocorrelation 0.84``."""
        return (f"offset {1000 * self.offset:.1f} mm, {1000 * self.flight:.1f} mm in flight, "
                f"{1000 * self.contact:.1f} mm in contact, lag-1 autocorrelation {self.rho:.2f}")

    def step_sd(self, in_contact: bool = False) -> float:
        """Standard deviation of the error's change from one frame to the next within one state, metres."""
        s = self.contact if in_contact else self.flight
        return s * math.sqrt(2 * (1 - self.rho))

    def draw(self, contact: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """The errors (n, T) metres of ``n`` throws whose frames touch the ground where ``contact`` (n, T) bool."""
        self.validate()
        contact = np.asarray(contact, dtype=bool)
        if contact.ndim != 2:
            raise TrajectoryError(f"contact flags: shape {contact.shape}; expected (n, T)")
        w = rng.standard_normal(contact.shape)  # first, so that white noise draws what noise() draws
        u = w
        if self.rho != 0:
            u = np.empty_like(w)
            u[:, 0] = w[:, 0]
            c = math.sqrt(1 - self.rho**2)
            for t in range(1, w.shape[1]):
                u[:, t] = self.rho * u[:, t - 1] + c * w[:, t]
        e = np.where(contact, self.contact, self.flight) * u
        if self.offset > 0:
            e = e + rng.standard_normal(len(e))[:, None] * self.offset
        return e


def tracker_noise(x: np.ndarray, model: TrackerNoise, rng: np.random.Generator,
                  rest_height: float = REST_HEIGHT) -> np.ndarray:
    """``x`` (n, T, 3) metres with the tracker's height error drawn from ``model`` added to the height; which
    frames touch the ground is read from ``x``'s own heights (:func:`in_contact`, the exact ones)."""
    x = _check(x).copy()
    model.validate()
    x[:, :, Z] += model.draw(in_contact(x[:, :, Z], rest_height, model.band), rng)
    return x


def fill_runs(values: np.ndarray, measured: np.ndarray, max_gap: int) -> tuple[np.ndarray, np.ndarray]:
    """The tracker's gap filling on one series: ``values`` (T, k) with rows where ``measured`` (T,) bool is
    False replaced by linear interpolation between their measured neighbours, for runs of at most
    ``max_gap`` frames; longer runs, and runs at either end, stay unfilled (nothing is invented).

    Returns the filled values (T, k) and ``segment`` (T,) int: the piece each row belongs to after
    splitting at the long gaps (-1 where still missing).
    """
    check_range("max_gap", max_gap, 0, 10_000)
    values = np.array(values, dtype=np.float64, copy=True)
    seg = np.full(len(values), -1, np.int32)
    idx = np.flatnonzero(measured)
    if len(idx) == 0:
        return values, seg
    s = 0
    seg[idx[0]] = 0
    for a, b in zip(idx[:-1], idx[1:]):
        gap = b - a - 1
        if gap > max_gap:
            s += 1
        elif gap > 0:
            w = ((np.arange(a + 1, b) - a) / (b - a))[:, None]
            values[a + 1 : b] = values[a] + w * (values[b] - values[a])
            seg[a + 1 : b] = s
        seg[b] = s
    return values, seg


def drop(x: np.ndarray, share: float | np.ndarray, rng: np.random.Generator, max_gap: int = 6) -> np.ndarray:
    """``x`` with each frame lost with probability ``share`` (a scalar, or (n,)), refilled as the tracker
    would: :func:`fill_runs` over gaps of up to ``max_gap`` frames. What the tracker cannot fill (a longer
    gap, or lost frames at the start or end) holds the nearest frame it has, since the classifier needs
    every frame; the first frame is always kept, so every trajectory starts where it was launched."""
    x = _check(x)
    p = np.broadcast_to(np.asarray(share, dtype=np.float64), (len(x),))
    if not np.isfinite(p).all() or (p < 0).any() or (p >= 1).any():
        raise ConfigError(f"drop share = {share!r}; it must lie in [0, 1) (the fraction of frames lost)")
    out = np.empty_like(x)
    lost = rng.random(x.shape[:2]) < p[:, None]
    lost[:, 0] = False
    for i in range(len(x)):
        filled, seg = fill_runs(x[i], ~lost[i], max_gap)
        have = np.flatnonzero(seg >= 0)
        nearest = have[np.clip(np.searchsorted(have, np.arange(len(seg))), 0, len(have) - 1)]
        out[i] = np.where((seg >= 0)[:, None], filled, filled[nearest])
    return out


def camera_rate(x: np.ndarray, fps: float, camera_fps: float, out_fps: float | None = None) -> np.ndarray:
    """``x`` (n, T, 3) at ``fps`` as a camera at ``camera_fps`` sees it, resampled to ``out_fps`` (default
    ``fps``) by linear interpolation, as the tracking path resamples a video to the model's rate.

    The camera samples the true motion at its own frame times, so ``fps`` must be a whole multiple of
    ``camera_fps`` (simulate at a high rate for a fast camera). Beyond the last camera frame the last
    value is held.
    """
    x = _check(x)
    check_range("camera_fps", camera_fps, 1.0, 10_000.0)
    out_fps = fps if out_fps is None else out_fps
    step = fps / camera_fps
    if abs(step - round(step)) > 1e-9 or round(step) < 1:
        raise ConfigError(f"camera_fps = {camera_fps:g}: the data's {fps:g} fps must be a whole multiple of it; "
                          "simulate at a higher frame rate for a faster camera")
    seen = x[:, :: int(round(step))]  # (n, Tc, 3): the camera's frames
    t_cam = np.arange(seen.shape[1]) / camera_fps
    t_out = np.arange(int(math.floor((x.shape[1] - 1) / fps * out_fps + 1e-9)) + 1) / out_fps
    out = np.empty((len(x), len(t_out), 3))
    for i in range(len(x)):
        for d in range(3):
            out[i, :, d] = np.interp(t_out, t_cam, seen[i, :, d])
    return out


CAMERAS = ("side",)
"""Camera set-ups :class:`Camera` knows: ``'side'``, a pinhole camera looking at the throw across the road."""


@dataclass(frozen=True)
class Camera:
    """A pinhole camera aimed at the launch point, for :func:`perspective`."""

    distance: float = 4.0
    """Metres from the camera to the launch point (horizontally, along its view), as in the rendered videos."""
    elevation: float = 0.0
    """Degrees the camera looks down (0: level, at the aim height)."""
    aim_height: float = 0.6
    """Height the camera looks at over the launch point, metres."""
    fovy: float = 45.0
    """Vertical field of view, degrees."""
    rows: int = 240
    """Image height, pixels."""
    kind: str = "side"
    """One of :data:`CAMERAS`."""

    def metres_per_pixel(self, depth: float | None = None) -> float:
        """The size of one pixel at ``depth`` metres along the view (default: the camera's distance), metres:
        ``2 depth tan(fovy / 2) / rows``."""
        self.validate()
        return 2 * (self.distance if depth is None else depth) * math.tan(math.radians(self.fovy) / 2) / self.rows

    def validate(self) -> None:
        if self.kind not in CAMERAS:
            raise ConfigError(f"Camera.kind = {self.kind!r} is unknown; use one of {', '.join(CAMERAS)}")
        check_range("Camera.distance", self.distance, 0.5, 1000.0)
        check_range("Camera.elevation", self.elevation, 0.0, 80.0)
        check_range("Camera.fovy", self.fovy, 1.0, 170.0, lo_open=True)
        check_range("Camera.rows", self.rows, 16, 100_000)


def turned_across_view(x: np.ndarray) -> np.ndarray:
    """Each trajectory of ``x`` (n, T, 3) turned about the vertical through its first point so that its
    overall horizontal travel (last point minus first) points along +x, across a camera looking along +y."""
    x = np.array(x, dtype=np.float64, copy=True)
    d = x[:, -1, :2] - x[:, 0, :2]
    angle = -np.arctan2(d[:, 1], d[:, 0])  # (n,)
    c, s = np.cos(angle)[:, None], np.sin(angle)[:, None]
    rel = x[:, :, :2] - x[:, :1, :2]
    x[:, :, 0] = x[:, :1, 0] + c * rel[:, :, 0] - s * rel[:, :, 1]
    x[:, :, 1] = x[:, :1, 1] + s * rel[:, :, 0] + c * rel[:, :, 1]
    return x


def perspective(x: np.ndarray, camera: Camera, rest_height: float = REST_HEIGHT) -> np.ndarray:
    """The heights one camera and the tracker recover: (n, T, 3) with x = y = 0 (one camera gives no depth)
    and z from the image row, as ``study.see.track`` computes it.

    Each centre is projected into the camera's image; the tracker's ground row is the lowest image row
    the object reaches (its largest v), and its scale, metres per pixel, is the object's size over its
    apparent size at its median depth. So an object moving towards or away from the camera, or one seen
    from above, has its height distorted as on video; ``rest_height`` is added back, as the tracker does.
    Each throw is first turned about the vertical through its launch point so that it crosses the
    camera's view (:func:`turned_across_view`), as the rendered videos are filmed.
    """
    x = turned_across_view(_check(x))
    camera.validate()
    e = math.radians(camera.elevation)
    back = np.array([0.0, -math.cos(e), math.sin(e)])  # from the aim point towards the camera
    aim = np.array([0.0, 0.0, camera.aim_height])
    eye = aim + camera.distance * back
    forward = -back
    up = np.array([0.0, math.sin(e), math.cos(e)])  # image up, orthogonal to forward
    rel = x - eye  # (n, T, 3)
    depth = rel @ forward  # (n, T)
    if (depth <= 0.05).any():
        raise ConfigError(f"Camera.distance = {camera.distance:g} m: the object passes behind the camera; move it back")
    f = 0.5 * camera.rows / math.tan(math.radians(camera.fovy) / 2)  # focal length, pixels
    v = -f * (rel @ up) / depth  # (n, T) image row, down positive (offset irrelevant: a ground row is subtracted)
    ground = v.max(axis=1, keepdims=True)
    # metres per pixel: the object's size over its apparent size (object_size * f / depth) at its median depth
    scale = np.median(depth, axis=1, keepdims=True) / f
    out = np.zeros_like(x)
    out[:, :, Z] = (ground - v) * scale + rest_height
    return out


def height_scale(x: np.ndarray, factor: float | np.ndarray, rest_height: float = REST_HEIGHT) -> np.ndarray:
    """Heights above the resting height multiplied by ``factor`` (a scalar or (n,)): a wrong pixel scale."""
    x = _check(x).copy()
    k = np.broadcast_to(np.asarray(factor, dtype=np.float64), (len(x),))
    if not np.isfinite(k).all() or (k <= 0).any():
        raise ConfigError(f"height scale factor = {factor!r}; it must be > 0")
    x[:, :, Z] = rest_height + (x[:, :, Z] - rest_height) * k[:, None]
    return x


@dataclass(frozen=True)
class Observation:
    """One way of observing a trajectory; the default observes it exactly. :meth:`apply` runs, in order:
    the camera (its frame rate, then its perspective if ``camera`` is set), the tracker's noise (white, or
    ``tracker``'s), its dropped frames, and a height-scale error."""

    noise: float = 0.0
    """Standard deviation of the tracker's position error as white noise, metres (0 where ``tracker`` is set)."""
    drop: float = 0.0
    """Share of frames the tracker loses, in [0, 1)."""
    camera_fps: float | None = None
    """Camera frame rate, frames per second; None: the data's own."""
    camera: Camera | None = None
    """The camera whose perspective turns image rows into heights; None: heights as simulated."""
    height_factor: float = 1.0
    """Factor on every height above the resting height (an error in the pixel scale)."""
    max_gap: int = 6
    """Longest gap the tracker fills, frames (``study.see.config.TrackConfig.max_gap``)."""
    tracker: TrackerNoise | None = None
    """The tracker's error as its fitted model draws it (:class:`TrackerNoise`); None: white noise of ``noise``."""

    def validate(self) -> None:
        check_range("Observation.noise (metres)", self.noise, 0.0, 10.0)
        if self.tracker is not None:
            self.tracker.validate("Observation.tracker")
            if self.noise != 0:
                raise ConfigError(f"Observation.noise = {self.noise!r} with a tracker model: set one of them "
                                  "(white noise of noise, or tracker's), the other to its default")
        check_range("Observation.drop", self.drop, 0.0, 1.0, hi_open=True)
        check_range("Observation.height_factor", self.height_factor, 0.0, 100.0, lo_open=True)
        if self.camera_fps is not None:
            check_range("Observation.camera_fps", self.camera_fps, 1.0, 10_000.0)
        if self.camera is not None:
            self.camera.validate()

    def apply(self, x: np.ndarray, fps: float, rng: np.random.Generator, out_fps: float | None = None,
              rest_height: float = REST_HEIGHT) -> np.ndarray:
        """``x`` (n, T, 3) metres at ``fps`` as observed: (n, T', 3) at ``out_fps`` (default ``fps``)."""
        self.validate()
        out_fps = fps if out_fps is None else out_fps
        y = _check(x)
        if self.camera_fps is not None or out_fps != fps:
            y = camera_rate(y, fps, self.camera_fps or fps, out_fps)
        if self.camera is not None:
            y = perspective(y, self.camera, rest_height=rest_height)
        if self.tracker is not None and not self.tracker.exact:
            y = tracker_noise(y, self.tracker, rng, rest_height=rest_height)
        elif self.noise > 0:
            y = noise(y, self.noise, rng)
        if self.drop > 0:
            y = drop(y, self.drop, rng, self.max_gap)
        if self.height_factor != 1.0:
            y = height_scale(y, self.height_factor, rest_height)
        return y

    def observe(self, x: np.ndarray, fps: float, seed: int, frames: int | None = None,
                rest_height: float = REST_HEIGHT) -> np.ndarray:
        """``x`` (n, T, 3) metres as observed (:meth:`apply`), drawn from a generator seeded by ``seed``, cut
        to its first ``frames`` frames (all if None): (n, frames, 3) metres."""
        y = self.apply(x, fps, np.random.default_rng(seed), rest_height=rest_height)
        return y[:, :frames] if frames else y

    def replace(self, **changes: Any) -> Observation:
        """This observation with ``changes`` applied (a sweep's point), validated."""
        new = replace(self, **changes)
        new.validate()
        return new


@dataclass(frozen=True)
class Randomisation:
    """Ranges from which :func:`randomised` draws each trajectory's observation (uniform unless stated)."""

    noise: tuple[float, float] = (0.0, 0.03)
    """Tracker error, metres."""
    drop: tuple[float, float] = (0.0, 0.3)
    """Share of frames lost."""
    camera_fps: tuple[float, ...] = (15.0, 30.0)
    """Camera frame rates, chosen with equal chance (no faster than the data's)."""
    distance: tuple[float, float] = (3.0, 12.0)
    """Camera distance, metres."""
    elevation: tuple[float, float] = (0.0, 30.0)
    """Camera elevation, degrees."""
    height_factor: tuple[float, float] = (0.8, 1.25)
    """Height-scale factor, log-uniform."""


def randomised(x: np.ndarray, fps: float, rng: np.random.Generator, ranges: Randomisation = Randomisation(),
               rest_height: float = REST_HEIGHT) -> np.ndarray:
    """Each trajectory of ``x`` through an observation drawn from ``ranges``: what a classifier is trained
    on when it must cope with whatever camera and tracker it gets. (n, T, 3) in, (n, T, 3) out."""
    x = _check(x)
    out = np.empty_like(x)
    for i in range(len(x)):
        ob = Observation(
            noise=float(rng.uniform(*ranges.noise)), drop=float(rng.uniform(*ranges.drop)),
            camera_fps=float(rng.choice(ranges.camera_fps)),
            camera=Camera(distance=float(rng.uniform(*ranges.distance)), elevation=float(rng.uniform(*ranges.elevation))),
            height_factor=float(np.exp(rng.uniform(*np.log(ranges.height_factor)))),
        )
        out[i] = ob.apply(x[i : i + 1], fps, rng, rest_height=rest_height)[0]
    return out


@dataclass(frozen=True)
class AnyCamera:
    """A pinhole camera set up by a user, not aimed across the throw: for :func:`filmed`. It stands ``distance`` from
    the middle of the throw's path (horizontally), ``height`` above the floor, turned ``yaw`` away from square-on
    and tilted ``tilt`` down, as the camera sweep's clips are filmed (``study.methods.sweep.camera``)."""

    height: float = 1.0
    """Camera height above the floor, metres."""
    tilt: float = 10.0
    """Degrees below the horizon."""
    yaw: float = 0.0
    """Degrees away from square-on to the throw (either sign)."""
    distance: float = 4.0
    """Horizontal metres from the middle of the throw's path."""

    def validate(self) -> None:
        check_range("AnyCamera.height (metres)", self.height, 0.0, 100.0, lo_open=True)
        check_range("AnyCamera.tilt (degrees)", self.tilt, -80.0, 80.0)
        check_range("AnyCamera.yaw (degrees)", self.yaw, -89.0, 89.0)
        check_range("AnyCamera.distance (metres)", self.distance, 0.5, 1000.0)


def _frame(camera: AnyCamera, mid: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The camera's eye (3,), forward (3,) and image-up (3,) unit vectors for a throw whose path's middle is ``mid``."""
    h, t = math.radians(90.0 + camera.yaw), math.radians(camera.tilt)  # square-on: looking along +y
    forward = np.array([math.cos(t) * math.cos(h), math.cos(t) * math.sin(h), -math.sin(t)])
    right = np.array([math.sin(h), -math.cos(h), 0.0])
    eye = np.array([mid[0] - camera.distance * math.cos(h), mid[1] - camera.distance * math.sin(h), camera.height])
    return eye, forward, np.cross(right, forward)


def filmed(x: np.ndarray, camera: AnyCamera, size_factor: float = 1.0,
           rest_height: float = REST_HEIGHT) -> np.ndarray | None:
    """The heights a user's path reads from a video of throw ``x`` (T, 3) metres filmed by ``camera``: (T, 3) with
    x = y = 0 and z from the image row; None where the object passes within 0.3 m of the camera's plane.

    The throw is first turned to cross the world's x axis (:func:`turned_across_view`), as the sweep's throws are.
    Each centre is projected; the ground is the lowest row the centre reaches; the scale, metres per pixel, is the
    object's size over its root-mean-square apparent size (``f size / depth``) over the frames, times
    ``size_factor`` (an error in the blob's measured size): ``study.see.scale.read_scale`` with ``how='mean'``.
    The focal length cancels, so the field of view and the frame size do not matter here."""
    camera.validate()
    x = turned_across_view(_check(x[None]))[0]
    eye, forward, up = _frame(camera, x.mean(axis=0))
    rel = x - eye  # (T, 3)
    depth = rel @ forward  # (T,)
    if (depth <= 0.3).any():
        return None
    v = -(rel @ up) / depth  # image row over the focal length, down positive
    scale = size_factor / math.sqrt(float(np.mean(depth**-2.0)))  # metres per (pixel over focal length)
    out = np.zeros_like(x)
    out[:, Z] = (v.max() - v) * scale + rest_height
    return out


@dataclass(frozen=True)
class CameraFamily:
    """One family of the cameras a user might film with: a range per quantity, each drawn uniformly."""

    key: str
    """Its name in the results (``usercamera.sweep.<key>``)."""
    height: tuple[float, float]
    """Camera height above the floor, metres."""
    tilt: tuple[float, float]
    """Tilt below the horizon, degrees."""
    yaw: tuple[float, float]
    """Yaw away from square-on to the throw, degrees (either side)."""
    distance: tuple[float, float]
    """Horizontal distance from the middle of the throw, metres."""


CAMERA_FAMILIES: tuple[CameraFamily, ...] = (
    CameraFamily("square-on", height=(0.8, 1.5), tilt=(0.0, 10.0), yaw=(0.0, 15.0), distance=(3.0, 5.0)),
    CameraFamily("low", height=(0.3, 0.6), tilt=(0.0, 10.0), yaw=(0.0, 60.0), distance=(2.0, 8.0)),
    CameraFamily("oblique", height=(0.3, 2.0), tilt=(0.0, 45.0), yaw=(30.0, 60.0), distance=(2.0, 8.0)),
    CameraFamily("high", height=(1.4, 2.0), tilt=(20.0, 45.0), yaw=(0.0, 60.0), distance=(2.0, 8.0)),
)
"""The camera families, defined once: the camera sweep films each (``study.methods.sweep``), :class:`AnyCameraRanges`
spans them all, and the results report each. Together they cover 0.3-2 m high, 0-45 degrees down, +-60 degrees,
2-8 m away."""


def _span(quantity: str) -> tuple[float, float]:
    """The range of ``quantity`` that covers every camera family."""
    ranges = [getattr(f, quantity) for f in CAMERA_FAMILIES]
    return min(lo for lo, _ in ranges), max(hi for _, hi in ranges)


@dataclass(frozen=True)
class AnyCameraRanges:
    """Ranges from which :func:`any_camera` draws each throw's camera and tracker (uniform unless stated): the camera
    families' (:data:`CAMERA_FAMILIES`), all together."""

    height: tuple[float, float] = _span("height")
    """Camera height, metres."""
    tilt: tuple[float, float] = _span("tilt")
    """Tilt below the horizon, degrees."""
    yaw: tuple[float, float] = (-_span("yaw")[1], _span("yaw")[1])
    """Yaw from square-on, degrees (either side)."""
    distance: tuple[float, float] = _span("distance")
    """Horizontal distance, metres."""
    size_factor: tuple[float, float] = (0.9, 1.1)
    """Error of the blob's measured size, log-uniform (one frame's is about 7.5 % off; the mean over a video less)."""
    noise: tuple[float, float] = (0.0, 0.03)
    """Tracker error, metres."""
    drop: tuple[float, float] = (0.0, 0.3)
    """Share of frames lost."""
    camera_fps: tuple[float, ...] = (15.0, 30.0)
    """Camera frame rates, chosen with equal chance (no faster than the data's)."""
    tries: int = 20
    """Cameras drawn for a throw before one that keeps it in front is found; each miss moves the next 1 m back."""


def any_camera(x: np.ndarray, fps: float, rng: np.random.Generator, ranges: AnyCameraRanges = AnyCameraRanges(),
               rest_height: float = REST_HEIGHT) -> np.ndarray:
    """Each trajectory of ``x`` (n, T, 3) metres as a user's camera and ``study classify`` would give it: a camera
    drawn from ``ranges`` (:func:`filmed`), then the tracker's frame rate, noise and lost frames as
    :func:`randomised` draws them. (n, T, 3) out, x = y = 0."""
    x = _check(x)
    out = np.empty_like(x)
    for i in range(len(x)):
        seen = None
        for k in range(ranges.tries):
            cam = AnyCamera(height=float(rng.uniform(*ranges.height)), tilt=float(rng.uniform(*ranges.tilt)),
                            yaw=float(rng.uniform(*ranges.yaw)), distance=float(rng.uniform(*ranges.distance)) + k)
            factor = float(np.exp(rng.uniform(*np.log(ranges.size_factor))))
            seen = filmed(x[i], cam, factor, rest_height)
            if seen is not None:
                break
        if seen is None:
            raise ConfigError(f"any_camera: no camera of {ranges.tries} tries keeps throw {i} in front of it; "
                              "raise AnyCameraRanges.distance or tries")
        ob = Observation(noise=float(rng.uniform(*ranges.noise)), drop=float(rng.uniform(*ranges.drop)),
                         camera_fps=float(rng.choice(ranges.camera_fps)))
        out[i] = ob.apply(seen[None], fps, rng, rest_height=rest_height)[0]
    return out
