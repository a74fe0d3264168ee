"""The chapter *What the motion allows*: every learner, trained and tested under each camera, against the exact
ceiling of the priors.

The chapter's table has a row per learner and a column per condition (:class:`Column`): the air on or off, and
the positions exact or observed by a camera whose error is white noise of one pixel of a 1080-row camera at 4 m,
the tracker's error as its fitted model draws it (``calibration.observation``: a per-throw offset and correlated noise,
one level in flight and another in contact, ``study.methods.tracker_model``), or white noise of one pixel of the
same camera at 55 m (with the tracker's share of lost frames in every observed column). Each learner is trained
on the condition it is tested on:

- the networks (:data:`NETWORKS`) with ``TrainConfig.observe = 'fixed'`` at the column's error (a fresh draw
  every epoch; validation observed the same way), over the preset's grid seeds;
- MiniRocket on one observed draw of the training split, once per seed;
- the physics baseline and the best one-feature rule fitted once on that draw;

and one more row, Table 1's network trained on exact positions and tested observed. Every learner of a
column is scored on the same observed test trajectories (one seeded draw per column), so two learners
compare paired. Z only (what one camera gives), the first T seconds of Table 1.

:func:`compute` runs it all on a runner (every run cached) and returns :class:`Motion`; :class:`Numbers` is
what the chapter reports, under the names ``motion.peephole_positions.air_on.exact`` and so on.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from functools import cached_property
from typing import get_args

import numpy as np

from study.learn.config import TrainConfig
from study.learn.metrics import Interval, bootstrap_accuracy, bootstrap_difference
from study.methods import calibration, ceiling, learners
from study.methods.camera import (
    AIR_OFF_PARAMETERS,
    AIR_ON_PARAMETERS,
    RULE_FEATURES,
    SHORT,
    Air,
    Column,
    View,
    column_ceiling,
    columns,
    trained_config,
)
from study.report.motion import (
    LEARNERS,
    SHOWN,  # noqa: F401  (the learners the page's figure draws)
    Best,
    Ceiling,
    Learner,
    Network,
    Numbers,
    Trained,
)
from study.report.reported import Number, count, number
from study.report.text import Table, pct, pct_ci, seeds_ci
from study.runs.runner import Runner
from study.simulate import observe
from study.simulate.synth import SynthConfig

NETWORKS: tuple[Network, ...] = get_args(Network)
NAMES: dict[Learner, str] = {name: learners.NAMES[name] for name in LEARNERS}
"""Each learner in words."""


# ---------------------------------------------------------------------------------------------
# The networks' configurations and runs


def configs(runner: Runner) -> dict[Trained, TrainConfig]:
    """Each network row's configuration before its column's condition: the paper's network at Table 1's point,
    the same fed velocity and the GRU fed velocity each at its own grid's point, and Table 1's network again for
    the row trained exact."""
    return {"peephole_positions": runner.table1_config(), "peephole_velocity": runner.table1_config("velocity"),
            "gru_velocity": dataclasses.replace(runner.winner("gru"), inputs="velocity"),
            "peephole_exact_trained": runner.table1_config()}


def network_configs(cfgs: Mapping[Trained, TrainConfig], column: Column) -> dict[Trained, TrainConfig]:
    """The config of every network row in ``column``: each of :data:`NETWORKS` trained on the column's condition,
    and, in an observed column, Table 1's network trained on exact positions."""
    out: dict[Trained, TrainConfig] = {name: trained_config(cfgs[name], column) for name in NETWORKS}
    if column.noise is not None:
        out["peephole_exact_trained"] = dataclasses.replace(cfgs["peephole_exact_trained"], dims="z")
    return out


Rates = Mapping[str, tuple[float, ...]]
"""Cell name (``TrainConfig.cell``) -> the Adam learning rates of its grid (``Preset.grid_lrs``)."""


def candidates(cfg: TrainConfig, rates: Rates) -> list[TrainConfig]:
    """A network row's configs in one column: ``cfg`` at its own rate first, then at every other rate of its cell's
    grid (``rates[cfg.cell]``; none when the cell is not in ``rates``). The grid picked the rate on exact inputs; a
    camera's noise can make it too high (the GRU picked on positions, fed velocity through the 4 cm camera, stays
    on the initial plateau at 0.003), so each column chooses again among them (:func:`chosen`)."""
    return [cfg] + [dataclasses.replace(cfg, lr=lr) for lr in rates.get(cfg.cell, ()) if lr != cfg.lr]


