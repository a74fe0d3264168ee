"""The tracker's error as a model a simulation can draw from: :class:`study.simulate.observe.TrackerNoise` (a per-throw
offset, plus noise correlated from frame to frame whose size differs in flight and in contact) fitted to rendered
throws whose true heights are known.

The fit (:func:`fit`) is a method of moments, matched exactly: over every video's measured frames it equates what
the model expects with what the tracker did for four statistics,

1. the squared position error in flight, each video's mean removed,
2. the same in contact,
3. the squared frame-to-frame change of the error (consecutive measured frames; what a velocity reads),
4. the squared mean error of each video (the offset),

with the expectations computed for the frames each video measured (removing a video's mean also removes part of
a correlated error, and the fit accounts for it), so the model reproduces the tracker's position error in each
state and its frame-to-frame error, not one at the cost of the other. Intervals: a bootstrap over the videos.
Lost frames are counted only while the object is in view.

The series are plain arrays (:class:`ErrorSeries`), so the fit is tested on series drawn from the model itself;
:func:`series_of` makes them from rendered videos, tracked end to end.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass

import numpy as np
from scipy.optimize import least_squares

from study.core.errors import DataError
from study.learn.metrics import Interval
from study.methods import tracker
from study.methods.videos import Video
from study.report.cues import TrackerFitNumbers
from study.report.reported import count, number
from study.see import render
from study.see.config import TrackConfig
from study.simulate import observe
from study.simulate.observe import CONTACT_BAND, REST_HEIGHT, TrackerNoise

FITTED = ("offset", "rho", "flight", "contact")
"""The model's parameters the fit estimates (``TrackerNoise``'s fields); its contact band is set, not fitted."""
BOOTSTRAP = 400
"""Resamples of the videos behind each parameter's interval."""


@dataclass(frozen=True)
class ErrorSeries:
    """One rendered throw's height error, frame by frame."""

    error: np.ndarray
    """(T,) float64 metres: the tracked height minus the true height; NaN where the tracker measured nothing."""
    contact: np.ndarray
    """(T,) bool: the object touches the ground (``observe.in_contact`` of the true height)."""
    in_view: np.ndarray
    """(T,) bool: the object is in the picture (a frame out of view is neither measured nor lost)."""

    @classmethod
    def of(cls, tracked: np.ndarray, true: np.ndarray, in_view: np.ndarray | None = None,
           rest_height: float = REST_HEIGHT, band: float = CONTACT_BAND) -> ErrorSeries:
        """The series of tracked heights ``tracked`` (T,) metres (NaN where lost) against the true ``true`` (T,),
        the contact read from the true heights; every frame in view unless ``in_view`` (T,) bool says otherwise."""
        tracked, true = np.asarray(tracked, np.float64), np.asarray(true, np.float64)
        if tracked.shape != true.shape or tracked.ndim != 1:
            raise DataError(f"error series: tracked {tracked.shape} and true {true.shape} heights; expected (T,) each")
        view = np.ones(len(true), bool) if in_view is None else np.asarray(in_view, bool)
        return cls(tracked - true, observe.in_contact(true, rest_height, band), view)

    @property
    def measured(self) -> np.ndarray:
        """(T,) bool: frames in view where the tracker measured the object."""
        return np.isfinite(self.error) & self.in_view


def series_of(videos: Sequence[Video], cfg: TrackConfig | None = None) -> list[ErrorSeries]:
    """The error series of the ``videos`` that have ground truth (rendered ones; the others are skipped): each
    tracked end to end as the classifier's input is (``study.methods.tracker.track_rendered``: heights from the
    render's camera at the object's depth), against the true centre's height; in view where the true centre
    projects inside the picture."""
    out = []
    for v in videos:
        if v.truth is None:
            continue
        truth = render.read_truth(v.truth)
        traj = tracker.track_rendered(v, cfg)
        tracked = np.where(traj.measured, traj.height + v.rest_height, np.nan)
        out.append(ErrorSeries.of(tracked, truth["z"], tracker.in_view(truth, traj.width, traj.height_px),
                                  v.rest_height))
    return out


