"""What holds the floor path's heights back: the same clips through ``study.see.floor.on_floor`` with its inputs
swapped one at a time, the marks clicked a pixel off as the camera sweep clicks them.

Renders (or reads from the cache) ``--per-family`` clips of each camera family at ``--seed`` (develop on another
seed than the sweep's own), then reads each clip's heights through the floor's camera from:

- ``tracked``: the tracker's pixels and blob sizes, as a user's video gives them (the shipped path);
- ``lit``: the tracker with the lower S and V bounds its presets had before issue 51 (:data:`LIT`), which drop a
  box's faces turned from the light (V 41-54 under the sweep's dim lights): the blob's centre sits on the lit faces;
- ``rendered``: the renderer's own pixel of each frame's centre (the truth CSV's ``u``, ``v``), the blob sizes
  still the tracker's;

each with the apparent size and without it (``size=None``). Prints each way's RMS height error with each clip's
median removed (and plain, in brackets), pooled over frames, by camera family and by frame height, millimetres, and
how many clips each way gave heights for; ``--clips`` adds a row per clip::

    .venv/bin/python scripts/floor_limits.py --per-family 3 --seed 2001 --out /tmp/floor-dev3
"""

from __future__ import annotations

import argparse
from dataclasses import replace
from pathlib import Path

import numpy as np

from study.core.errors import StudyError
from study.methods import camera_cost, sweep, tracker
from study.see import floor, render, track
from study.see.config import COLORS, TrackConfig
from study.see.trajectory import Trajectory
from study.simulate import synth

LIT: dict[str, tuple[int, ...]] = {"orange": tracker.TRACKERS["before"].hsv[1:3], "red": (120, 70), "green": (100, 60),
                                   "blue": (120, 60)}
"""Each object colour's lower S and V bounds before its preset kept the shaded faces ('orange' until issue 28, the
others until issue 51)."""
PIXELS = ("tracked", "lit", "rendered")


def lit_config(colour: str) -> TrackConfig:
    """The tracker's settings for ``colour`` with its lower S and V bounds at :data:`LIT`'s."""
    (h_lo, _, _), (h_hi, s_hi, v_hi) = COLORS[colour]
    return TrackConfig(hsv=(h_lo, *LIT[colour], h_hi, s_hi, v_hi), progress=False)


def rendered(px: Trajectory, truth: dict[str, np.ndarray]) -> Trajectory:
    """``px`` with each frame's centre the renderer's (where the truth has the frame)."""
    n = min(len(px.t), len(truth["u"]))
    return replace(px, u=np.r_[truth["u"][:n], px.u[n:]], v=np.r_[truth["v"][:n], px.v[n:]])


def errors(px: Trajectory, marks: floor.Floor, world: np.ndarray, rest: float, shape, sized: bool) -> np.ndarray:
    """(k,) metres: the floor path's height minus the truth ``world`` (n, 3) metres in each frame it places, through
    the camera the ``marks`` give, for an object resting ``rest`` metres up."""
    traj, _ = floor.on_floor(px, marks, rest, shape.mean_size() if sized else None, floor.contact_height(shape))
    h = np.where(traj.status > 0, traj.height, np.nan)
    n = min(len(h), len(world))
    e = h[:n] - (world[:n, 2] - rest)
    return e[np.isfinite(e)]


def centred_mm(parts: list[np.ndarray]) -> float:
    """The RMS of clips' height errors ``parts`` (each (k,) metres) with each clip's median removed, millimetres
    (``camera_cost.rms_mm``; NaN for none)."""
    return camera_cost.rms_mm(parts)[1]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--per-family", type=int, default=3, help="clips of each camera family (default 3)")
    ap.add_argument("--seed", type=int, default=2001,
                    help="seed of the throws and shots (default 2001: not the sweep's)")
    ap.add_argument("--out", type=Path, default=Path("/tmp/floor-limits"),
                    help="where the clips are rendered and cached")
    ap.add_argument("--clips", action="store_true", help="also print a row per clip")
    a = ap.parse_args()
    cfg = synth.SynthConfig.preset("paper")
    shape = camera_cost.shape_of(cfg)
    clips = sweep.sweep_set(cfg, per_family=a.per_family, seed=a.seed, out_dir=a.out, progress=True)
    ways = [(p, s) for p in PIXELS for s in (True, False)]
    table: dict[tuple[str, bool], dict[str, list[np.ndarray]]] = {w: {} for w in ways}
    rows = []
    for clip in clips:
        v = clip.video
        truth = render.read_truth(v.truth)
        cells = []
        try:
            px = {"tracked": track.track_video(v.path, v.track_config()),
                  "lit": track.track_video(v.path, lit_config(clip.shot.colour))}
        except StudyError as e:
            rows.append(f"{v.path.name}: not tracked ({str(e)[:60]})")
            continue
        px["rendered"] = rendered(px["tracked"], truth)
        world = np.column_stack([truth["x"], truth["y"], truth["z"]])
        marks = camera_cost.clicked_floor(sweep.camera(clip.shot, world), world, v.path.name)
        for w in ways:
            try:
                e = errors(px[w[0]], marks, world, v.rest_height, shape, w[1])
            except StudyError as err:
                cells.append(f"{type(err).__name__}")
                continue
            for g in camera_cost.groups_of(clip):
                table[w].setdefault(g, []).append(e)
            cells.append(f"{centred_mm([e]):.0f}")
        rows.append(f"{v.path.name} {camera_cost.resolution(clip)}: " + " | ".join(cells))
    names = [f"{p}{'' if s else ' no size'}" for p, s in ways]
    if a.clips:
        print("clip: " + " | ".join(names))
        print("\n".join(rows))
    print("group: " + " | ".join(names) + " (RMS mm, each clip's median removed; plain in brackets)")
    for g in table[ways[0]]:
        print(f"{g}: " + " | ".join("{1:.1f} ({0:.1f})".format(*camera_cost.rms_mm(table[w].get(g, []))) for w in ways))
    print(f"clips with heights, of {len(clips)}: " + " | ".join(str(sum(len(e) > 0 for e in table[w].get("all", [])))
                                                             for w in ways))


if __name__ == "__main__":
    main()
