"""Render a simulated throw to a video with a known answer, and write its ground truth beside it.

:func:`simulate` steps a compiled scene (``study.simulate.scene.compile_scene``) from an initial state with
``mujoco.mj_step``; :func:`render` draws the stored states through the scene's fixed camera with
MuJoCo's offscreen renderer, adds optional motion blur (the average of sub-frame renders over the
shutter time), sensor noise and JPEG-like degradation (a resting, asleep object's pose repeats bit
for bit, so its image is drawn once and reused), writes an mp4 (OpenCV, codec mp4v) and a CSV of
the truth: time, world x, y, z of the object's centre (metres) and its projection u, v (pixels).

Pixel coordinates: u to the right, v down, the centre of the top-left pixel at (0, 0), the same
convention as OpenCV's image moments, so a tracked centroid compares directly with (u, v).
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path

import cv2
import mujoco  # MUJOCO_GL's default (egl) is set in study/__init__.py, before any mujoco import
import numpy as np
from tqdm import tqdm

from study.core.cache import write_text_atomic
from study.core.errors import ConfigError, RenderError, check_range
from study.see.camera import Camera
from study.see.video import atomic_writer
from study.simulate import synth
from study.simulate.scene import Shape

CLASS_PARAMS: dict[str, dict[str, float]] = {
    "light": {"mass": 0.2, "damping": 100.0, "friction": 0.5},
    "heavy": {"mass": 5.0, "damping": 400.0, "friction": 0.5},
}
"""Physically sensible defaults per class for :func:`class_model` (kg, 1/s, dimensionless).
Damping 100 with stiffness 2.5e5 gives a bouncy contact (restitution about 0.7), 400 a dull one."""

STIFFNESS = synth.SynthConfig.stiffness
"""Contact stiffness k of the direct solref format, 1/s^2: synthesis's."""
TIMESTEP = synth.SynthConfig.timestep
"""Simulation step, seconds: synthesis's (it divides the frame period of 30 and 60 fps video)."""
OBJECT_RGBA = (0.9, 0.35, 0.05, 1.0)
"""The object's paint: a saturated orange the 'orange' tracker preset finds (hue about 10 of 180)."""
SLEEP_TOLERANCE = synth.SynthConfig.sleep_tolerance
"""m/s, synthesis's default: a resting object falls asleep, and its pose stays exactly the same."""


@dataclass
class RenderConfig:
    """How a throw becomes a video."""

    width: int = 640
    """Frame width, pixels."""
    height: int = 480
    """Frame height, pixels."""
    fps: float = 30.0
    """Video frame rate, frames per second; the simulation timestep must divide the frame period."""
    duration: float = 3.0
    """Length of the video, seconds."""
    camera: str = "side"
    """Name of the scene's fixed camera."""
    blur_subframes: int = 1
    """Sub-frame renders averaged into each frame (motion blur); 1 = no blur."""
    shutter: float = 0.5
    """Exposure time as a fraction of the frame period, centred on the frame time (with blur)."""
    noise_std: float = 0.0
    """Gaussian sensor noise, standard deviation in grey levels (0-255)."""
    jpeg_quality: int | None = None
    """If set (1-100), each frame is JPEG-encoded at this quality and decoded before writing."""
    shadows: bool = True
    """Draw shadows (slower)."""
    seed: int = 0
    """Seed of the sensor noise."""
    progress: bool = False
    """Show a progress bar."""

    def validate(self) -> None:
        """Raise :class:`ConfigError` for an out-of-range field."""
        check_range("RenderConfig.width", self.width, 16, 1920)
        check_range("RenderConfig.height", self.height, 16, 1080)
        check_range("RenderConfig.fps", self.fps, 1.0, 1000.0)
        check_range("RenderConfig.duration", self.duration, 0.0, 600.0, lo_open=True)
        check_range("RenderConfig.blur_subframes", self.blur_subframes, 1, 64)
        check_range("RenderConfig.shutter", self.shutter, 0.0, 1.0)
        check_range("RenderConfig.noise_std", self.noise_std, 0.0, 128.0)
        if self.jpeg_quality is not None:
            check_range("RenderConfig.jpeg_quality", self.jpeg_quality, 1, 100)


@dataclass
class Rendered:
    """A rendered video and its ground truth, one row per frame."""

    video: Path
    """The mp4 file."""
    truth: Path
    """The CSV file: t, x, y, z, u, v."""
    t: np.ndarray = field(repr=False)
    """(n,) float64 seconds, frame times."""
    xyz: np.ndarray = field(repr=False)
    """(n, 3) float64 metres, world position of the object's centre (z up, ground at 0)."""
    uv: np.ndarray = field(repr=False)
    """(n, 2) float64 pixels, the centre projected into the image (u right, v down)."""
    fps: float = 30.0
    """Frame rate, frames per second."""
    drawn: int = 0
    """Images MuJoCo rendered."""
    reused: int = 0
    """Sub-frame images not rendered again: the object's pose was bitwise that of the previous one."""


