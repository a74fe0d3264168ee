"""The videos of the real-world test: throws rendered with a known answer, and real clips read from a folder with
a manifest.

:func:`render_set` (:func:`book_set`, the book's) draws throws from the synthesis priors (``study.simulate.synth``)
and renders them with ``study.see.render`` from a side camera (the launch turned to cross the view, as in the
paper's videos), with a known class and ground truth: the paper's 20 + 20 design, heavy objects included; the
videos are cached by a key of everything that determines them, this module's code included
(``study.core.cache.code_hash("video")``). :func:`read_manifest` (:func:`real_clips`): a folder of labelled videos
with a ``MANIFEST.csv`` (columns ``file``, ``label``, and optionally ``color``, ``object_size``, ``object_shape``;
other columns are kept), the real clips beside the project or the reader's own.
"""

from __future__ import annotations

import csv
import difflib
import math
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from study import CLASSES
from study.core import cache, datadir
from study.core.errors import ConfigError, DataError
from study.core.progress import Progress
from study.see import render
from study.see.config import COLORS, TrackConfig
from study.see.scale import ObjectShape
from study.simulate import synth

LABEL_ALIASES = {"light": "light", "bouncy": "light", "ball": "light", "heavy": "heavy", "sliding": "heavy", "cube": "heavy"}
"""Manifest labels understood, mapped to the study's classes."""

REAL_CLIPS_ENV = "STUDY_REAL_VIDEO"
"""Environment variable that points :func:`real_clips_dir` at a folder of real clips."""
REAL_CLIPS_DEFAULT = Path("..") / "shared" / "data" / "real-video"
"""Where real clips recorded by others (tennis balls only) lie beside the project, relative to the
working folder (the project root when the book runs); read there, never copied into the project."""

TENNIS_BALL = 0.067
"""Diameter of a tennis ball, metres (ITF: 6.54-6.86 cm)."""


SHAPES = ("ball", "box", "cylinder")
"""What a manifest's ``object_shape`` may say was thrown."""

UNKNOWN_LABELS = ("", "?", "unknown")
"""Manifest labels that say the answer is not known: the video is classified, not scored."""


@dataclass
class Video:
    """One video, its label if known, and how to read it."""

    path: Path
    """The video file."""
    label: str | None
    """'light', 'heavy', or None where the manifest does not know (classified, not scored)."""
    color: str = "tennis"
    """The tracker's colour (``study.see.config.COLORS``; ignored where ``hsv`` is given)."""
    object_size: float = TENNIS_BALL
    """The object's size, metres: a ball's diameter, a box's edge, a cylinder's diameter (sets the pixel scale)."""
    rest_height: float = TENNIS_BALL / 2
    """Height of the object's centre when it rests on the ground, metres."""
    truth: Path | None = None
    """Ground-truth CSV of a rendered video (``study.see.render``), if any."""
    info: dict[str, Any] = field(default_factory=dict)
    """Other manifest columns."""
    hsv: tuple[int, int, int, int, int, int] | None = None
    """An explicit HSV range for the tracker (H, S, V low, then high; OpenCV's scale) instead of ``color``."""
    shape: str = "ball"
    """What was thrown, one of :data:`SHAPES` (its silhouette sets the scale)."""
    sizes: tuple[float, ...] = ()
    """All of the object's sizes where its shape takes more than ``object_size`` (a box's three edges, a cylinder's
    diameter and length), metres."""

    def track_config(self) -> TrackConfig:
        """The tracker's settings for this video: its colour or HSV range, no progress bar."""
        return TrackConfig(color=self.color, hsv=self.hsv, progress=False)

    def object_shape(self) -> ObjectShape:
        """The thrown object as ``study.see.scale`` reads its size off the video."""
        return ObjectShape("sphere" if self.shape == "ball" else self.shape, self.sizes or (self.object_size,))


def real_clips_dir(path: str | Path | None = None) -> Path:
    """The folder of real clips: ``path`` if given, else ``$STUDY_REAL_VIDEO``, else :data:`REAL_CLIPS_DEFAULT`.

    The folder may not exist (the clips are optional); :func:`read_manifest` says so if it is read.
    """
    if path:
        return Path(path)
    return Path(os.environ.get(REAL_CLIPS_ENV) or REAL_CLIPS_DEFAULT)


COLUMNS = ("file", "label", "color", "object_size", "object_shape")
"""The manifest's columns that say how a video is read."""
NOTES = ("object", "fps", "width", "height", "frames", "source_repository", "source_commit", "source_path", "licence",
         "notes", "family")
