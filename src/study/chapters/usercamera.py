"""The chapter *A camera nobody measured*: what a user's own camera leaves of the heights and of the answer.

A user has a phone, not the renderer's camera: ``study classify VIDEO --color C --object-size D`` knows the
object's colour, shape and size and nothing else. :func:`camera_sweep` films held-aside throws from randomised
cameras in the camera families (``study.simulate.observe.CAMERA_FAMILIES``; rendered once and cached,
``study.methods.sweep``), tracks each clip once, turns it into heights by every path of a user's
(``study.see.paths``, ``study.methods.camera_cost``) and classifies them by every candidate of
``study.methods.recommend``, beside the same throws' exact heights; the drag rule is read off each path's heights
too. :func:`compute` returns :class:`UserCamera`; :class:`Numbers` is what it reports, under
``usercamera.sweep.all.mean.accuracy`` and so on.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from study.learn import train
from study.learn.metrics import Interval
from study.methods import camera_cost, floor_model, sweep
from study.methods.floor_model import FloorFit
from study.methods.recommend import Recommendation, kind, recommend
from study.methods.tracked import track_clips
from study.report.reported import count, number
from study.report.text import Table, pct, pct_ci, points
from study.report.usercamera import FloorModel, Numbers, Sweep, SweepGroup, SweepKey, SweepPath
from study.see import marklayout, paths
from study.simulate import measure
from study.simulate.observe import CAMERA_FAMILIES

if TYPE_CHECKING:
    from study.runs.runner import Runner


# ---------------------------------------------------------------------------------------------
# The camera sweep: a camera nobody measured (study.methods.sweep, study.methods.camera_cost)

PATH_KEYS: dict[str, SweepKey] = {paths.EXACT: paths.EXACT, paths.KNOWN_WORDS: paths.KNOWN,
                                  **{p.words: p.key for p in paths.PATHS}}
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
    kinds: dict[str, str]
    """Candidate name -> its kind (``study.methods.recommend.kind``)."""
    floors: dict[str, camera_cost.Floor]
    """Group -> the one-scale floor (true and tracked image rows)."""
    drag: dict[str, Interval]
    """Path -> the drag rule's accuracy on the clips."""
    size_error: float
    """Median relative error of one frame's blob diameter (:func:`study.methods.camera_cost.size_error`)."""
    render_s: tuple[float, float, int]
    """CPU seconds and wall seconds the clips took to render, and how many clips' times were recorded."""
    floor_choice: str | None = None
    """The candidate recommended for the floor path (None: the floor path had no error model to train one for)."""
    floor_fit: FloorFit | None = None
    """The floor path's error model and its check (``study.methods.floor_model``; None: it could not be fitted)."""
    floor_render_cpu: float | None = None
    """CPU seconds the floor path's development clips (``floor_model.development_clips``) took to render (None:
    not every clip's time was kept, and a partial sum would understate it)."""

    @property
    def recommended(self) -> camera_cost.Measured:
        return self.measured[self.choice]

    def clips_in(self, group: str) -> int:
        """Clips in ``group`` ('all', a camera family or a frame height: ``camera_cost.groups_of``)."""
        return sum(group in camera_cost.groups_of(c) for c in self.clips)


def camera_sweep(runner: Runner, rec: Recommendation, progress: bool = False) -> CameraSweep:
    """The camera sweep on ``runner``'s preset (``preset.sweep_per_family`` clips a family, rendered once and
    cached): every clip tracked once, turned into heights by every path, classified by every candidate of ``rec``
    (its seeds), and the drag rule's threshold from the training throws applied to each path's heights."""
    p, cfg = runner.preset, runner.synth_config
    clips = sweep.sweep_set(cfg, per_family=p.sweep_per_family, seed=sweep.SWEEP_SEED,
                            out_dir=runner.data_dir / "realworld", progress=progress,
                            frame_scale=p.sweep_frame_scale, duration=p.length)
    shape = camera_cost.shape_of(cfg)
    tracked = track_clips(clips, shape, progress=progress)  # tracked once, then read back from the cache
    reads: dict[tuple[float, int], tuple[dict[str, np.ndarray], dict[str, np.ndarray]]] = {}

    def read(m: train.TrainedModel) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray]]:  # the candidates share one input
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
    kinds = {name: kind(name) for name in rec.models}
    fit = floor_model.fitted(runner, progress)  # renders the development clips where they are not yet
    return CameraSweep(tuple(clips), measured, rec.choice, kinds, camera_cost.floors(clips, tracked), drag,
                       camera_cost.size_error(clips, tracked, shape), _render_s(clips), rec.floor_choice, fit,
                       _render_cpu(floor_model.development_clips(runner)))


