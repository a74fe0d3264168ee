"""The runner: the dataset a chapter works on, and its runs, trained or read from the cache.

A chapter opens one runner and calls it::

    runner = Runner.open("paper", data_seed=0)          # the dataset, the data folder, workers, executor
    cfg = runner.table1_config()                         # the peephole grid's winner: Table 1's configuration
    rows = runner.seed_runs(cfg)                         # Table 1: Z and X, Y, Z over the preset's seeds

Every training run goes through :meth:`Runner.runs`, which reads cached records and trains the others
(``study.runs.schedule.run_all``: a local process pool, or a Dask cluster with ``scheduler``), and notes
each run in the runner's :class:`~study.runs.schedule.Plan`, so a build knows how many models it
trained. The configurations of the paper's experiments are in ``study.runs.paper``; Table 1's
configuration is derived once, here (:meth:`Runner.table1_config`), for every chapter. What only one chapter runs
is that chapter's function taking the runner (``study.chapters``); what looks through the camera is
``study.methods.calibration``.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, TypeVar

from study.core import datadir, ticket
from study.learn import train
from study.learn.config import Cell, Dims, Inputs, TrainConfig
from study.runs import paper, records, schedule
from study.runs.presets import Preset, preset
from study.runs.runtable import Run, Runs
from study.simulate import synth
from study.simulate.data import Dataset

T = TypeVar("T")


@dataclass(frozen=True)
class Runner:
    """The study's experiments on one dataset, with where and how their runs are trained.

    Example::

        if __name__ == "__main__":                    # its runs train in worker processes
            runner = study.Runner.open("smoke", data_seed=0)
            rows = runner.seed_runs(runner.table1_config())
    """

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
    _memo: dict[str, Any] = field(default_factory=dict, compare=False, repr=False)

    @classmethod
    def open(cls, preset_name: str, data_seed: int = 0, data_dir: str | Path | None = None, *, workers: int = 0,
             scheduler: str = "", progress: bool = False, render_seed: int = 1000, device: str | None = None) -> Runner:
        """The runner of preset ``preset_name`` on its dataset of ``data_seed`` (simulated once, then cached); its
        runs train on ``device`` (None: the device ``study book --device`` names in the chapter's ticket, else the
        CPU); its caches live in ``data_dir`` (None: ``study.core.datadir.resolve``'s, by default ``data/``)."""
        folder = datadir.resolve(data_dir).resolve()
        ds = synth.dataset(preset_name, seed=data_seed, data_dir=folder, progress=progress)
        return cls(ds, preset(preset_name), folder, workers, progress, scheduler, render_seed,
                   device or ticket.current().device or "cpu")

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

    def memo(self, name: str, make: Callable[[], T]) -> T:
        """``make()``, computed once per runner under ``name`` (what a chapter asks for several times, such as the
        tracker's fitted error model, ``study.methods.calibration``); another runner (:meth:`on`) starts afresh."""
        if name not in self._memo:
            self._memo[name] = make()
        return self._memo[name]

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

    def reject(self, cfgs: Iterable[TrainConfig]) -> None:
        """Say that the runs of ``cfgs`` were candidates the chapter did not choose (``Plan.reject``)."""
        for c in cfgs:
            self.plan.reject(self.dataset, c, self.device)

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

    # -----------------------------------------------------------------------------------------
    # Other datasets of the same study

    def air_off(self) -> Runner:
        """This runner on the same throws with the air removed (the random streams do not depend on ``air``)."""
        cfg = synth.SynthConfig.from_dict(self.dataset.meta["config"]).replace(air=False)
        return self.on(synth.dataset(cfg, int(self.dataset.meta["seed"]), data_dir=self.data_dir, progress=False))

    def with_data_seed(self, seed: int) -> Runner:
        """This runner on another data set of the same study: the same config simulated from ``seed`` (new
        throws from the same priors), cached like the first."""
        cfg = synth.SynthConfig.from_dict(self.dataset.meta["config"])
        return self.on(synth.dataset(cfg, seed, data_dir=self.data_dir, progress=self.progress))