"""Columns kept as they are, in :attr:`Video.info`: what the clip shows and where it comes from (a camera sweep's
clips: their camera family)."""


def read_manifest(video_dir: str | Path, color: str = "tennis", object_size: float | None = None,
                  what: str = "video_dir") -> list[Video]:
    """The videos listed in ``video_dir/MANIFEST.csv``, in file order. Its columns (a header row, then one row per
    video; only ``file`` is required)::

        file,label,color,object_size,object_shape
        throw1.mp4,light,tennis,0.067,ball
        block.mp4,heavy,orange,0.2,box
        mine.mp4,,20 100 100 35 255 255,0.07,ball

    ``label``: light or heavy (or an alias, :data:`LABEL_ALIASES`), or empty / ``?`` / ``unknown`` where it is not
    known; ``color``: a tracker colour (``study.see.config.COLORS``, any case) or an HSV range, six numbers low then
    high (default ``color``); ``object_size``: metres, a ball's diameter, a box's edge or three, a cylinder's
    diameter and length, separated by spaces (default ``object_size``; without one, a tennis ball's for the tennis
    colour only); ``object_shape``: ball, box or cylinder (default ball). The columns of :data:`NOTES` are kept in
    :attr:`Video.info`; any other column is refused (a misspelt header would otherwise be ignored). A manifest with
    only file and label (the older format) reads as before. ``what`` names the folder in errors (the option or
    parameter that gave it).

    Raises :class:`DataError` for a missing folder, manifest or video, :class:`ConfigError` for an unknown column,
    label, colour, shape or a bad or missing size, naming the manifest, the row's file and what to write.
    """
    d = Path(video_dir)
    m = d / "MANIFEST.csv"
    if d.is_file():
        raise DataError(f"{what} {d} is a file; give the folder that holds the videos and their MANIFEST.csv")
    if not d.is_dir():
        raise DataError(f"{what} {d}: no such folder; point it at a folder of videos with a MANIFEST.csv")
    if not m.is_file():
        raise DataError(f"{what} {d}: no MANIFEST.csv; write one with the columns file,label (and optionally "
                        "color,object_size,object_shape)")
    reader = csv.DictReader(m.open(newline=""))
    rows = list(reader)
    if not rows or "file" not in rows[0]:
        raise DataError(f"manifest {m}: needs a header with at least the column file, and one row per video")
    for column in reader.fieldnames or ():
        if column not in COLUMNS + NOTES:
            near = difflib.get_close_matches(column, COLUMNS + NOTES, n=1)
            raise ConfigError(f"manifest {m}: column {column!r} is unknown" + (f" (did you mean {near[0]!r}?)" if near
                              else "") + f"; its columns are {', '.join(COLUMNS)} (and, kept as notes, "
                              f"{', '.join(NOTES)})")
    out = []
    for r in rows:
        out.append(_manifest_row(m, {k: (v or "").strip() for k, v in r.items() if k is not None}, color, object_size))
    return sorted(out, key=lambda v: v.path.name)


