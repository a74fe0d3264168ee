"""What the motion chapter reports, typed: the names its numbers are glued and stored under (``motion.…``), read back
by the summary without running the chapter (``study.chapters.motion`` computes them)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal, get_args

from study.report import learners
from study.report.reported import Number, Reported, named

Air = Literal["air_on", "air_off"]
"""The two data sets: the study's throws (air drag and added mass on), and the same throws without air."""
View = Literal["exact", "near", "calibrated", "far"]
"""How each air setting's positions are seen, in the table's order."""
Observed = Literal["near", "calibrated", "far"]
"""The views through a camera."""
Network = Literal[learners.keys("motion", "network")]  # type: ignore[valid-type]
"""The networks trained on each column's condition, each at its own configuration."""


Trained = Literal[learners.keys("motion", "network", "exact-trained network")]  # type: ignore[valid-type]
"""Every network row: the three networks, and Table 1's network trained exact and tested observed."""


Learner = Literal[learners.keys("motion")]  # type: ignore[valid-type]
"""Every row of the table, the ceiling aside."""


@dataclass(frozen=True)
class Ceiling(Reported):
    """The exact ceiling of the priors."""

    air_off: Number
    """Without air: the Bayes rule told each throw's restitution and friction."""
    air_off_restitution: Number
    """Without air, told the restitution alone."""
    air_on: Number
    """With air: told the mass too."""


@dataclass(frozen=True)
class Best(Reported):
    """The best learner of one column: how far below the ceiling, and by how much ahead of the next."""

    gap_to_ceiling: Number
    """The ceiling minus the best learner's mean accuracy."""
    lead: Number
    """The best learner minus the next, paired; its source names ``best``, ``next`` and whether ``tied``."""

    @property
    def learner(self) -> Learner:
        return self.lead.source["best"]

    @property
    def runner_up(self) -> Learner:
        return self.lead.source["next"]

    @property
    def tied(self) -> bool:
        return bool(self.lead.source["tied"])


@dataclass(frozen=True)
class Numbers(Reported):
    """Every number the chapter *What the motion allows* reports."""

    CHAPTER = "motion"
    ceiling: Ceiling
    noise: dict[Observed, Number]
    """Each observed view's camera error, metres."""
    learners: dict[Learner, dict[Air, dict[View, Number]]] = named("")
    """Each learner's test accuracy in each column (``motion.peephole_positions.air_on.exact``)."""
    failed_runs: Number
    """Network runs of the chapter that failed to train (each run once)."""
    best: dict[Air, dict[View, Best]]
    """Each column's best learner."""


LEARNERS: tuple[Learner, ...] = get_args(Learner)
SHOWN: tuple[Learner, ...] = tuple(n for n in LEARNERS if n != "peephole_exact_trained")
"""The learners the chapter's figure draws (the exact-trained row is the paper's network under another name)."""
