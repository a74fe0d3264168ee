"""The Z model a camera should use, chosen on validation throws as a user's own camera gives them, and the step that
saves it for ``study classify``.

:func:`candidates` are the paper's network reading positions (Table 1's) or positions and velocity, each trained on
exact positions, on random observations, or on any camera (``study.simulate.observe.any_camera``);
:func:`recommended` chooses the one with the highest mean validation accuracy over seeds as a user's camera gives
the throws. The real-world chapters show the choice (:func:`recommend`); the book's builder runs :func:`make` once
the chapters' runs are trained, which writes it to the data folder (``study.runs.recommended``) with what the camera
sweep measured for it and its cannot-tell band (:func:`band`), keyed by content so that a rebuild that changed
nothing writes nothing.
"""

from __future__ import annotations

import contextlib
import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from study.core import cache
from study.core.errors import ConfigError, ModelError
from study.learn import train
from study.learn.config import TrainConfig
from study.learn.metrics import Interval, hierarchical_bootstrap
from study.learn.trained import Ensemble
from study.methods import calibration, certify, operating
from study.runs import measured as measured_
from study.runs import recommended as saved
from study.runs import records
from study.runs.stats import correct_of
from study.simulate import observe

if TYPE_CHECKING:
    from study.runs.runner import Runner

BAND_TARGET = 0.05
"""Each side of a recommended model's cannot-tell band: an answer of light may let through at most this share of
heavy objects, an answer of heavy at most this share of light ones, each certified at 95 %."""
CERTIFY_OBSERVE_SEED = 13
"""Seed of the certification split's cameras as a user's path sees them (the decision chapter's draws are 11, 12)."""


@dataclass(frozen=True)
class Recommendation:
    """The Z model a camera in a car should use (:func:`recommend`), chosen on validation throws as a user's camera
    gives them, by the mean over seeds."""

    choice: str
    """The chosen candidate's name (``"positions, exact"`` and so on, :func:`candidates`): the best on
    :attr:`val_user`, the validation throws as ``study classify`` sees a user's video."""
    val: dict[str, Interval]
    """Each candidate's accuracy on the validation throws observed through the calibrated tracker and the renderer's
    camera: the mean over its seeds (each seed scored on its own validation split), with a hierarchical bootstrap
    interval over seeds and throws."""
    val_user: dict[str, Interval]
    """The same on the validation throws as a user's camera, anywhere, and one scale give them
    (``study.simulate.observe.any_camera``)."""
    models: dict[str, Ensemble]
    """Each candidate's seeds, as one classifier (the mean of their probabilities)."""
    configs: dict[str, TrainConfig] = dataclasses.field(default_factory=dict)
    """Each candidate's config (Z; its seeds differ)."""

    @property
    def model(self) -> Ensemble:
        """The chosen model (its seeds' ensemble)."""
        return self.models[self.choice]


def candidates(runner: Runner, cfgs: dict[str, TrainConfig] | None = None,
               ob: observe.Observation | None = None) -> dict[str, TrainConfig]:
    """The Z models a camera could use: each of ``cfgs`` (name -> config; default: the paper's network reading
    positions at Table 1's point and reading positions and velocity at its own grid's point) trained on exact
    positions, on random observations as the calibrated tracker (or ``ob``) would see them, and on heights as a
    user's own camera anywhere gives them (``study.simulate.observe.any_camera``; names suffixed ', exact',
    ', randomised' and ', any-camera')."""
    cfgs = cfgs or {"positions": runner.table1_config(), "velocity": runner.table1_config("velocity")}
    out = {}
    for name, cfg in cfgs.items():
        z = dataclasses.replace(cfg, dims="z")
        out[f"{name}, exact"] = z
        out[f"{name}, randomised"] = calibration.randomised_config(runner, z, ob)
        out[f"{name}, any-camera"] = dataclasses.replace(out[f"{name}, randomised"], observe="any-camera")
    return out


def recommended(runner: Runner, cands: dict[str, TrainConfig], seeds: Sequence[int] = (0,),
                ob: observe.Observation | None = None) -> Recommendation:
    """Of ``cands`` (name -> config; :func:`candidates`), the one with the highest mean accuracy over ``seeds`` on
    each seed's validation trajectories as a user's camera gives them (``observe.any_camera``: what ``study classify``
    reads), each also scored as the calibrated tracker (or ``ob``) observes them (never the test split)."""
    if not seeds:
        raise ConfigError("recommended: seeds is empty; give at least one seed")
    ob = ob or calibration.observation(runner)
    first = next(iter(cands.values()))
    T, y = first.n_frames(runner.fps), runner.dataset.train.y
    correct: dict[str, list[np.ndarray]] = {k: [] for k in cands}
    correct_user: dict[str, list[np.ndarray]] = {k: [] for k in cands}
    members: dict[str, list[train.TrainedModel]] = {k: [] for k in cands}
    for seed in seeds:
        _, va = train.split_train_val(len(y), first.val_fraction, seed)
        x_val = ob.observe(runner.dataset.train.x[va, :T], runner.fps, seed=6)
        x_user = observe.any_camera(runner.dataset.train.x[va, :T], runner.fps,
                                    np.random.default_rng([seed, 7])).astype(np.float32)
        for k, c in cands.items():
            m = runner.trained(dataclasses.replace(c, dims="z", seed=seed))
            members[k].append(m)
            correct[k].append(correct_of([m], x_val, y[va])[0])
            correct_user[k].append(correct_of([m], x_user, y[va])[0])
    val = {k: hierarchical_bootstrap(c) for k, c in correct.items()}
    val_user = {k: hierarchical_bootstrap(c) for k, c in correct_user.items()}
    choice = max(val_user, key=lambda k: val_user[k].value)  # ties: the first candidate
    return Recommendation(choice, val, val_user, {k: Ensemble(tuple(ms)) for k, ms in members.items()}, dict(cands))


