"""The chapter *Real-world test*: videos in, tracked heights, the Z-only classifier's labels out.

The pipeline, video by video: the videos are rendered with a known answer or read from a folder with a
``MANIFEST.csv`` (``study.methods.videos``: :func:`book_set`, :func:`real_clips`); each is tracked, turned into
the model's input and labelled (``study.methods.labels``: :func:`track_all`, :func:`classify`).

:func:`compute` runs the chapter on a runner and returns :class:`RealWorld`:

1. the tracker against the rendered ground truth (:func:`tracking_error`) and the scale it read off the
   object's apparent size (:func:`scale_error`);
2. the model a camera in a car should use, chosen among six candidates (two inputs, three ways of training) on
   validation throws as a user's camera gives them
   (``study.methods.recommend``);
3. Table 1's Z model (and the recommended one, where it differs) on every video, per class with Wilson
   intervals beside the paper's 93 % and 100 % (``study.runs.paper.REAL_WORLD``), every candidate's
   label for every video, and how the labels move with a wrong scale (:data:`FACTORS`);
4. the data of the paper's Figures 1, 5 and 6 (:class:`Filmstrip`, :class:`HeightSeries`, :class:`TrackView`);
5. a user's camera: the rendered videos again on the path ``study classify VIDEO`` takes with no camera
   (:func:`user_tracks`). Throws filmed from cameras the study never saw are the next chapter's
   (``study.chapters.usercamera``).

:class:`Numbers` is what the chapter reports, under the names ``realworld.table1.rendered.light`` and so on.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Literal

import numpy as np

from study import CLASSES
from study.learn.config import Inputs
from study.learn.metrics import Interval
from study.learn.trained import Ensemble
from study.methods import calibration, camera_cost
from study.methods.videos import (  # noqa: F401  (re-exported: the chapter's videos)
    REAL_CLIPS_DEFAULT,
    REAL_CLIPS_ENV,
    TENNIS_BALL,
    Video,
    book_set,
    read_manifest,
    real_clips,
    real_clips_dir,
    render_set,
    throw,
)
from study.report import verdicts
from study.methods.labels import (  # noqa: F401  (re-exported: the chapter's tracking and labels)
    Label,
    Model,
    PixelError,
    Tracked,
    classify,
    per_class_interval,
    scale_error,
    track_all,
    tracking_error,
    true_scale,
    truth_tracks,
    user_tracks,
)
from study.methods.recommend import Recommendation, recommend
from study.report.realworld import (
    Candidate,
    Class,
    Classified,
    ModelKey,
    Numbers,
    Training,
)
from study.report.reported import Number, Verdict, count, number
from study.report.text import Table, pct, pct_ci
from study.runs import paper
from study.see import render, track, video

if TYPE_CHECKING:
    from study.runs.runner import Runner

# ---------------------------------------------------------------------------------------------
# What the chapter reports


WHY_NOT_COMPARABLE: dict[str, str] = {
    "rendered": "rendered MuJoCo throws from the study's priors, not the paper's filmed golf ball and wooden cube",
    "real": "{objects} filmed by others, classified by a model trained on 20 cm boxes, not the paper's golf ball",
}
"""Why neither of our video sets can be compared with the paper's footage (``{objects}``: what the real clips show)."""
REAL_OBJECTS = "tennis balls"
"""What the real clips beside the project show, as the chapter's words name them (a reader's own: the chapter's
``objects`` parameter)."""
FACTORS = (0.5, 0.75, 1.0, 1.5, 2.0)
"""Factors the pixel scale is multiplied by (a wrong scale), to measure how much the labels depend on it."""
FILM_FRAMES = 6
"""Frames of each video in Figure 1."""
FILM_SECONDS = 2.0
"""Figure 1 shows each video's first seconds, this many."""


# ---------------------------------------------------------------------------------------------
# What the figures draw


