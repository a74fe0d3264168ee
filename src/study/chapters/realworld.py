"""The chapter *Real-world test*: videos in, tracked heights, the Z-only classifier's labels out.

The pipeline, video by video:

- :func:`render_set` (:func:`book_set`, the book's): throws drawn from the synthesis priors
  (``study.simulate.synth``), rendered with ``study.see.render`` from a side camera (the launch turned to cross
  the view, as in the paper's videos), with a known class and ground truth: the paper's 20 + 20 design, heavy
  objects included. :func:`read_manifest` (:func:`real_clips`): a folder of labelled videos with a
  ``MANIFEST.csv`` (columns ``file`` and ``label``; other columns are kept), the real clips beside the project
  or the reader's own.
- :func:`track_all` tracks each video (heights in metres, the pixel scale taken from the object's known size);
  :func:`classify` turns each height series into the model's input (``study.see.track.to_model_input``) and
  records the model's :class:`Label`.

:func:`compute` runs the chapter on a runner and returns :class:`RealWorld`:

1. the tracker against the rendered ground truth (:func:`tracking_error`) and the scale it read off the
   object's apparent size (:func:`scale_error`);
2. the model a camera in a car should use, chosen among six candidates (two inputs, three ways of training) on
   validation throws as a user's camera gives them
   (:func:`recommend`);
3. Table 1's Z model (and the recommended one, where it differs) on every video, per class with Wilson
   intervals beside the paper's 93 % and 100 % (``study.runs.paper.REAL_WORLD``), every candidate's
   label for every video, and how the labels move with a wrong scale (:data:`FACTORS`);
4. the data of the paper's Figures 1, 5 and 6 (:class:`Filmstrip`, :class:`HeightSeries`, :class:`TrackView`);
5. a user's camera: the rendered videos again on the path ``study classify VIDEO`` takes with no camera
   (:func:`user_tracks`), and the camera sweep (:func:`camera_sweep`, :class:`CameraSweep`): throws filmed from
   cameras the study never saw, their heights had by every path of ``study.methods.camera_cost`` and classified
   by every candidate, beside the same throws' exact heights.

:class:`Numbers` is what the chapter reports, under the names ``realworld.table1.rendered.light`` and so on.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Literal

import numpy as np

from study import CLASSES
from study.core.errors import ConfigError, StudyError
from study.core.progress import Progress
from study.learn import train
from study.learn.config import Inputs, TrainConfig
from study.learn.metrics import Interval, hierarchical_bootstrap, wilson
from study.learn.trained import Ensemble
from study.methods import calibration, camera_cost, sweep, tracker
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
from study.report.realworld import (
    Candidate,
    Class,
    Classified,
    ModelKey,
    Numbers,
    PathKey,
    Sweep,
    SweepGroup,
    SweepPath,
    Training,
)
from study.report.reported import Number, Verdict, count, number
from study.report.text import Table, pct, pct_ci, points
from study.runs import paper, records
from study.runs import recommended as saved
from study.runs.stats import correct_of
from study.see import paths, render, scale, track, video
from study.simulate import measure, observe

if TYPE_CHECKING:
    from study.runs.runner import Runner

# ---------------------------------------------------------------------------------------------
# Videos: rendered with a known answer, or read from a folder with a manifest (study.methods.videos)


Model = train.TrainedModel | Ensemble
"""A model the chapter classifies videos with: one seed's, or the seeds' mean."""


# ---------------------------------------------------------------------------------------------
# Tracking, and the labels a model gives


@dataclass(frozen=True)
class Tracked:
    """What tracking one video gave: its trajectory, or why there is none."""

    trajectory: track.Trajectory | None
    """The tracked trajectory (heights in metres from the object's size), or None."""
    error: str = ""
    """Why the video could not be tracked ('' when it was)."""


def _as_a_user(v: Video, cfg: track.TrackConfig) -> track.Trajectory:
    """``v`` as ``study classify VIDEO --color C --object-size D`` tracks it: no camera, no ground truth; the scale
    read the default way (``study.see.scale.DEFAULT``) off the video's object."""
    return track.track_video(v.path, cfg, shape=v.object_shape(), scale_from=scale.DEFAULT)


def track_all(videos: Sequence[Video], progress: bool = True) -> dict[str, Tracked]:
    """Track every video: file name -> :class:`Tracked` (or why it could not be tracked). A rendered throw's heights
    come from the render's camera at the object's depth (``study.methods.tracker.track_rendered``); a real clip's,
    whose camera is unknown, as a user's would (``study classify``'s path)."""
    out: dict[str, Tracked] = {}
    with Progress("track videos", total=len(videos), show=progress, unit="video") as bar:
        for v in videos:
            try:
                cfg = v.track_config()
                out[v.path.name] = Tracked(tracker.track_rendered(v, cfg) if v.truth is not None else
                                           _as_a_user(v, cfg))
            except StudyError as e:
                out[v.path.name] = Tracked(None, str(e))
            bar.update()
    return out


def user_tracks(videos: Sequence[Video], heights: Sequence[camera_cost.Heights]) -> dict[str, Tracked]:
    """Every rendered video as ``study classify VIDEO --color C --object-size D`` tracks it (no camera, no ground
    truth): the default path's track of its :func:`study.methods.camera_cost.video_heights`, ``heights``, which
    tracked it once for every path."""
    path = camera_cost.DEFAULT_PATH
    return {v.path.name: Tracked(h.tracks[path]) if path in h.tracks else Tracked(None, str(h.paths[path]))
            for v, h in zip(videos, heights)}


def truth_tracks(videos: Sequence[Video]) -> dict[str, Tracked]:
    """Every rendered video's true centre (:func:`study.methods.camera_cost.truth_trajectory`): what the model
    answers from the throw's exact heights, with no tracker and no camera in the way."""
    return {v.path.name: Tracked(camera_cost.truth_trajectory(v)) if v.truth is not None else
            Tracked(None, "no ground truth") for v in videos}


@dataclass(frozen=True)
class Label:
    """What a model says about one video (:func:`classify`): its label and what the tracker saw, or why the video
    could not be tracked (then no label)."""

    file: str
    """The video's file name."""
    label: str
    """Its true class, 'light' or 'heavy'."""
    error: str = ""
    """Why the video could not be tracked ('' when it was)."""
    frames: int = 0
    """Frames of the video."""
    found: float = 0.0
    """Share of its frames in which the tracker measured the object."""
    filled: int = 0
    """Frames filled by interpolation."""
    pieces: int = 0
    """Pieces the trajectory split into at long gaps (the longest is classified)."""
    bounces: int | None = None
    """Bounces seen in the piece classified (None for a trajectory in pixels)."""
    metres_per_pixel: float = math.nan
    """The pixel scale, from the object's known size: metres per pixel."""
    p_light: float = math.nan
    """The model's probability of light."""
    p_heavy: float = math.nan
    """The model's probability of heavy."""
    predicted: str = ""
    """The model's label ('' when not tracked)."""

    @property
    def tracked(self) -> bool:
        return not self.error

    @property
    def correct(self) -> bool:
        """Labelled as its true class (False when not tracked)."""
        return self.tracked and self.predicted == self.label


def classify(
    model: Model,
    videos: Sequence[Video],
    tracks: dict[str, Tracked] | None = None,
    height_factor: float = 1.0,
    progress: bool = True,
) -> list[Label]:
    """Each video's :class:`Label` from its track (``tracks`` from :func:`track_all`, tracked here if None), in
    the order of ``videos``. ``height_factor`` multiplies every height (a wrong pixel scale), to measure how
    much the label depends on it."""
    if model.dims != "z":
        raise ConfigError(f"the model was trained on {model.dims!r}; one camera gives only the height: use a 'z' model")
    tracks = track_all(videos, progress) if tracks is None else tracks
    out = []
    for v in videos:
        tracked = tracks[v.path.name]
        traj = tracked.trajectory
        if traj is None:
            out.append(Label(v.path.name, v.label, tracked.error))
            continue
        piece = traj.longest()
        x = track.to_model_input(traj, model.fps, model.n_frames, height_factor=height_factor, rest_height=v.rest_height)
        p = np.asarray(model.predict_proba(x[None]))[0]
        out.append(Label(v.path.name, v.label, "", len(traj.t), traj.found_fraction, int(traj.filled.sum()),
                         len(traj.segments()), measure.bounce_count(piece.height) if piece.units == "m" else None,
                         traj.height_per_pixel, float(p[0]), float(p[1]), CLASSES[int(np.argmax(p))]))
    return out


def per_class_interval(labels: Sequence[Label]) -> dict[str, Interval | None]:
    """Accuracy per true class over the videos that were classified, with its Wilson interval (None for a class
    with no classified video): for 20 videos a bootstrap would understate the uncertainty."""
    out: dict[str, Interval | None] = {}
    for c in CLASSES:
        ok = [r.correct for r in labels if r.label == c and r.tracked]
        out[c] = wilson(sum(ok), len(ok)) if ok else None
    return out


@dataclass(frozen=True)
class PixelError:
    """The tracker against the rendered ground truth (:func:`tracking_error`)."""

    mean_px: float
    """Mean distance of the tracked centroid from the true centre's projection, pixels (NaN: none measured)."""
    p95_px: float
    """Its 95th percentile, pixels."""
    found: float
    """Share of the frames in which the object was found."""


def tracking_error(videos: Sequence[Video]) -> PixelError:
    """The tracker's pixel error against the rendered ground truth, over every measured frame of ``videos`` that
    have one (a video that cannot be tracked counts its frames as not found)."""
    errs, found, total = [], 0, 0
    for v in videos:
        if v.truth is None:
            continue
        gt = render.read_truth(v.truth)
        try:
            traj = track.detect_all(v.path, v.track_config())
        except StudyError:
            total += len(gt["t"])
            continue
        m = traj.measured
        errs.append(np.hypot(traj.u - gt["u"], traj.v - gt["v"])[m])
        found += int(m.sum())
        total += len(m)
    e = np.concatenate(errs) if errs else np.array([math.nan])
    return PixelError(float(np.mean(e)), float(np.percentile(e, 95)), found / max(total, 1))


def true_scale(rcfg: render.RenderConfig, depth: float = 4.0) -> float:
    """Metres per pixel of the rendered camera at the throw's ``depth`` (m): the scale the tracker should read."""
    return render.metres_per_pixel(render.class_model("light"), "side", rcfg.height, depth=depth)


def scale_error(tracks: Iterable[Tracked], true: float) -> float:
    """Median over the tracked videos of |scale / ``true`` - 1|: how far the scale read off the object's apparent
    size (its blob's equivalent-disc diameter) is from the true metres per pixel."""
    scales = np.array([t.trajectory.height_per_pixel for t in tracks if t.trajectory])
    return float(np.median(np.abs(scales / true - 1)))


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


@dataclass(frozen=True)
class Recommendation:
    """The Z model a camera in a car should use (:func:`recommend`), chosen on validation throws as a user's camera
    gives them, by the mean over seeds."""

    choice: str
    """The chosen candidate's name (``"positions, exact"`` and so on, :func:`candidates`): the best on
    :attr:`val_user`, the validation throws as ``study classify`` sees a user's video."""
    val: dict[str, Interval]
    """Each candidate's accuracy on the validation throws observed through the calibrated tracker and the renderer's
    camera: the mean over its seeds (each seed scored on its own validation split), with a hierarchical bootstrap
    interval over seeds and throws."""
    val_user: dict[str, Interval]
    """The same on the validation throws as a user's camera, anywhere, and one scale give them
    (``study.simulate.observe.any_camera``)."""
    models: dict[str, Ensemble]
    """Each candidate's seeds, as one classifier (the mean of their probabilities)."""

    @property
    def model(self) -> Ensemble:
        """The chosen model (its seeds' ensemble)."""
        return self.models[self.choice]


def candidates(runner: Runner, cfgs: dict[str, TrainConfig] | None = None,
               ob: observe.Observation | None = None) -> dict[str, TrainConfig]:
    """The Z models a camera could use: each of ``cfgs`` (name -> config; default: the paper's network reading
    positions at Table 1's point and reading positions and velocity at its own grid's point) trained on exact
    positions, on random observations as the calibrated tracker (or ``ob``) would see them, and on heights as a
    user's own camera anywhere gives them (``study.simulate.observe.any_camera``; names suffixed ', exact',
    ', randomised' and ', any-camera')."""
    cfgs = cfgs or {"positions": runner.table1_config(), "velocity": runner.table1_config("velocity")}
    out = {}
    for name, cfg in cfgs.items():
        z = dataclasses.replace(cfg, dims="z")
        out[f"{name}, exact"] = z
        out[f"{name}, randomised"] = calibration.randomised_config(runner, z, ob)
        out[f"{name}, any-camera"] = dataclasses.replace(out[f"{name}, randomised"], observe="any-camera")
    return out


def recommended(runner: Runner, cands: dict[str, TrainConfig], seeds: Sequence[int] = (0,),
                ob: observe.Observation | None = None) -> Recommendation:
    """Of ``cands`` (name -> config; :func:`candidates`), the one with the highest mean accuracy over ``seeds`` on
    each seed's validation trajectories as a user's camera gives them (``observe.any_camera``: what ``study classify``
    reads), each also scored as the calibrated tracker (or ``ob``) observes them (never the test split)."""
    if not seeds:
        raise ConfigError("recommended: seeds is empty; give at least one seed")
    ob = ob or calibration.observation(runner)
    first = next(iter(cands.values()))
    T, y = first.n_frames(runner.fps), runner.dataset.train.y
    correct: dict[str, list[np.ndarray]] = {k: [] for k in cands}
    correct_user: dict[str, list[np.ndarray]] = {k: [] for k in cands}
    members: dict[str, list[train.TrainedModel]] = {k: [] for k in cands}
    for seed in seeds:
        _, va = train.split_train_val(len(y), first.val_fraction, seed)
        x_val = ob.observe(runner.dataset.train.x[va, :T], runner.fps, seed=6)
        x_user = observe.any_camera(runner.dataset.train.x[va, :T], runner.fps,
                                    np.random.default_rng([seed, 7])).astype(np.float32)
        for k, c in cands.items():
            m = runner.trained(dataclasses.replace(c, dims="z", seed=seed))
            members[k].append(m)
            correct[k].append(correct_of([m], x_val, y[va])[0])
            correct_user[k].append(correct_of([m], x_user, y[va])[0])
    val = {k: hierarchical_bootstrap(c) for k, c in correct.items()}
    val_user = {k: hierarchical_bootstrap(c) for k, c in correct_user.items()}
    choice = max(val_user, key=lambda k: val_user[k].value)  # ties: the first candidate
    return Recommendation(choice, val, val_user, {k: Ensemble(tuple(ms)) for k, ms in members.items()})


def recommend(runner: Runner) -> Recommendation:
    """Of :func:`candidates` (the grid's seeds, trained together), the one with the highest mean accuracy on the
    validation throws observed as the tracker observes them (:func:`recommended`; never the test split or the
    videos), written to the data folder as the model ``study classify`` uses without ``--model``
    (``study.runs.recommended``)."""
    cands, seeds = candidates(runner), runner.preset.grid_seeds
    runner.prefetch([(runner, [dataclasses.replace(c, seed=s) for c in cands.values() for s in seeds], False)],
                    desc="candidates")
    rec = recommended(runner, cands, seeds)
    dirs = [records.model_dir(runner.dataset, dataclasses.replace(cands[rec.choice], dims="z", seed=s), runner.data_dir,
                              runner.device) for s in seeds]
    # study classify's default model
    saved.save(runner.data_dir, rec.choice, dirs, rec.val_user[rec.choice], runner.preset.name)
    return rec


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


# ---------------------------------------------------------------------------------------------
# The camera sweep: a camera nobody measured (study.methods.sweep, study.methods.camera_cost)

PATH_KEYS: dict[str, PathKey] = {paths.EXACT: paths.EXACT, **{p.words: p.key for p in paths.PATHS}}
"""Each path's name in the tables -> its key in the results file."""


@dataclass(frozen=True)
class CameraSweep:
    """Held-aside throws filmed from cameras the study never saw, read by a user's paths and classified."""

    clips: tuple[sweep.Clip, ...]
    """The clips, family by family."""
    measured: dict[str, camera_cost.Measured]
    """Candidate name -> its seeds on every path (the recommended one among them)."""
    choice: str
    """The recommended candidate's name."""
    floors: dict[str, camera_cost.Floor]
    """Group -> the one-scale floor (true and tracked image rows)."""
    drag: dict[str, Interval]
    """Path -> the drag rule's accuracy on the clips."""
    size_error: float
    """Median relative error of one frame's blob diameter (:func:`study.methods.camera_cost.size_error`)."""
    render_s: tuple[float, float, int]
    """CPU seconds and wall seconds the clips took to render, and how many clips' times were recorded."""

    @property
    def recommended(self) -> camera_cost.Measured:
        return self.measured[self.choice]

    def clips_in(self, group: str) -> int:
        """Clips in ``group`` ('all' or a camera family)."""
        return sum(group in ("all", c.shot.family) for c in self.clips)


def camera_sweep(runner: Runner, rec: Recommendation, progress: bool = False) -> CameraSweep:
    """The camera sweep on ``runner``'s preset (``preset.sweep_per_family`` clips a family, rendered once and
    cached): every clip tracked once, turned into heights by every path, classified by every candidate of ``rec``
    (its seeds), and the drag rule's threshold from the training throws applied to each path's heights."""
    p, cfg = runner.preset, runner.synth_config
    clips = sweep.sweep_set(cfg, per_family=p.sweep_per_family, seed=sweep.SWEEP_SEED,
                            out_dir=runner.data_dir / "realworld", progress=progress,
                            frame_scale=p.sweep_frame_scale, duration=p.length)
    shape = camera_cost.shape_of(cfg)
    tracked = camera_cost.track_clips(clips, shape, progress=progress)
    reads: dict[tuple[float, int], tuple[dict[str, np.ndarray], dict[str, np.ndarray]]] = {}

    def read(m: Model) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray]]:  # the candidates share one input
        if (m.fps, m.n_frames) not in reads:
            reads[m.fps, m.n_frames] = camera_cost.inputs(clips, tracked, m.fps, m.n_frames)
        return reads[m.fps, m.n_frames]

    measured = {name: camera_cost.measure(ens.members, clips, tracked, read(ens.members[0]))
                for name, ens in rec.models.items()}
    first = rec.model.members[0]
    fps, n = first.fps, first.n_frames
    contact = cfg.shape.bounding_radius
    ds = runner.dataset
    f_train = measure.fall_acceleration(ds.train.x[:, : round(n * ds.fps / fps), 2], ds.fps, contact)
    drag = camera_cost.drag_rule(f_train, ds.train.y, clips, read(first)[0], fps, contact)
    times = sweep.render_times(clips)
    cpu, wall = (sum(t[k] for t in times.values()) for k in ("cpu_s", "wall_s"))
    return CameraSweep(tuple(clips), measured, rec.choice, camera_cost.floors(clips, tracked), drag,
                       camera_cost.size_error(clips, tracked, shape), (cpu, wall, len(times)))


