"""What a user's camera costs the answer: the sweep's clips (``study.methods.sweep``) tracked and turned into
heights by each path a user without a calibrated camera has, classified, beside the same throws' exact heights.

A path reads only the video and what a user knows (the object's colour, shape and size):

- ``rest size``: one scale, the object's size over its blob's diameter at rest (``study.see.gaps.set_scale``:
  today's ``study classify VIDEO --object-size``), the ground at the lowest centre position;
- ``mean silhouette``: one scale, the object's mean-silhouette size (``study.see.size.apparent_size``) over the
  blob's root-mean-square diameter over every measured frame (a tumbling box shows every side on average);
- ``gravity``: one scale, g over the free flights' image curvature (``study.see.scale.gravity_scale``), the ground
  at the lowest centre position;
- ``geometry``: the camera's tilt, height and focal length fitted with gravity as the ruler
  (``study.see.geometry.recover``);
- ``floor marks``: the camera from marks a user taped on the floor around the throw (``study.see.marklayout.LAYOUT``
  about its middle, their pixels as a careful click gives them: the camera's projection plus :data:`CLICK_PX` of
  noise), then each frame's centre through it (``study.see.floor``: ``study classify --floor FLOOR.csv``);
- ``floor marks found`` (beside, where the marks were drawn: the sweep's clips): the same with the marks' pixels
  found in the video by their colour (``study.see.marks``: ``study classify --floor MARKS.csv``).

The exact path classifies the renderer's true heights: the camera's cost is the exact path's accuracy minus a
user path's, on the same clips and seeds (a paired bootstrap). A clip a path cannot turn into heights (the object
lost, no free flight) gets no answer and counts as a miss; :class:`PathResult` says how many.
"""

from __future__ import annotations

import math
import zlib
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace

import numpy as np

from study.core.errors import ConfigError, StudyError
from study.core.progress import Progress
from study.learn.metrics import Interval, bootstrap_accuracy, bootstrap_difference
from study.methods import sweep
from study.methods.sweep import Clip
from study.methods.videos import Video
from study.runs.stats import correct_of
from study.see import floor, geometry, marklayout, marks, paths, render, track
from study.see.camera import Camera
from study.see.gaps import set_camera, set_scale
from study.see.scale import DEFAULT, ObjectShape, read_scale
from study.see.trajectory import Trajectory
from study.simulate import measure as motion

PATHS: tuple[str, ...] = tuple(p.words for p in paths.PATHS if not p.found)
"""The user's paths from pixels to metres by their words, in the order the tables show them (``study.see.paths``):
those measured on every clip (the marks found by colour are :data:`FOUND`)."""
KNOWN = paths.KNOWN_WORDS
"""The tracker's pixels through the clip's own camera at each frame's true depth (``study.see.gaps.set_camera``):
what a path that knows the camera, as the floor path does, could reach at best; measured where the camera is known."""
FOUND = next(p.words for p in paths.PATHS if p.found)
"""The floor path with its marks found in the video by their colour: measured on clips whose marks were drawn."""
MEASURED: tuple[str, ...] = (KNOWN, *PATHS, FOUND)
"""Every way a clip's tracked pixels become heights: the known camera's, the user's paths, the floor path with its
marks found."""
FLOOR_PATH = next(p.words for p in paths.PATHS if p.floor and not p.found)
"""The path through floor marks (it needs the clip's camera to place the marks)."""
CLICK_PX = 1.0
"""A careful click's error on a mark, pixels (standard deviation, each coordinate)."""


def shape_of(cfg) -> ObjectShape:
    """The :class:`~study.see.scale.ObjectShape` of a ``synth.SynthConfig``'s object (its ``shape`` holds
    half-sizes)."""
    full = tuple(2 * float(s) for s in cfg.shape.size)
    n = {"box": 3, "sphere": 1}.get(cfg.shape.kind, 2)
    return ObjectShape(cfg.shape.kind, full[:n])


def _one_scale(how: str) -> Callable[[Trajectory, ObjectShape], Trajectory]:
    def scaled(traj: Trajectory, shape: ObjectShape) -> Trajectory:
        return set_scale(traj, metres_per_pixel=read_scale(traj, shape, how).metres_per_pixel)

    return scaled


