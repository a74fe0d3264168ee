"""The camera sweep: held-aside throws filmed from cameras the study never saw, to measure what a user's camera
leaves of the heights and of the answer.

Each clip is one throw of the study's priors (the test split of a seed no training set uses, launched across the
view as the book's renders are: ``study.methods.videos.throw``) rendered through a :class:`Shot`: a camera placed
at a random height, distance, yaw and tilt, with a random field of view, frame size and rate, floor, light and
object colour, drawn from one of the :data:`FAMILIES`. Six magenta floor marks lie about the throw's middle
(``study.see.marklayout.LAYOUT``, drawn by ``study.methods.marked``: the throw is bitwise the same), for the floor
path's clicks and for finding them by colour. A shot is kept only if the object stays in the picture and at least
:data:`MIN_PIXELS` pixels wide for the whole clip, and every mark is in the picture (checked on the simulated path
before anything is rendered). Clips are cached under ``out_dir/sweep-<key>/`` by a key of everything that determines them, this
module's code and the renderer's included, with a ``MANIFEST.csv`` (file, label, family, colour, object size) and,
beside each video, the renderer's ground truth (``study.see.render``).

    clips = sweep_set(synth.SynthConfig.preset("paper"), per_family=20, seed=SWEEP_SEED, out_dir=data_dir / "realworld")
"""

from __future__ import annotations

import json
from collections.abc import Callable
import math
import time
from dataclasses import asdict, dataclass, replace
from pathlib import Path

import mujoco
import numpy as np

from study import CLASSES
from study.core import cache
from study.core.progress import Progress
from study.methods import marked, videos
from study.see import marklayout, render
from study.see.camera import Camera
from study.see.size import apparent_size
from study.simulate.observe import CAMERA_FAMILIES, CameraFamily

FAMILIES: dict[str, CameraFamily] = {f.key: f for f in CAMERA_FAMILIES}
"""The camera families by key (``study.simulate.observe.CAMERA_FAMILIES``, where each is defined once)."""
FOV = (50.0, 90.0)
"""Vertical field of view, degrees."""
SIZES = ((640, 480), (854, 480), (1280, 720), (1920, 1080))
"""Frame sizes, pixels (480p, 720p and 1080p: the results are pooled by frame height too)."""
RATES = (30.0, 60.0)
"""Frame rates, frames per second."""
COLOURS: dict[str, tuple[float, float, float]] = {
    "orange": (0.9, 0.35, 0.05), "red": (0.8, 0.05, 0.08), "green": (0.1, 0.7, 0.15), "blue": (0.1, 0.25, 0.85),
}
"""Object paints (RGB, 0-1), each one of the tracker's named colours (``study.see.config.COLORS``)."""
FLOORS = ((1.0, 1.0, 1.0), (0.8, 0.6, 0.42), (0.5, 0.58, 0.5), (0.55, 0.55, 0.6))
"""Floor tints multiplying the checker texture: grey, wood-brown, greenish, dark."""
LIGHT = (0.45, 1.0)
"""Diffuse strength of the scene's light (0-1 per channel)."""
MIN_PIXELS = 8.0
"""Narrowest the object may appear, pixels."""
SWEEP_SEED = 3000
"""Seed of the sweep's throws (their test split): no data set trains on it, and the tracker's development renders
(``study.methods.calibration.DEVELOPMENT_RENDER_SEED``, 2000) and the book's (1000) are other throws."""

TIMES = "RENDER_SECONDS.json"
"""Beside the clips: each clip's rendering time as it was made, ``{file: {"cpu_s": ..., "wall_s": ...}}`` (the
process's CPU seconds and the wall clock's), so a cached sweep still says what it cost."""

DURATION = 3.0
"""Clip length, seconds (the models' input)."""


@dataclass(frozen=True)
class Shot:
    """How one clip is filmed."""

    family: str
    """A key of :data:`FAMILIES`."""
    height: float
    """Camera height above the floor, metres."""
    tilt: float
    """Camera tilt below the horizon, degrees."""
    yaw: float
    """Camera yaw away from square-on to the throw, degrees."""
    distance: float
    """Horizontal distance from the middle of the throw, metres."""
    fov: float
    """Vertical field of view, degrees."""
    width: int
    """Frame width, pixels."""
    height_px: int
    """Frame height, pixels."""
    fps: float
    """Frames per second."""
    colour: str
    """The object's paint, a key of :data:`COLOURS`."""
    floor: tuple[float, float, float]
    """Floor tint."""
    light: float
    """Light strength."""