def class_model(label: str, shape: Shape = Shape(), timestep: float = TIMESTEP, rgba=OBJECT_RGBA,
                sleep_tolerance: float = SLEEP_TOLERANCE) -> mujoco.MjModel:
    """The scene with one object of class ``label`` ('light' or 'heavy') using :data:`CLASS_PARAMS`.

    ``sleep_tolerance``: m/s, as ``study.simulate.synth.SynthConfig.sleep_tolerance`` (0: never asleep).
    """
    from study.simulate.scene import compile_scene

    if label not in CLASS_PARAMS:
        raise ConfigError(f"label = {label!r} is unknown; allowed: {', '.join(CLASS_PARAMS)}")
    check_range("sleep_tolerance", sleep_tolerance, 0.0, synth.max_sleep_tolerance(timestep))
    return compile_scene(shape, stiffness=STIFFNESS, timestep=timestep, rgba=rgba, sleep_tolerance=sleep_tolerance,
                         **CLASS_PARAMS[label])


def initial_state(
    pos: tuple[float, float, float],
    vel: tuple[float, float, float],
    angvel: tuple[float, float, float] = (0.0, 0.0, 0.0),
    quat: tuple[float, float, float, float] = (1.0, 0.0, 0.0, 0.0),
) -> tuple[np.ndarray, np.ndarray]:
    """(qpos (7,), qvel (6,)) of the free body: position m, orientation (w, x, y, z), velocity m/s, angular velocity rad/s."""
    return np.array([*pos, *quat], float), np.array([*vel, *angvel], float)


def steps_per_frame(model: mujoco.MjModel, fps: float) -> int:
    """Simulation steps in one frame period; raise :class:`ConfigError` unless the timestep divides it."""
    ratio = 1.0 / (fps * model.opt.timestep)
    k = round(ratio)
    if k < 1 or abs(ratio - k) > 1e-6 * ratio:
        raise ConfigError(
            f"timestep {model.opt.timestep!r} s does not divide the frame period 1/{fps} s; "
            "choose a timestep such as 1/1800 s for 30 or 60 fps"
        )
    return k


def simulate(model: mujoco.MjModel, qpos: np.ndarray, qvel: np.ndarray, n_steps: int) -> np.ndarray:
    """Step the scene ``n_steps`` times from (qpos, qvel); (n_steps + 1, nq) float64 states, the first the initial one."""
    data = mujoco.MjData(model)
    data.qpos[:] = qpos
    data.qvel[:] = qvel
    out = synth.step_states(model, data, n_steps)
    if not np.isfinite(out).all():
        raise ConfigError("the simulation diverged (NaN state); use a smaller timestep or a softer contact")
    return out


def project(model: mujoco.MjModel, data: mujoco.MjData, camera: str, points: np.ndarray, width: int, height: int) -> np.ndarray:
    """Pixel coordinates (n, 2) of world points (n, 3) metres, seen by ``camera`` in a width x height image.

    Uses the camera pose (``data.cam_xpos``, ``data.cam_xmat``; MuJoCo cameras look along -z with y
    up) and ``model.cam_fovy`` (vertical field of view, degrees). ``data`` must be forwarded.
    """
    cid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_CAMERA, camera)
    if cid < 0:
        raise ConfigError(f"camera {camera!r} is not in the scene")
    R = data.cam_xmat[cid].reshape(3, 3)  # columns: camera x, y, z axes in world
    rel = (np.asarray(points, float) - data.cam_xpos[cid]) @ R  # (n, 3) camera frame
    f = 0.5 * height / np.tan(np.deg2rad(model.cam_fovy[cid]) / 2)  # focal length, pixels
    depth = -rel[:, 2]
    u = 0.5 * width + f * rel[:, 0] / depth - 0.5
    v = 0.5 * height - f * rel[:, 1] / depth - 0.5
    return np.stack([u, v], axis=1)


def scene_camera(model: mujoco.MjModel, name: str, width: int, height: int) -> Camera:
    """The scene's fixed camera ``name`` as a :class:`~study.see.camera.Camera` for a width x height image: its
    pose in the model's initial state (a fixed camera does not move) and :func:`project`'s focal length."""
    cid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_CAMERA, name)
    if cid < 0:
        raise ConfigError(f"camera {name!r} is not in the scene")
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    f = 0.5 * height / np.tan(np.deg2rad(model.cam_fovy[cid]) / 2)
    return Camera(tuple(float(x) for x in data.cam_xpos[cid]), tuple(float(x) for x in data.cam_xmat[cid]),
                  float(f), int(width), int(height))