@dataclass(frozen=True)
class Filmstrip:
    """A video's first seconds in a few frames (the paper's Figure 1)."""

    title: str
    """Which video, in words."""
    times: tuple[str, ...]
    """Each frame's time, as the figure labels it."""
    frames: np.ndarray
    """(k, H, W, 3) uint8 RGB."""


@dataclass(frozen=True)
class TrackView:
    """One video's whole track over its last tracked frame (the paper's Figure 6)."""

    title: str
    """Which video, in words (and 'not tracked' when it was not)."""
    frame: np.ndarray | None
    """(H, W, 3) uint8 RGB, the last frame in which the object was found; None when not tracked."""
    u: np.ndarray
    """(n,) image column of the track, pixels."""
    v: np.ndarray
    """(n,) image row of the track, pixels."""
    status: np.ndarray
    """(n,) per frame: 1 measured, 2 filled by interpolation, 0 missing."""


@dataclass(frozen=True)
class HeightSeries:
    """One video's tracked height as the classifier sees it (the paper's Figure 5)."""

    group: Literal["rendered", "real"]
    """Which set of videos."""
    label: str
    """Its true class."""
    t: np.ndarray
    """(T,) seconds."""
    z: np.ndarray
    """(T,) metres: resampled to the model's frame rate, cut or zero-padded to its input."""


def filmstrip(v: Video, title: str, n: int = FILM_FRAMES, seconds: float = FILM_SECONDS) -> Filmstrip:
    """``n`` frames evenly spread over the first ``seconds`` of ``v``."""
    info = video.probe(v.path)
    picks = np.linspace(0, min(info.frames, round(seconds * info.fps)) - 1, n).round().astype(int)
    frames = video.read_frames(v.path, picks)
    return Filmstrip(title, tuple(f"{i / info.fps:.2f} s" for i in picks), np.stack([frames[i] for i in picks]))


def track_view(v: Video, tracked: Tracked, title: str) -> TrackView:
    """The track of ``v`` over its last tracked frame."""
    traj = tracked.trajectory
    if traj is None:
        empty = np.zeros(0)
        return TrackView(f"{title}: not tracked", None, empty, empty, empty.astype(int))
    last = int(np.flatnonzero(traj.status > 0)[-1])
    return TrackView(title, video.read_frames(v.path, [last])[last], traj.u, traj.v, traj.status)


def heights(model: Model, group: Literal["rendered", "real"], videos: Sequence[Video],
            tracks: dict[str, Tracked]) -> list[HeightSeries]:
    """The model's input height of every tracked video of ``videos``."""
    out = []
    for v in videos:
        traj = tracks[v.path.name].trajectory
        if traj is not None:
            z = track.to_model_input(traj, model.fps, model.n_frames, rest_height=v.rest_height)[:, 2]
            out.append(HeightSeries(group, v.label, np.arange(len(z)) / model.fps, z))
    return out


# ---------------------------------------------------------------------------------------------
# The experiment's steps


def scale_sweep(model: Model, rendered: Sequence[Video], real: Sequence[Video], tracks_rendered: dict[str, Tracked],
                tracks_real: dict[str, Tracked], factors: Sequence[float] = FACTORS) -> Table:
    """Every video classified again with its heights multiplied by each of ``factors`` (a wrong pixel scale)."""
    rows = []
    for f in factors:
        a = per_class_interval(classify(model, rendered, tracks_rendered, height_factor=f, progress=False))
        ar = per_class_interval(classify(model, real, tracks_real, height_factor=f, progress=False))
        rows.append({"factor": f"{f:g}", "light": _pct_ci(a["light"]), "heavy": _pct_ci(a["heavy"]),
                     "real": _pct_ci(ar["light"])})
    return Table(rows, {"factor": "scale × factor", "light": "rendered light", "heavy": "rendered heavy",
                        "real": "real balls (light)"})


def _pct_ci(iv: Interval | None) -> str:
    return "—" if iv is None else pct_ci(iv)


