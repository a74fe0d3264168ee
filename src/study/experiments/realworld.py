"""The paper's real-world experiment: videos in, tracked heights, the Z-only classifier's labels out.

Two sources of video:

- :func:`render_set`: throws drawn from the synthesis priors (``study.simulate.synth``), rendered with
  ``study.see.render`` from a side camera (the launch turned to cross the view, as in the paper's
  videos), with a known class and ground truth: the paper's 20 + 20 design, heavy objects included.
- :func:`read_manifest`: a folder of the user's own labelled videos with a ``MANIFEST.csv``
  (columns ``file`` and ``label``; other columns are kept).

:func:`classify` tracks each video, turns its height series into the model's input
(``study.see.track.to_model_input``) and records the model's probabilities.
"""

from __future__ import annotations

import csv
import math
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Protocol

import numpy as np

from study import CLASSES
from study.core import cache
from study.simulate import measure
from study.core.errors import ConfigError, DataError, StudyError
from study.learn.metrics import Interval, wilson
from study.core.progress import Progress
from study.see import render, track

LABEL_ALIASES = {"light": "light", "bouncy": "light", "ball": "light", "heavy": "heavy", "sliding": "heavy", "cube": "heavy"}
"""Manifest labels understood, mapped to the study's classes."""

REAL_CLIPS_ENV = "STUDY_REAL_VIDEO"
"""Environment variable that points :func:`real_clips_dir` at a folder of real clips."""
REAL_CLIPS_DEFAULT = Path("..") / "shared" / "data" / "real-video"
"""Where real clips recorded by others (tennis balls only) lie beside the project, relative to the
working folder (the project root when the book runs); read there, never copied into the project."""

TENNIS_BALL = 0.067
"""Diameter of a tennis ball, metres (ITF: 6.54-6.86 cm)."""


class Model(Protocol):
    """What :func:`classify` needs of a trained model (``study.learn.train.TrainedModel``)."""

    dims: str
    fps: float
    n_frames: int

    def predict_proba(self, x: np.ndarray) -> np.ndarray: ...


@dataclass
class Video:
    """One labelled video and how to read it."""

    path: Path
    """The video file."""
    label: str
    """'light' or 'heavy'."""
    color: str = "tennis"
    """Tracker HSV preset."""
    object_size: float = TENNIS_BALL
    """Equivalent-disc diameter of the object's image, metres (sets the pixel scale)."""
    rest_height: float = TENNIS_BALL / 2
    """Height of the object's centre when it rests on the ground, metres."""
    truth: Path | None = None
    """Ground-truth CSV of a rendered video (``study.see.render``), if any."""
    info: dict[str, Any] = field(default_factory=dict)
    """Other manifest columns."""


def real_clips_dir(path: str | Path | None = None) -> Path:
    """The folder of real clips: ``path`` if given, else ``$STUDY_REAL_VIDEO``, else :data:`REAL_CLIPS_DEFAULT`.

    The folder may not exist (the clips are optional); :func:`read_manifest` says so if it is read.
    """
    if path:
        return Path(path)
    return Path(os.environ.get(REAL_CLIPS_ENV) or REAL_CLIPS_DEFAULT)


def read_manifest(video_dir: str | Path, color: str = "tennis", object_size: float = TENNIS_BALL) -> list[Video]:
    """The videos listed in ``video_dir/MANIFEST.csv`` (columns ``file``, ``label``), in file order.

    Raises :class:`DataError` for a missing folder, manifest or video, :class:`ConfigError` for an
    unknown label (allowed: see :data:`LABEL_ALIASES`).
    """
    d = Path(video_dir)
    m = d / "MANIFEST.csv"
    if not d.is_dir():
        raise DataError(f"video_dir {d}: no such folder; point it at a folder of videos with a MANIFEST.csv")
    if not m.is_file():
        raise DataError(f"video_dir {d}: no MANIFEST.csv; write one with the columns file,label")
    rows = list(csv.DictReader(m.open(newline="")))
    if not rows or not {"file", "label"} <= set(rows[0]):
        raise DataError(f"manifest {m}: needs a header with the columns file and label, and one row per video")
    out = []
    for r in rows:
        lab = LABEL_ALIASES.get(r["label"].strip().lower())
        if lab is None:
            raise ConfigError(f"manifest {m}: label {r['label']!r} of {r['file']} is unknown; use one of {', '.join(LABEL_ALIASES)}")
        p = d / r["file"]
        if not p.is_file():
            raise DataError(f"manifest {m}: {r['file']} is listed but not in {d}")
        info = {k: v for k, v in r.items() if k not in ("file", "label")}
        out.append(Video(p, lab, color=color, object_size=object_size, rest_height=object_size / 2, info=info))
    return sorted(out, key=lambda v: v.path.name)


