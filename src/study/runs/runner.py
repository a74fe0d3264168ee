"""The runner: one object that holds what every experiment needs, and whose methods are the experiments.

A chapter opens one runner and calls it::

    runner = Runner.open("paper", data_seed=0)          # the dataset, the data folder, workers, executor
    cfg = runner.table1_config()                         # the peephole grid's winner: Table 1's configuration
    rows = runner.seed_runs(cfg)                         # Table 1: Z and X, Y, Z over the preset's seeds

Every training run goes through :meth:`Runner.runs`, which reads cached records and trains the others
(``study.runs.schedule.run_all``: a local process pool, or a Dask cluster with ``scheduler``), and notes
each run in the runner's :class:`~study.runs.schedule.Plan`, so a build knows how many models it
trained. The configurations of the paper's experiments are in ``study.runs.paper``; Table 1's
configuration is derived once, here (:meth:`Runner.table1_config`), for every chapter.
"""

from __future__ import annotations

import dataclasses
import json
import os
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import Any

import numpy as np

from study.core import cache
from study.runs import paper, records, schedule
from study.methods import tracker, tracker_model, videos
from study.runs.cluster import DEVICE_ENV
from study.runs.presets import Preset, preset
from study.runs.runtable import Fitted, Run, Runs
from study.runs.stats import scored
from study.methods.tracker import TrackerError
from study.learn import baseline, train
from study.learn.config import Cell, Dims, Inputs, TrainConfig
from study.learn.inputs import observe_fields
from study.learn.metrics import Interval
from study.see.config import TrackConfig
from study.simulate import data, observe, synth
from study.simulate.data import Dataset


DEVELOPMENT_RENDER_SEED = 2000
"""Seed of the development renders: throws other than the book's (``Runner.render_seed``), rendered alike, on which
the tracker's error model is fitted (``Runner.tracker_fit``)."""

OBSERVED_SEEDS: dict[str, int] = {"test": 3, "train": 4}
"""Seeds of the one observed draw of each split that chapters score learners on alike (:meth:`Runner.observed`)."""


@dataclass(frozen=True)
class Recommendation:
    """The Z model a camera in a car should use (:meth:`Runner.recommended`), chosen on observed validation throws."""

    choice: str
    """The chosen candidate's name (``"positions, exact"`` and so on, :meth:`Runner.candidates`)."""
    val: dict[str, Interval]
    """Each candidate's accuracy on the observed validation throws, with its bootstrap interval."""
    models: dict[str, train.TrainedModel]
    """Each candidate's trained model."""

    @property
    def model(self) -> train.TrainedModel:
        """The chosen model."""
        return self.models[self.choice]


