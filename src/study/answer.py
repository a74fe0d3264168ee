"""Light or heavy for one video or track of a user's own: ``study classify`` as one Python call.

The video is tracked (``study.see.track``), its pixels turned into heights by one scale read off the object
(``study.see.scale``: its mean apparent size by default), cut to the model's input, and classified by a trained Z
model: one given, or the one the last book build in the data folder recommends (``study.runs.recommended``).
The :class:`Answer` says what it assumed, so a wrong scale is never silent, and how far to trust it
(``study.trust``: what the study measured for such a model through that path on clips from cameras nobody
measured; "cannot tell" where the recommended model's probability falls inside its cannot-tell band).
"""

from __future__ import annotations

import contextlib
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from study.core.errors import ConfigError, ModelError, check_file
from study.learn.trained import Ensemble, TrainedModel
from study.learn.trained import load as load_model
from study.report.text import Table
from study.runs import measured, recommended
from study.see import track
from study.see.config import TrackConfig
from study.see.floor import Floor, calibrate, contact_height, on_floor
from study.see.marks import located, needs_finding, read as read_floor
from study.see.paths import FLOOR_KEYS
from study.see.scale import DEFAULT, SCALE_FROM, ObjectShape, read_scale
from study.see.trajectory import Trajectory
from study.see.video import probe
from study.trust import CANNOT_TELL, Measurements, Trust, exact_warning, for_answer, measurements, p_text, path_of

TENNIS_BALL = ObjectShape("sphere", (0.067,))
"""A tennis ball, 6.7 cm across."""


class _ByColour:
    """The default object: a tennis ball when the tracker looks for the tennis colour, else none assumed."""

    def __repr__(self) -> str:
        return "a tennis ball if the colour is tennis"


BY_COLOUR = _ByColour()
"""``object_shape``'s default: a tennis ball for the tennis colour, and for any other colour an error asking for
the object's size (a tennis ball's size is never assumed for an object of another colour)."""


def object_for(object_shape: ObjectShape | None | _ByColour, track_config: TrackConfig | None,
               what: str = "object_shape") -> ObjectShape | None:
    """The object the scale reads: ``object_shape`` itself, or for :data:`BY_COLOUR` a tennis ball when tracking the
    tennis colour (``track_config``: None is the tennis colour). :class:`ConfigError` naming ``what`` otherwise."""
    if not isinstance(object_shape, _ByColour):
        return object_shape
    tc = track_config or TrackConfig()
    if tc.hsv is None and tc.color.lower() == "tennis":
        return TENNIS_BALL
    colour = "an HSV range" if tc.hsv is not None else f"the colour {tc.color!r}"
    raise ConfigError(f"{what}: not given for {colour}; give the object's size in metres (and its shape), or a "
                      "measured scale: a tennis ball's 0.067 m is assumed only for the tennis colour")


@dataclass(frozen=True)
class Answer:
    """What :func:`classify` says about one throw.

    Example::

        answer = study.classify("throw.mp4")
        print(answer)                                 # the label, its probability, what it assumed
    """

    source: str
    """The video or CSV classified."""
    label: str
    """``"light"`` (bounces: safe to pass), ``"heavy"`` (slides: must avoid), or ``"cannot tell"``
    (``study.trust.CANNOT_TELL``: p(heavy) inside the model's cannot-tell band)."""
    p: float
    """The probability the model gives the likelier class, 0.5-1."""
    p_heavy: float
    """The probability of ``"heavy"``, 0-1."""
    model: str
    """Which model answered (a folder, or the recommended model and its seeds)."""
    assumed: str
    """What the answer rests on: the scale and where it came from, the ground, the frames read."""
    trajectory: Trajectory
    """The track, in metres, as classified."""
    warnings: tuple[str, ...] = ()
    """What makes the answer doubtful: each seed of the model that failed to train (its answers near chance), a
    model trained on exact trajectories."""
    trust: Trust | None = None
    """How far to trust it: the accuracy the study measured for such a model through this path, and the band."""

    def text(self, warnings: bool = True) -> str:
        """The answer as ``print(answer)`` shows it: the label, its probability, the trust, what it assumed, and
        (``warnings``) a line per warning (the command line prints those apart, on the error stream)."""
        trust = "" if self.trust is None else f"\n  trust: {self.trust}"
        warned = "".join(f"\n  warning: {w}" for w in self.warnings) if warnings else ""
        return (f"{self.source}: {self.label} (p(heavy) = {p_text(self.p_heavy)}; {self.model}){trust}\n"
                f"  assumed: {self.assumed}{warned}")

    def __str__(self) -> str:
        return self.text()