def draw_shot(family: str, rng: np.random.Generator) -> Shot:
    """A random :class:`Shot` of ``family``."""
    r = FAMILIES[family]
    u = {k: float(rng.uniform(*getattr(r, k))) for k in ("height", "tilt", "yaw", "distance")}
    u["yaw"] *= float(rng.choice([-1.0, 1.0]))
    w, h = SIZES[int(rng.integers(len(SIZES)))]
    return Shot(family=family, fov=float(rng.uniform(*FOV)), width=w, height_px=h, fps=float(rng.choice(RATES)),
                colour=str(rng.choice(list(COLOURS))), floor=FLOORS[int(rng.integers(len(FLOORS)))],
                light=float(rng.uniform(*LIGHT)), **u)


def camera(shot: Shot, path: np.ndarray) -> Camera:
    """The :class:`~study.see.camera.Camera` of ``shot`` for a throw whose centre follows ``path`` (n, 3) metres:
    it stands ``shot.distance`` from the path's middle (on the ground), yawed from square-on (the throws cross
    the world's x axis), looking at the middle's bearing, tilted down by ``shot.tilt``."""
    mid = path.mean(axis=0)
    heading = math.radians(90.0 + shot.yaw)  # square-on: looking along +y, across the throw
    t = math.radians(shot.tilt)
    fwd = np.array([math.cos(t) * math.cos(heading), math.cos(t) * math.sin(heading), -math.sin(t)])
    right = np.array([math.sin(heading), -math.cos(heading), 0.0])
    pos = (mid[0] - shot.distance * math.cos(heading), mid[1] - shot.distance * math.sin(heading), shot.height)
    focal = 0.5 * shot.height_px / math.tan(math.radians(shot.fov) / 2)
    axes = np.column_stack([right, np.cross(right, fwd), -fwd])
    return Camera(tuple(float(x) for x in pos), tuple(float(x) for x in axes.ravel()), float(focal),
                  shot.width, shot.height_px)


def visible(cam: Camera, path: np.ndarray, size: float) -> bool:
    """Whether an object of apparent ``size`` metres on ``path`` (n, 3) stays in ``cam``'s picture, in front of
    it, and at least :data:`MIN_PIXELS` wide, in every frame."""
    depth = cam.depth_of(path)
    if not (depth > 0.3).all():
        return False
    uv = cam.project(path)
    inside = (uv[:, 0] > 0) & (uv[:, 0] < cam.width - 1) & (uv[:, 1] > 0) & (uv[:, 1] < cam.height - 1)
    return bool(inside.all() and (cam.focal * size / depth >= MIN_PIXELS).all())


def marks_about(path: np.ndarray) -> np.ndarray:
    """(k, 2) metres: where the floor marks lie for a throw whose centre follows ``path`` (n, 3) metres at the
    clip's frame times (its truth CSV's rows): ``study.see.marklayout.LAYOUT`` about the path's middle on the floor."""
    return np.asarray(path, np.float64)[:, :2].mean(axis=0) + marklayout.LAYOUT


def marks_visible(cam: Camera, points: np.ndarray, margin: float = 0.02) -> bool:
    """Whether every floor point ``points`` (k, 2) metres lies in front of ``cam`` and inside its picture, at least
    ``margin`` of the frame's width and height from its edges."""
    ground = np.column_stack([points, np.zeros(len(points))])
    if not (cam.depth_of(ground) > 0.3).all():
        return False
    uv = cam.project(ground)
    du, dv = margin * cam.width, margin * cam.height
    return bool(((uv[:, 0] > du) & (uv[:, 0] < cam.width - 1 - du) & (uv[:, 1] > dv)
                 & (uv[:, 1] < cam.height - 1 - dv)).all())


