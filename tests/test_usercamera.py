"""The chapter *A camera nobody measured* (study.chapters.usercamera): its numbers keep their names and read back,
and its sentences follow them; made-up sweeps, no rendering."""

from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
import scripts_toys

from study.book import results, summary
from study.chapters import usercamera
from study.learn.metrics import Interval
from study.methods import camera_cost
from study.report.text import Table


def _iv(v: float, lo: float | None = None, hi: float | None = None) -> Interval:
    return Interval(v, v - 0.05 if lo is None else lo, v + 0.05 if hi is None else hi, "bootstrap")


def _sweep(best_path_gain: float = 0.02, drag_rest: Interval | None = None,
           drag_above: tuple[str, ...] = ()) -> usercamera.CameraSweep:
    """A camera sweep of two families made up here: exact 0.8 everywhere; every path but gravity (the default among
    them) 0.6, 0.7 on 'low' and 0.5 on 'high'; 'gravity' ``best_path_gain`` above it; 10 clips a family. The drag
    rule at chance on every path, or at ``drag_rest`` on all of them, or above chance on the paths ``drag_above``."""
    fams = ("low", "high")
    clips = tuple(SimpleNamespace(shot=SimpleNamespace(family=f, distance=4.0, height_px=480 if i < 7 else 720))
                  for f in fams for i in range(10))
    per = {"all": 0.6, "low": 0.7, "high": 0.5, "480p": 0.6, "720p": 0.6}
    res = {}
    for g, acc in per.items():
        rows = {"exact": camera_cost.PathResult(_iv(0.8), None, 0.0, 0.0, 0, _iv(0.8))}
        for k in camera_cost.PATHS:
            a = acc + (best_path_gain if k == "gravity" else 0.0)
            rows[k] = camera_cost.PathResult(_iv(a), _iv(0.8 - a), 150.0, 100.0, 0, _iv(a))
        res[g] = rows
    correct = {k: np.zeros((3, len(clips)), bool) for k in ("exact", *camera_cost.PATHS)}
    correct["mean silhouette"][:, :12] = True  # 60 %
    correct["gravity"][:, : 12 + round(20 * best_path_gain)] = True
    m = camera_cost.Measured(res, correct, tuple(camera_cost.groups_of(c) for c in clips))
    floors = {g: camera_cost.Floor(0.06, 0.062, 10) for g in per}
    drag = {"exact": _iv(0.75), **{k: _iv(0.5, 0.4, 0.6) for k in camera_cost.PATHS}}
    if drag_rest is not None:
        drag = {k: drag_rest if k != "exact" else v for k, v in drag.items()}
    drag.update({k: _iv(0.9) for k in drag_above})
    return usercamera.CameraSweep(clips, {"velocity, randomised": m, "velocity, exact": m}, "velocity, randomised",
                                  {"velocity, randomised": "velocity-randomised", "velocity, exact": "velocity-exact"},
                                  floors, drag, 0.075, (600.0, 330.0, len(clips)))


def _result(cs: usercamera.CameraSweep) -> usercamera.UserCamera:
    empty = Table([], {})
    return usercamera.UserCamera(usercamera.Numbers(usercamera._sweep_numbers(cs)), cs, empty, empty, empty, empty)