def shape(size: float | tuple[float, ...], kind: str = "ball") -> ObjectShape:
    """The thrown object for the scale: ``kind`` 'ball' (``size``: its diameter, metres), 'box' (one edge, a cube,
    or three) or 'cylinder' (diameter and length). No size is assumed: a tennis ball's is :data:`TENNIS_BALL`."""
    sizes = (float(size),) if np.isscalar(size) else tuple(float(s) for s in size)  # type: ignore[arg-type]
    return ObjectShape("sphere" if kind == "ball" else kind, sizes)


@dataclass(frozen=True)
class _Model:
    """The model that answers, what to call it, its cannot-tell band, and what the camera sweep measured (read once
    for every video it answers)."""

    model: TrainedModel | Ensemble
    which: str
    band: tuple[float, float] | None
    """The recommended model's band on the path it was recommended for (None: no band, or not the recommended
    model)."""
    seen: Measurements
    recommended_for: str | None = None
    """The camera path the build recommended it for (``recommended.PATHS``; None: not the recommended model)."""
    candidate: str | None = None
    """Its name among the build's candidates (None: not the recommended model)."""

    @property
    def kind(self) -> str:
        if self.candidate is not None:
            return measured.candidate_kind(self.candidate)
        m = self.model.members[0] if isinstance(self.model, Ensemble) else self.model
        return measured.kind(m.config)

    def band_for(self, route: str) -> tuple[float, float] | None:
        """Its cannot-tell band where the answer's heights came by the path it was recommended for (``route``:
        ``trust.path_of``), else None."""
        served = (recommended.FLOOR if route in FLOOR_KEYS else recommended.ONE_SCALE if route in SCALE_FROM
                  else None)
        return self.band if served is not None and served == self.recommended_for else None


def _model(model: str | Path | TrainedModel | Ensemble | None, data_dir: str | Path | None,
           floor: bool = False) -> _Model:
    """The model that answers: ``model``, or the recommended one for the floor path (``floor``) or the one-scale
    path (a build that recommends none for the floor path answers with its one-scale model, and says so)."""
    from study.core import datadir

    if model is None:
        folder = datadir.resolve(data_dir)
        rec = recommended.read(folder)
        path = recommended.FLOOR if floor and recommended.FLOOR in rec.paths else recommended.ONE_SCALE
        ensemble = recommended.ensemble(rec, folder, path)
        which = rec.describe(path) + (" for one scale: this build recommends none for the floor path"
                                      if floor and path != recommended.FLOOR else "")
        return _Model(ensemble, which, rec.path(path).band, measurements(rec, answering=True), path,
                      rec.path(path).name)
    m = model if isinstance(model, (TrainedModel, Ensemble)) else load_model(model)
    rec = None
    with contextlib.suppress(ModelError):  # only for what its build measured of models of this kind
        rec = recommended.read(datadir.resolve(data_dir))
    return _Model(m, "the model given" if m is model else f"model {model}", None, measurements(rec))


