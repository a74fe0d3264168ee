"""How well do heights come back from a camera nobody measured? Simulated throws seen through random cameras.

Throws of the study's priors (the test split of data seed 777, launched across the view as the book's renders
are) are simulated with MuJoCo and projected through random pinhole cameras -- height 0.3-2 m, distance 2-8 m,
yaw +-60 degrees, field of view 50-90 degrees, 640 x 480, tilt fixed per family -- keeping a camera only if the
object stays in the picture, 8 pixels wide or more, the whole clip. No rendering: the tracker's outputs are drawn
directly -- the centre's projection with 0.3 pixels of noise, and the apparent diameter of the box's true
silhouette (its projected area, which changes as it tumbles). Per tilt family it prints the heights' RMS error,
median removed, pooled over clips, of:

- ``image only``: ``study.see.geometry.recover`` -- the user's path, from u, v and the diameter alone;
- ``one scale``: the tracker's path before it (``study.see.gaps.set_scale``: the lowest row is the ground, one
  scale from the size at rest);
- ``true camera, size depth``: the real camera, each frame's depth from its apparent size (a floor for any method
  that reads the distance from the size frame by frame).

    python benchmarks/bench_geometry.py            # 6 throws a family, a minute
    python benchmarks/bench_geometry.py --throws 16
"""

from __future__ import annotations

import argparse
import math

import numpy as np

from study.methods import videos
from study.see import geometry, render
from study.see.camera import Camera
from study.see.size import apparent_size
from study.simulate import synth

WIDTH, HEIGHT, FPS, FRAMES = 640, 480, 30.0, 90
REST = 0.1
"""The 20 cm box's centre at rest, metres."""
FACE = 2 * math.sqrt(0.2 * 0.2 / math.pi)
"""The box's face as a disc's diameter: the size the one-scale path reads at rest."""


def throws(n: int, seed: int = 777) -> list[np.ndarray]:
    """``n`` simulated throws, each (FRAMES, 7) float64: position (metres) and orientation quaternion per frame."""
    cfg = synth.SynthConfig.preset("paper").replace(n_test=n)
    params = synth.sample_split(cfg, seed, "test")
    out = []
    for i in range(n):
        model, qpos, qvel = videos.throw(cfg, params, i)
        spf = render.steps_per_frame(model, FPS)
        out.append(render.simulate(model, qpos, qvel, FRAMES * spf)[::spf][:FRAMES])
    return out


def camera(states: np.ndarray, rng: np.random.Generator, tilt: float) -> Camera | None:
    """A random camera ``tilt`` degrees down that keeps the object in view, 8 pixels or wider; None if 50 draws fail."""
    mid = states[:, :3].mean(axis=0)
    for _ in range(50):
        height, dist = rng.uniform(0.3, 2.0), rng.uniform(2.0, 8.0)
        heading, fov = math.radians(90 + rng.uniform(-60, 60)), rng.uniform(50, 90)
        t = math.radians(tilt)
        fwd = np.array([math.cos(t) * math.cos(heading), math.cos(t) * math.sin(heading), -math.sin(t)])
        right = np.array([math.sin(heading), -math.cos(heading), 0.0])
        pos = np.array([mid[0] - dist * math.cos(heading), mid[1] - dist * math.sin(heading), height])
        f = 0.5 * HEIGHT / math.tan(math.radians(fov) / 2)
        cam = Camera(tuple(pos), tuple(np.column_stack([right, np.cross(right, fwd), -fwd]).ravel()), f, WIDTH, HEIGHT)
        uv, depth = cam.project(states[:, :3]), cam.depth_of(states[:, :3])
        inside = (uv[:, 0] > 0).all() and (uv[:, 0] < WIDTH).all() and (uv[:, 1] > 0).all() and (uv[:, 1] < HEIGHT).all()
        if (depth > 0.5).all() and inside and (silhouette(states, cam) >= 8).all():
            return cam
    return None


def silhouette(states: np.ndarray, cam: Camera, edge: float = 0.2) -> np.ndarray:
    """(n,) the box's apparent diameter, pixels: the disc of its projected area (edge^2 times the sum of the
    view direction's absolute components in the box's frame) at its depth."""
    out = np.empty(len(states))
    for i, s in enumerate(states):
        w, x, y, z = s[3:7]
        rot = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])
        ray = s[:3] - np.asarray(cam.position)
        area = edge * edge * np.abs(rot.T @ (ray / np.linalg.norm(ray))).sum()
        out[i] = cam.focal * 2 * math.sqrt(area / math.pi) / cam.depth_of(s[None, :3])[0]
    return out


def rms(err: np.ndarray) -> float:
    """Root mean square of ``err`` after removing its median, millimetres."""
    return 1000 * float(np.sqrt(np.mean((err - np.median(err)) ** 2)))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--throws", type=int, default=6, help="throws per tilt family")
    ap.add_argument("--seed", type=int, default=0, help="seed of the cameras and the noise")
    a = ap.parse_args()
    size = apparent_size("box", (0.2, 0.2, 0.2))
    states = throws(a.throws)
    rng = np.random.default_rng(a.seed)
    t = np.arange(FRAMES) / FPS
    print(f"{'tilt':>5} {'clips':>5} {'image only':>11} {'one scale':>10} {'true camera, size depth':>24}   (mm rms, median removed)")
    for tilt in (0, 20, 45):
        rows = []
        for st in states:
            cam = camera(st, rng, tilt)
            if cam is None:
                continue
            z = st[:, 2]
            uv = cam.project(st[:, :3]) + rng.normal(0, 0.3, (len(st), 2))
            diam = silhouette(st, cam)
            try:
                mine, _ = geometry.recover(t, uv[:, 0], uv[:, 1], diam, WIDTH, HEIGHT, size, REST)
                e_mine = rms(mine - z)
            except geometry.GeometryError:
                e_mine = math.nan
            one = (uv[:, 1].max() - uv[:, 1]) * FACE / np.median(diam[-5:]) + REST
            depth = cam.focal * size / np.median(np.lib.stride_tricks.sliding_window_view(np.pad(diam, 2, mode="edge"), 5), axis=1)
            floor = cam.position[2] + depth * cam.rays(uv[:, 0], uv[:, 1])[:, 2]
            rows.append((e_mine, rms(one - z), rms(floor - z)))
        r = np.array(rows)
        pooled = [float(np.sqrt(np.nanmean(c ** 2))) for c in r.T]
        failed = int(np.isnan(r[:, 0]).sum())
        print(f"{tilt:>4}° {len(r):>5} {pooled[0]:>11.0f} {pooled[1]:>10.0f} {pooled[2]:>24.0f}"
              + (f"   ({failed} without a flight or a ground frame)" if failed else ""))


if __name__ == "__main__":
    main()
