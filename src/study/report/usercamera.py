"""What the chapter *A camera nobody measured* reports, typed: the names its numbers are glued and stored under
(``usercamera.…``), read back by the summary without running the chapter (``study.chapters.usercamera`` computes
them)."""

from __future__ import annotations

from dataclasses import dataclass
from collections.abc import Mapping
from typing import Literal

from study.learn.metrics import Interval
from study.report.reported import Leaf, Number, Reported, named
from study.see.paths import PathKey  # the paths are defined once, there
from study.simulate.observe import CAMERA_FAMILIES

SweepKey = PathKey
"""How the sweep's heights were had (``study.see.paths.PathKey``)."""

Family = Literal[("all", *(f.key for f in CAMERA_FAMILIES))]  # type: ignore[valid-type]
"""The camera sweep's clips pooled, or one camera family (``study.simulate.observe.CAMERA_FAMILIES``)."""


RENDERS = {"sweep": "usercamera.sweep.render_cpu_s", "floor development clips": "usercamera.sweep.floor_render_cpu_s"}
"""What the chapter rendered -> the results' name for the CPU seconds it took."""


def render_cpu(leaves: Mapping[str, Leaf]) -> dict[str, float]:
    """CPU seconds each of :data:`RENDERS` took, from a results file's ``leaves``, by what was rendered (those it
    has; empty if none): what the build's ``timings.json`` and ``scripts/build_time.py`` report."""
    return {what: float(leaves[name].value) for what, name in RENDERS.items() if name in leaves}


@dataclass(frozen=True)
class SweepPath(Reported):
    """One path on a group of the camera sweep's clips, read by the recommended model."""

    accuracy: Number
    """Accuracy over the clips and the model's seeds (a clip without heights counts as a miss)."""
    heights_mm: Number | None = None
    """Root-mean-square height error after removing each clip's median error, millimetres (0: exact; None: the
    path turned no clip into heights)."""
    cost: Number | None = None
    """The exact heights' accuracy minus this path's, paired over clips and seeds, points (None: exact)."""
    heights_raw_mm: Number | None = None
    """Root-mean-square height error as it is, no median removed, millimetres (None: no clip turned into heights)."""
    no_heights: Number | None = None
    """Clips the path turned into no heights (each a miss in :attr:`accuracy`; None: exact)."""


@dataclass(frozen=True)
class SweepGroup(Reported):
    """A group of the camera sweep's clips."""

    clips: Number
    """Clips in the group."""
    floor_mm: Number
    """The least height error any one-scale path can reach on them, millimetres RMS (true image rows)."""
    paths: dict[SweepKey, SweepPath] = named("")
    """Each path, by name."""


@dataclass(frozen=True)
class FloorModel(Reported):
    """The model recommended for the floor path (``--floor``), on the whole sweep: the floor camera issue's bars."""

    floor: Number
    """Its accuracy through the floor path, over the clips and its seeds (a clip without heights is a miss)."""
    exact: Number
    """Its accuracy on the same clips' exact heights."""
    known: Number | None = None
    """Its accuracy through the known camera at each frame's true depth (the path's limit; None: not measured)."""
    known_minus_floor: Number | None = None
    """The known camera's accuracy minus the floor path's, paired over clips and seeds, points."""


@dataclass(frozen=True)
class Sweep(Reported):
    """What a camera nobody measured leaves of the heights and of the answer (the camera sweep)."""

    groups: dict[str, SweepGroup] = named("")
    """All clips (``all``), each camera family (:data:`Family`) and each frame height (``480p``, ``720p``: the sweep's
    ``SIZES``, ``study.methods.camera_cost.groups_of``)."""
    drag: dict[SweepKey, Number] = named("drag")
    """The drag rule's accuracy on the clips, by path."""
    size_error: Number | None = None
    """Median relative error of one frame's blob diameter against the object's true apparent size."""
    render_cpu_s: Number | None = None
    """CPU seconds the clips took to render, as recorded when they were made (None: not recorded)."""
    floor_model: FloorModel | None = None
    """The model recommended for the floor path (None: the build trained none)."""
    kinds: dict[str, dict[SweepKey, Number]] = named("kind", default_factory=dict)
    """Every candidate, by its kind (``study.runs.measured.kind``): its accuracy on exact heights and by each path,
    over the clips that path turned into heights (what an answer quotes for a model of that kind: an answer exists
    only where its path gave heights; each number's source says how many clips gave none)."""
    floor_render_cpu_s: Number | None = None
    """CPU seconds the floor path's development clips took to render, as recorded when they were made (None: not
    recorded)."""


@dataclass(frozen=True)
class Numbers(Reported):
    """Every number the chapter *A camera nobody measured* reports."""

    CHAPTER = "usercamera"
    sweep: Sweep
    """The camera sweep."""


def measured(leaves: Mapping[str, Leaf]) -> dict[str, dict[str, Interval]]:
    """What the camera sweep measured for each kind of model through each path (``usercamera.sweep.kind.*`` of a
    results file's ``leaves``), as intervals: what the recommended model's file and the package's shipped copy keep
    (``study.runs.measured.Measured``). Empty when the sweep is not among the leaves."""
    if not any(k.startswith("usercamera.sweep.kind.") for k in leaves):
        return {}
    kinds = Sweep.read(leaves, "usercamera.sweep").kinds
    return {k: {p: Interval(n.value, n.lo, n.hi, n.method) for p, n in by.items()} for k, by in kinds.items()}