def _geometry(traj: Trajectory, shape: ObjectShape) -> Trajectory:
    z, _ = geometry.recover(traj.t, traj.u, traj.v, traj.diameter, traj.width, traj.height_px, shape.mean_size(),
                            0.0, source=traj.source)
    return replace(traj, z=z, ground_z=0.0, units="m")


ONE_SCALE: dict[str, str] = {p.words: p.key for p in paths.PATHS if p.one_scale}
"""The one-scale paths -> how each reads its scale (``study.see.scale.SCALE_FROM``)."""
DEFAULT_PATH = next(name for name, how in ONE_SCALE.items() if how == DEFAULT)
"""The path ``study classify VIDEO`` takes unless told otherwise (``study.see.scale.DEFAULT``)."""
SCALE: dict[str, Callable[[Trajectory, ObjectShape], Trajectory]] = {
    **{name: _one_scale(how) for name, how in ONE_SCALE.items()}, "geometry": _geometry}
"""Each path: a pixel trajectory and the object's shape -> the trajectory with heights in metres."""


@dataclass(frozen=True)
class Heights:
    """One clip's centre heights above its rest height, metres, frame by frame (NaN where a path has none)."""

    exact: np.ndarray
    """(n,) the renderer's truth."""
    paths: dict[str, np.ndarray | str]
    """Path name -> (n,) its heights, or why it has none."""
    tracks: dict[str, Trajectory]
    """Path name -> the trajectory its heights came from (what the model reads)."""


def heights(clip: Clip, shape: ObjectShape) -> Heights:
    """Track ``clip`` once (pixels) and turn it into heights through the clip's own camera (:data:`KNOWN`) and by
    every path of :data:`PATHS`, for an object of ``shape`` (the floor path through marks placed by the clip's
    camera)."""
    return video_heights(clip.video, shape, lambda world: sweep.camera(clip.shot, world), drawn=True)


def clicked_floor(camera: Camera, path: np.ndarray, name: str) -> floor.Floor:
    """The floor marks a user would tape about a throw whose centre follows ``path`` (n, 3) metres
    (``study.methods.sweep.marks_about``) as ``camera`` sees them and a careful click gives them (:data:`CLICK_PX` of
    noise, seeded by the clip's ``name``): those in the picture."""
    return floor.seen(camera, sweep.marks_about(path), CLICK_PX, zlib.crc32(name.encode()), name)


def found_floor(v: Video, path: np.ndarray) -> floor.Floor:
    """The floor marks drawn about a throw whose centre follows ``path`` (n, 3) metres (``sweep.marks_about``),
    their pixels found in the video ``v`` by their colour and paired with their positions (``study.see.marks``)."""
    return marks.located(floor.Floor(np.full((len(marklayout.LAYOUT), 2), np.nan), sweep.marks_about(path)), v.path)


def video_heights(v: Video, shape: ObjectShape, camera: Callable[[np.ndarray], Camera] | None = None,
                  drawn: bool = False) -> Heights:
    """:func:`heights` of any rendered video (one with ground truth); the floor path only where ``camera`` gives
    the video's camera from its true centres (n, 3) metres (the sweep's depends on the throw), with its marks found
    by colour only where they were ``drawn`` (``study.methods.marked``)."""
    truth = render.read_truth(v.truth)
    world = np.column_stack([truth["x"], truth["y"], truth["z"]])
    rest = v.rest_height
    exact = truth["z"] - rest
    paths: dict[str, np.ndarray | str] = {}
    tracks: dict[str, Trajectory] = {}
    try:
        px = track.track_video(v.path, v.track_config())
    except StudyError as e:
        return Heights(exact, dict.fromkeys(MEASURED, str(e)), {})

    def read(name: str) -> Trajectory:
        """The tracked pixels in metres by ``name`` (one of :data:`MEASURED`)."""
        if name in SCALE:
            return SCALE[name](px, shape)
        if camera is None:
            raise ConfigError("no camera: the video's camera is not known")
        if name == KNOWN:  # the camera at the video's own size (an odd frame size is written one pixel narrower)
            own = camera(world)
            cam = replace(own, width=px.width or own.width, height=px.height_px or own.height)
            depth = cam.depth_of(world)
            depth = np.concatenate([depth, np.full(max(0, len(px.t) - len(depth)), depth[-1])])[: len(px.t)]
            return set_camera(px, cam, depth, rest)
        if name == FLOOR_PATH:
            marks = clicked_floor(camera(world), world, v.path.name)
        elif drawn:
            marks = found_floor(v, world)
        else:
            raise ConfigError("no floor marks drawn in the video")
        return floor.on_floor(px, marks, rest, shape.mean_size(), floor.contact_height(shape))[0]

    for name in MEASURED:
        try:
            t = read(name)
        except StudyError as e:
            paths[name] = str(e)
            continue
        tracks[name] = t
        paths[name] = _padded(np.where(t.status > 0, t.height, np.nan), len(exact))
    return Heights(exact, paths, tracks)