def launch_across_view(qpos: np.ndarray, qvel: np.ndarray, start_x: float = 1.2) -> tuple[np.ndarray, np.ndarray]:
    """A launch turned to cross the side camera's view: horizontal speed kept, direction +x or -x, start at -+start_x."""
    qpos, qvel = qpos.copy(), qvel.copy()
    speed = math.hypot(qvel[0], qvel[1])
    sign = 1.0 if qvel[0] >= 0 else -1.0
    qvel[0], qvel[1] = sign * speed, 0.0
    qpos[0], qpos[1] = -sign * start_x, 0.0
    return qpos, qvel


def throw(cfg, params: dict[str, np.ndarray], i: int, max_speed: float = 2.0):
    """Throw ``i`` of a split's ``params`` as :func:`render_set` films it: its model (``render.synth_model``)
    and its launch (qpos, qvel) turned across the camera's view, horizontal speed capped at ``max_speed`` m/s."""
    model, qpos, qvel = render.synth_model(cfg, params, i)
    qvel = qvel.copy()
    h = math.hypot(qvel[0], qvel[1])
    if h > max_speed:
        qvel[:2] *= max_speed / h
    qpos, qvel = launch_across_view(qpos, qvel)
    return model, qpos, qvel


def render_set(
    cfg,
    n_per_class: int,
    seed: int,
    out_dir: str | Path,
    rcfg: render.RenderConfig,
    max_speed: float = 2.0,
    progress: bool = True,
) -> list[Video]:
    """Render ``n_per_class`` throws of each class, drawn from ``cfg``'s priors (a ``synth.SynthConfig``).

    Objects and launches come from ``synth.sample_split(cfg, seed, "test")`` (so use a ``seed``
    other than the training data's); each launch is turned across the camera's view with its
    horizontal speed capped at ``max_speed`` m/s so the object stays in the picture longer. Videos
    are cached under ``out_dir/<key>/`` by a hash of everything that determines them.
    """
    from study.simulate import synth

    cfg = cfg.replace(n_test=n_per_class)
    key = cache.key({"synth": cfg.to_dict(), "seed": seed, "render": rcfg.__dict__ | {"progress": None},
                     "max_speed": max_speed,
                     "code": cache.source_hash("see.render", "simulate.scene", "simulate.synth", "experiments.realworld")})
    folder = Path(out_dir) / f"rendered-{key}"
    params = synth.sample_split(cfg, seed, "test")
    size = 2 * math.sqrt(4 * cfg.shape.size[0] * cfg.shape.size[1] / math.pi) if cfg.shape.kind == "box" else 2 * cfg.shape.size[0]
    videos = []
    for i in range(len(params["label"])):
        label = CLASSES[int(params["label"][i])]
        name = f"{label}_{i:03d}.mp4"
        videos.append(Video(folder / name, label, color="orange", object_size=size, rest_height=cfg.shape.rest_height,
                            truth=(folder / name).with_suffix(".csv"), info={"mass": float(params["mass"][i]),
                            "restitution": float(params["restitution"][i])}))
    todo = [i for i, v in enumerate(videos) if not (v.path.is_file() and v.truth.is_file())]
    with Progress("render videos", total=len(todo), show=progress, unit="video") as bar:
        for i in todo:
            render.render(*throw(cfg, params, i, max_speed), videos[i].path, rcfg)
            bar.update()
    (folder / "MANIFEST.csv").write_text("file,label\n" + "".join(f"{v.path.name},{v.label}\n" for v in videos))
    return videos


def book_set(preset_name: str, fps: float, duration: float, render_seed: int = 1000, data_dir: str | Path = "data",
             progress: bool = False) -> tuple[list[Video], render.RenderConfig]:
    """The rendered throws the book uses (the real-world chapter's, which the cue chapter measures the
    tracker on): the preset's ``videos_per_class`` of each class at 320 x 240, ``fps``, ``duration``
    seconds, with motion blur, sensor noise and JPEG loss; rendered once, then read from the cache."""
    from study.experiments.presets import preset
    from study.simulate import synth

    p = preset(preset_name)
    rcfg = render.RenderConfig(width=320, height=240, fps=fps, duration=duration, blur_subframes=2, noise_std=2.0,
                               jpeg_quality=85, shadows=p.render_shadows, seed=render_seed)
    cfg = synth.SynthConfig.preset(preset_name)
    videos = render_set(cfg, p.videos_per_class, render_seed, Path(data_dir) / "realworld", rcfg, progress=progress)
    return videos, rcfg


