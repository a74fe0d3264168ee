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
from study.methods import calibration, certify, floor_model, operating
from study.runs import measured as measured_
from study.runs.measured import candidate_kind as kind  # noqa: F401  (re-exported: recommend.kind)
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
    val_floor: dict[str, Interval] = dataclasses.field(default_factory=dict)
    """The same on the validation throws as the floor path gives them (its fitted error,
    ``study.methods.floor_model``); empty where the floor path has no error model."""

    @property
    def floor_choice(self) -> str | None:
        """The candidate for the floor path: the best on :attr:`val_floor` (None: no floor model)."""
        return max(self.val_floor, key=lambda k: self.val_floor[k].value) if self.val_floor else None

    @property
    def model(self) -> Ensemble:
        """The chosen model (its seeds' ensemble)."""
        return self.models[self.choice]


def candidates(runner: Runner, cfgs: dict[str, TrainConfig] | None = None,
               ob: observe.Observation | None = None, floor: observe.Observation | None = None) -> dict[str, TrainConfig]:
    """The Z models a camera could use: each of ``cfgs`` (name -> config; default: the paper's network reading
    positions at Table 1's point and reading positions and velocity at its own grid's point) trained on exact
    positions, on random observations as the calibrated tracker (or ``ob``) would see them, on heights as a
    user's own camera anywhere gives them (``study.simulate.observe.any_camera``), and, given the floor path's
    observation ``floor`` (``study.methods.floor_model``), on random observations validated as that path sees the
    throws and on the floor path's own error drawn afresh every epoch (names suffixed ', exact', ', randomised',
    ', any-camera', ', floor' and ', floor-fixed': :func:`kind` of a name)."""
    cfgs = cfgs or {"positions": runner.table1_config(), "velocity": runner.table1_config("velocity")}
    out = {}
    for name, cfg in cfgs.items():
        z = dataclasses.replace(cfg, dims="z")
        out[f"{name}, exact"] = z
        out[f"{name}, randomised"] = calibration.randomised_config(runner, z, ob)
        out[f"{name}, any-camera"] = dataclasses.replace(out[f"{name}, randomised"], observe="any-camera")
        if floor is not None:
            out[f"{name}, floor"] = calibration.randomised_config(runner, z, floor)
            out[f"{name}, floor-fixed"] = dataclasses.replace(out[f"{name}, floor"], observe="fixed")
    return out


def all_candidates(runner: Runner) -> dict[str, TrainConfig]:
    """:func:`candidates` with the floor path's where it has an error model: what the build trains and chooses
    from."""
    return candidates(runner, floor=floor_model.observation(runner))


def recommended(runner: Runner, cands: dict[str, TrainConfig], seeds: Sequence[int] = (0,),
                ob: observe.Observation | None = None, floor: observe.Observation | None = None) -> Recommendation:
    """Of ``cands`` (name -> config; :func:`candidates`), the one with the highest mean accuracy over ``seeds`` on
    each seed's validation trajectories as a user's camera gives them (``observe.any_camera``: what ``study classify``
    reads), each also scored as the calibrated tracker (or ``ob``) observes them and, given the floor path's
    observation ``floor``, as that path gives them (:attr:`Recommendation.floor_choice`); never the test split."""
    if not seeds:
        raise ConfigError("recommended: seeds is empty; give at least one seed")
    ob = ob or calibration.observation(runner)
    first = next(iter(cands.values()))
    T, y = first.n_frames(runner.fps), runner.dataset.train.y
    views = ("calibrated", "user", "floor") if floor is not None else ("calibrated", "user")
    correct: dict[str, dict[str, list[np.ndarray]]] = {v: {k: [] for k in cands} for v in views}
    members: dict[str, list[train.TrainedModel]] = {k: [] for k in cands}
    for seed in seeds:
        _, va = train.split_train_val(len(y), first.val_fraction, seed)
        x = runner.dataset.train.x[va, :T]
        seen = {"calibrated": ob.observe(x, runner.fps, seed=6),
                "user": observe.any_camera(x, runner.fps, np.random.default_rng([seed, 7])).astype(np.float32)}
        if floor is not None:
            seen["floor"] = floor.observe(x, runner.fps, seed=8)
        for k, c in cands.items():
            m = runner.trained(dataclasses.replace(c, dims="z", seed=seed))
            members[k].append(m)
            for v in views:
                correct[v][k].append(correct_of([m], seen[v], y[va])[0])
    val, val_user, val_floor = ({k: hierarchical_bootstrap(c) for k, c in correct.get(v, {}).items()}
                                for v in ("calibrated", "user", "floor"))
    choice = max(val_user, key=lambda k: val_user[k].value)  # ties: the first candidate
    return Recommendation(choice, val, val_user, {k: Ensemble(tuple(ms)) for k, ms in members.items()}, dict(cands),
                          val_floor)


def recommend(runner: Runner) -> Recommendation:
    """Of :func:`all_candidates` (the grid's seeds, trained together), the one with the highest mean accuracy on the
    validation throws as a user's camera gives them, and the one for the floor path (:func:`recommended`; never the
    test split or the videos). Nothing is written: the builder's step :func:`make` saves them for ``study
    classify``."""
    floor = floor_model.observation(runner)
    cands, seeds = candidates(runner, floor=floor), runner.preset.grid_seeds
    runner.prefetch([(runner, [dataclasses.replace(c, seed=s) for c in cands.values() for s in seeds], False)],
                    desc="candidates")
    return recommended(runner, cands, seeds, floor=floor)


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


def certified_band(runner: Runner, model: Ensemble, n_frames: int,
                   floor: observe.Observation | None = None) -> tuple[float, float] | None:
    """:func:`band` of ``model`` on the certification split (``study.methods.certify``) as a user's camera and one
    scale give it (``observe.any_camera``), or as the floor path gives it (its observation ``floor``), its first
    ``n_frames`` frames."""
    x, y = certify.split(runner)
    x = x[:, :n_frames]
    seen = (observe.any_camera(x, runner.fps, np.random.default_rng(CERTIFY_OBSERVE_SEED)) if floor is None
            else floor.observe(x, runner.fps, seed=CERTIFY_OBSERVE_SEED))
    return band(model.predict_proba(seen.astype(np.float32))[:, 1], y)


def step_key(runner: Runner, measured: measured_.Measured | None = None) -> str:
    """The content key of :func:`make` on ``runner``: every candidate run's key (its data, config and the training
    code), the sweep's numbers and this module's code. The same key, the same saved model."""
    cands, seeds = all_candidates(runner), runner.preset.grid_seeds
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

    def path_model(name: str, val: Interval, floor: observe.Observation | None = None) -> saved.PathModel:
        cfg = rec.configs[name]
        dirs = tuple(records.model_dir(runner.dataset, dataclasses.replace(cfg, dims="z", seed=s),
                                       runner.data_dir, runner.device) for s in runner.preset.grid_seeds)
        return saved.PathModel(name, dirs, val, dict((measured or {}).get(kind(name), {})),
                               certified_band(runner, rec.models[name], cfg.n_frames(runner.fps), floor))

    paths = {saved.ONE_SCALE: path_model(rec.choice, rec.val_user[rec.choice])}
    if rec.floor_choice is not None:
        paths[saved.FLOOR] = path_model(rec.floor_choice, rec.val_floor[rec.floor_choice], floor_model.observation(runner))
    return saved.save(runner.data_dir, runner.preset.name, paths, key, measured or {})
