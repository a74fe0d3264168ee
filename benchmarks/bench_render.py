"""Rendering cost of the real-world chapter's videos: as rendered before vs now, in one run.

The same synthesised throws (one light, one heavy by default, drawn as ``study.chapters.realworld.render_set``
draws them) are rendered with the chapter's settings (320x240, 30 fps, 3 s, two blur sub-frames,
noise, JPEG, shadows) two ways:

- before: every object awake, a 2048 shadow map, every sub-frame rendered;
- now: the defaults: resting objects asleep, a 1024 shadow map, and a sub-frame whose pose is
  bitwise the previous one's reuses its image.

Prints milliseconds per video frame for both, their ratio, and how many sub-frame renders were reused.

    MUJOCO_GL=egl python benchmarks/bench_render.py [--n 1]
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

from study.chapters import realworld
from study.see import render
from study.simulate import synth


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--n", type=int, default=1, help="throws per class")
    a = ap.parse_args()
    rcfg = render.RenderConfig(width=320, height=240, fps=30.0, duration=3.0, blur_subframes=2, noise_std=2.0,
                               jpeg_quality=85, shadows=True, seed=1000)
    ways = {"before": dict(sleep_tolerance=0.0, shadowsize=2048, reuse=False), "now": dict(reuse=True)}
    cfg = synth.SynthConfig.preset("paper").replace(n_test=a.n)
    params = synth.sample_split(cfg, 1000, "test")
    times, reused, drawn = {}, {}, {}
    with tempfile.TemporaryDirectory() as tmp:
        for name, way in ways.items():
            c = cfg.replace(sleep_tolerance=way.get("sleep_tolerance", cfg.sleep_tolerance))
            t0, reused[name], drawn[name] = time.perf_counter(), 0, 0
            for i in range(len(params["label"])):
                model, qpos, qvel = realworld.throw(c, params, i)  # as render_set films it
                if "shadowsize" in way:
                    model.vis.quality.shadowsize = way["shadowsize"]
                r = render.render(model, qpos, qvel, Path(tmp) / f"{name}-{i}.mp4", rcfg, reuse=way["reuse"])
                reused[name] += r.reused
                drawn[name] += r.drawn
            times[name] = time.perf_counter() - t0
    frames = len(params["label"]) * int(round(rcfg.duration * rcfg.fps))
    print(f"{len(params['label'])} videos x {frames // len(params['label'])} frames at {rcfg.width}x{rcfg.height}, "
          f"{rcfg.blur_subframes} sub-frames each")
    for name in ways:
        print(f"{name:<8}{1000 * times[name] / frames:>8.1f} ms/frame  rendered {drawn[name]}, reused {reused[name]}")
    print(f"ratio before / now: {times['before'] / times['now']:.2f}x")


if __name__ == "__main__":
    main()