def row_candidates(cfgs: Mapping[Trained, TrainConfig], column: Column, rates: Rates | None
                   ) -> dict[Trained, list[TrainConfig]]:
    """Each row's :func:`candidates` in ``column`` (:func:`network_configs`); the row trained exact has its own
    config only (Table 1's network as it is)."""
    return {name: candidates(cfg, (rates or {}) if name in NETWORKS else {})
            for name, cfg in network_configs(cfgs, column).items()}


def plan(runners: Mapping[bool, Runner], cfgs: Mapping[Trained, TrainConfig], cols: Sequence[Column],
         seeds: tuple[int, ...], rates: Rates | None = None) -> list[tuple[Runner, list[TrainConfig], bool]]:
    """Every network run of the table, as ``Runner.prefetch`` takes them: ``runners`` maps air on (True) / off
    to the runner on that data; ``rates``: each cell's grid rates (:func:`candidates`)."""
    return [(runners[c.air], [dataclasses.replace(cand, seed=s) for cands in row_candidates(cfgs, c, rates).values()
                              for cand in cands for s in seeds], True) for c in cols]


def chosen(runner: Runner, cands: Sequence[TrainConfig], seeds: tuple[int, ...], desc: str = "runs") -> TrainConfig:
    """The candidate whose runs over ``seeds`` have the highest mean validation accuracy (ties: the lower mean
    validation loss, then the first), Table 1's rule for its grid (``paper.best_config``)."""
    def rank(i: int) -> tuple[float, float, int]:
        runs = runner.train_runs(cands[i], (cands[i].dims,), seeds, desc=desc)
        return -float(np.mean(runs.val_accuracies())), float(np.mean([r.val_loss for r in runs])), i
    return cands[min(range(len(cands)), key=rank)]


def turned_down(cfgs: Mapping[Trained, TrainConfig], cols: Sequence[Column], seeds: tuple[int, ...], rates: Rates,
                picked: Mapping[tuple[Trained, str], float]) -> dict[bool, list[TrainConfig]]:
    """The runs the chapter trained as candidates and used nowhere, by air on (True) / off (each air setting is its
    own data): ``picked[row, column key]`` is the rate each row's column chose. A run one column turns down and
    another row uses (an exact column's config can be the row trained exact's) is used."""
    down: dict[bool, set[TrainConfig]] = {True: set(), False: set()}
    used: dict[bool, set[TrainConfig]] = {True: set(), False: set()}
    for c in cols:
        for name, cands in row_candidates(cfgs, c, rates).items():
            for cand in cands:
                runs = {dataclasses.replace(cand, seed=s) for s in seeds}
                (used if cand.lr == picked[name, c.key] else down)[c.air].update(runs)
    return {air: sorted(down[air] - used[air], key=repr) for air in down}


# ---------------------------------------------------------------------------------------------
# One learner in one column


@dataclass(frozen=True, eq=False)
class Entry:
    """One entry of the table: one learner in one column, and which test throws each of its seeds got right."""

    learner: Learner
    column: Column
    correct: np.ndarray
    """(S, n) bool: seed s got test throw i right (S = 1 for a learner without a seed)."""
    failed: int = 0
    """Seeds that failed to train."""
    val: float | None = None
    """Mean validation accuracy over the seeds (observed as in training), for the networks."""
    feature: str = ""
    """The rule's feature, for the rule."""
    seeds: tuple[int, ...] = ()
    """The seeds of its runs (none for the physics baseline and the rule)."""
    lr: float | None = None
    """The learning rate its column chose, for the networks (:func:`chosen`)."""

    @cached_property
    def interval(self) -> Interval:
        """Mean test accuracy with its bootstrap interval over the test throws and the seeds."""
        return bootstrap_accuracy(self.correct)