def _classified(name: str, rendered: Sequence[Label], real: Sequence[Label], objects: str = REAL_OBJECTS) -> Classified:
    def numbers(labels: Sequence[Label], where: str, what: str) -> dict[Class, Number]:
        return {c: number(iv, what.format(c=c), paper=paper.REAL_WORLD[c],
                          decision=verdicts.not_comparable(WHY_NOT_COMPARABLE[where].format(objects=objects)))
                for c, iv in per_class_interval(labels).items() if iv is not None}  # type: ignore[misc]

    return Classified(numbers(rendered, "rendered", "rendered {c} videos classified correctly, " + name),
                      numbers(real, "real", "real clips ({c}) classified correctly, " + name))


def _figures(objects: str = REAL_OBJECTS) -> dict[str, Verdict]:
    judged = {
        "figure1": ("frames of a light object bouncing and a heavy one landing: shown for rendered throws of both "
                    f"classes and for real {objects}; no real heavy object, since no such footage is public",
                    "the paper's Figure 1: frames of a light and a heavy object"),
        "figure5": ("tracked height series of real videos of both classes: shown for rendered throws of both classes "
                    f"and for real {objects} (light only)",
                    "the paper's Figure 5: tracked heights of the real videos"),
        "figure6": ("real video frames with the object tracked: the whole track drawn on the last tracked frame of "
                    "each rendered and real video", "the paper's Figure 6: frames of the real videos, tracked"),
    }
    return {k: Verdict(verdicts.qualitative(criterion), what) for k, (criterion, what) in judged.items()}


def _render_heights_table(render_heights: dict[str, tuple[float, float]]) -> Table:
    """Each path's height error on the book's renders (median removed, raw in brackets)."""
    def mm(pair: tuple[float, float]) -> str:
        return "—" if math.isnan(pair[0]) else f"{pair[1]:.0f} ({pair[0]:.0f})"

    rows = [{"path": k + (" (default)" if k == camera_cost.DEFAULT_PATH else ""), "book": mm(render_heights[k])}
            for k in camera_cost.PATHS]
    return Table(rows, {"path": "path", "book": "the book's renders: mm RMS, median removed (raw)"})


# ---------------------------------------------------------------------------------------------
# The chapter's result


