"""The floor path's height error as a model a simulation can draw from, so that a classifier can be trained for the
heights a user's floor marks give (``study classify --floor``).

The floor path (``study.see.floor``) is run on development clips of the camera sweep -- rendered as the sweep's are,
from another seed (:data:`DEVELOPMENT_SEED`), never the scored clips -- and its heights against the renderer's truth
are fitted with the tracker's error model (``study.methods.tracker_model.fit``: a per-throw offset, noise correlated
from frame to frame, one level in flight and one in contact). :func:`check` says how far that model describes the
floor path's error beyond the four statistics the fit matches: the autocorrelation at longer lags, where an error
that is smooth within a flight and starts afresh at the next would fall off otherwise than one AR(1).

The fit is cached in the data folder, keyed by the development clips and this code.
"""

from __future__ import annotations

import dataclasses
import json
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from study.core import cache
from study.core.errors import DataError
from study.methods import camera_cost, sweep, tracker, tracker_model
from study.see import render
from study.simulate import observe

if TYPE_CHECKING:
    from study.runs.runner import Runner

DEVELOPMENT_SEED = 2000
"""Seed of the development clips' throws and shots (the scored sweep's is ``sweep.SWEEP_SEED``)."""
DEVELOPMENT_SHARE = 4
"""The development clips are a quarter of the sweep's per family (at least one)."""
LAGS = (1, 2, 5, 10, 20)
"""Frame lags at which :func:`check` compares the error's autocorrelation with the model's."""
FITS = 0.1
"""The largest gap in autocorrelation at which the model counts as describing the path's error (:attr:`Check.worst`)."""


def development_clips(runner: Runner, progress: bool = False) -> list[sweep.Clip]:
    """The development clips (:data:`DEVELOPMENT_SEED`; a quarter of the preset's sweep per family), rendered once
    under the data folder as the sweep's are."""
    p = runner.preset
    return sweep.sweep_set(runner.synth_config, per_family=max(1, p.sweep_per_family // DEVELOPMENT_SHARE),
                           seed=DEVELOPMENT_SEED, out_dir=runner.data_dir / "realworld", progress=progress,
                           frame_scale=p.sweep_frame_scale, duration=p.length)


def series(clips: list[sweep.Clip], shape) -> list[tracker_model.ErrorSeries]:
    """Each clip's floor-path height error against its truth (:class:`~study.methods.tracker_model.ErrorSeries`;
    ``shape``: the object's ``ObjectShape``); a clip the path gives no heights for is left out."""
    out = []
    for c in clips:
        h = camera_cost.heights(c, shape)
        got = h.paths[camera_cost.FLOOR_PATH]
        if isinstance(got, str):
            continue
        truth = render.read_truth(c.video.truth)
        rest = c.video.rest_height
        view = tracker.in_view(truth, c.shot.width, c.shot.height_px)[: len(h.exact)]
        out.append(tracker_model.ErrorSeries.of(got + rest, h.exact + rest, view, rest))
    return out


@dataclass(frozen=True)
class Check:
    """How the fitted model's autocorrelation compares with the floor path's own, lag by lag."""

    lags: tuple[int, ...]
    """Frame lags."""
    measured: tuple[float, ...]
    """The error's autocorrelation at each lag, each clip's mean removed, pooled over clips."""
    model: tuple[float, ...]
    """The model's: its AR(1) coefficient to the power of the lag."""

    @property
    def worst(self) -> float:
        """The largest gap between the two, in autocorrelation."""
        return max(abs(a - b) for a, b in zip(self.measured, self.model))


def check(errors: list[tracker_model.ErrorSeries], fit: tracker_model.TrackerFit, lags: tuple[int, ...] = LAGS) -> Check:
    """:class:`Check` of ``fit`` against the series it was fitted to (their measured frames, each clip's mean
    removed)."""
    e = [s.error[s.measured] - s.error[s.measured].mean() for s in errors if s.measured.sum() > 1]
    den = sum(float(np.sum(x * x)) for x in e)
    if den <= 0:
        raise DataError("floor model check: no varying error to correlate")
    measured = tuple(sum(float(np.sum(x[k:] * x[:-k])) for x in e if len(x) > k) / den for k in lags)
    return Check(tuple(lags), measured, tuple(fit.model.rho ** k for k in lags))


@dataclass(frozen=True)
class FloorFit:
    """The floor path's error model and how well it describes that error."""

    fit: tracker_model.TrackerFit
    """The model, fitted on the development clips."""
    check: Check
    """Its autocorrelation against the floor path's own (:func:`check`)."""

    def to_json(self) -> dict:
        return {"fit": self.fit.to_json(), "check": dataclasses.asdict(self.check)}

    @classmethod
    def from_json(cls, stored: dict) -> FloorFit:
        c = stored["check"]
        return cls(tracker_model.TrackerFit.from_json(stored["fit"]),
                   Check(tuple(c["lags"]), tuple(c["measured"]), tuple(c["model"])))


def fit(runner: Runner, progress: bool = False) -> FloorFit:
    """The floor path's error model fitted on the :func:`development_clips`, and its :func:`check` (cached in the
    data folder, keyed by the clips and this code); computed once per runner. :class:`DataError` where the floor
    path gives no heights on any development clip."""
    def make() -> FloorFit:
        clips = development_clips(runner, progress)
        folder = clips[0].video.path.parent
        key = cache.key({"clips": folder.name, "code": cache.source_hash(*cache.closure(__name__))})
        path = runner.data_dir / "realworld" / f"floor-fit-{key}.json"
        if path.is_file():
            try:
                return FloorFit.from_json(json.loads(path.read_text()))
            except (ValueError, KeyError, TypeError):
                pass  # a damaged cache file: fitted again and rewritten
        errors = series(clips, camera_cost.shape_of(runner.synth_config))
        if not errors:
            raise DataError(f"floor model: the floor path gave no heights on any of the {len(clips)} development "
                            f"clips in {folder}")
        fitted = tracker_model.fit(errors)
        fitted = dataclasses.replace(fitted, fitted_on=(
            f"the floor path on {fitted.n_videos} development clips of the camera sweep (seed {DEVELOPMENT_SEED}, "
            f"not the scored sweep's {sweep.SWEEP_SEED})"))
        out = FloorFit(fitted, check(errors, fitted))
        cache.write_text_atomic(path, json.dumps(out.to_json(), indent=1) + "\n")
        return out
    return runner.memo("floor_fit", make)


def fitted(runner: Runner, progress: bool = False) -> FloorFit | None:
    """:func:`fit`, or None where the floor path gave no heights on the development clips (then no model is trained
    for it, and the page says so)."""
    try:
        return fit(runner, progress)
    except DataError:
        return None


def observation(runner: Runner) -> observe.Observation | None:
    """The floor path's observation, its fitted error and its share of lost frames (:func:`fitted`; None without)."""
    f = fitted(runner)
    return None if f is None else f.fit.observation()