def _sweep_numbers(cs: CameraSweep) -> Sweep:
    groups: dict[str, SweepGroup] = {}
    for g, rows in cs.recommended.results.items():
        by_path = {PATH_KEYS[k]: SweepPath(
            number(r.accuracy, f"camera sweep ({g}): recommended model's accuracy, heights {k}"),
            None if math.isnan(r.rms_centred_mm) else
            number(r.rms_centred_mm, f"camera sweep ({g}): height error after each clip's median, {k}", unit="mm"),
            None if r.cost is None else number(r.cost, f"camera sweep ({g}): exact heights' accuracy minus {k}'s",
                                               signed=True))
            for k, r in rows.items()}
        groups[g] = SweepGroup(count(cs.clips_in(g), f"camera sweep ({g}): clips"),
                               number(1000 * cs.floors[g].true_rows if g in cs.floors else math.nan,
                                      f"camera sweep ({g}): least one-scale height error", unit="mm"), by_path)
    drag = {PATH_KEYS[k]: number(iv, f"camera sweep: drag rule's accuracy, heights {k}") for k, iv in cs.drag.items()}
    cpu, _, timed = cs.render_s
    return Sweep(groups, drag, number(cs.size_error, "camera sweep: median relative error of a frame's blob size"),  # type: ignore[arg-type]
                 number(cpu, "camera sweep: CPU seconds to render the clips", unit="s") if timed == len(cs.clips)
                 else None)