@dataclass(frozen=True)
class RealWorld:
    """Everything the chapter shows: its numbers, its tables and sentences, its figures' data."""

    numbers: Numbers
    """What the chapter reports (the results file's ``realworld.*``)."""
    rendered: tuple[Video, ...]
    """The rendered videos, light and heavy."""
    real: tuple[Video, ...]
    """The real clips (none without footage)."""
    recommendation: Recommendation
    """The candidates' validation accuracies and the model chosen."""
    pixel_error: PixelError
    """The tracker against the rendered ground truth."""
    filmstrips: tuple[Filmstrip, ...]
    """Figure 1: a rendered light and heavy throw and, with footage, the sharpest real clip."""
    track_views: tuple[TrackView, ...]
    """Figure 6: the rendered light and heavy throw and the first two real clips, tracked."""
    heights: tuple[HeightSeries, ...]
    """Figure 5: every tracked video's height as the classifier sees it."""
    val_table: Table
    """Each candidate's observed validation accuracy, the chosen one marked."""
    acc_table: Table
    """Each model's accuracy per class, rendered and real, beside the paper's."""
    real_table: Table
    """Table 1's model on each real clip."""
    every_table: Table
    """Every candidate's label for every video."""
    sweep_table: Table
    """The labels with the pixel scale multiplied by each of :data:`FACTORS`."""
    n_rendered: int
    """Rendered videos per class."""
    n_real: int
    """Real clips classified."""
    model_frames: int
    """The classifier's input length, frames."""
    model_seconds: str
    """The same in seconds, as the text writes it."""
    render_size: str
    """Width × height of the rendered videos, pixels."""
    scale_err: str
    """Median relative error of the pixel scale read off the rendered object's apparent size."""
    user_table: Table
    """Each model on the rendered videos by the known camera and by a user's path, per class."""
    heights_table: Table
    """Each path's height error on the book's renders."""
    real_objects: str = REAL_OBJECTS
    """What the real clips show, as the chapter's words name them."""
    real_found: int | None = None
    """Real clips the folder held, before the preset's limit (None: not counted)."""

    @property
    def real_count_words(self) -> str:
        """How many real clips were classified, and of how many, when a preset keeps only some."""
        n = len(self.real)
        if self.real_found is not None and self.real_found > n:
            return f"the first {n} of the folder's {self.real_found} clips (this preset keeps {n})"
        return "none were found here" if n == 0 else f"{n} clip{'s' if n != 1 else ''}"

    # Sentences whose words depend on the numbers -------------------------------------------------

    @property
    def err_mean(self) -> str:
        return f"{self.pixel_error.mean_px:.1f}"

    @property
    def err_p95(self) -> str:
        return f"{self.pixel_error.p95_px:.1f}"

    @property
    def found_rendered(self) -> str:
        return pct(self.pixel_error.found)

    @property
    def choice_text(self) -> str:
        if "recommended" in self.numbers.models:
            return f"the recommended one, {self.recommendation.choice}"
        return "the recommended one, which is Table 1's model itself"

    @property
    def user_words(self) -> str:
        """What Table 1's model does on the rendered videos with no camera, beside the known camera and the
        throws' exact heights."""
        user, known = self.numbers.user.get("table1", {}), self.numbers.models["table1"].rendered
        exact = self.numbers.exact.get("table1", {})
        parts = [f"{pct_ci(user[c].interval)} of the {c} ones" for c in CLASSES if c in user]
        if not parts:
            return "no rendered video could be tracked on a user's path"
        out = "on a user's path, with no camera, it labels " + " and ".join(parts)
        if known:
            out += " (by the renderer's camera: " + ", ".join(pct(known[c].value) for c in CLASSES if c in known)
            out += "; from the throws' exact heights: " + ", ".join(pct(exact[c].value) for c in CLASSES
                                                                      if c in exact) + ")" if exact else ")"
        return out

    @property
    def credits(self) -> Table:
        """Where each real clip comes from, as its manifest says (repository, commit, path, licence)."""
        rows = []
        for v in self.real:
            i = v.info
            where = " ".join(str(i[k]) for k in ("source_repository", "source_commit", "source_path") if i.get(k))
            rows.append({"file": v.path.name, "source": where or "not stated",
                         "licence": i.get("licence") or "not stated"})
        return Table(rows, {"file": "clip", "source": "recorded by (repository, commit, path)", "licence": "licence"},
                     empty="*No real clips were classified.*")

    @property
    def real_words(self) -> str:
        real = self.numbers.models["table1"].real
        if not real:
            return "no real clips were found to classify"
        return "; ".join(f"of the real clips ({c}), it labels {pct_ci(n.interval)} correctly" for c, n in real.items())


def table1_model(runner: Runner) -> Ensemble:
    """Table 1's Z model over Table 1's seeds as one classifier (the mean of their probabilities): the videos'
    labels do not hang on one seed."""
    cfg = runner.table1_config()
    return Ensemble(tuple(runner.trained(dataclasses.replace(cfg, seed=s)) for s in runner.preset.seeds))


def shown(real: Sequence[Video], video_dir: str, limit: int) -> list[Video]:
    """The real clips the chapter classifies: every clip of a folder the reader gave (``video_dir``), or the first
    ``limit`` of the shared clips beside the project (a small preset's few)."""
    return list(real) if video_dir else list(real[:limit])


