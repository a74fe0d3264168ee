"""How far an answer on a video can be trusted: the accuracy the study measured for the answering model's kind
through the path its heights came by (the camera sweep: clips from cameras nobody measured), and the band of
p(heavy) where the study cannot tell the classes apart.

The numbers come from the recommended model's file in the data folder (``study.runs.recommended``: what the book
build there measured), else from the copy of a paper build's that ships with the package
(``study.runs.measured.SHIPPED``). :func:`for_answer` puts them together for one answer; :meth:`Trust.label`
turns p(heavy) into ``"light"``, ``"heavy"`` or :data:`CANNOT_TELL`.
"""

from __future__ import annotations

from dataclasses import dataclass

from study import CLASSES
from study.core import presets
from study.learn.metrics import Interval
from study.report.text import pct_ci
from study.runs import recommended
from study.runs.measured import Measured, read_shipped
from study.runs.stats import label_of
from study.see import paths

CANNOT_TELL = "cannot tell"
"""The answer where p(heavy) falls inside the model's cannot-tell band: neither right nor wrong in a tally."""
FLOOR = next(p.key for p in paths.PATHS if p.floor and not p.found)
"""The path of heights placed through the camera that floor marks give (``--floor``, experimental), the marks' pixels
given."""
MEASURED_SCALE = "measured scale"
"""The path of a scale the user measured (``--metres-per-pixel``): the sweep has no such path."""


@dataclass(frozen=True)
class Trust:
    """How far one answer can be trusted."""

    accuracy: Interval | None
    """The share of the camera sweep's throws that models of this kind labelled right through this path, of those
    the path turned into heights (an answer exists only there), with its 95 % interval (None: not measured;
    :attr:`source` says why)."""
    source: str
    """Where :attr:`accuracy` comes from, or why there is none."""
    band: tuple[float, float] | None = None
    """p(heavy) from ``band[0]`` to ``band[1]``, ends included: the study cannot tell the classes apart there
    (None: no band, the likelier class is the answer)."""

    def label(self, p_heavy: float) -> str:
        """``"light"``, ``"heavy"`` (the likelier class), or :data:`CANNOT_TELL` inside :attr:`band`."""
        if self.band is not None and self.band[0] <= p_heavy <= self.band[1]:
            return CANNOT_TELL
        return CLASSES[label_of(p_heavy)]

    def __str__(self) -> str:
        acc = "not measured" if self.accuracy is None else f"{pct_ci(self.accuracy)} right"
        band = ("" if self.band is None else
                f"; cannot tell for p(heavy) {p_text(self.band[0])}-{p_text(self.band[1])}")
        return f"{acc} ({self.source}){band}"


def p_text(p: float) -> str:
    """A probability as every answer prints it (the band's edges and p(heavy) alike, so one inside the band reads
    inside it)."""
    return f"{p:.3f}"


def _words(path: str) -> str | None:
    """What the book calls the path ``path`` (a key of ``study.see.paths.PATHS``); None for a path the sweep does not
    have (:data:`MEASURED_SCALE`)."""
    return next((p.words for p in paths.PATHS if p.key == path), None)


def path_of(floor: bool, scale_from: str, metres_per_pixel: float | None, found: bool = False) -> str:
    """The path an answer's heights came by: :data:`FLOOR` (``study.see.paths.FOUND`` where the marks were
    ``found`` in the video by their colour), :data:`MEASURED_SCALE` or a one-scale path's key."""
    if floor:
        return paths.FOUND if found else FLOOR
    return MEASURED_SCALE if metres_per_pixel is not None else scale_from


@dataclass(frozen=True)
class Measurements:
    """What the camera sweep measured, and where that comes from (read once for every answer a model gives)."""

    measured: Measured
    """Kind -> path -> accuracy on the sweep; empty when no build's sweep is at hand."""
    source: str = ""
    """Which sweep: the data folder's build, or the shipped copy's ('' for none)."""


def measurements(rec: recommended.Recommended | None, answering: bool = False) -> Measurements:
    """What the sweep measured and where it comes from: the data folder's build (``rec``) if it measured it and
    either answers itself (``answering``: its recommended model is the one answering, so its own numbers weigh it) or
    is a paper build, else the shipped copy; empty when neither has it. A smaller build's numbers (the smoke
    preset's models train for a few epochs) never weigh a model it did not make."""
    if rec is not None and rec.measured and (answering or rec.preset == presets.DEFAULT):
        return Measurements(rec.measured, f"the camera sweep of the {rec.preset} build beside the recommended model")
    shipped = read_shipped()
    if shipped is not None:
        return Measurements(shipped.measured, f"the camera sweep of {shipped.source()}")
    return Measurements({})


def for_answer(kind: str, path: str, seen: Measurements, band: tuple[float, float] | None = None) -> Trust:
    """The trust of an answer by a model of ``kind`` (``study.runs.measured.kind``) whose heights came by
    ``path`` (:func:`path_of`); ``seen``: what the sweep measured (:func:`measurements`); ``band``: the answering
    model's cannot-tell band on this path (the recommended model's; None for any other)."""
    measured, source = seen.measured, seen.source
    if path == MEASURED_SCALE:
        return Trust(None, "a scale you measured: the camera sweep measured one scale read off the object", band)
    words = _words(path) or path
    if not measured:
        return Trust(None, f"no build's camera sweep is at hand for the {words} path: build the book to measure it",
                     band)
    if kind not in measured:
        return Trust(None, f"{source} scored no model of this kind ({kind}; it scored {', '.join(measured)})", band)
    got = measured[kind].get(path)
    said = ", on the throws it gave heights for" if got is not None else " (not measured there)"
    return Trust(got, f"{source}: models of this kind ({kind}) through the {words} path{said}", band)


def exact_warning(kind: str, which: str, seen: Measurements, path: str = paths.DEFAULT,
                  recommended: bool = False) -> str | None:
    """For a model trained on exact trajectories given a video: a warning saying what the sweep measured for such
    models through the answer's ``path`` (:func:`path_of`; ``seen``: :func:`measurements`), and what to use instead
    (a build can recommend one: ``recommended``); None for any other kind."""
    if not kind.endswith("-exact"):
        return None
    if _words(path) is None:  # a scale the user measured: the sweep read one off the object
        path = paths.DEFAULT
    got = seen.measured.get(kind, {}).get(path)
    words = _words(path)
    said = ("" if got is None else
            f"; on {seen.source}, such models labelled {pct_ci(got)} of the throws right through the {words} path")
    instead = ("train one with --observe any-camera (in Python TrainConfig(observe='any-camera'))" if recommended else
               "use the recommended model (no --model; in Python model=None) or train with --observe any-camera "
               "(TrainConfig(observe='any-camera'))")
    return f"{which} was trained on exact trajectories, not on heights a camera gives{said}. For video, {instead}"
