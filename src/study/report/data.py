"""What the data chapter reports, typed: the names its numbers are glued and stored under (``data.…``), read back
by the summary without running the chapter (``study.chapters.data`` computes them)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from study.report.reported import Number, Reported, Verdict, named

RuleName = Literal["bounces", "time_to_rest", "distance", "max_height_after_1s"]


@dataclass(frozen=True)
class Figure3(Reported):
    """The paper's reading of its Figure 3, as statistics of the test throws."""

    bounces: Number
    """Light minus heavy, mean number of bounces (bootstrap over the throws), ordered against the paper's claim."""
    time_to_rest: Number
    """Light minus heavy, mean time to rest, seconds."""
    verdict: Verdict = named("")
    """Both claims together (``data.figure3``)."""


@dataclass(frozen=True)
class Numbers(Reported):
    """Every number the chapter *The data* reports."""

    CHAPTER = "data"
    figure2: Verdict
    """The paper's Figure 2, a figure without a number."""
    figure3: Figure3
    rule: dict[RuleName, Number]
    """Test accuracy of the best threshold on each summary (bootstrap over the test throws)."""
