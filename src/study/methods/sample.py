"""Sample clips for a user to try the video path on (``study render``): throws of each class drawn from the study's
priors and rendered as the book renders them, with everything a user's own folder would hold — the videos, a
``MANIFEST.csv`` (file, label, colour, size and shape), and floor marks in view (magenta discs at
``study.see.marklayout.LAYOUT``) for ``study classify --floor``: ``FLOOR.csv`` gives their positions with their pixels
through the renderer's camera (as exact clicks), ``MARKS.csv`` their positions only (the marks found in the video);
and, beside each video, its ground truth (``study.see.render``'s CSV).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from study import CLASSES
from study.core.cache import write_text_atomic
from study.core.errors import ConfigError, check_writable
from study.core.progress import Progress
from study.methods.marked import throw_xml, with_marks
from study.methods.videos import throw
from study.see import floor, marklayout, render
from study.see.camera import Camera
from study.simulate import synth

SEED = 7
"""The throws' default seed: other throws than any split the book trains or tests on (those are seeds 0-2 and their
offsets)."""
COLOR = "orange"
"""The rendered object's colour (``study.see.config.COLORS``)."""


def render_config(seed: int = SEED) -> render.RenderConfig:
    """How a sample is filmed: 640 x 360 at 60 frames a second for 3 s, as a phone would, with motion blur, sensor
    noise, JPEG loss and shadows."""
    return render.RenderConfig(width=640, height=360, fps=60.0, duration=3.0, blur_subframes=2, noise_std=2.0,
                               jpeg_quality=85, shadows=True, seed=seed)


def floor_rows(camera: Camera, points: np.ndarray = marklayout.LAYOUT) -> list[tuple[float, float, float, float]]:
    """The ``FLOOR.csv`` rows ``(u, v, x, y)`` of the floor points ``points`` (n, 2) metres (by default the marks the
    samples show, ``study.see.marklayout.LAYOUT``, about the middle of the throws' path) that ``camera`` sees inside its
    image, exact; :class:`ConfigError` when fewer than four are in view."""
    marked = floor.seen(camera, points)
    if len(marked.points) < floor.MIN_MARKS:
        raise ConfigError(f"only {len(marked.points)} of the floor points are in the camera's view; need four")
    return [(float(u), float(v), float(x), float(y)) for (u, v), (x, y) in zip(marked.pixels, marked.points)]


def write(out_dir: str | Path, per_class: int = 1, seed: int = SEED, progress: bool = True) -> list[Path]:
    """Render ``per_class`` throws of each class into ``out_dir`` (``light_000.mp4``, ``heavy_000.mp4``, ... with
    their truth CSVs), with ``MANIFEST.csv``, ``FLOOR.csv`` and ``MARKS.csv``; returns the videos. Raises :class:`ConfigError` for
    a bad ``per_class`` and ``DataError`` for a folder that cannot be written (before anything is rendered)."""
    if not isinstance(per_class, int) or isinstance(per_class, bool) or not 1 <= per_class <= 20:
        raise ConfigError(f"per_class = {per_class!r}; give a whole number of throws a class from 1 to 20")
    out = Path(out_dir)
    check_writable(out / "MANIFEST.csv", "sample folder")
    cfg = synth.SynthConfig.preset("paper").replace(n_test=per_class)
    rcfg = render_config(seed)
    params = synth.sample_split(cfg, seed, "test")
    edge = 2 * cfg.shape.size[0]  # the shape's sizes are half-extents
    kind = {"box": "box", "sphere": "ball", "cylinder": "cylinder"}[cfg.shape.kind]
    videos, rows = [], []
    with Progress("render samples", total=len(params["label"]), show=progress, unit="video") as bar:
        for i in range(len(params["label"])):
            label = CLASSES[int(params["label"][i])]
            video = out / f"{label}_{sum(CLASSES[int(c)] == label for c in params['label'][:i]):03d}.mp4"
            _, qpos, qvel = throw(cfg, params, i)
            model = with_marks(throw_xml(cfg, params, i), marklayout.LAYOUT)  # the same throw, the marks drawn
            render.render(model, qpos, qvel, video, rcfg)
            videos.append(video)
            rows.append(f"{video.name},{label},{COLOR},{edge:g},{kind}\n")
            bar.update()
    camera = render.scene_camera(model, rcfg.camera, rcfg.width, rcfg.height)
    write_text_atomic(out / "FLOOR.csv", "u,v,x,y\n" + "".join(f"{u:.2f},{v:.2f},{x:g},{y:g}\n"
                                                             for u, v, x, y in floor_rows(camera)))
    write_text_atomic(out / "MARKS.csv", "x,y\n" + "".join(f"{x:g},{y:g}\n" for x, y in marklayout.LAYOUT))
    write_text_atomic(out / "MANIFEST.csv", "file,label,color,object_size,object_shape\n" + "".join(rows))
    return videos

