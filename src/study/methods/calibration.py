"""The tracker calibrated on rendered throws: the videos, the tracker's measured error, its fitted error model,
and the observation it gives, for every chapter that looks through the camera.

Each function takes the chapter's :class:`~study.runs.runner.Runner` (its preset, frame rate, render seed and data
folder); what is expensive is cached on disk by key (the videos, the measured error) or kept on the runner for the
rest of the chapter (the fitted model).

    ob = calibration.observation(runner)                 # the tracker's error, as its fitted model draws it
    x_test = calibration.observed(runner, "test", ob, T)  # the test split as that tracker sees it
"""

from __future__ import annotations

import dataclasses
import json
from typing import TYPE_CHECKING, Any

import numpy as np

from study.core import cache
from study.learn.config import TrainConfig
from study.learn.inputs import observe_fields
from study.methods import tracker, tracker_model, videos
from study.methods.tracker import TrackerError
from study.see.config import TrackConfig
from study.simulate import observe

if TYPE_CHECKING:
    from study.runs.runner import Runner

DEVELOPMENT_RENDER_SEED = 2000
"""Seed of the development renders: throws other than the book's (``Runner.render_seed``), rendered alike, on which
the tracker's error model is fitted (:func:`tracker_fit`)."""

OBSERVED_SEEDS: dict[str, int] = {"test": 3, "train": 4}
"""Seeds of the one observed draw of each split that chapters score learners on alike (:func:`observed`)."""


def rendered(runner: Runner) -> tuple[list[videos.Video], Any]:
    """The real-world chapter's rendered throws at the data's frame rate, as long as Table 1's input (the
    videos the tracker is calibrated on), rendered once."""
    return _book_set(runner, runner.render_seed)


def _book_set(runner: Runner, seed: int) -> tuple[list[videos.Video], Any]:
    """The book's renders (``study.methods.videos.book_set``) at the runner's preset and frame rate, from ``seed``."""
    p = runner.preset
    return videos.book_set(p.name, p.videos_per_class, p.render_shadows, runner.fps, p.length, seed, runner.data_dir)


def tracker_error(runner: Runner) -> TrackerError:
    """The tracker's error on the rendered throws (``study.methods.tracker.measure``), measured once and cached
    by the videos' key, the tracker's settings and the tracker's code."""
    return runner.memo("tracker_error", lambda: _tracker_error(runner))


def _tracker_error(runner: Runner) -> TrackerError:
    shown, _ = rendered(runner)
    key = cache.key({"videos": sorted({v.path.parent.name for v in shown}), "n": len(shown),
                     "track": dataclasses.asdict(TrackConfig(color=shown[0].color, progress=False)),
                     "code": cache.code_hash("tracker-error")})
    path = runner.data_dir / "observation" / f"tracker-error-{key}.json"
    try:
        return TrackerError.from_json(json.loads(path.read_text()))
    except (OSError, ValueError, KeyError):
        pass  # not measured yet, or damaged: measure again
    error = tracker.measure(shown)
    cache.write_text_atomic(path, json.dumps(error.to_json(), indent=1) + "\n")
    return error


def decomposition(runner: Runner) -> dict[str, tracker.Decomposition]:
    """The tracker's error on the rendered throws taken apart (``study.methods.tracker.decompose``), for each of
    :data:`study.methods.tracker.TRACKERS` (the settings before and after the shaded faces)."""
    shown, _ = rendered(runner)
    return {name: tracker.decompose(shown, cfg) for name, cfg in tracker.TRACKERS.items()}


def development_rendered(runner: Runner) -> list[videos.Video]:
    """Throws rendered as the book's are (:func:`rendered`), from :data:`DEVELOPMENT_RENDER_SEED`: what the
    tracker's settings and its error model are chosen on, never the book's."""
    shown, _ = _book_set(runner, DEVELOPMENT_RENDER_SEED)
    return shown


def tracker_fit(runner: Runner) -> tracker_model.TrackerFit:
    """The tracker's error model (``study.methods.tracker_model.fit``: a per-throw offset, correlated noise, one
    level in flight and one in contact) fitted on the development renders, tracked end to end."""
    def fit() -> tracker_model.TrackerFit:
        fitted = tracker_model.fit(tracker_model.series_of(development_rendered(runner)))
        return dataclasses.replace(fitted, fitted_on=f"{fitted.n_videos} development renders (render seed "
                                                     f"{DEVELOPMENT_RENDER_SEED}, not the book's {runner.render_seed})")
    return runner.memo("tracker_fit", fit)


def observation(runner: Runner) -> observe.Observation:
    """The calibrated observation: the tracker's error as its fitted model draws it, and its share of lost
    frames (:func:`tracker_fit`)."""
    return tracker_fit(runner).observation()


def observed(runner: Runner, split: str, ob: observe.Observation, n_frames: int) -> np.ndarray:
    """The first ``n_frames`` of the runner's ``split`` ('train' or 'test') as ``ob`` observes them, (n, T, 3)
    metres: the one seeded draw (:data:`OBSERVED_SEEDS`) every chapter that scores learners on observed
    positions shares."""
    x = getattr(runner.dataset, split).x
    return ob.observe(x[:, :n_frames], runner.fps, seed=OBSERVED_SEEDS[split])


def randomised_config(runner: Runner, cfg: TrainConfig, ob: observe.Observation | None = None) -> TrainConfig:
    """``cfg`` trained on random observations, its validation observed as the calibrated tracker (or ``ob``)
    would."""
    ob = ob or observation(runner)
    return dataclasses.replace(cfg, observe="randomised", **observe_fields(ob))
