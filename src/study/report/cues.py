"""What the cue chapter reports, typed: the names its numbers are glued and stored under (``cues.…``), read back
by the summary without running the chapter (``study.chapters.cues`` computes them)."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Literal

from study.learn.config import Dims
from study.report.reported import Leaf, Number, Reported, Verdict, named

Condition = Literal["a", "b", "c", "d"]


RuleCondition = Literal["a", "b", "c"]
"""The conditions the one-feature rules are fitted in ((d) differs from (c) only in the network's training)."""


Group = Literal["exact", "random"]
"""The two groups of Z models: trained on exact positions (Table 1's), or on random observations."""


GROUPS: dict[Group, str] = {"exact": "trained on exact positions", "random": "trained on random observations"}
"""Each group of Z models in words."""


@dataclass(frozen=True)
class TrackerFitNumbers(Reported):
    """The tracker's fitted error model as a chapter reports it (:meth:`TrackerFit.numbers`), metres."""

    offset: Number
    """Standard deviation of the per-throw offset (about 0: the offsets' common part is in it)."""
    rho: Number
    """Lag-1 autocorrelation of the varying error."""
    flight: Number
    """Standard deviation of the varying error in flight."""
    contact: Number
    """The same in contact."""
    step_sd: Number
    """The tracker's frame-to-frame error, measured (the fit reproduces it)."""
    white_step_sd: Number
    """What white noise at the tracker's pooled position error would make of it."""
    drop: Number
    """Share of the frames in view the tracker lost."""
    videos: Number
    """Rendered videos fitted on."""


@dataclass(frozen=True)
class DragRuleNumbers(Reported):
    """One threshold on the first fall's acceleration, chosen on the training split."""

    exact: Number
    """Test accuracy on exact positions."""
    noise: dict[str, Number] = named("noise_{key}mm")
    """Test accuracy with each tracker noise (the key: millimetres, as the chapter writes them)."""


@dataclass(frozen=True)
class DecomposedNumbers(Reported):
    """One tracker's height error on the book's rendered throws, taken apart
    (:class:`~study.methods.tracker.Decomposition`)."""

    bias: Number
    offset: Number
    noise: Number
    rho: Number
    flight: Number
    contact: Number
    velocity: Number
    height_rms: Number
    height_rms_median: Number
    scale_rms_median: Number
    lost: Number


@dataclass(frozen=True)
class TrackerNumbers(Reported):
    """The tracker's error on rendered video (:class:`~study.methods.tracker.TrackerError`)."""

    noise_m: Number
    """Its vertical error, metres."""
    drop: Number
    """The share of frames it lost."""
    decomposed: dict[Literal["before", "after"], DecomposedNumbers] = named("", default_factory=dict)
    """The tracked height's error taken apart, for the tracker with the old bounds (before) and now (after)."""


@dataclass(frozen=True)
class CeilingNumbers(Reported):
    """What the priors allow a classifier told each throw's true parameters."""

    restitution_friction: Number
    """The fitted estimate: logistic regression on the true restitution and friction, on the test split."""
    with_mass: Number
    """The same, told the mass too."""
    exact: Number
    """The exact ceiling of the priors on restitution and friction (``study.methods.ceiling``)."""


@dataclass(frozen=True)
class Curve(Reported):
    """One sweep of the observation model: each group's accuracy at each of its values.

    A value's key is the value as ``:g`` writes it (``"0.1"``), so it may hold a dot: :meth:`read` finds the keys
    by the groups that end each name."""

    points: dict[str, dict[Group, Number]] = named("")

    @classmethod
    def read(cls, stored: Mapping[str, Leaf], prefix: str | None = None) -> Curve:
        base = f"{prefix}."
        values: list[str] = []
        for name in stored:
            for g in GROUPS:
                if name.startswith(base) and name.endswith(f".{g}") and len(name) > len(base) + len(g) + 1:
                    v = name[len(base):-len(g) - 1]
                    values += [v] if v not in values else []
        return cls({v: {g: stored[f"{base}{v}.{g}"] for g in GROUPS if f"{base}{v}.{g}" in stored} for v in values})


@dataclass(frozen=True)
class ErrorNumbers(Reported):
    """Where the errors fall (Z only)."""

    overlap_z: Number
    """Accuracy on throws whose restitution lies where the two priors overlap."""
    outside_z: Number
    """Accuracy on the other throws."""


@dataclass(frozen=True)
class ShapeNumbers(Reported):
    """One test shape."""

    cube_model: Number
    """Table 1's Z models (trained on the 20 cm cube)."""
    mixed_model: Number
    """The Z models trained on mixed shapes."""


@dataclass(frozen=True)
class Numbers(Reported):
    """Every number the chapter *What the network sees* reports."""

    CHAPTER = "cues"
    drag_rule: DragRuleNumbers
    tracker: TrackerNumbers
    conditions: dict[Condition, dict[Dims, Number]] = named("condition_{key}")
    """The peephole LSTM in each condition."""
    best_rule: dict[RuleCondition, Number] = named("best_rule_{key}")
    """The best one-feature rule (chosen on training accuracy) in each condition."""
    drag_rules: dict[RuleCondition, Number] = named("drag_rule_{key}")
    """The drag rule in each condition."""
    ceiling: CeilingNumbers = named("ceiling")
    network_minus_rule_b: dict[Dims, Number] = named("network_minus_rule_b")
    """Without air: the network (mean of seeds) minus the best rule, with the verdict that it is above."""
    claim_without_drag: Verdict = named("claim_without_drag")
    """Both inputs' verdicts made one: without drag, the network beats every one-feature rule."""
    robustness: dict[str, Curve] = named("robustness")
    """Each sweep of the observation model."""
    errors: ErrorNumbers = named("errors")
    shape: dict[str, ShapeNumbers] = named("shape")
    """Each test shape, by :func:`shape_key`."""
    tracker_model: TrackerFitNumbers | None = None
    """The tracker's error model fitted on development renders (``calibration.tracker_fit``): the calibrated observation."""