# ---------------------------------------------------------------------------------------------
# What each video contributes: its statistics, and the counts its expectations need


@dataclass(frozen=True)
class _Video:
    """One video's four statistics and, for its expectations, how many pairs of its measured frames lie k frames
    apart within flight (``ff``), between flight and contact (``fc``, one direction) and within contact (``cc``)."""

    sums: np.ndarray
    """(4,) observed: flight and contact squared error about the mean, squared frame-to-frame change, squared mean."""
    n: int
    n_flight: int
    n_contact: int
    ff: np.ndarray
    fc: np.ndarray
    cc: np.ndarray
    steps: np.ndarray
    """(3,) consecutive measured pairs both in flight, one in each state, both in contact."""


def _video(s: ErrorSeries, T: int) -> _Video | None:
    m = s.measured
    t = np.flatnonzero(m)
    if len(t) == 0:
        return None
    e, c = s.error[t], np.asarray(s.contact, bool)[t]
    r = e - e.mean()
    step = (np.diff(t) == 1)
    de = np.diff(e)[step]
    sums = np.array([np.sum(r[~c] ** 2), np.sum(r[c] ** 2), np.sum(de**2), e.mean() ** 2])
    lag = np.abs(t[:, None] - t[None, :])

    def pairs(a: np.ndarray, b: np.ndarray) -> np.ndarray:
        return np.bincount(lag[np.ix_(a, b)].ravel(), minlength=T)[:T].astype(np.float64)

    f = ~c
    c0, c1 = c[:-1][step], c[1:][step]
    steps = np.array([np.sum(~c0 & ~c1), np.sum(c0 != c1), np.sum(c0 & c1)], np.float64)
    return _Video(sums, len(t), int(f.sum()), int(c.sum()), pairs(f, f), pairs(f, c), pairs(c, c), steps)


@dataclass(frozen=True)
class _Stack:
    """Every video's contributions, stacked, so that a bootstrap reweights videos without recounting."""

    sums: np.ndarray  # (V, 4)
    n: np.ndarray  # (V,)
    n_flight: np.ndarray
    n_contact: np.ndarray
    ff: np.ndarray  # (V, T)
    fc: np.ndarray
    cc: np.ndarray
    steps: np.ndarray  # (V, 3)

    @classmethod
    def of(cls, videos: Sequence[_Video]) -> _Stack:
        return cls(np.stack([v.sums for v in videos]), *(np.array([getattr(v, k) for v in videos], np.float64)
                                                          for k in ("n", "n_flight", "n_contact")),
                   *(np.stack([getattr(v, k) for v in videos]) for k in ("ff", "fc", "cc", "steps")))

    def expected(self, flight: float, contact: float, rho: float, w: np.ndarray) -> np.ndarray:
        """(4,) what the varying part of the model (no offset) expects of the four statistics, videos weighted
        by ``w`` (V,)."""
        p = rho ** np.arange(self.ff.shape[1])
        rff, rfc, rcc = self.ff @ p, self.fc @ p, self.cc @ p  # (V,) sums of the correlation over each block
        f2, c2, fc = flight**2, contact**2, flight * contact
        total = f2 * rff + 2 * fc * rfc + c2 * rcc  # n^2 times the variance of the video's mean
        a = f2 * self.n_flight - 2 * (f2 * rff + fc * rfc) / self.n + self.n_flight * total / self.n**2
        b = c2 * self.n_contact - 2 * (c2 * rcc + fc * rfc) / self.n + self.n_contact * total / self.n**2
        ff, mixed, cc = self.steps.T
        step = 2 * (1 - rho) * (f2 * ff + c2 * cc) + (f2 + c2 - 2 * rho * fc) * mixed
        return np.array([w @ a, w @ b, w @ step, w @ (total / self.n**2)])