def _sweep_table(cs: CameraSweep) -> Table:
    """The recommended model per camera family: accuracy on the exact heights and by each path, with the
    camera's cost."""
    rows = []
    for g, res in cs.recommended.results.items():
        row = {"group": g, "clips": cs.clips_in(g),
               "exact": pct_ci(res["exact"].accuracy)}
        for k in camera_cost.PATHS:
            r = res[k]
            row[k] = f"{pct(r.accuracy.value)} (cost {points(r.cost)})" + (f", {r.no_heights} without" if r.no_heights else "")
        rows.append(row)
    return Table(rows, {"group": "cameras", "clips": "clips", "exact": "exact heights [95 % CI]",
                        **{k: f"{k} (exact minus it, points [95 % CI])" for k in camera_cost.PATHS}})


def _heights_table(cs: CameraSweep) -> Table:
    """Height error per camera family and path, and the one-scale floor."""
    rows = []
    for g, res in cs.recommended.results.items():
        fl = cs.floors.get(g)
        row = {"group": g, "floor": "—" if fl is None else f"{1000 * fl.true_rows:.0f}",
               "tracked": "—" if fl is None else f"{1000 * fl.tracked_rows:.0f}"}
        row |= {k: "—" if math.isnan(res[k].rms_mm) else f"{res[k].rms_centred_mm:.0f} ({res[k].rms_mm:.0f})"
                for k in camera_cost.PATHS}
        rows.append(row)
    return Table(rows, {"group": "cameras", "floor": "one-scale floor, true rows (mm)",
                        "tracked": "the same, tracked rows (mm)",
                        **{k: f"{k}: mm RMS, median removed (raw)" for k in camera_cost.PATHS}})