def _padded(h: np.ndarray, n: int) -> np.ndarray:
    """(n,) the first ``n`` of ``h``, NaN beyond its end."""
    return h[:n] if len(h) >= n else np.pad(h, (0, n - len(h)), constant_values=np.nan)


def truth_trajectory(video: Video, fps: float | None = None) -> Trajectory:
    """A rendered video's true centre as a trajectory in metres (every frame measured, its heights exact): what a
    perfect tracker and camera would give. ``fps``: the video's frame rate (None: from the truth's times)."""
    truth = render.read_truth(video.truth)
    n = len(truth["t"])
    rate = fps if fps is not None else float(1 / np.median(np.diff(truth["t"])))
    return Trajectory(t=truth["t"], u=truth["u"], v=truth["v"], status=np.ones(n, np.int8),
                      segment=np.zeros(n, np.int32), confidence=np.ones(n), diameter=np.full(n, np.nan),
                      fps=rate, source=video.truth, units="m", z=truth["z"], ground_z=video.rest_height)


def exact_input(clip: Clip, fps: float, n_frames: int) -> np.ndarray:
    """(n_frames, 3) float32: the clip's true centre heights as the model reads them (z only), resampled to
    ``fps``, metres."""
    traj = truth_trajectory(clip.video, clip.shot.fps)
    return track.to_model_input(traj, fps, n_frames, rest_height=clip.video.rest_height)


def line_rms(v: np.ndarray, z: np.ndarray) -> float:
    """Root-mean-square error, in ``z``'s units, of the best line ``z ~ a v + b`` (least squares over the frames where
    both are finite): the least error of one scale ``a`` and one ground row."""
    m = np.isfinite(v) & np.isfinite(z)
    line = np.stack([v[m], np.ones(int(m.sum()))], axis=1)
    fit = np.linalg.lstsq(line, z[m], rcond=None)[0]
    return float(np.sqrt(np.mean((line @ fit - z[m]) ** 2)))


def one_scale_floor(clip: Clip) -> float:
    """The least height error, metres RMS, any one-scale path can reach on ``clip``: its true heights against the
    best line through its true image rows (one scale and one ground row, fitted with hindsight). What is left is the
    camera's mixing of height with distance: an object that slides or bounces towards a camera above the floor
    moves down the picture as if it fell, and one scale cannot undo that."""
    truth = render.read_truth(clip.video.truth)
    return line_rms(truth["v"], truth["z"] - clip.video.rest_height)


@dataclass(frozen=True)
class Floor:
    """Where a one-scale path's height error comes from, on a group of clips (metres RMS, pooled over clips)."""

    true_rows: float
    """:func:`one_scale_floor`: the camera's own limit, with the true image rows."""
    tracked_rows: float
    """The same with the tracker's rows: the limit plus what the tracker adds."""
    clips: int
    """Clips tracked."""


def resolution(clip: Clip) -> str:
    """A clip's frame height as a group's name: ``"480p"``, ``"720p"``."""
    return f"{clip.shot.height_px}p"


def groups_of(clip: Clip) -> tuple[str, str, str]:
    """The groups a clip's results are pooled in: 'all', its camera family and its :func:`resolution`."""
    return ("all", clip.shot.family, resolution(clip))