def recommend(runner: Runner) -> Recommendation:
    """Of :func:`candidates` (the grid's seeds, trained together), the one with the highest mean accuracy on the
    validation throws as a user's camera gives them (:func:`recommended`; never the test split or the videos).
    Nothing is written: the builder's step :func:`make` saves it for ``study classify``."""
    cands, seeds = candidates(runner), runner.preset.grid_seeds
    runner.prefetch([(runner, [dataclasses.replace(c, seed=s) for c in cands.values() for s in seeds], False)],
                    desc="candidates")
    return recommended(runner, cands, seeds)


def band(p_heavy: np.ndarray, y: np.ndarray, target: float = BAND_TARGET) -> tuple[float, float] | None:
    """The cannot-tell band of p(heavy), from a model's ``p_heavy`` (n,) on the certification split (labels ``y``,
    1 = heavy) as a path sees it: below its low side an answer of light lets through at most ``target`` of the heavy
    objects, above its high side an answer of heavy at most ``target`` of the light ones, each side
    ``operating.certified_threshold`` at 95 %. ``(0, 1)`` when the split is too small to certify a side (no answer
    can be stood behind); None when the sides cross (every answer is certified, and the label is the likelier
    class)."""
    p, y = np.asarray(p_heavy, dtype=np.float64), np.asarray(y)
    low = operating.certified_threshold(p, y, target)
    light_side = operating.certified_threshold(1.0 - p, 1 - y, target)
    if low is None or light_side is None:
        return (0.0, 1.0)
    high = 1.0 - light_side
    return None if low > high else (low, high)


def certified_band(runner: Runner, model: Ensemble, n_frames: int) -> tuple[float, float] | None:
    """:func:`band` of ``model`` on the certification split (``study.methods.certify``) as a user's camera and one
    scale give it (``observe.any_camera``), its first ``n_frames`` frames."""
    x, y = certify.split(runner)
    seen = observe.any_camera(x[:, :n_frames], runner.fps, np.random.default_rng(CERTIFY_OBSERVE_SEED))
    return band(model.predict_proba(seen.astype(np.float32))[:, 1], y)


def step_key(runner: Runner, measured: measured_.Measured | None = None) -> str:
    """The content key of :func:`make` on ``runner``: every candidate run's key (its data, config and the training
    code), the sweep's numbers and this module's code. The same key, the same saved model."""
    cands, seeds = candidates(runner), runner.preset.grid_seeds
    runs = sorted(records.run_key(runner.dataset, dataclasses.replace(c, dims="z", seed=s), False, runner.device)
                  for c in cands.values() for s in seeds)
    sweep = {k: {p: dataclasses.astuple(iv) for p, iv in by.items()} for k, by in (measured or {}).items()}
    return cache.key({"runs": runs, "code": cache.code_hash("recommended"), "preset": runner.preset.name,
                      "sweep": sweep})


def make(runner: Runner, measured: measured_.Measured | None = None) -> Path:
    """The builder's step: :func:`recommend` saved in the data folder as the model ``study classify`` uses without
    ``--model`` (``study.runs.recommended``), for the one-scale path, with its cannot-tell band
    (:func:`certified_band`) and what the camera sweep ``measured`` for it and for every
    kind of model; skipped when the file there has this very :func:`step_key`. Returns the file."""
    key = step_key(runner, measured)
    with contextlib.suppress(ModelError):
        if saved.read(runner.data_dir).key == key:
            return Path(runner.data_dir) / saved.FILE
    rec = recommend(runner)
    seeds, cfg = runner.preset.grid_seeds, rec.configs[rec.choice]
    dirs = tuple(records.model_dir(runner.dataset, dataclasses.replace(cfg, dims="z", seed=s),
                                   runner.data_dir, runner.device) for s in seeds)
    accuracy = dict((measured or {}).get(measured_.kind(cfg), {}))
    one = saved.PathModel(rec.choice, dirs, rec.val_user[rec.choice], accuracy,
                          certified_band(runner, rec.model, cfg.n_frames(runner.fps)))
    return saved.save(runner.data_dir, runner.preset.name, {saved.ONE_SCALE: one}, key, measured or {})
