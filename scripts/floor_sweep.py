"""Heights through a camera the floor calibrates, on camera-sweep clips, beside the default one-scale path and the
known camera: how far a user who lays marks on the floor gets (``study.see.floor``), with the marks clicked and
found by their colour.

Renders (or reads from the cache) ``--per-family`` clips of each camera family at ``--seed`` (develop on another
seed than the sweep's own, ``study.methods.sweep.SWEEP_SEED``), each with its six magenta marks in view, and reads
each clip as ``study.methods.camera_cost.heights`` does. Prints, per camera family, per frame height and pooled,
each way's RMS height error with each clip's median removed and raw, millimetres, and the clips without heights::

    .venv/bin/python scripts/floor_sweep.py --per-family 5 --seed 2000 --out /tmp/floor-dev
"""

from __future__ import annotations

import argparse
from pathlib import Path

from study.methods import camera_cost, sweep
from study.simulate import synth

WAYS = (camera_cost.KNOWN, camera_cost.FLOOR_PATH, camera_cost.FOUND, camera_cost.DEFAULT_PATH)
"""The ways to heights compared."""


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--per-family", type=int, default=5, help="clips of each camera family (default 5)")
    ap.add_argument("--seed", type=int, default=2000, help="seed of the throws and shots (default 2000: not the sweep's)")
    ap.add_argument("--out", type=Path, default=Path("/tmp/floor-sweep"), help="where the clips are rendered and cached")
    a = ap.parse_args()
    cfg = synth.SynthConfig.preset("paper")
    clips = sweep.sweep_set(cfg, per_family=a.per_family, seed=a.seed, out_dir=a.out, progress=True)
    tracked = camera_cost.track_clips(clips, camera_cost.shape_of(cfg), progress=True)
    groups: dict[str, list[int]] = {}
    for i, c in enumerate(clips):
        for g in camera_cost.groups_of(c):
            groups.setdefault(g, []).append(i)
    print("group clips | " + " | ".join(f"{w}: RMS median removed, raw (mm), clips without" for w in WAYS))
    for g, idx in groups.items():
        cells = []
        for w in WAYS:
            raw, centred = camera_cost.rms_mm([camera_cost.path_errors(tracked[i], w) for i in idx])
            without = sum(isinstance(tracked[i].paths.get(w, ""), str) for i in idx)
            cells.append(f"{centred:.0f} {raw:.0f} {without}")
        print(g, len(idx), "|", " | ".join(cells))


if __name__ == "__main__":
    main()
