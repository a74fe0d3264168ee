"""What the real-world chapter reports, typed: the names its numbers are glued and stored under (``realworld.…``), read back
by the summary without running the chapter (``study.chapters.realworld`` computes them)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from study.learn.config import Inputs
from study.see.paths import PathKey  # the paths are defined once, there
from study.simulate.observe import CAMERA_FAMILIES
from study.report.reported import Number, Reported, Verdict, named

Class = Literal["light", "heavy"]
"""The study's classes (``study.CLASSES``)."""


Training = Literal["exact", "randomised", "any-camera"]
"""How a candidate was trained: on exact positions, on random observations, or on heights as a user's own camera
gives them."""


ModelKey = Literal["table1", "recommended"]
"""The models the chapter classifies the videos with: Table 1's Z model, and the recommended one where it differs."""


@dataclass(frozen=True)
class Candidate(Reported):
    """One candidate model for a camera."""

    val: Number
    """Accuracy on the validation throws (mean over seeds), observed as the calibrated tracker observes them."""
    val_user: Number
    """The same as a user's own camera, anywhere, gives them (``study.simulate.observe.any_camera``): what chooses."""


@dataclass(frozen=True)
class Classified(Reported):
    """One model's labels of the videos, per true class, each with its Wilson interval and beside the paper's."""

    rendered: dict[Class, Number]
    """The rendered videos (a class with no video tracked is left out)."""
    real: dict[Class, Number]
    """The real clips (only the classes they hold)."""


Group = Literal[("all", *(f.key for f in CAMERA_FAMILIES))]  # type: ignore[valid-type]
"""The camera sweep's clips pooled, or one camera family (``study.simulate.observe.CAMERA_FAMILIES``)."""


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


@dataclass(frozen=True)
class SweepGroup(Reported):
    """A group of the camera sweep's clips."""

    clips: Number
    """Clips in the group."""
    floor_mm: Number
    """The least height error any one-scale path can reach on them, millimetres RMS (true image rows)."""
    paths: dict[PathKey, SweepPath] = named("")
    """Each path, by name."""


@dataclass(frozen=True)
class Sweep(Reported):
    """What a camera nobody measured leaves of the heights and of the answer (the camera sweep)."""

    groups: dict[Group, SweepGroup] = named("")
    """All clips and each camera family."""
    drag: dict[PathKey, Number] = named("drag")
    """The drag rule's accuracy on the clips, by path."""
    size_error: Number | None = None
    """Median relative error of one frame's blob diameter against the object's true apparent size."""
    render_cpu_s: Number | None = None
    """CPU seconds the clips took to render, as recorded when they were made (None: not recorded)."""


@dataclass(frozen=True)
class Numbers(Reported):
    """Every number and verdict the chapter *Real-world test* reports."""

    CHAPTER = "realworld"
    candidate: dict[Inputs, dict[Training, Candidate]]
    """Each candidate, by what it reads and how it was trained."""
    figure1: Verdict
    """The paper's Figure 1: frames of a light and a heavy object."""
    figure5: Verdict
    """The paper's Figure 5: tracked heights of the real videos."""
    figure6: Verdict
    """The paper's Figure 6: frames of the real videos, tracked."""
    models: dict[ModelKey, Classified] = named("")
    """Each model's labels: ``realworld.table1.rendered.light`` and so on."""
    user: dict[ModelKey, dict[Class, Number]] = named("user", default_factory=dict)
    """Each model's labels of the rendered videos on a user's path (no camera: ``study classify VIDEO`` with the
    object's colour, shape and size): ``realworld.user.table1.light`` and so on."""
    exact: dict[ModelKey, dict[Class, Number]] = named("exact", default_factory=dict)
    """Each model's labels of the rendered videos from their exact heights (the renderer's truth: no tracker, no
    camera): ``realworld.exact.table1.light`` and so on."""
    sweep: Sweep | None = None
    """The camera sweep (None: not run)."""
