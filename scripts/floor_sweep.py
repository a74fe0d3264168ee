"""Heights through a camera the floor calibrates, on the camera sweep's clips, beside the default one-scale path:
how far a user who tapes a few marks on the floor gets (``study.see.floor``).

For each clip of a sweep folder (``study.methods.sweep``: the videos, each with its ground truth), the renderer's
projection is recovered from the truth's centres and pixels (a direct linear transform, only to synthesise the
user's clicks); six floor marks around the throw (a 2 m x 1.5 m rectangle's corners and the middles of its long
sides) are projected through it with ``--click-px`` pixels of noise, as a careful click gives them. The clip is
tracked once (pixels) and turned into heights by the floor's camera (``study.see.floor.on_floor``) and by the
mean-silhouette scale (``study classify``'s default). Prints, per camera family and pooled, the RMS height error
with each clip's median removed and raw, millimetres, and the clips without heights::

    .venv/bin/python scripts/floor_sweep.py DATA/realworld/sweep-<key> [--click-px 1]
    .venv/bin/python scripts/floor_sweep.py --render 5 --out /tmp/sweep   # render 5 clips a family first
"""

from __future__ import annotations

import argparse
import csv
import sys
from pathlib import Path

import numpy as np

from study.core.errors import StudyError
from study.methods import camera_cost, sweep
from study.see import floor, render, track
from study.see.config import TrackConfig
from study.see.scale import ObjectShape

sys.path.insert(0, str(Path(__file__).parent))
from ground_points_sweep import _rms, dlt  # noqa: E402  (the same clicks and the same RMS as the one-plane path)



def measure(folder: Path, click_px: float) -> None:
    rng = np.random.default_rng(0)
    rows = list(csv.DictReader((folder / "MANIFEST.csv").open()))
    err: dict[str, dict[str, list[np.ndarray]]] = {}
    missing: dict[str, int] = {}
    for r in rows:
        video = folder / r["file"]
        truth = render.read_truth(video.with_suffix(".csv"))
        world = np.column_stack([truth["x"], truth["y"], truth["z"]])
        pm = dlt(world, np.column_stack([truth["u"], truth["v"]]))
        xy = world[:, :2].mean(axis=0) + floor.MARKS
        hom = pm @ np.column_stack([xy, np.zeros(len(xy)), np.ones(len(xy))]).T
        clicks = (hom[:2] / hom[2]).T + rng.normal(0.0, click_px, (len(xy), 2))
        fam = r["family"]
        err.setdefault(fam, {"floor": [], "mean": []})
        try:
            px = track.track_video(video, TrackConfig(color=r["color"], progress=False))
        except StudyError as e:
            print(f"{r['file']}: not tracked: {e}")
            missing[fam] = missing.get(fam, 0) + 1
            continue
        rest = float(truth["z"].min())  # the object's centre at rest (the truth's lowest)
        n = min(len(px.t), len(truth["z"]))
        try:
            marks = floor.Floor(clicks, xy, r["file"])
            on, cal = floor.on_floor(px, marks, rest)
            z = np.where(px.measured, on.z, np.nan)[:n]
            err[fam]["floor"].append(z - truth["z"][:n])
        except StudyError as e:
            missing[fam] = missing.get(fam, 0) + 1
            print(f"{r['file']}: the floor path failed: {e}")
        size = tuple(float(s) for s in r["object_size"].split())
        scaled = camera_cost.SCALE[camera_cost.DEFAULT_PATH](px, ObjectShape(r.get("object_shape", "box") or "box",
                                                                            size))
        h = np.where(scaled.status > 0, scaled.height, np.nan)[:n] + rest
        err[fam]["mean"].append(h - truth["z"][:n])
    print(f"clicks {click_px:g} px | family clips | floor: RMS median removed, raw (mm), clips without heights "
          "| mean silhouette: the same")
    pooled: dict[str, list[np.ndarray]] = {"floor": [], "mean": []}
    for fam, e in err.items():
        cells = []
        for path in ("floor", "mean"):
            pooled[path] += e[path]
            cells.append(_rms(e[path]))
        print(fam, len(e["mean"]), "|", *cells[0], missing.get(fam, 0), "|", *cells[1])
    print("all", sum(len(e["mean"]) for e in err.values()), "|", *_rms(pooled["floor"]), sum(missing.values()), "|",
          *_rms(pooled["mean"]))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("folder", type=Path, nargs="?", help="a sweep folder (MANIFEST.csv, clips and their truth CSVs)")
    ap.add_argument("--click-px", type=float, default=1.0, help="the user's clicking error, pixels (std)")
    ap.add_argument("--render", type=int, default=0, metavar="N", help="render N clips a family first (into --out)")
    ap.add_argument("--out", type=Path, default=Path("/tmp/floor-sweep"), help="where --render puts the clips")
    ap.add_argument("--seed", type=int, default=sweep.SWEEP_SEED,
                    help="seed of the rendered throws and shots (default: the sweep's own; develop on another)")
    a = ap.parse_args()
    folder = a.folder
    if a.render:
        from study.simulate import synth

        clips = sweep.sweep_set(synth.SynthConfig.preset("paper"), per_family=a.render, seed=a.seed,
                                out_dir=a.out, progress=True)
        folder = clips[0].video.path.parent
    if folder is None:
        ap.error("give a sweep folder, or --render N")
    measure(folder, a.click_px)


if __name__ == "__main__":
    main()