def _candidates_sweep_table(cs: CameraSweep) -> Table:
    """Every candidate on the sweep, pooled: exact heights against the default path."""
    default = camera_cost.DEFAULT_PATH
    rows = []
    for name, m in cs.measured.items():
        r = m.results["all"]
        best = max(camera_cost.PATHS, key=lambda k: r[k].accuracy.value)
        rows.append({"model": name + (" ✓" if name == cs.choice else ""), "exact": pct_ci(r["exact"].accuracy),
                     "user": pct_ci(r[default].accuracy), "cost": points(r[default].cost),
                     "best": f"{best}: {pct(r[best].accuracy.value)}"})
    return Table(rows, {"model": "candidate (✓ recommended)", "exact": "exact heights [95 % CI]",
                        "user": f"user's default path ({default}) [95 % CI]", "cost": "camera's cost, points [95 % CI]",
                        "best": "best path"})


def _render_heights_table(render_heights: dict[str, tuple[float, float]], cs: CameraSweep) -> Table:
    """Each path's height error (median removed, raw in brackets), on the book's renders and on the sweep."""
    def mm(pair: tuple[float, float]) -> str:
        return "—" if math.isnan(pair[0]) else f"{pair[1]:.0f} ({pair[0]:.0f})"

    sweep_all = cs.recommended.results["all"]
    rows = [{"path": k + (" (default)" if k == camera_cost.DEFAULT_PATH else ""), "book": mm(render_heights[k]),
             "sweep": mm((sweep_all[k].rms_mm, sweep_all[k].rms_centred_mm))} for k in camera_cost.PATHS]
    return Table(rows, {"path": "path", "book": "the book's renders: mm RMS, median removed (raw)",
                        "sweep": "the camera sweep: the same"})