def floors(clips: Sequence[Clip], tracked: Sequence[Heights]) -> dict[str, Floor]:
    """:class:`Floor` for every clip tracked (each group of :func:`groups_of`, as :func:`measure`), from each clip's
    :func:`heights` (``tracked``, in the order of ``clips``: the tracking :func:`measure` already did)."""
    rows: dict[str, list[tuple[float, float]]] = {"all": []}
    for clip, h in zip(clips, tracked, strict=True):
        if not h.tracks:
            continue
        t = next(iter(h.tracks.values()))
        n = min(len(t.v), len(h.exact))
        pair = (one_scale_floor(clip), line_rms(np.where(t.status[:n] > 0, t.v[:n], np.nan), h.exact[:n]))
        for g in groups_of(clip):
            rows.setdefault(g, []).append(pair)
    return {g: Floor(*np.sqrt(np.mean(np.square(r), axis=0)).tolist(), len(r)) for g, r in rows.items()}


def path_errors(h: Heights, path: str) -> np.ndarray:
    """(frames,) one video's height error by ``path`` on every frame it has a height for, metres."""
    got = h.paths[path]
    return np.array([]) if isinstance(got, str) else (got - h.exact)[np.isfinite(got)]


def rms_mm(errors: Sequence[np.ndarray]) -> tuple[float, float]:
    """(root-mean-square over every frame, the same after removing each video's median error), millimetres, of
    several videos' height errors (NaN for none)."""
    e = [x for x in errors if len(x)]
    if not e:
        return math.nan, math.nan
    raw, centred = np.concatenate(e), np.concatenate([x - np.median(x) for x in e])
    return 1000 * float(np.sqrt(np.mean(raw**2))), 1000 * float(np.sqrt(np.mean(centred**2)))


def height_errors(tracked: Sequence[Heights]) -> dict[str, tuple[float, float]]:
    """Each way's height error over ``tracked`` videos (:data:`MEASURED`; NaN where none had heights): way ->
    :func:`rms_mm` (raw, median removed), mm."""
    return {k: rms_mm([path_errors(h, k) for h in tracked]) for k in MEASURED}


@dataclass(frozen=True)
class PathResult:
    """One path on a group of clips."""

    accuracy: Interval
    """Accuracy over the clips and the model's seeds (a clip without heights is a miss)."""
    cost: Interval | None
    """The exact path's accuracy minus this one's, paired over clips and seeds (None for the exact path)."""
    rms_mm: float
    """Root-mean-square height error over every frame with a height, millimetres."""
    rms_centred_mm: float
    """The same after removing each clip's median error (what one offset cannot fix), millimetres."""
    no_heights: int
    """Clips the path could not turn into heights."""
    answered: Interval | None = None
    """Accuracy over the clips the path did turn into heights and the model's seeds: what an answer the path gave
    can be trusted to (None: it turned none)."""


def track_clips(clips: Sequence[Clip], shape: ObjectShape, progress: bool = True) -> list[Heights]:
    """:func:`heights` of every clip, in order: each clip tracked once, for every model and rule to read."""
    out = []
    with Progress("track the camera sweep", total=len(clips), show=progress, unit="clip") as bar:
        for clip in clips:
            out.append(heights(clip, shape))
            bar.update()
    return out


def inputs(clips: Sequence[Clip], tracked: Sequence[Heights], fps: float, n_frames: int
           ) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray]]:
    """What a model reads of every clip by every path: (path -> (n_clips, n_frames, 3) float32 metres, path ->
    (n_clips,) bool, the clips the path has no heights for, whose rows are zeros)."""
    names = ("exact", *MEASURED)
    x = {k: np.zeros((len(clips), n_frames, 3), np.float32) for k in names}
    missing = {k: np.zeros(len(clips), bool) for k in names}
    for i, (clip, h) in enumerate(zip(clips, tracked, strict=True)):
        x["exact"][i] = exact_input(clip, fps, n_frames)
        for k in MEASURED:
            if isinstance(h.paths[k], str):
                missing[k][i] = True
                continue
            try:
                x[k][i] = track.to_model_input(h.tracks[k], fps, n_frames, rest_height=clip.video.rest_height)
            except StudyError:
                missing[k][i] = True
    return x, missing


@dataclass(frozen=True)
class Measured:
    """One model (the seeds of one configuration) on the sweep, by every path."""

    results: dict[str, dict[str, PathResult]]
    """Group ('all', each family, each resolution: :func:`groups_of`) -> path ('exact' and :data:`PATHS`) ->
    :class:`PathResult`."""
    correct: dict[str, np.ndarray]
    """Path -> (seeds, clips) bool: which seed labelled which clip right."""
    groups: tuple[tuple[str, ...], ...]
    """Each clip's groups (:func:`groups_of`), in order."""

    def difference(self, a: str, b: str, group: str = "all") -> Interval:
        """Path ``a``'s accuracy minus path ``b``'s on ``group``'s clips, paired over clips and seeds."""
        sel = np.array([group in gs for gs in self.groups])
        return bootstrap_difference(self.correct[a][:, sel], self.correct[b][:, sel])


