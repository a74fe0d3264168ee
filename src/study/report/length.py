"""What the length chapter reports, typed: the names its numbers are glued and stored under (``length.…``), read back
by the summary without running the chapter (``study.chapters.length`` computes them)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from study.learn.config import Dims
from study.report.reported import Number, Reported, Verdict, named

LengthKey = Literal["0.5s", "1s", "1.5s", "2s", "3s", "6s"]
"""The results file's name of each input length of the book's presets (:func:`length_key`)."""


Truncation = Literal["truncated", "whole"]
"""A cell's back-propagation: Table 1's truncation, or the whole input."""


Forget = Literal["constant", "chrono"]
"""A cell's forget-gate start: Table 1's constant bias, or chrono initialisation."""


@dataclass(frozen=True)
class Window(Reported):
    """The one-feature rules on the first T seconds, the window the network sees."""

    other_rule: Number
    """The best rule on another feature than the first fall's acceleration (by test accuracy, as the cue chapter
    chooses it)."""
    drag_rule: Number
    """The drag rule (the first fall's acceleration)."""


@dataclass(frozen=True)
class Factorial(Reported):
    """The 2 x 2 at the longest input for one input: each cell, both main effects, and the test of fading."""

    cells: dict[Truncation, dict[Forget, Number]] = named("")
    """Each cell's test accuracy (source: its runs and how many failed to train)."""
    effect_truncation: Number = named("effect_truncation")
    """The whole input minus truncated, averaged over the forget starts (paired)."""
    effect_chrono: Number = named("effect_chrono")
    """Chrono minus constant, averaged over the truncations (paired)."""
    vanishing: Number = named("vanishing")
    """With full back-propagation, chrono minus constant: the gradient reaches the start; does it fade? With the
    verdict on the paper's explanation (vanishing gradients: the memory still helps)."""


@dataclass(frozen=True)
class Numbers(Reported):
    """Every number the chapter *Accuracy against input length* reports."""

    CHAPTER = "length"
    failed_runs: Number
    """Length-sweep runs that failed to train."""
    sweep: dict[Dims, dict[LengthKey, Number]] = named("")
    """Mean test accuracy at each length (``length.z.1s``)."""
    long_memory: dict[Dims, dict[LengthKey, Number]] = named("long_memory")
    """The same with a memory that spans the input, at the long lengths."""
    drop: dict[Dims, Number] = named("drop")
    """The longest input minus the best length, with the verdict on the paper's claim that it falls."""
    drop_at_long_inputs: Verdict = named("drop_at_long_inputs")
    """Both inputs' drops: the paper's Figure 4."""
    window: dict[LengthKey, Window] = named("window")
    """The rules on the shortest window."""
    factorial: dict[Dims, Factorial] = named("factorial")
    """The paper's explanation, one factor at a time."""
    paper_explanation: Verdict = named("paper_explanation")
    """Both inputs' tests of fading."""