def _manifest_row(m: Path, r: dict[str, str], color: str, object_size: float | None) -> Video:
    """One row of :func:`read_manifest`'s manifest ``m`` as a :class:`Video`."""
    where = f"manifest {m}, {r['file'] or 'a row without a file'}"
    raw = r.get("label", "").lower()
    label = None if raw in UNKNOWN_LABELS else LABEL_ALIASES.get(raw)
    if raw not in UNKNOWN_LABELS and label is None:
        raise ConfigError(f"{where}: label {r['label']!r} is unknown; use one of {', '.join(LABEL_ALIASES)}, or "
                          "leave it empty where the answer is not known")
    p = m.parent / r["file"]
    if not r["file"] or not p.is_file():
        raise DataError(f"{where}: listed but not in {m.parent}")
    colour, hsv = (r.get("color") or color).lower(), None
    if any(c.isdigit() for c in colour):
        try:
            hsv = tuple(int(float(x)) for x in colour.replace(",", " ").split())
        except ValueError:
            hsv = ()
        if len(hsv) != 6:
            raise ConfigError(f"{where}: color {colour!r}; give a colour name ({', '.join(COLORS)}) or an HSV range "
                              "of six numbers, low H S V then high H S V")
        colour = color.lower()
    elif colour not in COLORS:
        raise ConfigError(f"{where}: color {colour!r} is unknown; use one of {', '.join(COLORS)} or six HSV numbers")
    given = r.get("object_size") or ("" if object_size is None else str(object_size))
    if not given:
        if colour != "tennis" or hsv is not None:
            raise ConfigError(f"{where}: no object_size for an object that is not tennis-yellow; give its size in metres "
                              "(the column object_size, or for every row --object-size): a tennis ball's 0.067 is "
                              "assumed only for the tennis colour")
        given = str(TENNIS_BALL)
    try:
        sizes = tuple(float(x) for x in given.split())
    except ValueError:
        sizes = ()
    if not sizes or not all(0.001 <= x <= 10.0 for x in sizes):
        raise ConfigError(f"{where}: object_size {r.get('object_size')!r}; give the object's size in metres "
                          "(a tennis ball: 0.067; a cylinder's diameter and length: 0.2 0.5)")
    shape = (r.get("object_shape") or "ball").lower()
    if shape not in SHAPES:
        raise ConfigError(f"{where}: object_shape {shape!r} is unknown; use one of {', '.join(SHAPES)}")
    v = Video(p, label, color=colour, object_size=sizes[0], hsv=hsv, shape=shape,  # type: ignore[arg-type]
              sizes=sizes if len(sizes) > 1 else (),
              info={k: x for k, x in r.items() if k not in ("file", "label", "color", "object_size", "object_shape")})
    try:
        v.rest_height = v.object_shape().rest_height()
    except ConfigError as e:
        raise ConfigError(f"{where}: {e}") from None
    return v


def real_clips(video_dir: str | Path = "", color: str = "tennis", object_size: float | None = None,
               limit: int | None = None) -> list[Video]:
    """The real clips the chapter classifies: those of ``video_dir``'s manifest (:func:`read_manifest`), or, with
    no ``video_dir``, of :func:`real_clips_dir`'s folder if it holds a manifest (none there: no real clips); the
    first ``limit`` of them (None: all)."""
    folder = real_clips_dir(video_dir)
    if not video_dir and not (folder / "MANIFEST.csv").is_file():
        return []
    return read_manifest(folder, color=color, object_size=object_size)[:limit]


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


def rendered(v: Video) -> bool:
    """Whether ``v``'s video and its truth are both on disk (each is written atomically)."""
    return v.path.is_file() and v.truth.is_file()


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
    cfg = cfg.replace(n_test=n_per_class)
    key = cache.key({"synth": cfg.to_dict(), "seed": seed, "render": rcfg.__dict__ | {"progress": None},
                     "max_speed": max_speed, "code": cache.code_hash("video")})
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
    todo = [i for i, v in enumerate(videos) if not rendered(v)]
    with Progress("render videos", total=len(todo), show=progress, unit="video") as bar:
        for i in todo:
            with cache.one_maker(videos[i].path):  # two chapters of a build render it once
                if not rendered(videos[i]):
                    render.render(*throw(cfg, params, i, max_speed), videos[i].path, rcfg)
            bar.update()
    manifest = "file,label\n" + "".join(f"{v.path.name},{v.label}\n" for v in videos)
    if not (folder / "MANIFEST.csv").is_file() or (folder / "MANIFEST.csv").read_text() != manifest:
        cache.write_text_atomic(folder / "MANIFEST.csv", manifest)  # written once: readers never see half of it
    return videos


def book_set(preset_name: str, per_class: int, shadows: bool, fps: float, duration: float, render_seed: int = 1000,
             data_dir: str | Path | None = None, progress: bool = False) -> tuple[list[Video], render.RenderConfig]:
    """The rendered throws the book uses (the real-world chapter's, which the cue chapter measures the
    tracker on): ``per_class`` throws of each class drawn from preset ``preset_name``'s priors (a preset's
    ``videos_per_class``), at 320 x 240, ``fps``, ``duration`` seconds, with motion blur, sensor noise, JPEG loss
    and shadows if ``shadows``; rendered once, then read from the cache.

    The preset's sizes are passed in rather than read here: this module's code is part of every render's key, and
    ``study.runs`` (the training scheduler) is not render code."""
    rcfg = render.RenderConfig(width=320, height=240, fps=fps, duration=duration, blur_subframes=2, noise_std=2.0,
                               jpeg_quality=85, shadows=shadows, seed=render_seed)
    cfg = synth.SynthConfig.preset(preset_name)
    videos = render_set(cfg, per_class, render_seed, datadir.resolve(data_dir) / "realworld", rcfg, progress=progress)
    return videos, rcfg