def column_entries(runner: Runner, cfgs: Mapping[Trained, TrainConfig], column: Column, seeds: tuple[int, ...],
                   contact_height: float, rates: Rates | None = None) -> list[Entry]:
    """Every learner of :data:`LEARNERS` trained and tested on ``column``, with ``runner`` on the column's data
    (air on or off), in the table's order: the networks trained on the column's condition, each at the rate of its
    grid the column's validation chose (:func:`chosen`; ``rates`` as :func:`plan`'s), MiniRocket once per seed (the
    cached exact fit in an exact column), the physics baseline and the best rule of :data:`RULE_FEATURES` on the
    height alone, each fitted on the column's training inputs and scored on its test inputs
    (``study.methods.learners``)."""
    ds = runner.dataset
    T = cfgs["peephole_positions"].n_frames(ds.fps)
    x_train, x_test = column.inputs(ds, T)
    tests = {"test": (x_test, ds.test.y)}
    nets = {name: chosen(runner, cands, seeds, desc=f"{column.key} {name}")
            for name, cands in row_candidates(cfgs, column, rates).items()}
    fitted: list[tuple[learners.Learner, np.ndarray | None]] = [
        (learners.Network(name, cfg, seeds, desc=f"{column.key} {name}"), None) for name, cfg in nets.items()]
    fitted += [(learners.Rocket("z", T, seeds), None if column.noise is None else x_train),
               (learners.Physics("z", T / ds.fps), x_train),
               (learners.Rule(RULE_FEATURES, contact_height), x_train)]
    out = []
    for learner, train_x in fitted:
        s = learner.score(runner, train_x, tests)
        lr = nets[learner.name].lr if learner.name in nets else None  # type: ignore[index]
        out.append(Entry(learner.name, column, s.correct["test"], s.failed, s.val, s.feature, s.seeds, lr))  # type: ignore[arg-type]
    return sorted(out, key=lambda e: LEARNERS.index(e.learner))


@dataclass(frozen=True)
class Lead:
    """The learner with the highest mean accuracy in one column, and its paired lead over the next."""

    best: Learner
    next: Learner
    difference: Interval
    """Best minus next, paired on the same test throws (bootstrap)."""

    @property
    def tied(self) -> bool:
        """The difference's interval spans 0."""
        return self.difference.lo <= 0 <= self.difference.hi


def best_of(entries: Sequence[Entry]) -> Lead:
    """The learner with the highest mean accuracy among ``entries`` (one column; ties: the first), and its lead
    over the next."""
    ranked = sorted(entries, key=lambda e: -e.correct.mean())
    first, second = ranked[0], ranked[1]
    return Lead(first.learner, second.learner, bootstrap_difference(first.correct, second.correct))


# ---------------------------------------------------------------------------------------------
# What the chapter reports


def ceiling_numbers(prior: SynthConfig) -> Ceiling:
    """The exact ceilings of ``prior``, without air (told the restitution and friction, or the restitution
    alone) and with it (the mass too)."""
    return Ceiling(
        number(ceiling.exact_ceiling(prior, AIR_OFF_PARAMETERS),
               "exact ceiling, air off: Bayes rule on the true restitution and friction"),
        number(ceiling.exact_ceiling(prior, ("restitution",)), "exact ceiling on the restitution alone"),
        number(ceiling.exact_ceiling(prior, AIR_ON_PARAMETERS),
               "exact ceiling, air on: the mass too (drag makes it visible)"))


def learner_numbers(entries: Mapping[tuple[Learner, str], Entry],
                    cols: Sequence[Column]) -> dict[Learner, dict[Air, dict[View, Number]]]:
    """Each entry's accuracy with its interval, under its learner, air and view."""
    out: dict[Learner, dict[Air, dict[View, Number]]] = {}
    for name in LEARNERS:
        for c in cols:
            e = entries.get((name, c.key))
            if e is None:
                continue
            out.setdefault(name, {}).setdefault(c.air_key, {})[c.name] = number(
                e.interval, f"{NAMES[name]}, Z, {'air on' if c.air else 'air off'}, {c.label}",
                seeds=list(e.seeds) if e.correct.shape[0] > 1 else [], failed=e.failed,
                **({} if e.lr is None else {"lr": e.lr}))
    return out


