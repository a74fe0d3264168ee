"""Videos tracked and labelled by a model: what each video's track gave, and the label a Z model gives it.

:func:`track_all` tracks each video (heights in metres, the pixel scale from the object's known size, as a user's
path reads it: ``study.see.track``); :func:`user_tracks` and :func:`truth_tracks` give the same videos on a user's
camera path and from their exact heights; :func:`classify` turns each height series into the model's input
(``study.see.track.to_model_input``) and records the model's :class:`Label`, as ``study classify`` would answer
(``study.answer``). :func:`tracking_error` and :func:`scale_error` measure the tracker on rendered ground truth.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import numpy as np

from study import CLASSES
from study.core.errors import ConfigError, StudyError
from study.core.progress import Progress
from study.learn import train
from study.learn.metrics import Interval, wilson
from study.learn.trained import Ensemble
from study.methods import camera_cost, tracker
from study.methods.videos import Video
from study.runs.stats import label_of
from study.see import render, scale, track
from study.simulate import measure


Model = train.TrainedModel | Ensemble
"""A model the chapter classifies videos with: one seed's, or the seeds' mean."""


# ---------------------------------------------------------------------------------------------
# Tracking, and the labels a model gives


@dataclass(frozen=True)
class Tracked:
    """What tracking one video gave: its trajectory, or why there is none."""

    trajectory: track.Trajectory | None
    """The tracked trajectory (heights in metres from the object's size), or None."""
    error: str = ""
    """Why the video could not be tracked ('' when it was)."""


def _as_a_user(v: Video, cfg: track.TrackConfig) -> track.Trajectory:
    """``v`` as ``study classify VIDEO --color C --object-size D`` tracks it: no camera, no ground truth; the scale
    read the default way (``study.see.scale.DEFAULT``) off the video's object."""
    return track.track_video(v.path, cfg, shape=v.object_shape(), scale_from=scale.DEFAULT)


def track_all(videos: Sequence[Video], progress: bool = True) -> dict[str, Tracked]:
    """Track every video: file name -> :class:`Tracked` (or why it could not be tracked). A rendered throw's heights
    come from the render's camera at the object's depth (``study.methods.tracker.track_rendered``); a real clip's,
    whose camera is unknown, as a user's would (``study classify``'s path)."""
    out: dict[str, Tracked] = {}
    with Progress("track videos", total=len(videos), show=progress, unit="video") as bar:
        for v in videos:
            try:
                cfg = v.track_config()
                out[v.path.name] = Tracked(tracker.track_rendered(v, cfg) if v.truth is not None else
                                           _as_a_user(v, cfg))
            except StudyError as e:
                out[v.path.name] = Tracked(None, str(e))
            bar.update()
    return out


def user_tracks(videos: Sequence[Video], heights: Sequence[camera_cost.Heights],
                path: str = camera_cost.DEFAULT_PATH) -> dict[str, Tracked]:
    """Every rendered video as ``study classify VIDEO --color C --object-size D`` tracks it (no camera, no ground
    truth): ``path``'s track (by default the default path's; ``camera_cost.FLOOR_PATH``: ``--floor``'s) of its
    :func:`study.methods.camera_cost.video_heights`, ``heights``, which tracked it once for every path."""
    return {v.path.name: Tracked(h.tracks[path]) if path in h.tracks else Tracked(None, str(h.paths[path]))
            for v, h in zip(videos, heights)}


def truth_tracks(videos: Sequence[Video]) -> dict[str, Tracked]:
    """Every rendered video's true centre (:func:`study.methods.camera_cost.truth_trajectory`): what the model
    answers from the throw's exact heights, with no tracker and no camera in the way."""
    return {v.path.name: Tracked(camera_cost.truth_trajectory(v)) if v.truth is not None else
            Tracked(None, "no ground truth") for v in videos}


@dataclass(frozen=True)
class Label:
    """What a model says about one video (:func:`classify`): its label and what the tracker saw, or why the video
    could not be tracked (then no label)."""

    file: str
    """The video's file name."""
    label: str
    """Its true class, 'light' or 'heavy'."""
    error: str = ""
    """Why the video could not be tracked ('' when it was)."""
    frames: int = 0
    """Frames of the video."""
    found: float = 0.0
    """Share of its frames in which the tracker measured the object."""
    filled: int = 0
    """Frames filled by interpolation."""
    pieces: int = 0
    """Pieces the trajectory split into at long gaps (the longest is classified)."""
    bounces: int | None = None
    """Bounces seen in the piece classified (None for a trajectory in pixels)."""
    metres_per_pixel: float = math.nan
    """The pixel scale, from the object's known size: metres per pixel."""
    p_light: float = math.nan
    """The model's probability of light."""
    p_heavy: float = math.nan
    """The model's probability of heavy."""
    predicted: str = ""
    """The model's label ('' when not tracked)."""

    @property
    def tracked(self) -> bool:
        return not self.error

    @property
    def correct(self) -> bool:
        """Labelled as its true class (False when not tracked)."""
        return self.tracked and self.predicted == self.label


def classify(
    model: Model,
    videos: Sequence[Video],
    tracks: dict[str, Tracked] | None = None,
    height_factor: float = 1.0,
    progress: bool = True,
) -> list[Label]:
    """Each video's :class:`Label` from its track (``tracks`` from :func:`track_all`, tracked here if None), in
    the order of ``videos``. ``height_factor`` multiplies every height (a wrong pixel scale), to measure how
    much the label depends on it."""
    if model.dims != "z":
        raise ConfigError(f"the model was trained on {model.dims!r}; one camera gives only the height: use a 'z' model")
    tracks = track_all(videos, progress) if tracks is None else tracks
    out = []
    for v in videos:
        tracked = tracks[v.path.name]
        traj = tracked.trajectory
        if traj is None:
            out.append(Label(v.path.name, v.label, tracked.error))
            continue
        piece = traj.longest()
        x = track.to_model_input(traj, model.fps, model.n_frames, height_factor=height_factor, rest_height=v.rest_height)
        p = np.asarray(model.predict_proba(x[None]))[0]
        out.append(Label(v.path.name, v.label, "", len(traj.t), traj.found_fraction, int(traj.filled.sum()),
                         len(traj.segments()), measure.bounce_count(piece.height) if piece.units == "m" else None,
                         traj.height_per_pixel, float(p[0]), float(p[1]), CLASSES[label_of(float(p[1]))]))
    return out


def per_class_interval(labels: Sequence[Label]) -> dict[str, Interval | None]:
    """Accuracy per true class over the videos that were classified, with its Wilson interval (None for a class
    with no classified video): for 20 videos a bootstrap would understate the uncertainty."""
    out: dict[str, Interval | None] = {}
    for c in CLASSES:
        ok = [r.correct for r in labels if r.label == c and r.tracked]
        out[c] = wilson(sum(ok), len(ok)) if ok else None
    return out


@dataclass(frozen=True)
class PixelError:
    """The tracker against the rendered ground truth (:func:`tracking_error`)."""

    mean_px: float
    """Mean distance of the tracked centroid from the true centre's projection, pixels (NaN: none measured)."""
    p95_px: float
    """Its 95th percentile, pixels."""
    found: float
    """Share of the frames in which the object was found."""


def tracking_error(videos: Sequence[Video]) -> PixelError:
    """The tracker's pixel error against the rendered ground truth, over every measured frame of ``videos`` that
    have one (a video that cannot be tracked counts its frames as not found)."""
    errs, found, total = [], 0, 0
    for v in videos:
        if v.truth is None:
            continue
        gt = render.read_truth(v.truth)
        try:
            traj = track.detect_all(v.path, v.track_config())
        except StudyError:
            total += len(gt["t"])
            continue
        m = traj.measured
        errs.append(np.hypot(traj.u - gt["u"], traj.v - gt["v"])[m])
        found += int(m.sum())
        total += len(m)
    e = np.concatenate(errs) if errs else np.array([math.nan])
    return PixelError(float(np.mean(e)), float(np.percentile(e, 95)), found / max(total, 1))


def true_scale(rcfg: render.RenderConfig, depth: float = 4.0) -> float:
    """Metres per pixel of the rendered camera at the throw's ``depth`` (m): the scale the tracker should read."""
    return render.metres_per_pixel(render.class_model("light"), "side", rcfg.height, depth=depth)


def scale_error(tracks: Iterable[Tracked], true: float) -> float:
    """Median over the tracked videos of |scale / ``true`` - 1|: how far the scale read off the object's apparent
    size (its blob's equivalent-disc diameter) is from the true metres per pixel."""
    scales = np.array([t.trajectory.height_per_pixel for t in tracks if t.trajectory])
    return float(np.median(np.abs(scales / true - 1)))