def compute(runner: Runner, real: Sequence[Video] = (), model: Model | None = None, model_name: str = "",
            objects: str = REAL_OBJECTS, real_found: int | None = None) -> RealWorld:
    """The chapter *Real-world test* on ``runner``'s preset: its rendered throws and the ``real`` clips
    (:func:`real_clips`; ``objects`` says what they show, ``real_found`` how many the folder held before a preset's
    limit), classified by Table 1's Z model (its seeds as one classifier, :func:`table1_model`) or by ``model`` if
    given (named ``model_name`` in the tables), and by the model :func:`recommend` chooses. Every run is cached;
    the videos are rendered and tracked once."""
    tm = model if model is not None else table1_model(runner)
    rendered, rcfg = calibration.rendered(runner)
    real = list(real)
    pixel = tracking_error(rendered)
    tracks_r, tracks_q = track_all(rendered, progress=False), track_all(real, progress=False)
    rec = recommend(runner)
    models: dict[ModelKey, tuple[str, Model]] = {
        "table1": (model_name or ("your model" if model is not None else "Table 1's Z model"), tm)}
    if rec.choice != "positions, exact" or model is not None:  # otherwise the recommended model is Table 1's
        models["recommended"] = (f"recommended ({rec.choice})", rec.model)
    if rec.floor_choice is not None:
        models["floor"] = (f"recommended for floor marks ({rec.floor_choice})", rec.models[rec.floor_choice])
    labels = {key: (classify(m, rendered, tracks_r, progress=False), classify(m, real, tracks_q, progress=False))
              for key, (_, m) in models.items()}
    shape = camera_cost.shape_of(runner.synth_config)
    side = render.scene_camera(render.class_model("light"), rcfg.camera, rcfg.width, rcfg.height)  # the scene's own
    on_renders = [camera_cost.video_heights(v, shape, lambda _: side) for v in rendered]  # tracked once, read every way
    tracks_u = user_tracks(rendered, on_renders)
    tracks_f = user_tracks(rendered, on_renders, camera_cost.FLOOR_PATH)
    render_heights = camera_cost.height_errors(on_renders)
    user = {key: classify(m, rendered, tracks_u, progress=False) for key, (_, m) in models.items()}
    floor = {key: classify(m, rendered, tracks_f, progress=False) for key, (_, m) in models.items()}
    tracks_x = truth_tracks(rendered)
    exact = {key: classify(m, rendered, tracks_x, progress=False) for key, (_, m) in models.items()}
    numbers = reported(rec, {key: (models[key][0], *labels[key]) for key in models}, user, exact, objects, floor)
    classified = numbers.models

    light = next(v for v in rendered if v.label == "light")
    heavy = next(v for v in rendered if v.label == "heavy")
    strips = [filmstrip(light, "light (rendered)"), filmstrip(heavy, "heavy (rendered)")]
    if real:
        clip = max(real, key=lambda v: video.probe(v.path).height)  # the sharpest real clip
        strips.append(filmstrip(clip, f"{clip.label} (real: {clip.path.name})"))
    shown = [("rendered light", light, tracks_r), ("rendered heavy", heavy, tracks_r)]
    shown += [(f"real: {v.path.name}", v, tracks_q) for v in real[:2]]
    n = runner.preset.videos_per_class
    return RealWorld(
        numbers, tuple(rendered), tuple(real), rec, pixel, tuple(strips),
        tuple(track_view(v, tracks[v.path.name], title) for title, v, tracks in shown),
        tuple(heights(tm, "rendered", rendered, tracks_r) + heights(tm, "real", real, tracks_q)),
        _val_table(rec),
        _acc_table({models[k][0]: (classified[k], labels[k][1]) for k in models}, n, objects),
        _real_table(labels["table1"][1]),
        _every_table(rec, rendered, real, tracks_r, tracks_q),
        scale_sweep(tm, rendered, real, tracks_r, tracks_q),
        n_rendered=n, n_real=len(real), model_frames=tm.n_frames, model_seconds=f"{tm.n_frames / tm.fps:g}",
        render_size=f"{rcfg.width}×{rcfg.height}", scale_err=pct(scale_error(tracks_r.values(), true_scale(rcfg))),
        user_table=_user_table({models[k][0]: (exact[k], labels[k][0], user[k], floor[k]) for k in models}),
        heights_table=_render_heights_table(render_heights), real_objects=objects,
        real_found=real_found if real_found is not None else len(real))


