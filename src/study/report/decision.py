"""What the decision chapter reports, typed: the names its numbers are glued and stored under (``decision.…``), read back
by the summary without running the chapter (``study.chapters.decision`` computes them)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from study.learn.config import Inputs
from study.report.reported import Number, Reported, named

NetworkKey = Literal["exact", "observed"]
"""The networks that answer at every frame: the paper's on exact positions, the camera's through the tracker."""


ConditionKey = Literal["exact", "observed", "randomised", "camera"]
"""The Z classifiers whose operating points the chapter sets: Table 1's on exact and on observed positions, the
same trained on random observations, and the camera's network at its last frame."""


@dataclass(frozen=True)
class Choice(Reported):
    """The camera's network, chosen between positions and velocity."""

    val: dict[Inputs, Number]
    """Each one's observed validation accuracy, mean over the grid seeds."""


@dataclass(frozen=True)
class SeedClearing(Reported):
    """One seed's clearing on the test split."""

    share: Number
    """Light test objects cleared within the input."""
    miss: Number
    """Heavy test objects ever cleared."""


@dataclass(frozen=True)
class ClearNumbers(Reported):
    """How soon one network answering at every frame clears the light objects (certifiable, or a count of 0)."""

    certifiable: Number | None = None
    """0 (a count) when no per-frame thresholds can be certified; absent when they can."""
    share_by_end: Number | None = None
    """Light test objects cleared within the input, pooled over the seeds."""
    per_seed: dict[str, SeedClearing] = named("seed{key}", default_factory=dict)
    """Each seed's (keys: the seeds)."""
    median_s: Number | None = None
    """Median time to clear the light objects cleared, seconds."""
    ensemble: SeedClearing | None = None
    """The seeds as one classifier (the mean of their probabilities, certified once): what holds whatever the seed."""

    @property
    def headline(self) -> Number | None:
        """The share of light objects cleared that the chapter's answer quotes: the ensemble's, which does not hang
        on a seed, where it could be certified; else the seeds' pooled share."""
        return self.ensemble.share if self.ensemble is not None else self.share_by_end


@dataclass(frozen=True)
class ConditionNumbers(Reported):
    """One Z classifier's operating points and the trust its probabilities deserve."""

    auc: Number
    """Area under the ROC curve, mean over seeds."""
    ece: Number
    """Expected calibration error, mean over seeds."""
    ece_scaled: Number
    """The same after temperature scaling."""
    miss: Number | None
    """Heavy called light at the certified point, seed 0 (absent when not certifiable)."""
    false_alarm: Number | None
    """Light called heavy there, seed 0."""
    miss_empirical: Number
    """Heavy called light at the certification split's empirical quantile, seed 0."""


@dataclass(frozen=True)
class CertifiedNumbers(Reported):
    """Whether the certificates carried to the test split."""

    points: Number
    """Certified operating points, every classifier and seed."""
    above_target: Number
    """Of them, those whose test miss rate's interval lies wholly above the target."""
    point_above: Number
    """Of them, those whose test miss rate's point estimate lies above the target."""


@dataclass(frozen=True)
class Numbers(Reported):
    """Every number the chapter *From accuracy to a decision* reports."""

    CHAPTER = "decision"
    choice: Choice
    clear: dict[NetworkKey, ClearNumbers]
    conditions: dict[ConditionKey, ConditionNumbers] = named("")
    certified: CertifiedNumbers = named("certified")