@dataclass(frozen=True)
class Runner:
    """The study's experiments on one dataset, with where and how their runs are trained."""

    dataset: Dataset
    """The dataset every experiment trains on (``study.simulate.synth.dataset``)."""
    preset: Preset
    """How much of each experiment to run."""
    data_dir: Path
    """The cache folder, absolute: datasets, run records, models, videos."""
    workers: int = 0
    """Training processes at once on this machine; 0: one per CPU."""
    progress: bool = False
    """Show progress bars where the runner is called (a chapter's progress reaches the terminal anyway)."""
    scheduler: str = ""
    """Where runs are trained: '' a local process pool; 'local' a Dask ``LocalCluster``; else a Dask scheduler's
    address (``tls://host:8786``)."""
    render_seed: int = 1000
    """Seed of the rendered throws of the real-world chapter, on which the tracker is calibrated."""
    device: str = "cpu"
    """Where runs train: 'cpu', or a torch device ('cuda'); part of every run's key."""
    plan: schedule.Plan = field(default_factory=schedule.Plan.from_env, compare=False, repr=False)
    """Every run this runner was asked for (``study.runs.schedule.Plan``)."""

    @classmethod
    def open(cls, preset_name: str, data_seed: int = 0, data_dir: str | Path = "data", *, workers: int = 0,
             scheduler: str = "", progress: bool = False, render_seed: int = 1000, device: str | None = None) -> Runner:
        """The runner of preset ``preset_name`` on its dataset of ``data_seed`` (simulated once, then cached); its
        runs train on ``device`` (None: ``$STUDY_DEVICE``, which ``study book --device`` sets, else the CPU)."""
        folder = Path(data_dir).resolve()
        ds = synth.dataset(preset_name, seed=data_seed, data_dir=folder, progress=progress)
        return cls(ds, preset(preset_name), folder, workers, progress, scheduler, render_seed,
                   device or os.environ.get(DEVICE_ENV) or "cpu")

    def on(self, dataset: Dataset) -> Runner:
        """The same runner on another dataset (the same throws without air, other shapes, ...); it shares this
        runner's plan."""
        return dataclasses.replace(self, dataset=dataset, plan=self.plan)

    @property
    def fps(self) -> float:
        """The dataset's frame rate, frames per second."""
        return self.dataset.fps

    @property
    def synth_config(self) -> synth.SynthConfig:
        """The preset's synthesis config (the priors, the shape, the scene)."""
        return synth.SynthConfig.preset(self.preset.name)

    # -----------------------------------------------------------------------------------------
    # Runs

    def runs(self, cfgs: list[TrainConfig], test: bool = True, desc: str = "runs") -> list[dict[str, Any]]:
        """The records of ``cfgs`` on this runner's dataset, cached or trained (``schedule.run_all``)."""
        for c in cfgs:
            self.plan.add(self.dataset, c, self.data_dir, test, self.device)
        schedule.ask([(self.dataset, c, test) for c in cfgs], self.data_dir, self.device)  # a planned build trains
        return schedule.run_all(self.dataset, cfgs, self.data_dir, test, desc=desc, progress=self.progress,
                                workers=self.workers or None, scheduler=self.scheduler or None, device=self.device)

    def prefetch(self, batches: Iterable[tuple[Runner, Sequence[TrainConfig], bool]], desc: str = "runs") -> None:
        """Train (or read) every run of ``batches`` -- (runner, configs, scored on the test split?) -- at once,
        before the experiments ask for them one by one: one pool for a whole chapter keeps every core busy,
        where experiments of three seeds each on two cores would leave one idle at the end of each."""
        jobs = []
        for r, cfgs, test in batches:
            for c in cfgs:
                r.plan.add(r.dataset, c, r.data_dir, test, self.device)
                jobs.append((r.dataset, c, test))
        schedule.ask(jobs, self.data_dir, self.device)
        schedule.run_many(jobs, self.data_dir, desc=desc, progress=self.progress, workers=self.workers or None,
                          scheduler=self.scheduler or None, device=self.device)

    def rows(self, cfgs: list[TrainConfig], test: bool = True, desc: str = "runs") -> Runs:
        """The runs of ``cfgs`` on this runner's dataset as a table (:class:`~study.runs.runtable.Runs`)."""
        y = self.dataset.test.y
        return Runs(Run.from_record(r, y) for r in self.runs(cfgs, test, desc))

    def train_runs(self, cfg: TrainConfig, dims: tuple[Dims, ...], seeds: tuple[int, ...], desc: str = "runs",
                   **changes: Any) -> Runs:
        """``cfg`` (with ``changes``) for each of ``dims`` and ``seeds``, scored on the test split: one run per
        (dims, seed)."""
        return self.rows(paper.seed_configs(cfg, seeds, dims, **changes), desc=desc)

    def trained(self, cfg: TrainConfig) -> train.TrainedModel:
        """The kept model of ``cfg`` on this dataset, trained first if no run has left it; in the plan either way,
        so the book's count of models does not depend on what the cache held."""
        if not records.model_dir(self.dataset, cfg, self.data_dir, self.device).is_dir():
            self.runs([cfg], test=False, desc="model")
        else:
            self.plan.add(self.dataset, cfg, self.data_dir, False, self.device)
        return records.trained(self.dataset, cfg, self.data_dir, self.device)

    def models(self, cfg: TrainConfig, seeds: tuple[int, ...], **changes: Any) -> list[train.TrainedModel]:
        """The kept models of ``cfg`` (with ``changes``) for each seed."""
        return [self.trained(dataclasses.replace(cfg, seed=s, **changes)) for s in seeds]

    # -----------------------------------------------------------------------------------------
    # The paper's experiments

    def grid(self, cell: Cell = "peephole", inputs: Inputs = "positions") -> Runs:
        """The grid search on ``preset.ablation_dims`` for ``cell`` reading ``inputs``: one run per (point, seed),
        validation only."""
        return self.rows(paper.grid_configs(self.preset, cell, inputs), test=False,
                         desc=f"grid ({cell}{', velocity' if inputs == 'velocity' else ''})")

    def winner(self, cell: Cell = "peephole", inputs: Inputs = "positions") -> TrainConfig:
        """The best point of ``cell``'s grid (by the mean validation accuracy over the grid seeds)."""
        return paper.best_config(self.grid(cell, inputs), self.preset)

    def table1_config(self, inputs: Inputs = "positions") -> TrainConfig:
        """Table 1's configuration: the paper's network (the peephole LSTM) at its grid's best point, on Z. Every
        chapter that uses "Table 1's model" starts from this. With ``inputs='velocity'``, the same network
        reading velocity at the best point of its own grid (the same points, chosen by the same rule)."""
        return self.winner("peephole", inputs)

    def seed_runs(self, cfg: TrainConfig) -> Runs:
        """Table 1: ``cfg`` for Z and X, Y, Z, one run per (dims, seed), with test accuracy."""
        return self.rows(paper.seed_configs(cfg, self.preset.seeds), desc="Table 1")

    def protocol_runs(self, cfg: TrainConfig) -> Runs:
        """Every protocol of ``paper.protocol_changes`` at ``cfg``, for Z and X, Y, Z, validation only: one run per
        (protocol, dims, seed), labelled ``protocol``."""
        plan = paper.protocol_plan(cfg, self.preset)
        rows = self.rows([c for _, c in plan], test=False, desc="protocols")
        return rows.labelled({"protocol": name} for name, _ in plan)

    def ablation(self, winners: dict[Cell, TrainConfig]) -> Runs:
        """Each cell at its own grid winner on Z with the test seeds: one run per (cell, seed)."""
        return self.rows(paper.ablation_configs(winners, self.preset), desc="ablation")

    def length_sweep(self, cfg: TrainConfig) -> Runs:
        """Accuracy against input length: one run per (dims, length, seed) at ``cfg``, labelled ``frames``."""
        cfgs = paper.length_configs(cfg, self.preset)
        return self.rows(cfgs, desc="lengths").labelled({"frames": c.n_frames(self.fps)} for c in cfgs)

    def long_memory(self, cfg: TrainConfig) -> Runs:
        """The length sweep at the preset's long lengths with a memory that spans the input (chrono
        initialisation, full BPTT): one run per (dims, length, seed), labelled ``frames``."""
        cfgs = paper.long_memory_configs(cfg, self.preset, self.fps)
        return self.rows(cfgs, desc="long memory").labelled({"frames": c.n_frames(self.fps)} for c in cfgs)

    def factorial(self, cfg: TrainConfig) -> Runs:
        """Figure 4's explanation one factor at a time (``paper.factorial_configs``): one run per (truncation,
        forget start, dims, seed) at the longest input, labelled ``truncated`` and ``forget``."""
        plan = paper.factorial_configs(cfg, self.preset, self.fps)
        rows = self.rows([c for _, _, c in plan], desc="truncation x forget start")
        return rows.labelled({"truncated": trunc, "forget": forget} for trunc, forget, _ in plan)

    def baseline_runs(self) -> dict[Dims, Fitted]:
        """The physics baseline for Z and X, Y, Z at the preset's length, fitted once each (it has no seed)."""
        out = {}
        for d in paper.BOTH:
            m = baseline.fit(self.dataset, d, self.preset.length)
            pred = m.predict_proba(self.dataset.test.x).argmax(axis=1)
            res = train.metrics(self.dataset.test.y, pred)
            out[d] = Fitted(d, res["accuracy"], pred == np.asarray(self.dataset.test.y), res["per_class_accuracy"],
                            m.coefficients)
        return out

    # -----------------------------------------------------------------------------------------
    # The camera: rendered throws, the tracker's error, the model a car would use

    def rendered(self) -> tuple[list[videos.Video], Any]:
        """The real-world chapter's rendered throws at the data's frame rate, as long as Table 1's input (the
        videos the tracker is calibrated on), rendered once."""
        return videos.book_set(self.preset.name, self.fps, self.preset.length, self.render_seed, self.data_dir)

    @cached_property
    def _tracker_error(self) -> TrackerError:
        rendered, _ = self.rendered()
        key = cache.key({"videos": sorted({v.path.parent.name for v in rendered}), "n": len(rendered),
                         "track": dataclasses.asdict(TrackConfig(color=rendered[0].color, progress=False)),
                         "code": cache.code_hash("tracker-error")})
        path = self.data_dir / "observation" / f"tracker-error-{key}.json"
        try:
            return TrackerError.from_json(json.loads(path.read_text()))
        except (OSError, ValueError, KeyError):
            pass  # not measured yet, or damaged: measure again
        error = tracker.measure(rendered)
        cache.write_text_atomic(path, json.dumps(error.to_json(), indent=1) + "\n")
        return error

    def tracker_error(self) -> TrackerError:
        """The tracker's error on the rendered throws (``study.methods.tracker.measure``), measured once per
        build and cached by the videos' key, the tracker's settings and the tracker's code."""
        return self._tracker_error

    def tracker_decomposition(self) -> dict[str, tracker.Decomposition]:
        """The tracker's error on the rendered throws taken apart (``study.methods.tracker.decompose``), for
        each of :data:`study.methods.tracker.TRACKERS` (the settings before and after the shaded faces)."""
        rendered, _ = self.rendered()
        return {name: tracker.decompose(rendered, cfg) for name, cfg in tracker.TRACKERS.items()}

    def development_rendered(self) -> list[videos.Video]:
        """Throws rendered as the book's are (:meth:`rendered`), from :data:`DEVELOPMENT_RENDER_SEED`: what the
        tracker's settings and its error model are chosen on, never the book's."""
        rendered, _ = videos.book_set(self.preset.name, self.fps, self.preset.length, DEVELOPMENT_RENDER_SEED,
                                      self.data_dir)
        return rendered

    @cached_property
    def _tracker_fit(self) -> tracker_model.TrackerFit:
        fitted = tracker_model.fit(tracker_model.series_of(self.development_rendered()))
        return dataclasses.replace(fitted, fitted_on=f"{fitted.n_videos} development renders (render seed "
                                                     f"{DEVELOPMENT_RENDER_SEED}, not the book's {self.render_seed})")

    def tracker_fit(self) -> tracker_model.TrackerFit:
        """The tracker's error model (``study.methods.tracker_model.fit``: a per-throw offset, correlated noise, one
        level in flight and one in contact) fitted on the development renders, tracked end to end."""
        return self._tracker_fit

    def observation(self) -> observe.Observation:
        """The calibrated observation: the tracker's error as its fitted model draws it, and its share of lost
        frames (:meth:`tracker_fit`)."""
        return self.tracker_fit().observation()

    def observed(self, split: str, ob: observe.Observation, n_frames: int) -> np.ndarray:
        """The first ``n_frames`` of this dataset's ``split`` ('train' or 'test') as ``ob`` observes them: the one
        seeded draw (:data:`OBSERVED_SEEDS`) every chapter that scores learners on observed positions shares."""
        x = getattr(self.dataset, split).x
        return ob.observe(x[:, :n_frames], self.fps, seed=OBSERVED_SEEDS[split])

    def randomised_config(self, cfg: TrainConfig, ob: observe.Observation | None = None) -> TrainConfig:
        """``cfg`` trained on random observations, its validation observed as the calibrated tracker (or ``ob``)
        would."""
        ob = ob or self.observation()
        return dataclasses.replace(cfg, observe="randomised", **observe_fields(ob))

    def candidates(self, cfgs: dict[str, TrainConfig], ob: observe.Observation | None = None) -> dict[str, TrainConfig]:
        """Each of ``cfgs`` (name -> config) trained on exact positions and on random observations (names
        suffixed ', exact' and ', randomised'): the models a camera in a car could use, all on Z."""
        out = {}
        for name, cfg in cfgs.items():
            z = dataclasses.replace(cfg, dims="z")
            out[f"{name}, exact"] = z
            out[f"{name}, randomised"] = self.randomised_config(z, ob)
        return out

    def recommended(self, candidates: dict[str, TrainConfig], seed: int = 0,
                    ob: observe.Observation | None = None) -> Recommendation:
        """The Z model a camera in a car should use: of ``candidates`` (name -> config; :meth:`candidates`), the
        one with the highest accuracy on ``seed``'s validation trajectories observed as the calibrated tracker
        (or ``ob``) observes them (never the test split)."""
        ob = ob or self.observation()
        models = {k: self.trained(dataclasses.replace(c, dims="z", seed=seed)) for k, c in candidates.items()}
        first = next(iter(candidates.values()))
        _, va = train.split_train_val(len(self.dataset.train.y), first.val_fraction, seed)
        T = first.n_frames(self.fps)
        x_val = ob.observe(self.dataset.train.x[va, :T], self.fps, seed=6)
        val = {k: scored([m], x_val, self.dataset.train.y[va]) for k, m in models.items()}
        choice = max(val, key=lambda k: val[k].value)  # ties: the first candidate
        return Recommendation(choice, val, models)

    def rocket(self, dims: Dims, n_frames: int, seed: int, tests: dict[str, np.ndarray],
               train_x: np.ndarray | None = None) -> dict[str, np.ndarray]:
        """MiniRocket's labels on each of ``tests``, fitted on this dataset's training split (or ``train_x``),
        cached like a run (``study.methods.rockets``)."""
        from study.methods.rockets import rocket_predictions

        return rocket_predictions(self.dataset, dims, n_frames, seed, tests, self.data_dir, train_x)

    # -----------------------------------------------------------------------------------------
    # Other datasets of the same study

    def air_off(self) -> Runner:
        """This runner on the same throws with the air removed (the random streams do not depend on ``air``)."""
        cfg = synth.SynthConfig.from_dict(self.dataset.meta["config"]).replace(air=False)
        return self.on(synth.dataset(cfg, int(self.dataset.meta["seed"]), data_dir=self.data_dir, progress=False))

    def in_engine(self, engine: str) -> Runner:
        """This runner on the same throws, without air, simulated by ``engine`` ('mujoco' or 'bullet'): the same
        sampled objects and launches, index by index."""
        cfg = synth.SynthConfig.from_dict(self.dataset.meta["config"]).replace(air=False, engine=engine)
        return self.on(synth.dataset(cfg, int(self.dataset.meta["seed"]), data_dir=self.data_dir,
                                     progress=self.progress))

    def with_data_seed(self, seed: int) -> Runner:
        """This runner on another data set of the same study: the same config simulated from ``seed`` (new
        throws from the same priors), cached like the first."""
        cfg = synth.SynthConfig.from_dict(self.dataset.meta["config"])
        return self.on(synth.dataset(cfg, seed, data_dir=self.data_dir, progress=self.progress))

    def saved(self, dataset: Dataset, name: str) -> Dataset:
        """An in-memory ``dataset`` (one with a key but no file) written to the cache once, so that workers read
        it from the shared folder; returns it as read back."""
        path = self.data_dir / f"{name}-{dataset.key}.npz"
        if not path.is_file():
            data.save(dataset, path)
        return data.load(path)
