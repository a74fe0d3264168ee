"""The camera page's tracking of its sweep: every clip tracked by every path (``camera_cost.track_clips``, the plain
loop) against the same clips' heights kept and read back (``study.methods.tracked``), in one run.

A small sweep (one clip a camera family; ``--frame-scale`` and ``--duration`` set its size) is rendered into a
temporary folder, then timed three ways: the plain loop; the kept loop on an empty cache (it tracks and keeps); the
kept loop again (it reads). Prints seconds per clip for each and the plain loop's time over the read's; the kept
heights are checked against the plain loop's, bit for bit, on every array.

    MUJOCO_GL=egl python benchmarks/bench_tracked.py [--frame-scale 1 --duration 3]
"""

from __future__ import annotations

import argparse
import tempfile
import time

import numpy as np

from study.methods import camera_cost, sweep, tracked
from study.simulate import synth


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--frame-scale", type=float, default=0.5, help="frame size over the paper sweep's (default 0.5)")
    ap.add_argument("--duration", type=float, default=1.0, help="seconds a clip (the paper's: 3)")
    a = ap.parse_args()
    cfg = synth.SynthConfig.preset("smoke")
    with tempfile.TemporaryDirectory() as tmp:
        clips = sweep.sweep_set(cfg, per_family=1, seed=2000, out_dir=tmp, progress=False,
                                frame_scale=a.frame_scale, duration=a.duration)
        shape = camera_cost.shape_of(cfg)
        seconds = {}
        for name, fn in (("plain loop", camera_cost.track_clips), ("kept, first pass", tracked.track_clips),
                         ("kept, read back", tracked.track_clips)):
            t0 = time.perf_counter()
            got = fn(clips, shape, progress=False)
            seconds[name] = time.perf_counter() - t0
            if name == "plain loop":
                plain = got
            else:
                for h, k in zip(plain, got, strict=True):
                    arrays = [(h.exact, k.exact)] + [(h.paths[p], k.paths[p]) for p in h.paths
                                                     if not isinstance(h.paths[p], str)]
                    assert all(x.tobytes() == y.tobytes() for x, y in arrays), "kept heights differ from the plain loop's"
        for name, s in seconds.items():
            print(f"{name:18s} {s / len(clips):8.3f} s a clip")
        print(f"plain loop / read back: {seconds['plain loop'] / seconds['kept, read back']:.0f}x "
              f"({len(clips)} clips, {np.mean([c.shot.height_px for c in clips]):.0f} px high on average)")


if __name__ == "__main__":
    main()