def _solve(stack: _Stack, w: np.ndarray) -> tuple[float, float, float, float]:
    """(offset, rho, flight, contact) whose expectations equal the observed statistics of the videos weighted by
    ``w``; a state no frame of them is in takes the other's level."""
    obs = w @ stack.sums
    has_f, has_c = w @ stack.n_flight > 0, w @ stack.n_contact > 0
    if w @ stack.steps.sum(axis=1) == 0:
        raise DataError("camera fit: no two consecutive measured frames in any video; the frame-to-frame error "
                        "cannot be measured")

    def levels(x: np.ndarray) -> tuple[float, float, float]:
        flight, contact = (x[0], x[1]) if has_f and has_c else (x[0], x[0])
        return flight, contact, x[-1]

    rows = [i for i, keep in enumerate((has_f, has_c, True)) if keep]
    scale = np.maximum(obs[:3], 1e-30)

    def residual(x: np.ndarray) -> np.ndarray:
        return (stack.expected(*levels(x), w)[:3] - obs[:3])[rows] / scale[rows]

    frames = np.maximum(np.array([w @ stack.n_flight, w @ stack.n_contact]), 1.0)
    sd = np.sqrt(obs[:2] / frames) + 1e-9
    start = [sd[0], sd[1]] if has_f and has_c else [sd[0] if has_f else sd[1]]
    x = least_squares(residual, [*start, 0.5], bounds=([0.0] * len(start) + [-0.99], [np.inf] * len(start) + [0.999]),
                      x_scale=[*start, 0.5], xtol=1e-12, ftol=1e-12, gtol=1e-12).x
    flight, contact, rho = levels(x)
    noise_mean = stack.expected(flight, contact, rho, w)[3]
    offset = math.sqrt(max(0.0, (obs[3] - noise_mean) / w.sum()))
    return offset, float(rho), float(flight), float(contact)


# ---------------------------------------------------------------------------------------------
# The fit


@dataclass(frozen=True)
class TrackerFit:
    """The tracker's error model fitted to rendered throws (:func:`fit`), with what it was fitted to."""

    model: TrackerNoise
    """The fitted model (its offset, rho, flight and contact levels; the contact band it was fitted with)."""
    drop: float
    """Share of the frames in view that the tracker lost."""
    intervals: dict[str, Interval]
    """Each of :data:`FITTED`'s 95 % interval (bootstrap over the videos)."""
    n_videos: int
    """Videos fitted on."""
    n_frames: int
    """Measured frames, over every video."""
    n_contact: int
    """Of those, frames in contact."""
    step_sd: float
    """Root mean square of the error's change between consecutive measured frames, metres (the tracker's)."""
    pooled_sd: float
    """Standard deviation of the error with each video's mean removed, pooled over the videos, metres (the size a
    white-noise calibration draws)."""
    bias: float
    """Mean of the videos' mean errors, metres (the offsets' centre; the model's offsets are centred on 0, so
    its :attr:`TrackerNoise.offset` is their root mean square)."""
    lag1: float
    """Lag-1 autocorrelation of the error with each video's mean removed, pooled (as measured, not corrected for
    the mean's removal)."""
    fitted_on: str = ""
    """Which renders, in words (``calibration.tracker_fit`` sets it)."""

    def observation(self) -> observe.Observation:
        """The fitted observation: the model's error and the tracker's share of lost frames."""
        return observe.Observation(tracker=self.model, drop=self.drop)

    @property
    def white_step_sd(self) -> float:
        """The frame-to-frame error that white noise of :attr:`pooled_sd` would have, metres."""
        return math.sqrt(2) * self.pooled_sd

    @property
    def white_overstates(self) -> float:
        """How many times white noise at the pooled position error overstates the tracker's frame-to-frame error."""
        return self.white_step_sd / self.step_sd if self.step_sd > 0 else math.inf

    def numbers(self) -> TrackerFitNumbers:
        """The fit as a chapter reports it."""
        on = f" on {self.fitted_on}" if self.fitted_on else ""
        return TrackerFitNumbers(
            number(self.intervals["offset"], f"tracker error model{on}: standard deviation of the per-throw offset",
                   unit="m"),
            number(self.intervals["rho"], f"tracker error model{on}: lag-1 autocorrelation from frame to frame",
                   unit="coefficient"),
            number(self.intervals["flight"], f"tracker error model{on}: varying error in flight", unit="m"),
            number(self.intervals["contact"], f"tracker error model{on}: varying error in contact", unit="m"),
            number(self.step_sd, f"tracker's frame-to-frame height error{on} (root mean square)", unit="m"),
            number(self.white_step_sd, f"the frame-to-frame error of white noise at the tracker's pooled error{on}",
                   unit="m"),
            number(self.drop, f"share of the frames in view the tracker lost{on}"),
            count(self.n_videos, f"rendered videos the tracker's error model was fitted on{on}"))

    def to_json(self) -> dict:
        """Its fields as JSON-able values (a cache file)."""
        out = asdict(self)
        out["intervals"] = {k: asdict(v) for k, v in self.intervals.items()}
        return out

    @classmethod
    def from_json(cls, stored: Mapping) -> TrackerFit:
        """The fit of a file written by :meth:`to_json`."""
        d = dict(stored)
        d["model"] = TrackerNoise(**d["model"])
        d["intervals"] = {k: Interval(**v) for k, v in d["intervals"].items()}
        return cls(**d)