def test_the_camera_sweeps_numbers_read_back_and_its_sentences_follow_them(tmp_path):
    cs = _sweep()
    n = usercamera.Numbers(usercamera._sweep_numbers(cs))
    names = [name for name, _ in n.entries()]
    assert {"usercamera.sweep.all.clips", "usercamera.sweep.low.rest.accuracy", "usercamera.sweep.high.rest.cost",
            "usercamera.sweep.all.exact.heights_mm", "usercamera.sweep.all.floor_mm", "usercamera.sweep.drag.rest",
            "usercamera.sweep.size_error", "usercamera.sweep.render_cpu_s", "usercamera.sweep.kind.velocity-exact.mean",
            "usercamera.sweep.kind.velocity-randomised.exact"} <= set(names)
    assert "usercamera.sweep.all.exact.cost" not in names, "the exact path has no cost"
    assert "usercamera.sweep.floor_render_cpu_s" not in names, "the development clips' renders: not recorded here"
    import dataclasses

    timed = usercamera._sweep_numbers(dataclasses.replace(cs, floor_render_cpu=60.0))
    assert timed.floor_render_cpu_s.value == 60.0
    clips = [SimpleNamespace(video=SimpleNamespace(path=Path(f"c{i}.mp4"))) for i in range(5)]
    kept = {f"c{i}.mp4": {"cpu_s": 12.0, "wall_s": 6.0} for i in range(5)}
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(usercamera.sweep, "render_times", lambda cs: {c.video.path.name: kept[c.video.path.name]
                                                                  for c in cs if c.video.path.name in kept})
        assert usercamera._render_cpu(clips) == 60.0
        del kept["c4.mp4"]
        assert usercamera._render_cpu(clips) is None, "4 of 5 clips timed: a partial sum would understate the renders"
    floor = n.sweep.groups["all"].paths["floor"]  # the floor camera issue's bars, each a number of the results
    assert floor.heights_raw_mm.value == 150.0 and floor.heights_mm.value == 100.0 and floor.no_heights.value == 0
    assert "usercamera.sweep.high.floor.heights_raw_mm" in names and "usercamera.sweep.all.exact.no_heights" not in names
    assert n.sweep.groups["low"].clips.value == 10 and n.sweep.groups["all"].clips.value == 20
    assert n.sweep.groups["480p"].clips.value == 14 and "usercamera.sweep.720p.floor.accuracy" in names, "by resolution"
    assert "most from the high cameras" in _result(cs).sweep_words, "the worst of the families, not of the resolutions"
    f = tmp_path / "results.json"
    f.write_text(results.dumps(n.entries()))
    assert usercamera.Numbers.read(results.load(f)) == n
    r = _result(cs)
    assert r.sweep_words.startswith("On 20 clips") and "most from the high cameras" in r.sweep_words
    assert "interval that holds 0" in r.default_words and "the default stays" in r.default_words
    assert r.floor_marks_words.startswith("with 6 marks taped around the throw, the heights are")
    assert "usercamera.sweep.all.floor.accuracy" in names and "usercamera.sweep.kind.velocity-exact.floor" in names
    assert r.floor_marks_words.endswith("no model was trained for the floor path (its error model could not be fitted)")
    assert r.floor_model_words.startswith("the floor path gave no heights on the development clips")
    assert "does not survive" in r.drag_words and "mean silhouette path" in r.drag_words
    assert r.depth_words == "7.5 % of the median camera distance, 4.0 m, is 30 cm of depth"
    assert "the tracker is not what limits" in r.floor_words
    assert r.render_words.startswith("rendering the 20 clips took 10.0 CPU-minutes (5.5 minutes")
    clear = _result(_sweep(best_path_gain=0.5, drag_rest=_iv(0.9)))
    assert "interval clear of 0" in clear.default_words and "should default to it" in clear.default_words
    assert "survives every path" in clear.drag_words
    one_scale = _result(_sweep(drag_above=("mean silhouette",))).drag_words  # the smoke build's case
    assert "it survives only the mean silhouette path: on rest size," in one_scale and "does not survive" not in one_scale
    said = summary.Findings._user_camera.fget(SimpleNamespace(sweep=n.sweep))  # the summary's sentence
    assert said.startswith(" A camera nobody measured leaves less still: on 20 clips") and "(heights off by 100 mm" in said
    assert summary.Findings._user_camera.fget(SimpleNamespace(sweep=None)) == ""


def test_the_families_are_described_from_their_records():
    words = _result(_sweep()).families_words
    for f in usercamera.CAMERA_FAMILIES:
        assert f"*{f.key}*" in words and f"{f.height[0]:g}–{f.height[1]:g} m up" in words


