"""What the baselines chapter reports, typed: the names its numbers are glued and stored under (``baselines.…``), read back
by the summary without running the chapter (``study.chapters.baselines`` computes them)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from study.learn.config import Dims
from study.report import learners
from study.report.reported import Number, Reported, Verdict, named

Method = Literal[learners.keys("baselines")]  # type: ignore[valid-type]
"""The methods compared, by their name in the results file (``study.report.learners``)."""


Condition = Literal["exact", "observed"]
"""Exact positions, or positions as the calibrated tracker observes them (Z only)."""


@dataclass(frozen=True)
class Timing(Reported):
    """One method's cost on Z, one thread."""

    fit_s: Number
    """One training, seconds."""
    infer_us: Number
    """Inference per test trajectory, microseconds."""


@dataclass(frozen=True)
class Numbers(Reported):
    """Every number the chapter *What a practitioner would try first* reports."""

    CHAPTER = "baselines"
    accuracy: dict[Method, dict[Dims, dict[Condition, Number]]] = named("")
    """Each method's test accuracy (``baselines.minirocket.z.exact``)."""
    time: dict[Method, Timing] = named("time")
    """Each method's cost."""
    peephole_minus_rule: dict[Dims, dict[Condition, Number]] = named("peephole_minus_rule")
    """The paper's network minus the best one-feature rule, with the verdict on its claim that it does better."""
    more_involved_required: Verdict = named("more_involved_required")
    """That claim over every cell."""