def fit(series: Sequence[ErrorSeries], band: float = CONTACT_BAND, bootstrap: int = BOOTSTRAP,
        seed: int = 0) -> TrackerFit:
    """The model of :class:`TrackerNoise` whose offset, autocorrelation and two levels reproduce the errors of
    ``series`` (one per rendered throw; the moments of this module's docstring), with bootstrap intervals over the
    throws (``bootstrap`` resamples, seeded by ``seed``; 0: none). ``band``: the contact band the series' contact
    flags were read with, kept in the model so that it draws contact as it was fitted."""
    if not series:
        raise DataError("camera fit: no error series; render throws with ground truth and track them first")
    T = max(len(s.error) for s in series)
    videos = [v for v in (_video(s, T) for s in series) if v is not None]
    if not videos:
        raise DataError(f"camera fit: the tracker measured no frame in any of the {len(series)} videos")
    stack = _Stack.of(videos)
    ones = np.ones(len(videos))
    est = dict(zip(FITTED, _solve(stack, ones)))
    draws = []
    rng = np.random.default_rng(seed)
    for _ in range(bootstrap):
        w = rng.multinomial(len(videos), ones / len(videos)).astype(np.float64)
        try:
            draws.append(_solve(stack, w))
        except DataError:
            continue  # a resample without consecutive frames: it says nothing about the model
    method = f"bootstrap over {len(videos)} videos ({bootstrap} resamples)"
    intervals = {k: Interval(v, *(map(float, np.percentile([d[i] for d in draws], [2.5, 97.5])) if draws else (v, v)),
                             method)
                 for i, (k, v) in enumerate(est.items())}
    in_view = sum(int(s.in_view.sum()) for s in series)
    measured = sum(int(s.measured.sum()) for s in series)
    return TrackerFit(
        TrackerNoise(flight=est["flight"], contact=est["contact"], offset=est["offset"], rho=est["rho"], band=band),
        drop=(in_view - measured) / max(in_view, 1), intervals=intervals, n_videos=len(videos), n_frames=measured,
        n_contact=int(stack.n_contact.sum()), step_sd=math.sqrt(stack.sums[:, 2].sum() / stack.steps.sum()),
        **_as_measured([s for s in series if s.measured.any()]))


def _as_measured(series: Sequence[ErrorSeries]) -> dict[str, float]:
    """What ``series`` (each with a measured frame) show before any model: the pooled standard deviation and lag-1
    autocorrelation of the error with each video's mean removed, and the mean of the videos' means, metres."""
    resid, lagged, means = [], [], []
    for s in series:
        t = np.flatnonzero(s.measured)
        e = s.error[t]
        r = e - e.mean()
        step = np.diff(t) == 1
        resid.append(r)
        lagged.append(np.stack([r[:-1][step], r[1:][step]]))
        means.append(e.mean())
    r, (a, b) = np.concatenate(resid), np.concatenate(lagged, axis=1)
    denom = math.sqrt(float(np.sum(a * a) * np.sum(b * b)))
    return {"pooled_sd": float(r.std()), "bias": float(np.mean(means)),
            "lag1": float(np.sum(a * b) / denom) if denom > 0 else 0.0}
