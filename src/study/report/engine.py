"""What the engine chapter reports, typed: the names its numbers are glued and stored under (``engine.…``), read back
by the summary without running the chapter (``study.chapters.engine`` computes them)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from study.learn.config import Dims
from study.report import learners
from study.report.reported import Number, Reported
from study.simulate.synth import Engine

Learner = Literal[learners.keys("engine")]  # type: ignore[valid-type]
"""The learners of the cross-engine table (``study.report.learners``)."""


View = Literal["exact", "calibrated"]
"""How the positions are seen (``camera.Column.name``)."""


Pair = Literal["mujoco_to_mujoco", "mujoco_to_bullet", "bullet_to_mujoco", "bullet_to_bullet"]
"""A training engine and a test engine."""


Feature = Literal["bounces", "time_to_rest", "first_rebound", "distance"]
"""What :func:`agreement` compares, throw by throw."""


ClassName = Literal["light", "heavy"]
"""``study.CLASSES``."""


@dataclass(frozen=True)
class Table1Row(Reported):
    """One row of Table 1 in one engine."""

    paper_way: Number
    """The run validation picks (one data set: the bootstrap of that run); in Bullet, against the paper's."""
    mean: Number
    """The mean over the seeds."""


@dataclass(frozen=True)
class MassOnly(Reported):
    """The mass-only test in one engine."""

    accuracy: Number
    """The chapter's best learner trained and tested on two classes whose only difference is the mass."""
    above_chance: Number
    """That accuracy minus one half, in points."""


@dataclass(frozen=True)
class PairedNumbers(Reported):
    """The paired check in one engine: the same throws as a light and as a heavy object."""

    max_distance: Number
    """Median over the throws of each throw's largest distance over the record, m."""
    largest: Number
    """The largest of those, m."""
    first_second: Number
    """Median over the throws of the largest distance in the first second, m."""
    parted: Number
    """Throws whose two trajectories part by more than a micrometre within the record."""
    parting_time: Number | None
    """Median over those throws of the time they part, s (absent when none does)."""


@dataclass(frozen=True)
class Numbers(Reported):
    """Every number the chapter *Another engine* reports."""

    CHAPTER = "engine"
    agreement: dict[Feature, dict[ClassName, Number]]
    """Median of Bullet minus MuJoCo per throw, by class."""
    cross: dict[Learner, dict[View, dict[Pair, Number]]]
    """Each learner trained in one engine and tested in another (``mujoco_to_bullet``)."""
    ceiling: Number
    """The exact ceiling of the priors (both engines: the same draws)."""
    transfer: dict[Learner, dict[View, dict[Engine, Number]]]
    """Trained in an engine: the other engine's accuracy minus its own."""
    table1: dict[Dims, Table1Row]
    """Table 1 in Bullet, the paper's engine."""
    table1_mujoco_air_off: dict[Dims, Table1Row]
    """Table 1 in MuJoCo on the same throws without air."""
    mass_only: dict[Engine, MassOnly]
    """Each engine's mass-only test (``engine.mass_only.bullet.accuracy``)."""
    mass_only_ceiling: Number
    """The exact ceiling of the mass-only priors (one half: the same restitution and friction)."""
    paired: dict[Engine, PairedNumbers]
    """Each engine's paired check (``engine.paired.bullet.max_distance``)."""