def _render_cpu(clips: list[sweep.Clip]) -> float | None:
    """CPU seconds ``clips`` took to render; None unless every clip's time was kept (a partial sum understates it)."""
    return _all_timed(_render_s(clips), len(clips))


def _all_timed(render_s: tuple[float, float, int], n_clips: int) -> float | None:
    """The CPU seconds of ``render_s`` (:func:`_render_s`) if it timed all ``n_clips`` clips, else None."""
    cpu, _, timed = render_s
    return cpu if timed == n_clips else None


def _render_s(clips: list[sweep.Clip]) -> tuple[float, float, int]:
    """CPU and wall seconds ``clips`` took to render, as recorded when each was made, and how many were recorded."""
    times = sweep.render_times(clips)
    return (sum(t["cpu_s"] for t in times.values()), sum(t["wall_s"] for t in times.values()), len(times))


def _sweep_numbers(cs: CameraSweep) -> Sweep:
    groups: dict[str, SweepGroup] = {}
    for g, rows in cs.recommended.results.items():
        by_path = {PATH_KEYS[k]: SweepPath(
            number(r.accuracy, f"camera sweep ({g}): recommended model's accuracy, heights {k}"),
            None if math.isnan(r.rms_centred_mm) else
            number(r.rms_centred_mm, f"camera sweep ({g}): height error after each clip's median, {k}", unit="mm"),
            None if r.cost is None else number(r.cost, f"camera sweep ({g}): exact heights' accuracy minus {k}'s",
                                               signed=True),
            None if math.isnan(r.rms_mm) else
            number(r.rms_mm, f"camera sweep ({g}): height error as it is, {k}", unit="mm"),
            None if r.cost is None else count(r.no_heights, f"camera sweep ({g}): clips without heights, {k}"))
            for k, r in rows.items()}
        groups[g] = SweepGroup(count(cs.clips_in(g), f"camera sweep ({g}): clips"),
                               number(1000 * cs.floors[g].true_rows if g in cs.floors else math.nan,
                                      f"camera sweep ({g}): least one-scale height error", unit="mm"), by_path)
    drag = {PATH_KEYS[k]: number(iv, f"camera sweep: drag rule's accuracy, heights {k}") for k, iv in cs.drag.items()}
    cpu = _all_timed(cs.render_s, len(cs.clips))
    kinds = {cs.kinds[name]: {PATH_KEYS[k]: number(r.answered, f"camera sweep: {name}'s accuracy on the clips "
                                                   f"that gave heights {k}", no_heights=r.no_heights)
                              for k, r in m.results["all"].items() if r.answered is not None}
             for name, m in cs.measured.items()}
    return Sweep(groups, drag, number(cs.size_error, "camera sweep: median relative error of a frame's blob size"),  # type: ignore[arg-type]
                 None if cpu is None else number(cpu, "camera sweep: CPU seconds to render the clips", unit="s"),
                 _floor_model_numbers(cs), kinds,
                 None if cs.floor_render_cpu is None else
                 number(cs.floor_render_cpu, "the floor path's development clips: CPU seconds to render", unit="s"))


def _floor_model_numbers(cs: CameraSweep) -> FloorModel | None:
    """The floor path's own model on the whole sweep: through the floor path, exact, the known camera, and the
    known camera's paired gain over the floor path (None: the build trained no model for the floor path)."""
    if cs.floor_choice is None:
        return None
    m = cs.measured[cs.floor_choice]
    r, floor, known = m.results["all"], camera_cost.FLOOR_PATH, camera_cost.KNOWN
    what = f"camera sweep: the floor path's model ({cs.floor_choice})"
    return FloorModel(number(r[floor].accuracy, f"{what}, through the floor path"),
                      number(r["exact"].accuracy, f"{what}, exact heights"),
                      number(r[known].accuracy, f"{what}, through the known camera") if known in r else None,
                      number(m.difference(known, floor), f"{what}: known camera minus floor path, paired",
                             signed=True) if known in r else None)


def _sweep_table(cs: CameraSweep) -> Table:
    """The recommended model per camera family: accuracy on the exact heights and by each path, with the
    camera's cost."""
    rows = []
    for g, res in cs.recommended.results.items():
        row = {"group": g, "clips": cs.clips_in(g),
               "exact": pct_ci(res["exact"].accuracy)}
        for k in _shown(res):
            r = res[k]
            row[k] = f"{pct(r.accuracy.value)} (cost {points(r.cost)})" + (f", {r.no_heights} without" if r.no_heights else "")
        rows.append(row)
    return Table(rows, {"group": "cameras", "clips": "clips", "exact": "exact heights [95 % CI]",
                        **{k: f"{k} (exact minus it, points [95 % CI])" for k in _shown(cs.recommended.results["all"])}})