def _drag_table(cs: CameraSweep) -> Table:
    rows = [{"path": k, "acc": pct_ci(iv)} for k, iv in cs.drag.items()]
    return Table(rows, {"path": "heights", "acc": "drag rule's accuracy on the sweep [95 % CI]"})


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
    camera: CameraSweep
    """The camera sweep."""
    sweep_acc_table: Table
    """The recommended model per camera family, exact heights and each path."""
    sweep_heights_table: Table
    """Height error per camera family and path, and the one-scale floor."""
    sweep_models_table: Table
    """Every candidate on the sweep, pooled."""
    drag_table: Table
    """The drag rule on the sweep's heights, by path."""
    heights_table: Table
    """Each path's height error on the book's renders and on the camera sweep, pooled."""
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
    def sweep_words(self) -> str:
        """The camera sweep's answer in one sentence: the recommended model's accuracy on exact heights and by
        the default path, pooled, and the family where the camera costs most."""
        res = self.camera.recommended.results
        default = camera_cost.DEFAULT_PATH
        worst = max((g for g in res if g != "all"), key=lambda g: res[g][default].cost.value)
        a = res["all"]
        return (f"On {len(self.camera.clips)} clips from cameras the study never saw, the recommended model labels "
                f"{pct_ci(a['exact'].accuracy)} of the throws right from their exact heights and "
                f"{pct_ci(a[default].accuracy)} from a user's path ({default}): the camera costs "
                f"{points(a[default].cost)}, most from the {worst} cameras ({points(res[worst][default].cost)})")

    @property
    def drag_words(self) -> str:
        """Whether the drag cue survives a user's camera: the drag rule's interval on each path against chance."""
        d = self.camera.drag
        default = camera_cost.DEFAULT_PATH
        at_chance = [k for k in camera_cost.PATHS if d[k].lo <= 0.5]
        verdict = ("it does not survive: on " + ", ".join(at_chance) + " heights the rule's interval holds chance"
                   if at_chance else "it survives every path (each interval above chance)")
        return (f"the drag rule (one threshold on the first fall's acceleration, set on the training throws) gets "
                f"{pct_ci(d['exact'])} of the sweep's throws from their exact heights and {pct_ci(d[default])} "
                f"from the {default} path; {verdict}")

    @property
    def default_words(self) -> str:
        """Which path a user should take: the best path's paired difference against the default."""
        m = self.camera.recommended
        res = m.results["all"]
        default = camera_cost.DEFAULT_PATH
        best = max(camera_cost.PATHS, key=lambda k: res[k].accuracy.value)
        if best == default:
            return f"the default ({default}) is also the most accurate path on the sweep"
        diff = m.difference(best, default)
        if diff.lo <= 0 <= diff.hi:
            return (f"the most accurate path, {best}, beats the default ({default}) by {points(diff)}, an "
                    f"interval that holds 0: the paths cannot be told apart on these clips, and the default stays")
        return (f"the most accurate path, {best}, beats the default ({default}) by {points(diff)}, an "
                f"interval clear of 0: `study classify --scale-from` should default to it")

    @property
    def size_words(self) -> str:
        """How far one frame's apparent size says where the object is."""
        return pct(self.camera.size_error)

    @property
    def depth_words(self) -> str:
        """What one frame's size error is in depth, at the sweep's median camera distance."""
        d = float(np.median([c.shot.distance for c in self.camera.clips]))
        return (f"{pct(self.camera.size_error)} of the median camera distance, {d:.1f} m, is "
                f"{100 * self.camera.size_error * d:.0f} cm of depth")

    @property
    def floor_words(self) -> str:
        """Whether the tracker's rows reach the one-scale floor the true rows do."""
        f = self.camera.floors.get("all")
        if f is None:
            return "no clip was tracked"
        close = f.tracked_rows <= f.true_rows + 0.005
        return (f"the best line through the tracker's rows is {1000 * f.tracked_rows:.0f} mm against "
                f"{1000 * f.true_rows:.0f} mm through the true ones: "
                + ("the tracker is not what limits the heights" if close else
                   "the tracker adds to the floor"))

    @property
    def models_words(self) -> str:
        """The camera's cost to each candidate, by how it was trained."""
        default = camera_cost.DEFAULT_PATH
        parts = [f"{name} {points(m.results['all'][default].cost)}" for name, m in self.camera.measured.items()]
        return "the camera's cost in points, exact heights minus the default path: " + "; ".join(parts)

    @property
    def render_words(self) -> str:
        cpu, wall, timed = self.camera.render_s
        n = len(self.camera.clips)
        if not timed:
            return f"the {n} clips' rendering times were not recorded (rendered before they were kept)"
        return (f"rendering the {n} clips took {cpu / 60:.1f} CPU-minutes ({wall / 60:.1f} minutes of wall time"
                f"{'' if timed == n else f', for the {timed} clips timed'}), once: they are cached by key")

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
    labels = {key: (classify(m, rendered, tracks_r, progress=False), classify(m, real, tracks_q, progress=False))
              for key, (_, m) in models.items()}
    shape = camera_cost.shape_of(runner.synth_config)
    on_renders = [camera_cost.video_heights(v, shape) for v in rendered]  # each tracked once, read every way
    tracks_u = user_tracks(rendered, on_renders)
    render_heights = camera_cost.height_errors(on_renders)
    user = {key: classify(m, rendered, tracks_u, progress=False) for key, (_, m) in models.items()}
    tracks_x = truth_tracks(rendered)
    exact = {key: classify(m, rendered, tracks_x, progress=False) for key, (_, m) in models.items()}
    cs = camera_sweep(runner, rec)
    numbers = reported(rec, {key: (models[key][0], *labels[key]) for key in models}, user, cs, exact, objects)
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
        user_table=_user_table({models[k][0]: (exact[k], labels[k][0], user[k]) for k in models}), camera=cs,
        sweep_acc_table=_sweep_table(cs), sweep_heights_table=_heights_table(cs),
        sweep_models_table=_candidates_sweep_table(cs), drag_table=_drag_table(cs),
        heights_table=_render_heights_table(render_heights, cs), real_objects=objects,
        real_found=real_found if real_found is not None else len(real))