def classify(source: str | Path, model: str | Path | TrainedModel | Ensemble | None = None, *,
             track_config: TrackConfig | None = None, object_shape: ObjectShape | None | _ByColour = BY_COLOUR,
             scale_from: str = DEFAULT, metres_per_pixel: float | None = None, rest_height: float | None = None,
             data_dir: str | Path | None = None, floor: str | Path | Floor | None = None) -> Answer:
    """Light or heavy for the throw in ``source``: a video (tracked with ``track_config``, by default a
    tennis-yellow ball) or a trajectory CSV from ``study track --out`` (pixels are scaled as a video's are).

    ``model``: a trained Z model (a folder, or a loaded model or ensemble); None: the model the last book build in
    ``data_dir`` recommends. The scale: ``metres_per_pixel`` if you measured it, else read off ``object_shape`` (by
    default a tennis ball, for the tennis colour only: :data:`BY_COLOUR`) as ``scale_from`` says ('mean': its mean
    apparent size; 'rest'; 'gravity'). ``rest_height``: the centre's height at rest, metres (default: the shape's).
    ``floor``: a ``FLOOR.csv`` of four or more floor marks (their pixels and positions, or only the positions of
    five or more magenta marks to find in the video: ``study.see.marks.read``), or the marks: the camera they give places each frame's centre (no one scale;
    the size then sets only the rest height). The answer says how far to trust it (``study.trust``). Raises
    ``ModelError`` for a model that does not read heights only, ``ConfigError`` for a track in pixels with nothing to scale it by, ``TrackingError`` / ``GeometryError`` /
    ``VideoError`` naming the file and what to do.

    Example::

        answer = study.classify("throw.mp4", track_config=study.TrackConfig(color="orange"),
                                object_shape=study.answer.shape(0.2, "box"))
        print(answer.label, answer.p, answer.assumed)
    """
    check_file(source, "video or trajectory CSV", "give the path of a video, or of a CSV from 'study track --out'")
    shape_ = None if metres_per_pixel is not None and isinstance(object_shape, _ByColour) else \
        object_for(object_shape, track_config)  # before the model: the input's problems first
    marks = read_floor(floor) if isinstance(floor, (str, Path)) else floor
    return _answer(source, _model(model, data_dir, marks is not None), track_config, shape_, scale_from,
                   metres_per_pixel, rest_height, marks)


def checked_floor(floor: Floor, source: str | Path) -> Floor:
    """``floor`` with its marks found in the video ``source`` where it gives only their positions
    (``study.see.marks.located``), and, for a video, checked against its frame size (``study.see.floor.calibrate``:
    a mark outside the image, a camera below the floor) now, before minutes of tracking; raises the
    :class:`ConfigError` that would otherwise come after them."""
    found = located(floor, source)
    if Path(source).suffix.lower() != ".csv":
        info = probe(source)
        calibrate(found, info.width, info.height)
    return found


def in_metres(traj: Trajectory, object_shape: ObjectShape | None, scale_from: str = DEFAULT,
              metres_per_pixel: float | None = None) -> tuple[Trajectory, str]:
    """``traj`` (a track in pixels, or one already in metres) with heights in metres, and what scale it assumed:
    ``metres_per_pixel`` if given, else its own if it is in metres, else read off ``object_shape`` as
    ``scale_from`` says (``study.see.scale.read_scale``). Raises ``ConfigError`` for pixels with nothing to scale
    them by."""
    if metres_per_pixel is not None:
        scaled = track.set_scale(traj, ground_v=traj.ground_v, metres_per_pixel=metres_per_pixel)
        return scaled, f"scale {metres_per_pixel * 1000:.2f} mm/px as given"
    if traj.units == "m":
        return traj, f"heights as the track holds them ({traj.height_per_pixel * 1000:.2f} mm/px)"
    if object_shape is None:
        raise ConfigError(f"{traj.source}: heights are in pixels; give the object's size (--object-size D, metres) or "
                          "--metres-per-pixel, so the model sees metres")
    read = read_scale(traj, object_shape, scale_from)
    return track.set_scale(traj, ground_v=traj.ground_v, metres_per_pixel=read.metres_per_pixel), read.note()