def best_numbers(leads: Mapping[str, Lead], ceilings: Mapping[str, float], entries: Mapping[tuple[Learner, str], Entry],
                 cols: Sequence[Column]) -> dict[Air, dict[View, Best]]:
    """Each column's best learner: its gap to the ceiling and its lead over the next."""
    out: dict[Air, dict[View, Best]] = {}
    for c in cols:
        b = leads[c.key]
        gap = ceilings[c.key] - entries[b.best, c.key].interval.value
        out.setdefault(c.air_key, {})[c.name] = Best(
            number(gap, f"ceiling minus the best learner, {c.key}"),
            number(b.difference, f"the best learner minus the next, paired, {c.key}", signed=True,
                   best=b.best, next=b.next, tied=bool(b.tied)))
    return out


# ---------------------------------------------------------------------------------------------
# The chapter's result


@dataclass(frozen=True)
class Motion:
    """Everything the chapter shows: its numbers (:attr:`numbers`), its tables and sentences, its figure's data."""

    numbers: Numbers
    """What the chapter reports (the results file's ``motion.*``)."""
    columns: tuple[Column, ...]
    """The table's columns, air on first."""
    configs: dict[Trained, TrainConfig]
    """Each network row's configuration before its column's condition."""
    entries: dict[tuple[Learner, str], Entry]
    """Every (learner, column key) of the table."""
    ceilings: dict[str, float]
    """Each column's exact ceiling, by column key."""
    leads: dict[str, Lead]
    """Each column's best learner, by column key."""
    motion_table: Table
    """Every learner in every column, and the ceiling."""
    seed_table: Table
    """Every learned entry seed by seed."""
    best_table: Table
    """Each column's best learner, its lead and its distance from the ceiling."""
    gap_table: Table
    """How far each learner is from its column's ceiling."""
    conditions: str
    """The air-on columns in words."""
    drop_pct: str
    """The share of frames every observed column loses, percent."""
    restitution_overlap: str
    """Where the two classes' restitution priors overlap."""
    length_s: float
    """Input length, seconds."""
    n_runs: int
    """Network runs of the chapter."""
    n_failed: int
    """Of those, runs that failed to train."""
    fitted_on: str = ""
    """What the calibrated column's error model was fitted on, in words (``calibration.tracker_fit``)."""

    def curve(self, learner: Learner, air: bool) -> tuple[np.ndarray, list[Interval]]:
        """One learner's accuracy against the camera's error at one air setting: (k,) errors in millimetres (0
        for exact positions) and the k intervals."""
        cs = [c for c in self.columns if c.air == air]
        return np.array([1000 * (c.noise or 0.0) for c in cs]), [self.entries[learner, c.key].interval for c in cs]

    def ceiling_of(self, air: bool) -> float:
        """The exact ceiling with the air on or off."""
        return self.ceilings["air_on.exact" if air else "air_off.exact"]

    # The wide tables, one air setting at a time (four conditions fit a phone's page) ---------------

    def _half(self, table: Table, air: bool) -> Table:
        heads = {"learner": f"{table.columns['learner']}, {'air on' if air else 'air off'}",
                 **{c.key: SHORT[c.name] for c in self.columns if c.air == air}}
        return Table([{k: row[k] for k in heads} for row in table.rows], heads)

    @property
    def table_air_on(self) -> Table:
        """:attr:`motion_table`'s air-on columns."""
        return self._half(self.motion_table, True)

    @property
    def table_air_off(self) -> Table:
        """:attr:`motion_table`'s air-off columns."""
        return self._half(self.motion_table, False)

    @property
    def gap_air_on(self) -> Table:
        """:attr:`gap_table`'s air-on columns, points below the ceiling."""
        return self._half(self.gap_table, True)

    @property
    def gap_air_off(self) -> Table:
        """:attr:`gap_table`'s air-off columns, points below the ceiling."""
        return self._half(self.gap_table, False)

    # Sentences whose words depend on the numbers -------------------------------------------------

    @property
    def calibrated_model(self) -> str:
        """The calibrated column's error model in words (white noise where it has none)."""
        c = next(c for c in self.columns if c.name == "calibrated")
        return c.tracker.describe() if c.tracker is not None else f"white noise of {1000 * (c.noise or 0):.1f} mm"

    @property
    def vel_point(self) -> str:
        c = self.configs["peephole_velocity"]
        return f"lr {c.lr:g}, truncation {c.truncation}"

    @property
    def gru_point(self) -> str:
        c = self.configs["gru_velocity"]
        return f"lr {c.lr:g}, truncation {c.truncation}"

    @property
    def rates_moved(self) -> str:
        """Where a column chose a network's rate other than its grid's pick (:func:`chosen`), grouped by rate:
        ``the GRU with velocity: lr 0.001 in air on, 4 cm at 55 m``; or that none did."""
        parts = []
        for name in NETWORKS:
            base = self.configs[name].lr
            by_rate: dict[float, list[str]] = {}
            for col in self.columns:
                lr = self.entries[name, col.key].lr
                if lr is not None and lr != base:
                    by_rate.setdefault(lr, []).append(col.heading)
            parts += [f"the {NAMES[name]}: lr {lr:g} in {'; '.join(heads)}" for lr, heads in sorted(by_rate.items())]
        return "; ".join(parts) if parts else "no column chose another rate than its grid's"

    def _velocity_gain(self, air: Air) -> str:
        vel, pos = (self.entries[n, f"{air}.exact"].interval.value for n in ("peephole_velocity", "peephole_positions"))
        return f"{100 * (vel - pos):+.1f}"

    @property
    def vel_gain_on(self) -> str:
        """What velocity adds to the paper's network on exact positions with the air, points."""
        return self._velocity_gain("air_on")

    @property
    def vel_gain_off(self) -> str:
        """The same without air."""
        return self._velocity_gain("air_off")

    def _best_words(self, key: str) -> str:
        b = self.leads[key]
        iv = self.entries[b.best, key].interval
        tie = f"; tied with the {NAMES[b.next]}" if b.tied else ""
        return (f"the {NAMES[b.best]} at {pct(iv.value)} ({100 * (self.ceilings[key] - iv.value):.1f} points below "
                f"the ceiling{tie})")

    @property
    def answer(self) -> str:
        """The chapter's answer in one paragraph."""
        n = self.numbers.ceiling
        return (f"Without air no classifier of these trajectories can beat {pct(n.air_off.value)}; with the air, "
                f"whose drag makes the mass visible, {pct(n.air_on.value)}. On exact positions the best learner is "
                f"{self._best_words('air_on.exact')} with the air and {self._best_words('air_off.exact')} without; "
                f"through the calibrated tracker, {self._best_words('air_on.calibrated')} with the air and "
                f"{self._best_words('air_off.calibrated')} without.")