def reported(rec: Recommendation, labels: dict[ModelKey, tuple[str, Sequence[Label], Sequence[Label]]],
             user: dict[ModelKey, Sequence[Label]] | None = None,
             exact: dict[ModelKey, Sequence[Label]] | None = None, objects: str = REAL_OBJECTS,
             floor: dict[ModelKey, Sequence[Label]] | None = None) -> Numbers:
    """What the chapter reports: each candidate's validation accuracy (``rec``), the paper's figures judged,
    each model's accuracy per class from its ``labels`` (model key -> (its name, its labels of the rendered
    videos, of the real clips)), its labels of the rendered videos on a user's path (``user``), from their exact
    heights (``exact``) and through floor marks (``floor``)."""
    judged = _figures(objects)
    why = verdicts.not_comparable(WHY_NOT_COMPARABLE["rendered"])

    def per_class(got: dict[ModelKey, Sequence[Label]] | None, how: str) -> dict[ModelKey, dict[Class, Number]]:
        return {key: {c: number(iv, f"rendered {c} videos classified correctly {how}, {labels[key][0]}",  # type: ignore[misc]
                                paper=paper.REAL_WORLD[c], decision=why)
                      for c, iv in per_class_interval(ls).items() if iv is not None}
                for key, ls in (got or {}).items()}

    gap = {key: {c: count(_right(ls, c) - _right(labels[key][1], c),  # type: ignore[misc]
                          f"rendered {c} videos right through floor marks minus through the renderer's camera, "
                          f"{labels[key][0]}", signed=True) for c in CLASSES if any(r.label == c for r in ls)}
           for key, ls in (floor or {}).items()}
    return Numbers(_candidates(rec), judged["figure1"], judged["figure5"], judged["figure6"],
                   {key: _classified(name, rendered, real, objects) for key, (name, rendered, real) in labels.items()},
                   per_class(user, "on a user's path"), per_class(exact, "from their exact heights"),
                   per_class(floor, "through floor marks"), gap)


def _candidates(rec: Recommendation) -> dict[Inputs, dict[Training, Candidate]]:
    out: dict[str, dict[str, Candidate]] = {}
    for name, iv in rec.val.items():
        inputs, training = name.split(", ")  # "positions, exact" (candidates)
        out.setdefault(inputs, {})[training] = Candidate(
            number(iv, f"validation accuracy under the calibrated observation, {name}"),
            number(rec.val_user[name], f"validation accuracy as a user's camera gives the throws, {name}"),
            number(rec.val_floor[name], f"validation accuracy as the floor path gives the throws, {name}")
            if name in rec.val_floor else None)
    return out  # type: ignore[return-value]


# ---------------------------------------------------------------------------------------------
# The tables


def _val_table(rec: Recommendation) -> Table:
    floor = {"floor": "validation, the floor path (chooses its model) [95 % CI]"} if rec.val_floor else {}
    rows = [{"model": n, "val": pct_ci(iv), "user": pct_ci(rec.val_user[n]),
             **({"floor": pct_ci(rec.val_floor[n])} if floor else {}),
             "chosen": ("✓" if n == rec.choice else "") + (" ✓ floor" if n == rec.floor_choice else "")}
            for n, iv in rec.val.items()]
    return Table(rows, {"model": "candidate (Z)", "val": "validation, calibrated tracker [95 % CI]",
                        "user": "validation, a user's camera (chooses) [95 % CI]", **floor, "chosen": "chosen"})