def reported(rec: Recommendation, labels: dict[ModelKey, tuple[str, Sequence[Label], Sequence[Label]]],
             user: dict[ModelKey, Sequence[Label]] | None = None, cs: CameraSweep | None = None,
             exact: dict[ModelKey, Sequence[Label]] | None = None, objects: str = REAL_OBJECTS) -> Numbers:
    """What the chapter reports: each candidate's validation accuracy (``rec``), the paper's figures judged,
    each model's accuracy per class from its ``labels`` (model key -> (its name, its labels of the rendered
    videos, of the real clips)), its labels of the rendered videos on a user's path (``user``), and the camera
    sweep (``cs``)."""
    judged = _figures(objects)
    why = verdicts.not_comparable(WHY_NOT_COMPARABLE["rendered"])

    def per_class(got: dict[ModelKey, Sequence[Label]] | None, how: str) -> dict[ModelKey, dict[Class, Number]]:
        return {key: {c: number(iv, f"rendered {c} videos classified correctly {how}, {labels[key][0]}",  # type: ignore[misc]
                                paper=paper.REAL_WORLD[c], decision=why)
                      for c, iv in per_class_interval(ls).items() if iv is not None}
                for key, ls in (got or {}).items()}

    return Numbers(_candidates(rec), judged["figure1"], judged["figure5"], judged["figure6"],
                   {key: _classified(name, rendered, real, objects) for key, (name, rendered, real) in labels.items()},
                   per_class(user, "on a user's path"), per_class(exact, "from their exact heights"),
                   None if cs is None else _sweep_numbers(cs))


