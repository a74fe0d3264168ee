"""What the real-world chapter reports, typed: the names its numbers are glued and stored under (``realworld.…``), read back
by the summary without running the chapter (``study.chapters.realworld`` computes them)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from study.learn.config import Inputs
from study.report.reported import Number, Reported, Verdict, named

Class = Literal["light", "heavy"]
"""The study's classes (``study.CLASSES``)."""


Training = Literal["exact", "randomised", "any-camera", "floor", "floor-fixed"]
"""How a candidate was trained: on exact positions, on random observations, on heights as a user's own camera
gives them, on random observations for the floor path's error, or on that error itself
(``study.methods.recommend.candidates``)."""


ModelKey = Literal["table1", "recommended", "floor"]
"""The models the chapter classifies the videos with: Table 1's Z model, the recommended one where it differs, and
the one recommended for the floor path where the build trained one."""


@dataclass(frozen=True)
class Candidate(Reported):
    """One candidate model for a camera."""

    val: Number
    """Accuracy on the validation throws (mean over seeds), observed as the calibrated tracker observes them."""
    val_user: Number
    """The same as a user's own camera, anywhere, gives them (``study.simulate.observe.any_camera``): what chooses."""
    val_floor: Number | None = None
    """The same as the floor path gives them (its fitted error): what chooses the floor path's model (None: the
    floor path had no error model)."""


@dataclass(frozen=True)
class Classified(Reported):
    """One model's labels of the videos, per true class, each with its Wilson interval and beside the paper's."""

    rendered: dict[Class, Number]
    """The rendered videos (a class with no video tracked is left out)."""
    real: dict[Class, Number]
    """The real clips (only the classes they hold)."""


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
    floor: dict[ModelKey, dict[Class, Number]] = named("floor", default_factory=dict)
    """Each model's labels of the rendered videos through floor marks clicked a pixel off (``study classify
    --floor``): ``realworld.floor.floor.light`` and so on."""
    floor_minus_known: dict[ModelKey, dict[Class, Number]] = named("floor_minus_known", default_factory=dict)
    """Each model's rendered videos right through floor marks minus right through the renderer's camera, per class,
    a count (the floor camera issue asks for at most 2 either way): ``realworld.floor_minus_known.floor.light``."""
