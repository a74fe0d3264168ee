"""Tracking cost against decoding alone, at 320x240, 640x480 and 1920x1080, in one run.

For each size a synthetic clip (an orange disc bouncing across a textured grey background, mp4v, 10 s
at 30 fps by default) is written to a temporary folder; then the same file is (a) only decoded with
cv2.VideoCapture and (b) decoded and tracked with study.track. Prints frames per second for both
and their ratio (tracking pipeline fps / decode-only fps; 1.0 = tracking is free). Target >= 0.8.

When the real clips are present (``study.chapters.realworld.real_clips_dir()``), the same measurement runs on two of
them too (H.264, tennis preset), since real footage decodes slower than mp4v and is harder to track.

    PYTHONPATH=src python benchmarks/bench_track.py [--seconds 10] [--repeats 5]
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import cv2
import numpy as np

from study.chapters import realworld
from study.see import track
from study.see.video import frames

SIZES = [(320, 240), (640, 480), (1920, 1080)]


def make_clip(path: Path, size: tuple[int, int], seconds: float, fps: float = 30.0) -> Path:
    """A disc of diameter H/20 bouncing under gravity over a fixed noisy background."""
    w, h = size
    rng = np.random.default_rng(0)
    bg = (rng.normal(110, 12, (h, w, 3))).clip(0, 255).astype(np.uint8)
    bg = cv2.GaussianBlur(bg, (0, 0), 2)
    r = max(3, h // 40)
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"mp4v"), fps, size)
    x, y, vx, vy = 0.1 * w, 0.2 * h, 0.25 * w, 0.0
    g, dt = 2.5 * h, 1 / fps
    for _ in range(int(seconds * fps)):
        vy += g * dt
        x, y = x + vx * dt, y + vy * dt
        if y > 0.9 * h:
            y, vy = 0.9 * h, -0.75 * vy
        if not 0 < x < w:
            vx = -vx
        f = bg.copy()
        cv2.circle(f, (int(x), int(y)), r, (0, 100, 235), -1, cv2.LINE_AA)
        writer.write(f)
    writer.release()
    return path


def decode_only(path: Path) -> tuple[int, float]:
    t0 = time.perf_counter()
    n = sum(1 for _ in frames(path))
    return n, time.perf_counter() - t0


REAL = realworld.real_clips_dir()  # $STUDY_REAL_VIDEO, or ../shared/data/real-video from the project root


def decode_and_track(path: Path, color: str = "orange") -> tuple[int, float, float]:
    t0 = time.perf_counter()
    traj = track.detect_all(path, track.TrackConfig(color=color, progress=False))
    return len(traj.t), time.perf_counter() - t0, traj.found_fraction


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--seconds", type=float, default=10.0, help="clip length, seconds (default: %(default)s)")
    ap.add_argument("--repeats", type=int, default=5, help="timings per measurement; the best is kept (default: %(default)s)")
    a = ap.parse_args()
    cv2.setNumThreads(1)  # both paths on one thread: the ratio then measures work, not scheduling
    print(f"{'size':>10} {'decode fps':>11} {'track fps':>10} {'ratio':>6} {'found':>6}")

    def measure(label: str, clip: Path, color: str) -> None:
        decs, runs = [], []
        for _ in range(a.repeats):  # interleaved, best of each: load from other processes hits both alike
            decs.append(decode_only(clip)[1])
            runs.append(decode_and_track(clip, color))
        n, dec, trk = runs[0][0], min(decs), min(r[1] for r in runs)
        print(f"{label:>10} {n / dec:11.1f} {n / trk:10.1f} {dec / trk:6.2f} {runs[0][2]:6.2f}")

    with tempfile.TemporaryDirectory() as d:
        for w, h in SIZES:
            measure(f"{w}x{h}", make_clip(Path(d) / f"clip_{w}x{h}.mp4", (w, h), a.seconds), "orange")
    for name in ("tennis_ex5_small.mp4", "tennis_table_drop.mp4"):
        if (REAL / name).exists():
            measure(name.removeprefix("tennis_").removesuffix(".mp4"), REAL / name, "tennis")


if __name__ == "__main__":
    main()