def dress(model: mujoco.MjModel, shot: Shot, cam: Camera) -> None:
    """Put ``cam`` into ``model``'s 'side' camera (pose and field of view) and paint the object, floor and light
    as ``shot`` says, in place."""
    cid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_CAMERA, "side")
    quat = np.empty(4)
    mujoco.mju_mat2Quat(quat, np.asarray(cam.rotation, np.float64))
    model.cam_pos[cid] = cam.position
    model.cam_quat[cid] = quat
    model.cam_fovy[cid] = shot.fov
    model.geom_rgba[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, "object")][:3] = COLOURS[shot.colour]
    model.mat_rgba[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_MATERIAL, "ground")][:3] = shot.floor
    model.light_diffuse[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_LIGHT, "sun")] = shot.light


@dataclass
class Clip:
    """One rendered clip of the sweep."""

    video: videos.Video
    """The video, its label, colour and object size (the user's flags), and its ground truth."""
    shot: Shot
    """How it was filmed."""


def sweep_set(cfg, per_family: int, seed: int, out_dir: str | Path, progress: bool = True,
              max_draws: int = 50, frame_scale: float = 1.0, duration: float = DURATION) -> list[Clip]:
    """``per_family`` clips of each family in :data:`FAMILIES`, the classes alternating within each, from ``cfg``'s priors (a
    ``synth.SynthConfig``; throws of ``synth.sample_split(cfg, seed, "test")``, so give a ``seed`` no training set
    uses), each through a shot drawn until the object is :func:`visible` (at most ``max_draws`` draws, else the
    throw is skipped). ``frame_scale`` shrinks every frame size and ``duration`` (seconds) cuts the clips (a smoke test's). Rendered once under ``out_dir``,
    then read from the cache."""
    n = per_family * len(FAMILIES)
    cfg = cfg.replace(n_test=2 * n)  # spare throws for the ones no shot can keep in view
    code = cache.source_hash(*cache.closure("study.methods.sweep"))
    key = cache.key({"synth": cfg.to_dict(), "seed": seed, "per_family": per_family, "max_draws": max_draws,
                     "frame_scale": frame_scale, "duration": duration, "code": code})
    folder = Path(out_dir) / f"sweep-{key}"
    params = synth_split(cfg, seed)
    size = _object_size(cfg)
    rng = np.random.default_rng(seed)
    queues = [list(np.flatnonzero(params["label"] == k)) for k in range(len(CLASSES))]  # throws of each class
    plan: list[tuple[int, Shot, Camera, np.ndarray]] = []
    for family in FAMILIES:
        for k in range(per_family):
            queue = queues[k % len(CLASSES)]  # the classes alternate within a family
            while queue:
                i = int(queue.pop(0))
                model, qpos, qvel = videos.throw(cfg, params, i)
                path = render.simulate(model, qpos, qvel, round(duration / model.opt.timestep))[:, :3]
                shot = _keep(family, lambda fps: at_frames(model, path, fps, duration), size, rng, max_draws,
                             frame_scale)
                if shot is not None:
                    plan.append((i, *shot))
                    break
    clips = []
    for i, shot, _, _ in plan:
        label = CLASSES[int(params["label"][i])]
        name = f"{shot.family}_{len(clips):03d}_{label}.mp4"
        v = videos.Video(folder / name, label, color=shot.colour, object_size=size, rest_height=cfg.shape.rest_height,
                         truth=(folder / name).with_suffix(".csv"), info={"family": shot.family, **asdict(shot)})
        clips.append(Clip(v, shot))
    todo = [(c, i, cam, xy) for c, (i, _, cam, xy) in zip(clips, plan) if not videos.rendered(c.video)]
    with Progress("render the camera sweep", total=len(todo), show=progress, unit="clip") as bar:
        for c, i, cam, xy in todo:
            with cache.one_maker(c.video.path):  # two chapters of a build render it once
                if not videos.rendered(c.video):
                    _render_clip(cfg, params, i, c.shot, cam, xy, c.video.path, duration, seed)
            bar.update()
    manifest = "file,label,family,color,object_size\n" + "".join(
        f"{c.video.path.name},{c.video.label},{c.shot.family},{c.shot.colour},{size:.6g}\n" for c in clips)
    if not (folder / "MANIFEST.csv").is_file() or (folder / "MANIFEST.csv").read_text() != manifest:
        cache.write_text_atomic(folder / "MANIFEST.csv", manifest)
    return clips