def _answer(source: str | Path, got: _Model, track_config: TrackConfig | None, object_shape: ObjectShape | None,
            scale_from: str, metres_per_pixel: float | None, rest_height: float | None,
            floor: Floor | None = None) -> Answer:
    """:func:`classify` with the model loaded."""
    m, which = got.model, got.which
    if m.dims != "z":
        raise ModelError(f"{which} was trained on {m.dims!r}; one camera gives only the height: use a model trained "
                         "on 'z' (the paper's real-world test does)")
    path = Path(source)
    if floor is not None and needs_finding(floor) and path.suffix.lower() == ".csv":
        raise ConfigError(f"{floor.source}: positions only, and {path.name} is a track, not a video: the marks are "
                          "found in the video; classify the video, or give the marks' pixels (header u,v,x,y)")
    floor = checked_floor(floor, path) if floor is not None else None  # a bad floor before the tracking
    pixels = (track.read_csv(path) if path.suffix.lower() == ".csv" else
              track.track_video(path, track_config or TrackConfig()))  # pixels: scaled once, below
    rest = rest_height if rest_height is not None else object_shape.rest_height() if object_shape else 0.0
    if floor is not None:  # the camera the floor marks give: each frame's own depth
        size = object_shape.mean_size() if object_shape else None
        contact = contact_height(object_shape) if object_shape and rest_height is None else rest
        traj, cal = on_floor(pixels, floor, rest, size, contact)
        weighed = f", the blob's size against a {size:.3f} m mean silhouette" if size else ""
        how = (f"{cal.note()}; each frame's centre from the contacts and the flights between them{weighed}, the "
               f"centre {rest:.3f} m up at rest and {contact:.3f} m on average at a contact")
    else:
        traj, scale = in_metres(pixels, object_shape, scale_from, metres_per_pixel)
        how = (f"{scale}; the ground at the lowest centre (row {traj.ground_v:.0f}), one scale for the whole video "
               f"(the camera's tilt and the object's changing distance ignored), the centre {rest:.3f} m up at rest")
    x = track.to_model_input(traj, m.fps, m.n_frames, rest_height=rest)
    p_heavy = float(m.predict_proba(x[None])[0, 1])
    found = floor is not None and floor.found
    route = path_of(floor is not None, scale_from, metres_per_pixel, found)  # how the heights were had
    trust = for_answer(got.kind, route, got.seen, got.band_for(route))
    piece = traj.longest()
    members = m.members if isinstance(m, Ensemble) else (m,)
    assumed = (f"{how}; read {piece.t[-1] - piece.t[0]:.2f} s, {int(traj.measured.sum())} of {len(traj.t)} frames "
               f"found, {len(traj.segments())} piece(s)")
    failed = [mm for mm in members if mm.failed]
    warnings = (f"{which}: {len(failed)} of {len(members)} seed(s) failed to train (on their validation throws they "
                "could not be told from a coin), so their answers are near chance: retrain with another seed ('study "
                "train --seed N'; in Python TrainConfig(seed=N)) or give another model",) if failed else ()
    exact = exact_warning(got.kind, which, got.seen, route, got.candidate is not None)
    return Answer(str(source), trust.label(p_heavy), max(p_heavy, 1.0 - p_heavy), p_heavy, which, assumed, traj,
                  warnings + ((exact,) if exact else ()), trust)


CSV_COLUMNS = ["file", "true", "label", "p", "p_heavy", "correct", "trust", "assumed", "warnings", "error"]
"""The columns of ``study classify --manifest --out``'s CSV (:meth:`FolderAnswer.row`)."""