@dataclass(frozen=True)
class Tracked:
    """What tracking one video gave: its trajectory, or why there is none."""

    trajectory: track.Trajectory | None
    """The tracked trajectory (heights in metres from the object's size), or None."""
    error: str = ""
    """Why the video could not be tracked ('' when it was)."""


def track_all(videos: list[Video], progress: bool = True) -> dict[str, Tracked]:
    """Track every video (heights in metres from its object size): file name -> :class:`Tracked`."""
    out: dict[str, Tracked] = {}
    with Progress("track videos", total=len(videos), show=progress, unit="video") as bar:
        for v in videos:
            try:
                out[v.path.name] = Tracked(track.track_video(v.path, track.TrackConfig(color=v.color, progress=False),
                                                             object_size=v.object_size))
            except StudyError as e:
                out[v.path.name] = Tracked(None, str(e))
            bar.update()
    return out


def classify(
    model: Model,
    videos: list[Video],
    tracks: dict[str, Tracked] | None = None,
    height_factor: float = 1.0,
    progress: bool = True,
) -> list[dict[str, Any]]:
    """Classify each video from its track (``tracks`` from :func:`track_all`, tracked here if None).

    Row: file, label, frames, found (fraction measured), filled, pieces, bounces (in the piece
    used), metres_per_pixel (from the object size), p_light, p_heavy, predicted, correct, and
    error (the reason, if the video could not be tracked; then no prediction). ``height_factor``
    multiplies every height (a wrong pixel scale), to measure how much the label depends on it.
    """
    if model.dims != "z":
        raise ConfigError(f"the model was trained on {model.dims!r}; one camera gives only the height: use a 'z' model")
    tracks = track_all(videos, progress) if tracks is None else tracks
    rows = []
    for v in videos:
        row: dict[str, Any] = {"file": v.path.name, "label": v.label}
        tracked = tracks[v.path.name]
        traj = tracked.trajectory
        if traj is None:
            rows.append(row | {"error": tracked.error})
            continue
        piece = traj.longest()
        x = track.to_model_input(traj, model.fps, model.n_frames, height_factor=height_factor, rest_height=v.rest_height)
        p = np.asarray(model.predict_proba(x[None]))[0]
        pred = CLASSES[int(np.argmax(p))]
        row |= {"frames": len(traj.t), "found": traj.found_fraction, "filled": int(traj.filled.sum()),
                "pieces": len(traj.segments()), "bounces": measure.bounce_count(piece.height) if piece.units == "m" else None,
                "metres_per_pixel": traj.height_per_pixel,
                "p_light": float(p[0]), "p_heavy": float(p[1]), "predicted": pred, "correct": pred == v.label,
                "error": ""}
        rows.append(row)
    return rows


def per_class_interval(rows: list[dict[str, Any]]) -> dict[str, Interval | None]:
    """Accuracy per true class over the rows that were classified, with its Wilson interval (None for a
    class with no classified video): for 20 videos a bootstrap would understate the uncertainty."""
    out: dict[str, Interval | None] = {}
    for c in CLASSES:
        ok = [bool(r["correct"]) for r in rows if r["label"] == c and not r.get("error")]
        out[c] = wilson(sum(ok), len(ok)) if ok else None
    return out


def tracking_error(videos: list[Video]) -> dict[str, float]:
    """Pixel error of the tracker against the rendered ground truth, over all measured frames of ``videos``.

    Returns mean and 95th-percentile error (pixels) and the fraction of frames found.
    """
    errs, found, total = [], 0, 0
    for v in videos:
        if v.truth is None:
            continue
        try:
            traj = track.detect_all(v.path, track.TrackConfig(color=v.color, progress=False))
        except StudyError:
            gt = render.read_truth(v.truth)
            total += len(gt["t"])
            continue
        gt = render.read_truth(v.truth)
        m = traj.measured
        errs.append(np.hypot(traj.u - gt["u"], traj.v - gt["v"])[m])
        found += int(m.sum())
        total += len(m)
    e = np.concatenate(errs) if errs else np.array([math.nan])
    return {"mean_px": float(np.mean(e)), "p95_px": float(np.percentile(e, 95)), "found": found / max(total, 1)}