def _renderer(model: mujoco.MjModel, height: int, width: int) -> mujoco.Renderer:
    """MuJoCo's offscreen renderer with MUJOCO_GL's backend, falling back from EGL to OSMesa."""
    gl = os.environ.get("MUJOCO_GL", "egl")
    try:
        return mujoco.Renderer(model, height, width)
    except Exception as first:
        if gl == "egl":
            from mujoco.rendering.classic import gl_context

            original = getattr(gl_context, "GLContext", None)
            try:  # the renderer looks its context class up at construction: swap in OSMesa's
                from mujoco.osmesa import GLContext

                gl_context.GLContext = GLContext
                return mujoco.Renderer(model, height, width)
            except Exception as second:
                gl_context.GLContext = original
                raise RenderError(
                    f"MuJoCo cannot render: EGL failed ({first}) and OSMesa failed ({second}); install "
                    "the system library libEGL (apt install libegl1) or libOSMesa (apt install libosmesa6)"
                ) from second
        lib = {"osmesa": "libOSMesa (apt install libosmesa6)"}.get(gl, f"the OpenGL library for {gl}")
        raise RenderError(f"MuJoCo cannot render with MUJOCO_GL={gl}: {first}; install {lib}, or set MUJOCO_GL=egl") from first


def render(
    model: mujoco.MjModel,
    qpos: np.ndarray,
    qvel: np.ndarray,
    out: str | Path,
    cfg: RenderConfig | None = None,
    reuse: bool = True,
) -> Rendered:
    """Simulate the throw from (qpos, qvel) and render it to ``out`` (mp4) plus ``out`` with suffix .csv (truth).

    Frame i shows the scene at time i / fps; with blur it averages ``blur_subframes`` renders spread
    over the shutter time centred on it. Both files are written atomically. ``reuse``: a sub-frame
    whose object pose is bitwise that of the previous one (at rest, asleep) reuses its image instead
    of rendering it again; the video is the same either way.
    """
    cfg = cfg or RenderConfig()
    cfg.validate()
    out = Path(out)
    spf = steps_per_frame(model, cfg.fps)
    n_frames = int(round(cfg.duration * cfg.fps))
    half = int(round(cfg.shutter * spf / 2)) if cfg.blur_subframes > 1 else 0
    states = simulate(model, qpos, qvel, n_frames * spf + half)  # one half-shutter beyond the last frame

    data = mujoco.MjData(model)
    renderer = _renderer(model, cfg.height, cfg.width)
    renderer.scene.flags[mujoco.mjtRndFlag.mjRND_SHADOW] = cfg.shadows
    rng = np.random.default_rng(cfg.seed)
    if cfg.blur_subframes > 1:
        offsets = np.round(np.linspace(-half, half, cfg.blur_subframes)).astype(int)
    else:
        offsets = np.zeros(1, int)

    last_pose, last_image, drawn, reused = b"", None, 0, 0

    def draw(step: int) -> np.ndarray:
        nonlocal last_pose, last_image, drawn, reused
        pose = states[step].tobytes()
        if reuse and pose == last_pose:
            reused += 1
            return last_image
        data.qpos[:] = states[step]
        mujoco.mj_forward(model, data)
        renderer.update_scene(data, camera=cfg.camera)
        last_pose, last_image = pose, renderer.render()  # (H, W, 3) uint8 RGB, row 0 at the top
        drawn += 1
        return last_image

    t = np.arange(n_frames) / cfg.fps
    xyz = np.empty((n_frames, 3))
    uv = np.empty((n_frames, 2))
    try:
        with atomic_writer(out, cfg.fps, (cfg.width, cfg.height)) as writer:
            for i in tqdm(range(n_frames), desc=f"render {out.name}", disable=not cfg.progress, unit="frame"):
                centre = i * spf
                acc = np.zeros((cfg.height, cfg.width, 3), np.float32)
                for off in offsets:
                    acc += draw(int(np.clip(centre + off, 0, len(states) - 1)))
                data.qpos[:] = states[centre]
                mujoco.mj_forward(model, data)
                xyz[i] = data.qpos[:3]
                uv[i] = project(model, data, cfg.camera, data.qpos[None, :3], cfg.width, cfg.height)[0]
                img = acc / len(offsets)
                if cfg.noise_std > 0:
                    img += rng.normal(0.0, cfg.noise_std, img.shape).astype(np.float32)
                bgr = np.ascontiguousarray(np.clip(img + 0.5, 0, 255).astype(np.uint8)[:, :, ::-1])
                if cfg.jpeg_quality is not None:
                    ok, buf = cv2.imencode(".jpg", bgr, [cv2.IMWRITE_JPEG_QUALITY, int(cfg.jpeg_quality)])
                    bgr = cv2.imdecode(buf, cv2.IMREAD_COLOR)
                writer.write(bgr)
    finally:
        renderer.close()

    truth = out.with_suffix(".csv")
    rows = ["t,x,y,z,u,v"] + [
        f"{ti:.6f},{p[0]:.6f},{p[1]:.6f},{p[2]:.6f},{q[0]:.3f},{q[1]:.3f}" for ti, p, q in zip(t, xyz, uv)
    ]
    write_text_atomic(truth, "\n".join(rows) + "\n")
    return Rendered(video=out, truth=truth, t=t, xyz=xyz, uv=uv, fps=cfg.fps, drawn=drawn, reused=reused)


