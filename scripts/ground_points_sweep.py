"""Heights from four floor points on the camera sweep's clips, beside the default one-scale path: how far a user who
measures a few points on the floor gets (``study.see.ground``).

For each clip of a sweep folder (``study.methods.sweep``: the videos, each with its ground truth), the camera is
recovered from the truth's centre positions and pixels (a direct linear transform, for synthesising the user's
clicks only), four floor points 1 m around the throw's middle are projected through it with a pixel of noise, as a
user would click them, and the clip is tracked (pixels) and turned into heights by ``study.see.ground`` from those
points alone, and by the mean-silhouette scale (``study classify``'s default). Prints each family's RMS height
error, median removed and raw, millimetres::

    .venv/bin/python scripts/ground_points_sweep.py ~/study-cold/realworld/sweep-<key>
"""

from __future__ import annotations

import argparse
import csv
from pathlib import Path

import numpy as np

from study.core.errors import StudyError
from study.methods import camera_cost
from study.see import ground, render, track
from study.see.config import TrackConfig
from study.see.scale import ObjectShape


def dlt(world: np.ndarray, pixels: np.ndarray) -> np.ndarray:
    """(3, 4) the projection matrix that takes ``world`` (n, 3) to ``pixels`` (n, 2), least squares (n >= 6)."""
    rows = []
    for (x, y, z), (u, v) in zip(world, pixels):
        p = [x, y, z, 1.0]
        rows.append([*p, 0, 0, 0, 0, *(-u * np.array(p))])
        rows.append([0, 0, 0, 0, *p, *(-v * np.array(p))])
    return np.linalg.svd(np.asarray(rows))[2][-1].reshape(3, 4)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("folder", type=Path, help="a sweep folder (MANIFEST.csv, clips and their truth CSVs)")
    ap.add_argument("--click-px", type=float, default=1.0, help="the user's clicking error, pixels (std)")
    a = ap.parse_args()
    rng = np.random.default_rng(0)
    rows = list(csv.DictReader((a.folder / "MANIFEST.csv").open()))
    err: dict[str, dict[str, list[np.ndarray]]] = {}
    failed: dict[str, int] = {}
    for r in rows:
        video = a.folder / r["file"]
        truth = render.read_truth(video.with_suffix(".csv"))
        world = np.column_stack([truth["x"], truth["y"], truth["z"]])
        pm = dlt(world, np.column_stack([truth["u"], truth["v"]]))
        mid = world.mean(axis=0)
        floor = np.array([[mid[0] + dx, mid[1] + dy] for dx in (-1.0, 1.0) for dy in (-1.0, 1.0)])
        hom = pm @ np.column_stack([floor, np.zeros(4), np.ones(4)]).T
        clicks = (hom[:2] / hom[2]).T + rng.normal(0.0, a.click_px, (4, 2))
        try:
            px = track.track_video(video, TrackConfig(color=r["color"], progress=False))
        except StudyError as e:
            print(f"{r['file']}: not tracked: {e}")
            failed["not tracked"] = failed.get("not tracked", 0) + 1
            continue
        rest = float(truth["z"].min())  # the object's centre at rest (the truth's lowest)
        n = min(len(px.t), len(truth["z"]))
        fam = r["family"]
        err.setdefault(fam, {"ground": [], "mean": []})
        try:
            cam = ground.camera_from_floor(clicks, floor, px.width, px.height_px)
            u = np.where(px.measured, px.u, np.nan)
            v = np.where(px.measured, px.v, np.nan)
            z = ground.heights(cam, px.t, u, v, rest)[:n]
            err[fam]["ground"].append(z - truth["z"][:n])
        except StudyError as e:
            failed[fam] = failed.get(fam, 0) + 1
            print(f"{r['file']}: ground points failed: {e}")
        scaled = camera_cost.SCALE[camera_cost.DEFAULT_PATH](px, ObjectShape("sphere", (float(r["object_size"]),)))
        h = np.where(scaled.status > 0, scaled.height, np.nan)[:n] + rest
        err[fam]["mean"].append(h - truth["z"][:n])
    print("family clips | ground points: RMS median removed, raw (mm), failed | mean silhouette: the same")
    pooled: dict[str, list[np.ndarray]] = {"ground": [], "mean": []}
    for fam, e in err.items():
        cells = []
        for path in ("ground", "mean"):
            pooled[path] += e[path]
            cells.append(_rms(e[path]))
        print(fam, len(e["mean"]), "|", *cells[0], failed.get(fam, 0), "|", *cells[1])
    print("all", sum(len(e["mean"]) for e in err.values()), "|", *_rms(pooled["ground"]), sum(failed.values()), "|",
          *_rms(pooled["mean"]))


def _rms(errors: list[np.ndarray]) -> tuple[str, str]:
    """(median removed, raw) RMS of several clips' height errors, mm, as printed (``camera_cost.rms_mm``)."""
    if not errors:
        return "-", "-"
    raw, centred = camera_cost.rms_mm([e[np.isfinite(e)] for e in errors])
    return f"{centred:.0f}", f"{raw:.0f}"


if __name__ == "__main__":
    main()
