"""The experiments of the chapter on cues: which cue separates the classes, and how robust the classifier is.

Our classes differ in restitution and friction, as the paper intends, but also in mass, and mass shows
in the motion through air drag: a light box falls measurably slower than a heavy one. These functions
ask which of those cues a classifier uses, with Table 1's protocol and configuration (no new grid):

- :func:`observation_calibration`: the tracker's error on rendered video, the size of the observation
  model's noise (``study.simulate.observe``; the runner caches it: ``Runner.calibration``);
- :func:`rules`: the one-feature rules on the first T seconds the networks see;
- :func:`ceiling`: what a classifier given each throw's true restitution and friction (and mass) reaches;
- :func:`robustness`: accuracy against each parameter of the observation model;
- :func:`by_parameter`: accuracy against each throw's restitution, mass and friction;
- :func:`shape_sets`, :func:`mixed_shapes`: other shapes, and a training set that mixes them.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from study.core import cache
from study.experiments import realworld
from study.experiments.stats import scored
from study.learn import baseline
from study.learn.metrics import Interval, bootstrap_accuracy
from study.see import render, track
from study.simulate import data, measure, observe, synth
from study.simulate.scene import Shape

# ---------------------------------------------------------------------------------------------
# The observation model's size, from the tracker on rendered video


def observation_calibration(videos: Sequence[realworld.Video], depth: float = 4.0) -> dict[str, float]:
    """The tracker's vertical error on rendered videos with known truth, as the observation model needs it.

    For each video the tracked centroid's image row minus the true centre's projection, over the frames
    the tracker measured, has its median removed (the constant offset between the centre of the box's
    visible faces and the image of its centre); what is left is pooled over the videos. Returns
    ``noise_px``, its standard deviation in pixels; ``noise_m``, the same in metres at ``depth`` (the
    camera's distance to the throw); ``drop``, the share of frames the tracker lost while the object
    was in the picture; and ``n_frames``.
    """
    residuals, lost, seen = [], 0, 0
    for v in videos:
        if v.truth is None:
            continue
        truth = render.read_truth(v.truth)
        traj = track.detect_all(v.path, track.TrackConfig(color=v.color, progress=False))
        m = traj.measured
        err = (traj.v - truth["v"])[m]
        residuals.append(err - np.median(err))
        lost += int((~m).sum())
        seen += len(m)
    r = np.concatenate(residuals)
    mpp = render.metres_per_pixel(render.class_model("light"), "side", 240, depth=depth)
    return {"noise_px": float(r.std()), "noise_m": float(r.std() * mpp), "drop": lost / max(seen, 1),
            "n_frames": int(len(r)), "metres_per_pixel": mpp}


# ---------------------------------------------------------------------------------------------
# What separates the classes without learning


def rules(train_x: np.ndarray, train_y: np.ndarray, test_x: np.ndarray, test_y: np.ndarray, fps: float,
          contact_height: float, names: Sequence[str] | None = None) -> list[dict]:
    """The one-feature rules of ``study.simulate.measure`` on exactly these inputs (the first T seconds),
    each with the bootstrap interval of its test accuracy."""
    rows = measure.simple_rules(train_x, train_y, test_x, test_y, fps, contact_height, tuple(names or measure.FEATURES))
    return [r | {"interval": bootstrap_accuracy(r["correct"])} for r in rows]


def window_cues(dataset: data.Dataset, lengths: Sequence[float], contact_height: float) -> list[dict]:
    """What the first T seconds of each test throw hold, for each T (s) of ``lengths``: the share whose first
    fall has ended inside the window (``landed``), the drag rule's test accuracy on the window (``drag``)
    and the best other one-feature rule's (``other``, named by ``other_feature``), intervals over test throws."""
    rows = []
    for length in lengths:
        n = round(length * dataset.fps)
        xte = dataset.test.x[:, :n]
        ends = [measure.first_contact(z) for z in xte[..., 2]]
        by = {r["feature"]: r for r in rules(dataset.train.x[:, :n], dataset.train.y, xte, dataset.test.y,
                                             dataset.fps, contact_height)}
        drag = by.pop("fall_acceleration")
        other = max(by.values(), key=lambda r: r["test_accuracy"])
        rows.append({"length": float(length), "landed": float(np.mean([e is not None for e in ends])),
                     "drag": drag["interval"], "other": other["interval"], "other_feature": other["feature"]})
    return rows


def ceiling(dataset: data.Dataset, with_mass: bool = False) -> Interval:
    """The accuracy the priors allow a classifier that is told each throw's true restitution and friction
    (and, with ``with_mass``, its log mass): a logistic regression on them, fitted on the training
    split, scored on the test split."""
    names = ("restitution", "friction") + (("mass",) if with_mass else ())

    def table(split: data.Split) -> np.ndarray:
        return np.column_stack([np.log(split.params[k]) if k == "mass" else split.params[k] for k in names])

    f_tr, f_te = table(dataset.train), table(dataset.test)
    mean, std = f_tr.mean(0), f_tr.std(0)
    w = baseline.logistic_regression((f_tr - mean) / std, np.asarray(dataset.train.y, float))
    p = baseline.sigmoid(np.column_stack([(f_te - mean) / std, np.ones(len(f_te))]) @ w)
    return bootstrap_accuracy((p > 0.5) == (np.asarray(dataset.test.y) == 1))


# ---------------------------------------------------------------------------------------------
# Robustness and errors


def robustness(models: dict[str, Sequence[Any]], x: np.ndarray, y: np.ndarray, fps: float, frames: int,
               sweeps: dict[str, tuple[str, Sequence[Any], Callable[[Any], observe.Observation]]],
               seed: int = 0, rest_height: float = 0.1, high: tuple[np.ndarray, float] | None = None) -> list[dict]:
    """Accuracy of each group of ``models`` under each point of each sweep: one row per (sweep, value,
    group) with the interval over test trajectories and seeds.

    ``sweeps``: name -> (axis label, values, value -> Observation). ``high``: the same test trajectories
    recorded at a higher frame rate (x, fps), for camera rates above ``fps``.
    """
    rows = []
    for name, (label, values, make) in sweeps.items():
        for value in values:
            ob = make(value)
            if ob.camera_fps is not None and ob.camera_fps > fps:
                if high is None:
                    continue
                xo = ob.apply(high[0], high[1], np.random.default_rng(seed), out_fps=fps, rest_height=rest_height)
            else:
                xo = ob.apply(x, fps, np.random.default_rng(seed), rest_height=rest_height)
            xo = xo[:, :frames]
            for group, ms in models.items():
                rows.append({"sweep": name, "label": label, "value": value, "group": group,
                             "interval": scored(ms, xo, y)})
    return rows


def by_parameter(rows: Sequence[dict], split: data.Split, name: str, bins: int = 8) -> list[dict]:
    """Accuracy of the runs ``rows`` (each with ``correct``) against the test throws' parameter ``name``,
    per class and in ``bins`` quantile bins of that class's values: one row per (class, bin)."""
    correct = np.stack([r["correct"] for r in rows]).mean(axis=0)  # (n,) share of runs right
    out = []
    for label in (0, 1):
        sel = np.flatnonzero(np.asarray(split.y) == label)
        v = split.params[name][sel]
        edges = np.quantile(v, np.linspace(0, 1, bins + 1))
        which = np.clip(np.searchsorted(edges, v, side="right") - 1, 0, bins - 1)
        for b in range(bins):
            m = which == b
            if m.any():
                out.append({"class": label, "bin": b, "centre": float(np.median(v[m])),
                            "accuracy": float(correct[sel][m].mean()), "n": int(m.sum())})
    return out


# ---------------------------------------------------------------------------------------------
# Shapes


SHAPES: dict[str, Shape] = {
    "20 cm cube (trained)": Shape("box", (0.1, 0.1, 0.1)),
    "10 cm cube": Shape("box", (0.05, 0.05, 0.05)),
    "30 cm cube": Shape("box", (0.15, 0.15, 0.15)),
    "flat box 30 x 30 x 10 cm": Shape("box", (0.15, 0.15, 0.05)),
    "ball, 20 cm": Shape("sphere", (0.1,)),
    "cylinder, 20 cm": Shape("cylinder", (0.1, 0.1)),
}
"""The shapes the classifier is tested on; the mixed training set uses :data:`MIXED`."""
MIXED = ("20 cm cube (trained)", "flat box 30 x 30 x 10 cm", "ball, 20 cm", "cylinder, 20 cm")
"""The shapes whose throws make up the mixed training set (the other two sizes of cube stay unseen)."""


def shape_config(preset: str, shape: Shape, duration: float, n_train: int, n_test: int) -> synth.SynthConfig:
    """The preset's synthesis config for another ``shape``, recorded for ``duration`` seconds."""
    return synth.SynthConfig.preset(preset).replace(shape=shape, duration=duration, n_train=n_train, n_test=n_test)


def shape_sets(preset: str, seed: int, duration: float, n_train: int, n_test: int,
               data_dir: str | Path = "data") -> dict[str, data.Dataset]:
    """One dataset per shape of :data:`SHAPES`, recorded for ``duration`` seconds, cached like any other."""
    return {name: synth.dataset(shape_config(preset, s, duration, n_train, n_test), seed, data_dir=data_dir,
                                progress=False) for name, s in SHAPES.items()}


def mixed_shapes(sets: dict[str, data.Dataset], names: Sequence[str] = MIXED) -> data.Dataset:
    """The training splits of ``names`` pooled into one training set (the test split: the first's), with a
    key that names its parts, so runs on it are cached like any other."""
    parts = [sets[n] for n in names]
    train = data.Split(x=np.concatenate([d.train.x for d in parts]), y=np.concatenate([d.train.y for d in parts]))
    key = cache.key({"mixed": [d.key for d in parts]})
    return data.Dataset(train=train, test=parts[0].test, fps=parts[0].fps, meta={"key": key})


def drag_per_class(a: np.ndarray, y: np.ndarray) -> dict[str, float]:
    """Median fall acceleration (m/s^2) of each class, from :func:`study.simulate.measure.fall_acceleration`."""
    return {c: float(np.nanmedian(a[np.asarray(y) == k])) for k, c in enumerate(("light", "heavy"))}


def high_rate_test(preset: str, seed: int, seconds: float, fps: float = 120.0,
                   data_dir: str | Path = "data") -> data.Dataset:
    """The same test throws recorded at ``fps`` for ``seconds`` (a fast camera's view), one training throw
    per class (the test split's random streams do not depend on the training split's size)."""
    cfg = synth.SynthConfig.preset(preset).replace(fps=fps, duration=seconds + 2 / fps, n_train=1)
    return synth.dataset(cfg, seed, data_dir=data_dir, progress=False)