def _shown(res: dict[str, camera_cost.PathResult]) -> tuple[str, ...]:
    """The ways to heights a table shows: the known camera's where it was measured, then every path."""
    return tuple(k for k in camera_cost.MEASURED if k in res)


def _heights_table(cs: CameraSweep) -> Table:
    """Height error per camera family and path, and the one-scale floor."""
    rows = []
    for g, res in cs.recommended.results.items():
        fl = cs.floors.get(g)
        row = {"group": g, "floor": "—" if fl is None else f"{1000 * fl.true_rows:.0f}",
               "tracked": "—" if fl is None else f"{1000 * fl.tracked_rows:.0f}"}
        row |= {k: "—" if math.isnan(res[k].rms_mm) else f"{res[k].rms_centred_mm:.0f} ({res[k].rms_mm:.0f})"
                for k in _shown(res)}
        rows.append(row)
    return Table(rows, {"group": "cameras", "floor": "one-scale floor, true rows (mm)",
                        "tracked": "the same, tracked rows (mm)",
                        **{k: f"{k}: mm RMS, median removed (raw)" for k in _shown(cs.recommended.results["all"])}})


def _candidates_sweep_table(cs: CameraSweep) -> Table:
    """Every candidate on the sweep, pooled: exact heights against the default path."""
    default = camera_cost.DEFAULT_PATH
    rows = []
    for name, m in cs.measured.items():
        r = m.results["all"]
        best = max(camera_cost.PATHS, key=lambda k: r[k].accuracy.value)
        mark = " ✓" if name == cs.choice else ""
        mark += " ✓ floor" if name == cs.floor_choice else ""
        rows.append({"model": name + mark, "exact": pct_ci(r["exact"].accuracy),
                     "user": pct_ci(r[default].accuracy), "cost": points(r[default].cost),
                     "best": f"{best}: {pct(r[best].accuracy.value)}"})
    return Table(rows, {"model": "candidate (✓ recommended; ✓ floor: for the floor path)", "exact": "exact heights [95 % CI]",
                        "user": f"user's default path ({default}) [95 % CI]", "cost": "camera's cost, points [95 % CI]",
                        "best": "best path"})


def _drag_table(cs: CameraSweep) -> Table:
    rows = [{"path": k, "acc": pct_ci(iv)} for k, iv in cs.drag.items()]
    return Table(rows, {"path": "heights", "acc": "drag rule's accuracy on the sweep [95 % CI]"})



# ---------------------------------------------------------------------------------------------
# The chapter's result


def _mm_off(r: camera_cost.PathResult) -> str:
    """A path's height error in words: millimetres RMS with each clip's median removed, or that it gave none."""
    return "no heights" if math.isnan(r.rms_centred_mm) else f"{r.rms_centred_mm:.0f} mm off"