def _render_clip(cfg, params: dict, i: int, shot: Shot, cam: Camera, xy: np.ndarray, path: Path, duration: float,
                 seed: int) -> None:
    """Render throw ``i`` of ``params`` through ``shot``'s camera ``cam`` with its floor marks at ``xy`` (k, 2)
    metres to ``path``, and add its rendering time to the folder's :data:`TIMES`."""
    cpu, wall = time.process_time(), time.perf_counter()
    _, qpos, qvel = videos.throw(cfg, params, i)
    model = marked.with_marks(marked.throw_xml(cfg, params, i), xy)  # the same throw, its marks drawn
    dress(model, shot, cam)
    rcfg = render.RenderConfig(width=shot.width, height=shot.height_px, fps=shot.fps, duration=duration,
                               blur_subframes=2, noise_std=2.0, jpeg_quality=85, seed=seed + i)
    render.render(model, qpos, qvel, path, rcfg)
    spent = {"cpu_s": round(time.process_time() - cpu, 2), "wall_s": round(time.perf_counter() - wall, 2)}
    with cache.one_maker(path.parent / TIMES):  # read again: another process may have added its clips
        times = {**_read_times(path.parent), path.name: spent}
        cache.write_text_atomic(path.parent / TIMES, json.dumps(times, indent=1, sort_keys=True))


def render_times(clips: list[Clip]) -> dict[str, dict[str, float]]:
    """Each of ``clips``' rendering time as it was made (:data:`TIMES`): file name -> ``{"cpu_s", "wall_s"}``,
    seconds; a clip rendered before times were kept is missing."""
    out: dict[str, dict[str, float]] = {}
    for folder in dict.fromkeys(c.video.path.parent for c in clips):
        out.update(_read_times(folder))
    return {c.video.path.name: out[c.video.path.name] for c in clips if c.video.path.name in out}


def _read_times(folder: Path) -> dict[str, dict[str, float]]:
    """The folder's :data:`TIMES` ({} where none or unreadable: the times are a record, not a cache)."""
    try:
        got = json.loads((folder / TIMES).read_text())
    except (OSError, ValueError):
        return {}
    return got if isinstance(got, dict) else {}


def at_frames(model: mujoco.MjModel, path: np.ndarray, fps: float, duration: float) -> np.ndarray:
    """(n, 3) the centres ``path`` (one row a simulation step, the first the launch) at a clip's frame times: the
    rows its truth CSV holds (``study.see.render.render``), so the camera and the marks placed about them here are
    the ones the camera cost places about the truth."""
    return path[:: render.steps_per_frame(model, fps)][: round(duration * fps)]


def _keep(family: str, frames_at: Callable[[float], np.ndarray], size: float, rng: np.random.Generator,
          max_draws: int, frame_scale: float) -> tuple[Shot, Camera, np.ndarray] | None:
    """The first of up to ``max_draws`` shots of ``family`` that keeps the throw (``frames_at(fps)``: its centres at
    the frame times, (n, 3) metres) :func:`visible` and the floor marks about it in the picture
    (:func:`marks_visible`), with its camera and the marks' positions (k, 2) metres; or None."""
    for _ in range(max_draws):
        shot = draw_shot(family, rng)
        if frame_scale != 1.0:
            shot = replace(shot, width=max(16, round(shot.width * frame_scale)),
                           height_px=max(16, round(shot.height_px * frame_scale)))
        path = frames_at(shot.fps)
        cam, xy = camera(shot, path), marks_about(path)
        if visible(cam, path, size) and marks_visible(cam, xy):
            return shot, cam, xy
    return None


def synth_split(cfg, seed: int) -> dict[str, np.ndarray]:
    """The held-aside throws: ``synth.sample_split(cfg, seed, "test")``."""
    from study.simulate import synth

    return synth.sample_split(cfg, seed, "test")


def _object_size(cfg) -> float:
    """The object's size as the user's path reads it (``study.see.size.apparent_size``), metres."""
    return apparent_size(cfg.shape.kind, tuple(2 * s for s in cfg.shape.size) if cfg.shape.kind == "box"
                         else (2 * cfg.shape.size[0],) if cfg.shape.kind == "sphere"
                         else (2 * cfg.shape.size[0], 2 * cfg.shape.size[1]))