def read_truth(path: str | Path) -> dict[str, np.ndarray]:
    """The ground-truth CSV written by :func:`render` as columns {'t', 'x', 'y', 'z', 'u', 'v'}, each (n,) float64."""
    a = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    return {k: a[:, j] for j, k in enumerate("txyzuv")}


def synth_model(cfg, params: dict[str, np.ndarray], i: int) -> tuple[mujoco.MjModel, np.ndarray, np.ndarray]:
    """The compiled scene and MuJoCo initial state (qpos, qvel) of trajectory ``i`` of a synth split.

    ``cfg`` is a ``study.simulate.synth.SynthConfig``; ``params`` a split's ``params`` dict (mass, damping,
    friction, qpos0, qvel0). The velocity is staggered exactly as synthesis does, so the rendered
    motion is the dataset's trajectory.
    """
    model, data = synth.initial_data(cfg, params, i)
    return model, data.qpos.copy(), data.qvel.copy()


def framing_camera(path: np.ndarray, fovy: float = 45.0) -> mujoco.MjvCamera:
    """A free camera that sees the whole ``path`` ((n, 3) metres) side-on, from slightly above.

    It looks at the middle of the path, across its main horizontal direction of travel, from far
    enough away that the path's extent fits in the vertical field of view ``fovy`` (degrees).
    """
    path = np.asarray(path, float)
    lo, hi = path.min(axis=0), path.max(axis=0)
    travel = path[-1, :2] - path[0, :2]
    heading = np.degrees(np.arctan2(travel[1], travel[0])) if np.linalg.norm(travel) > 1e-3 else 0.0
    extent = max(float(np.linalg.norm(hi[:2] - lo[:2])), 2.0 * float(hi[2]), 1.0)
    cam = mujoco.MjvCamera()
    cam.type = mujoco.mjtCamera.mjCAMERA_FREE
    cam.lookat[:] = [(lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, max(hi[2] / 2, 0.2)]
    cam.azimuth = heading - 90.0  # look across the direction of travel
    cam.elevation = -8.0
    cam.distance = 0.55 * extent / np.tan(np.radians(fovy) / 2)
    return cam


def filmstrip(cfg, params: dict[str, np.ndarray], i: int, times, width: int = 320, height: int = 240,
              camera: str = "auto", shadows: bool = True) -> list[np.ndarray]:
    """Frames of trajectory ``i`` of a synth split at ``times`` (seconds): a list of (height, width, 3) uint8 RGB.

    ``camera``: a camera of the scene by name, or ``"auto"`` for one fixed camera that frames the whole
    throw (:func:`framing_camera`).
    """
    model, qpos, qvel = synth_model(cfg, params, i)
    steps = np.round(np.asarray(times, float) / model.opt.timestep).astype(int)
    if len(steps) == 0 or steps.min() < 0:
        raise ConfigError(f"times = {list(times)!r}: give one or more times >= 0 s")
    states = simulate(model, qpos, qvel, int(steps.max()))
    view = framing_camera(states[: steps.max() + 1, :3]) if camera == "auto" else camera
    data = mujoco.MjData(model)
    renderer = _renderer(model, height, width)
    renderer.scene.flags[mujoco.mjtRndFlag.mjRND_SHADOW] = shadows
    out = []
    try:
        for s in steps:
            data.qpos[:] = states[s]
            mujoco.mj_forward(model, data)
            renderer.update_scene(data, camera=view)
            out.append(renderer.render().copy())
    finally:
        renderer.close()
    return out


def metres_per_pixel(model: mujoco.MjModel, camera: str, height: int, depth: float) -> float:
    """Size in metres of one pixel at ``depth`` metres along the view axis, for an image ``height`` pixels high."""
    cid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_CAMERA, camera)
    if cid < 0:
        raise ConfigError(f"camera {camera!r} is not in the scene")
    return float(2 * depth * np.tan(np.deg2rad(model.cam_fovy[cid]) / 2) / height)