def measure(members: Sequence, clips: Sequence[Clip], tracked: Sequence[Heights],
            read: tuple[dict[str, np.ndarray], dict[str, np.ndarray]] | None = None) -> Measured:
    """Every path on ``clips`` (their :func:`track_clips`, ``tracked``) classified by each of ``members`` (trained
    'z' models: the seeds of one configuration, each with ``predict_proba``, ``fps`` and ``n_frames``). ``read``:
    the clips' :func:`inputs` at the members' rate and length, if already made (several models share them)."""
    first = members[0]
    x, missing = read if read is not None else inputs(clips, tracked, first.fps, first.n_frames)
    y = np.array([c.video.label == "heavy" for c in clips])
    correct = {k: correct_of(members, xk, y) & ~missing[k] for k, xk in x.items()}
    errors = {"exact": [np.zeros(1)] * len(clips), **{k: [path_errors(h, k) for h in tracked] for k in MEASURED}}
    groups = tuple(groups_of(c) for c in clips)
    out: dict[str, dict[str, PathResult]] = {}
    sizes = sorted({gs[2] for gs in groups}, key=lambda r: int(r[:-1]))  # by frame height
    for g in ("all", *dict.fromkeys(gs[1] for gs in groups), *sizes):
        sel = np.array([g in gs for gs in groups])
        out[g] = {}
        for k in x:
            raw, centred = rms_mm([errors[k][i] for i in np.flatnonzero(sel)])
            seen = sel & ~missing[k]
            out[g][k] = PathResult(
                bootstrap_accuracy(correct[k][:, sel]),
                None if k == "exact" else bootstrap_difference(correct["exact"][:, sel], correct[k][:, sel]),
                raw, centred, int(missing[k][sel].sum()), bootstrap_accuracy(correct[k][:, seen]) if seen.any() else None)
    return Measured(out, correct, groups)


def drag_rule(f_train: np.ndarray, y_train: np.ndarray, clips: Sequence[Clip], x: dict[str, np.ndarray],
              fps: float, contact_height: float) -> dict[str, Interval]:
    """The drag rule (one threshold on the first fall's vertical acceleration, ``study.simulate.measure``), its
    threshold chosen on the training throws' exact accelerations ``f_train`` (n,) m/s^2 with labels ``y_train``
    (n,), scored on ``clips`` read by each path (and exactly) at ``fps`` (``x``: their :func:`inputs`): path ->
    accuracy over the clips. A clip without heights gets the training median's label."""
    y = np.array([c.video.label == "heavy" for c in clips], int)
    out = {}
    for k, xk in x.items():
        f = motion.fall_acceleration(xk[..., 2], fps, contact_height)
        out[k] = bootstrap_accuracy(motion.best_threshold_rule(f_train, y_train, f, y)["correct"])
    return out


def size_error(clips: Sequence[Clip], tracked: Sequence[Heights], shape: ObjectShape) -> float:
    """Median over the clips of each clip's median relative error of the blob's diameter, frame by frame, against
    the disc of the object's mean silhouette at its true depth (``study.see.size``): how far one frame's apparent
    size says where the object is."""
    errs = []
    for clip, h in zip(clips, tracked, strict=True):
        if not h.tracks:
            continue
        t = next(iter(h.tracks.values()))
        truth = render.read_truth(clip.video.truth)
        points = np.stack([truth["x"], truth["y"], truth["z"]], axis=1)
        cam = sweep.camera(clip.shot, points)
        true_px = cam.focal * shape.mean_size() / cam.depth_of(points)
        n = min(len(true_px), len(t.diameter))
        rel = np.abs(np.where(t.status[:n] > 0, t.diameter[:n], np.nan) / true_px[:n] - 1)
        if np.isfinite(rel).any():
            errs.append(float(np.nanmedian(rel)))
    return float(np.median(errs)) if errs else math.nan