def _motion_table(entries: Mapping[tuple[Learner, str], Entry], cols: Sequence[Column], ceilings: Mapping[str, float],
                  heads: Mapping[str, str]) -> Table:
    rows = []
    for name in LEARNERS:
        row = {"learner": NAMES[name]}
        for c in cols:
            e = entries.get((name, c.key))
            if e is None:
                row[c.key] = "—"
                continue
            extra = f" ({e.feature})" if e.feature else ""
            note = f"; {e.failed} failed" if e.failed else ""
            row[c.key] = f"{pct_ci(e.interval)}{extra}{note}"
        rows.append(row)
    rows.append({"learner": "**ceiling of the priors**", **{c.key: f"**{pct(ceilings[c.key])}**" for c in cols}})
    return Table(rows, heads)


def _seed_table(entries: Mapping[tuple[Learner, str], Entry], cols: Sequence[Column]) -> Table:
    rows = [{"learner": NAMES[n], "column": c.heading, "seeds": seeds_ci(entries[n, c.key].correct)}
            for n in LEARNERS for c in cols if (n, c.key) in entries and entries[n, c.key].correct.shape[0] > 1]
    return Table(rows, {"learner": "learner", "column": "condition",
                        "seeds": "mean [bootstrap 95 % CI]; t-interval over the seeds; each seed (%)"})


def _best_table(leads: Mapping[str, Lead], entries: Mapping[tuple[Learner, str], Entry], cols: Sequence[Column],
                ceilings: Mapping[str, float]) -> Table:
    rows = []
    for c in cols:
        b = leads[c.key]
        value = entries[b.best, c.key].interval.value
        d = b.difference.value
        lead = (f"tied with the {NAMES[b.next]} ({100 * d:+.1f} points, interval across 0)" if b.tied
                else f"{100 * d:.1f} points ahead of the {NAMES[b.next]}")
        rows.append({"column": c.heading, "best": NAMES[b.best], "accuracy": pct(value), "lead": lead,
                     "gap": f"{100 * (ceilings[c.key] - value):.1f}"})
    return Table(rows, {"column": "condition", "best": "best learner", "accuracy": "its accuracy",
                        "lead": "against the next", "gap": "below the ceiling (points)"})