def _acc_table(models: dict[str, tuple[Classified, Sequence[Label]]], n_rendered: int,
               objects: str = REAL_OBJECTS) -> Table:
    """Each model (by name: its numbers and its labels of the real clips), per class, beside the paper's."""
    rows = []
    for name, (numbers, real) in models.items():
        for c in CLASSES:
            rendered, on_real = numbers.rendered.get(c), numbers.real.get(c)  # type: ignore[call-overload]
            rows.append({"model": name, "class": c,
                         "paper": f"{pct(paper.REAL_WORLD[c], 0)} ({paper.REAL_OBJECTS[c]}, real)",
                         "rendered": "—" if rendered is None else pct_ci(rendered.interval),
                         "verdict": "—" if rendered is None else rendered.verdict,
                         "real": "no footage" if on_real is None else
                         f"{pct_ci(on_real.interval)} ({objects}, n = {sum(r.label == c for r in real)})"})
    return Table(rows, {"model": "model", "class": "class", "paper": "paper",
                        "rendered": f"ours, rendered ({n_rendered} per class) [95 % Wilson]",
                        "verdict": "paper vs ours", "real": "ours, real [95 % Wilson]"})


def _right(labels: Sequence[Label], c: str) -> int:
    """How many of the videos of class ``c`` ``labels`` got right."""
    return sum(r.correct for r in labels if r.label == c)


def _user_table(models: dict[str, tuple[Sequence[Label], ...]]) -> Table:
    """Each model (by name: its labels of the rendered videos from their exact heights, by the renderer's camera,
    by a user's path and through floor marks) per class: the videos right as counts, with their 95 % interval."""
    rows = []
    for name, labels in models.items():
        ivs = [per_class_interval(got) for got in labels]
        for c in CLASSES:
            row = {"model": name, "class": c}
            for key, got, iv in zip(("exact", "known", "user", "floor"), labels, ivs):
                right, n = _right(got, c), sum(r.label == c for r in got)
                row[key] = f"{right}/{n}" + ("" if iv[c] is None else f" ({100 * iv[c].lo:.0f}-{100 * iv[c].hi:.0f} %)")
            rows.append(row)
    return Table(rows, {"model": "model", "class": "class", "exact": "exact heights (the renderer's truth)",
                        "known": "the renderer's camera", "user": "a user's path, no camera",
                        "floor": "floor marks, clicked (--floor)"})  # cells: right/videos (95 % interval)


def _real_table(labels: Sequence[Label]) -> Table:
    rows = [{"file": r.file, "true": r.label or "not known", "found": pct(r.found, 0) if r.tracked else "—",
             "pieces": r.pieces if r.tracked else "—", "bounces": r.bounces if r.tracked else "—",
             "p_light": f"{r.p_light:.2f}" if r.tracked else "—",
             "label": r.predicted if r.tracked else "not tracked: " + r.error} for r in labels]
    return Table(rows, {"file": "file", "true": "true class", "found": "found", "pieces": "pieces",
                        "bounces": "bounces", "p_light": "p_light", "label": "label (Table 1's model)"},
                 empty="*No real clips were found.*")


def _every_table(rec: Recommendation, rendered: Sequence[Video], real: Sequence[Video],
                 tracks_rendered: dict[str, Tracked], tracks_real: dict[str, Tracked]) -> Table:
    labels = {n: classify(m, rendered, tracks_rendered, progress=False) + classify(m, real, tracks_real, progress=False)
              for n, m in rec.models.items()}
    rows = []
    for i, v in enumerate(list(rendered) + list(real)):
        first = labels[rec.choice][i]
        row = {"video": ("real: " if i >= len(rendered) else "") + v.path.name, "label": v.label,
               "found": pct(first.found, 0) if first.tracked else "not tracked"}
        for n in rec.models:
            r = labels[n][i]
            row[n] = f"{r.predicted} ({r.p_light:.2f})" if r.tracked else "—"
        rows.append(row)
    return Table(rows, {"video": "video", "label": "true class", "found": "found", **{n: n for n in rec.models}})