def _candidates(rec: Recommendation) -> dict[Inputs, dict[Training, Candidate]]:
    out: dict[str, dict[str, Candidate]] = {}
    for name, iv in rec.val.items():
        inputs, training = name.split(", ")  # "positions, exact" (candidates)
        out.setdefault(inputs, {})[training] = Candidate(
            number(iv, f"validation accuracy under the calibrated observation, {name}"),
            number(rec.val_user[name], f"validation accuracy as a user's camera gives the throws, {name}"))
    return out  # type: ignore[return-value]


# ---------------------------------------------------------------------------------------------
# The tables


def _val_table(rec: Recommendation) -> Table:
    rows = [{"model": n, "val": pct_ci(iv), "user": pct_ci(rec.val_user[n]), "chosen": "✓" if n == rec.choice else ""}
            for n, iv in rec.val.items()]
    return Table(rows, {"model": "candidate (Z)", "val": "validation, calibrated tracker [95 % CI]",
                        "user": "validation, a user's camera (chooses) [95 % CI]", "chosen": "chosen"})


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


def _user_table(models: dict[str, tuple[Sequence[Label], Sequence[Label], Sequence[Label]]]) -> Table:
    """Each model (by name: its labels of the rendered videos from their exact heights, by the renderer's camera,
    and by a user's path) per class, with the videos right as counts."""
    rows = []
    for name, labels in models.items():
        ivs = [per_class_interval(got) for got in labels]
        for c in CLASSES:
            row = {"model": name, "class": c}
            for key, got, iv in zip(("exact", "known", "user"), labels, ivs):
                right, n = sum(r.correct for r in got if r.label == c), sum(r.label == c for r in got)
                row[key] = f"{right} / {n}, {_pct_ci(iv[c])}"
            rows.append(row)
    return Table(rows, {"model": "model", "class": "class", "exact": "exact heights (the renderer's truth)",
                        "known": "the renderer's camera", "user": "a user's path, no camera"})


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