def _gap_table(entries: Mapping[tuple[Learner, str], Entry], cols: Sequence[Column], ceilings: Mapping[str, float],
               heads: Mapping[str, str]) -> Table:
    rows = [{"learner": NAMES[n], **{c.key: f"{100 * (ceilings[c.key] - entries[n, c.key].correct.mean()):.1f}"
                                      if (n, c.key) in entries else "—" for c in cols}} for n in LEARNERS]
    return Table(rows, heads)


def report(prior: SynthConfig, cfgs: Mapping[Trained, TrainConfig], cols: Sequence[Column],
           entries: Mapping[tuple[Learner, str], Entry], drop: float, fitted_on: str = "") -> Motion:
    """The chapter's result from its entries (``entries[learner, column.key]``, from :func:`column_entries`):
    numbers, tables and sentences. ``drop``: the share of frames the tracker loses; ``fitted_on``: what the
    calibrated column's error model was fitted on."""
    entries = dict(entries)
    ceilings = {c.key: column_ceiling(prior, c) for c in cols}
    leads = {c.key: best_of([entries[n, c.key] for n in LEARNERS if (n, c.key) in entries]) for c in cols}
    nets = [e for (n, _), e in entries.items() if n in NETWORKS]  # each run once: not the exact-trained row
    n_failed = sum(e.failed for e in nets)
    numbers = Numbers(
        ceiling_numbers(prior),
        {c.name: number(c.noise, f"camera error of the column: {c.label}", unit="m")  # type: ignore[misc]
         for c in cols if c.air and c.noise is not None},
        learner_numbers(entries, cols),
        count(n_failed, "network runs of this chapter that failed to train"),
        best_numbers(leads, ceilings, entries, cols))
    length = cfgs["peephole_positions"].length
    heads = {"learner": f"learner (Z, {length:g} s)", **{c.key: c.heading for c in cols}}
    light, heavy = prior.light.restitution, prior.heavy.restitution
    return Motion(
        numbers, tuple(cols), dict(cfgs), entries, ceilings, leads, _motion_table(entries, cols, ceilings, heads),
        _seed_table(entries, cols), _best_table(leads, entries, cols, ceilings), _gap_table(entries, cols, ceilings, heads),
        conditions="; ".join(c.label for c in cols if c.air), drop_pct=f"{100 * drop:.1f}",
        restitution_overlap=f"{max(light[0], heavy[0]):g}–{min(light[1], heavy[1]):g}", length_s=length,
        n_runs=sum(e.correct.shape[0] for e in nets), n_failed=n_failed, fitted_on=fitted_on)


def compute(runner: Runner, cfgs: Mapping[Trained, TrainConfig] | None = None,
            calibrated: observe.Observation | None = None) -> Motion:
    """The chapter *What the motion allows* on ``runner``'s data (air on) and the same throws without air: every
    network run at once (so every core stays busy), then every entry of the table and the result.

    ``cfgs``: each network row's configuration (default :func:`configs`); ``calibrated``: the calibrated tracker's
    observation (default ``calibration.observation(runner)``, the error model fitted on rendered throws)."""
    cfgs = configs(runner) if cfgs is None else cfgs
    fitted_on = calibration.tracker_fit(runner).fitted_on if calibrated is None else ""
    calibrated = calibration.observation(runner) if calibrated is None else calibrated
    cols = columns(calibrated)
    on = {True: runner, False: runner.air_off()}
    seeds = runner.preset.grid_seeds
    rates = {cell: runner.preset.grid_lrs(cell) for cell in {cfg.cell for cfg in cfgs.values()}}
    runner.prefetch(plan(on, cfgs, cols, seeds, rates), desc="every network")
    contact = runner.synth_config.shape.bounding_radius
    entries = {(e.learner, c.key): e for c in cols
               for e in column_entries(on[c.air], cfgs, c, seeds, contact, rates)}
    picked = {key: e.lr for key, e in entries.items() if e.lr is not None}
    for air, runs in turned_down(cfgs, cols, seeds, rates, picked).items():  # type: ignore[arg-type]
        on[air].reject(runs)
    return report(runner.synth_config, cfgs, cols, entries, calibrated.drop, fitted_on)