@dataclass(frozen=True)
class FolderAnswer:
    """One video of a manifest, answered or not."""

    file: str
    """The video's file name."""
    true: str | None
    """Its class as the manifest says, None where not known."""
    answer: Answer | None
    """What :func:`classify` said; None where it could not (see ``error``)."""
    error: str = ""
    """Why the video could not be classified ('' when it was)."""

    @property
    def correct(self) -> bool | None:
        """Whether the answer is the manifest's class (None: no class given, no answer, or "cannot tell")."""
        if self.true is None or self.answer is None or self.answer.label == CANNOT_TELL:
            return None
        return self.answer.label == self.true

    def row(self) -> dict[str, object]:
        """The CSV row: file, true, label, p, p_heavy, correct, trust, assumed, warnings (joined by ' | '), error."""
        a = self.answer
        return {"file": self.file, "true": self.true or "", "label": a.label if a else "",
                "p": f"{a.p:.4f}" if a else "", "p_heavy": f"{a.p_heavy:.4f}" if a else "",
                "correct": "" if self.correct is None else str(self.correct).lower(),
                "trust": str(a.trust) if a and a.trust else "", "assumed": a.assumed if a else "",
                "warnings": " | ".join(a.warnings) if a else "", "error": self.error}


def manifest_folder(manifest: str | Path, what: str = "manifest") -> Path:
    """The folder of ``manifest``: the ``MANIFEST.csv`` file itself, or the folder that holds it; :class:`DataError`
    naming ``what`` (the option that gave it) and the path when there is neither."""
    from study.core.errors import DataError

    m = Path(manifest)
    if m.is_dir():
        return m
    if m.suffix.lower() == ".csv" and not m.is_file():
        raise DataError(f"{what} {m}: no such file; give the MANIFEST.csv that lists the videos, or their folder")
    if not m.exists():
        raise DataError(f"{what} {m}: no such file or folder; give the MANIFEST.csv that lists the videos, or "
                        "their folder")
    if m.name != "MANIFEST.csv":
        raise ConfigError(f"{what} {m}: name it MANIFEST.csv, beside the videos it lists (or give their folder)")
    return m.parent


def classify_manifest(manifest: str | Path, model: str | Path | TrainedModel | Ensemble | None = None, *,
                      color: str = "tennis", object_size: float | None = None, scale_from: str = DEFAULT,
                      data_dir: str | Path | None = None, what: str = "manifest",
                      floor: str | Path | Floor | None = None) -> list[FolderAnswer]:
    """Every video of a ``MANIFEST.csv`` (``study.methods.videos.read_manifest``: its file, label if known, colour or
    HSV range, size and shape; ``color`` and ``object_size`` for rows that give none, a tennis ball's size only for
    the tennis colour) classified as :func:`classify` does, by one model loaded once. A video that cannot be
    tracked or scaled gets its error, and the others go on. ``what`` names the manifest in errors (``--manifest``);
    ``floor``: one ``FLOOR.csv`` for every clip (a camera that stood still), as :func:`classify` takes it.

    Example::

        for row in study.answer.classify_manifest("my-videos/MANIFEST.csv"):
            print(row.file, row.true, row.answer.label if row.answer else row.error)
    """
    from study.core.errors import StudyError
    from study.methods.videos import read_manifest

    videos = read_manifest(manifest_folder(manifest, what), color=color, object_size=object_size,
                           what=what)  # before the model
    marks = read_floor(floor) if isinstance(floor, (str, Path)) else floor
    got = _model(model, data_dir, marks is not None)
    out = []
    for v in videos:
        try:
            ans = _answer(v.path, got, v.track_config(), v.object_shape(), scale_from, None, v.rest_height, marks)
            out.append(FolderAnswer(v.path.name, v.label, ans))
        except StudyError as e:
            out.append(FolderAnswer(v.path.name, v.label, None, str(e)))
    return out


def write_answers(rows: list[FolderAnswer], path: str | Path) -> Path:
    """``rows`` as a CSV at ``path`` (:data:`CSV_COLUMNS`, one row a video; written atomically)."""
    return Table([r.row() for r in rows], {c: c for c in CSV_COLUMNS}).write_csv(path)