@dataclass(frozen=True)
class UserCamera:
    """Everything the chapter shows: its numbers, its tables and sentences, its figures' data."""

    numbers: Numbers
    """What the chapter reports (the results file's ``usercamera.*``)."""
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

    # Sentences whose words depend on the numbers -------------------------------------------------

    @property
    def families_words(self) -> str:
        """The camera families in words, from their records (``study.simulate.observe.CAMERA_FAMILIES``)."""
        def span(r: tuple[float, float], unit: str) -> str:
            return f"{r[0]:g}–{r[1]:g}{unit}"

        families = "; ".join(f"*{f.key}* ({span(f.height, ' m')} up, tilted {span(f.tilt, '°')}, yawed "
                             f"{span(f.yaw, '°')}, {span(f.distance, ' m')} away)" for f in CAMERA_FAMILIES)
        sizes = " or ".join(f"{h}p" for h in sorted({h for _, h in sweep.SIZES}))
        rates = " or ".join(f"{r:g}" for r in sweep.RATES)
        return (f"{families}; each at {span(sweep.FOV, '°')} field of view, {sizes}, {rates} frames a second, the "
                f"object's colour drawn, a camera kept only if the object stays in the picture and at least "
                f"{sweep.MIN_PIXELS:g} pixels wide")

    @property
    def sweep_words(self) -> str:
        """The camera sweep's answer in one sentence: the recommended model's accuracy on exact heights and by
        the default path, pooled, and the family where the camera costs most."""
        res = self.camera.recommended.results
        default = camera_cost.DEFAULT_PATH
        families = {f.key for f in CAMERA_FAMILIES}
        worst = max((g for g in res if g in families), key=lambda g: res[g][default].cost.value)
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
        kept = [k for k in camera_cost.PATHS if k not in at_chance]
        chance = f": on {', '.join(at_chance)} heights the rule's interval holds chance"
        if not at_chance:
            verdict = "it survives every path (each interval above chance)"
        elif not kept:
            verdict = "it does not survive" + chance
        else:
            verdict = f"it survives only the {', '.join(kept)} path{'s' if len(kept) > 1 else ''}" + chance
        return (f"the drag rule (one threshold on the first fall's acceleration, set on the training throws) gets "
                f"{pct_ci(d['exact'])} of the sweep's throws from their exact heights and {pct_ci(d[default])} "
                f"from the {default} path; {verdict}")


    @property
    def floor_marks_words(self) -> str:
        """What marks on the floor give: the floor path's height error and the accuracy through it of the model
        recommended for it (else the one-scale model's), beside the default one-scale path's and the exact
        heights'."""
        res = self.camera.recommended.results["all"]
        fl, default = res[camera_cost.FLOOR_PATH], res[camera_cost.DEFAULT_PATH]
        found = res.get(camera_cost.FOUND)  # measured where the clips show their marks
        found_mm = ("" if found is None else f"; with the marks found by their colour, not clicked, {_mm_off(found)}"
                    + (f" ({found.no_heights} clips without)" if found.no_heights else ""))
        words = (f"with {len(marklayout.LAYOUT)} marks taped around the throw, the heights are {_mm_off(fl)} (one "
                 f"scale: {default.rms_centred_mm:.0f} mm){found_mm}; the recommended model labels "
                 f"{pct_ci(fl.accuracy)} "
                 f"right ({pct_ci(default.accuracy)} with one scale)")
        name = self.camera.floor_choice
        if name is None:
            return words + "; no model was trained for the floor path (its error model could not be fitted)"
        m = self.camera.measured[name]
        r = m.results["all"]
        known = ("" if camera_cost.KNOWN not in r else
                 f", {pct_ci(r[camera_cost.KNOWN].accuracy)} through the known camera (the path's limit, "
                 f"{points(m.difference(camera_cost.KNOWN, camera_cost.FLOOR_PATH))} more; heights "
                 f"{r[camera_cost.KNOWN].rms_centred_mm:.0f} mm off)")
        return (words + f"; the model trained for that path ({name}) labels "
                f"{pct_ci(r[camera_cost.FLOOR_PATH].accuracy)} through it ({pct_ci(r['exact'].accuracy)} from exact "
                f"heights{known})")

    @property
    def floor_model_words(self) -> str:
        """The floor path's fitted error model in words, and how far its autocorrelation is the path's own."""
        f = self.camera.floor_fit
        if f is None:
            return "the floor path gave no heights on the development clips, so no error model was fitted"
        m, c = f.fit.model, f.check
        k = c.lags.index(10) if 10 in c.lags else len(c.lags) - 1
        fits = (f"which holds at every lag from {c.lags[0]} to {c.lags[-1]} frames (within {c.worst:.2f})"
                if c.worst <= floor_model.FITS else
                f"which it does not hold: the path's error is {c.measured[k]:.2f} correlated {c.lags[k]} frames "
                f"on, the model's {c.model[k]:.2f} (the path's "
                + ("forgets faster" if c.measured[k] < c.model[k] else "remembers longer") + ")")
        return (f"fitted on {f.fit.fitted_on}: a per-throw offset of {1000 * m.offset:.0f} mm and "
                f"{1000 * m.flight:.0f} mm in flight ({1000 * m.contact:.0f} mm in contact), correlated "
                f"{m.rho:.2f} from frame to frame as an AR(1), {fits}")

    @property
    def default_words(self) -> str:
        """Which one-scale path a user without floor marks should take: the best one's paired difference against
        the default."""
        m = self.camera.recommended
        res = m.results["all"]
        default = camera_cost.DEFAULT_PATH
        best = max(camera_cost.ONE_SCALE, key=lambda k: res[k].accuracy.value)
        if best == default:
            return f"the default ({default}) is also the most accurate one-scale path on the sweep"
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



def compute(runner: Runner, progress: bool = False) -> UserCamera:
    """The chapter on ``runner``'s preset: the camera sweep classified by every candidate of the recommended model
    (``study.methods.recommend``; every run cached, the clips rendered once)."""
    cs = camera_sweep(runner, recommend(runner), progress)
    return UserCamera(Numbers(_sweep_numbers(cs)), cs, _sweep_table(cs), _heights_table(cs),
                      _candidates_sweep_table(cs), _drag_table(cs))