def test_the_shipped_copy_is_written_from_a_paper_builds_sweep_and_refused_from_another(tmp_path):
    import pytest

    from study.runs import measured

    script = scripts_toys.script("scripts/shipped_measured.py")
    n = usercamera.Numbers(usercamera._sweep_numbers(_sweep()))
    (tmp_path / "paper.json").write_text(results.dumps(n.entries(), preset="paper"))
    got = script.shipped(tmp_path / "paper.json", "abc1234")
    assert got.clips == 20 and set(got.measured) == {"velocity-randomised", "velocity-exact"}
    assert set(got.measured["velocity-exact"]) == {"exact", "rest", "mean", "gravity", "geometry", "floor"}
    assert measured.read_shipped(measured.write_shipped(tmp_path / "m.json", got)) == got
    (tmp_path / "smoke.json").write_text(results.dumps(n.entries(), preset="smoke"))
    with pytest.raises(SystemExit, match="'smoke' build"):
        script.shipped(tmp_path / "smoke.json", "abc1234")


def test_the_floor_paths_model_is_reported_through_its_path_with_its_error_models_fit():
    """The sweep with a model recommended for the floor path and the floor path's fitted error: the sentence quotes
    that model through the floor path beside its exact heights, and says whether an AR(1) holds the path's error."""
    import dataclasses

    from study.methods import floor_model, tracker_model
    from study.simulate.observe import TrackerNoise

    cs = _sweep()
    fit = tracker_model.TrackerFit(TrackerNoise(flight=0.068, contact=0.0075, offset=0.009, rho=0.96), 0.02, {}, 18,
                                   2288, 100, 0.014, 0.05, -0.02, 0.96, "the floor path on 18 development clips")
    loose = floor_model.Check((1, 2, 5, 10, 20), (0.93, 0.84, 0.58, 0.26, 0.03), (0.96, 0.92, 0.82, 0.66, 0.44))
    cs = dataclasses.replace(cs, floor_choice="velocity, exact", floor_fit=floor_model.FloorFit(fit, loose))
    assert "through the known camera" not in _result(cs).floor_marks_words, "not measured: unsaid"
    m = cs.measured["velocity, exact"]
    m.results["all"][camera_cost.KNOWN] = camera_cost.PathResult(_iv(0.75), _iv(0.05), 30.0, 20.0, 0)
    m.correct[camera_cost.KNOWN] = m.correct["mean silhouette"].copy()
    r = _result(cs)
    said = r.floor_marks_words  # the known camera labels 12 of 20 clips right in every seed, the floor path none
    assert "from exact heights, 75.0 % [70.0, 80.0] through the known camera (the path's limit, +60.0 points [" \
           in said and said.endswith("more; heights 20 mm off))")
    assert "the model trained for that path (velocity, exact) labels 60.0 % [55.0, 65.0] through it (80.0 % " \
           "[75.0, 85.0] from exact heights" in r.floor_marks_words
    fm = r.numbers.sweep.floor_model  # the same figures stored, for the summary and the bars
    assert (fm.floor.value, fm.exact.value, fm.known.value) == (0.6, 0.8, 0.75) and fm.known_minus_floor.value == 0.6
    assert usercamera.Numbers.read(dict(r.numbers.entries())).sweep.floor_model == fm
    assert usercamera.Numbers(usercamera._sweep_numbers(_sweep())).sweep.floor_model is None, "no floor model: absent"
    words = r.floor_model_words
    assert words.startswith("fitted on the floor path on 18 development clips: a per-throw offset of 9 mm and 68 mm")
    assert "which it does not hold: the path's error is 0.26 correlated 10 frames on, the model's 0.66" in words
    tight = floor_model.Check((1, 2, 5, 10, 20), (0.96, 0.92, 0.82, 0.66, 0.44), (0.96, 0.92, 0.8, 0.64, 0.41))
    held = _result(dataclasses.replace(cs, floor_fit=floor_model.FloorFit(fit, tight))).floor_model_words
    assert held.endswith("which holds at every lag from 1 to 20 frames (within 0.03)")
