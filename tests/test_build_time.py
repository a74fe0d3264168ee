"""scripts/build_time.py adds the camera sweep's rendering CPU (from the build's results) to the runs' and bounds a
cold build's wall time by the cores; a file that is not a build's, and a bad --cores, are one line and exit 2."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
import scripts_toys

from study.book import results
from study.report import reported


def _script():
    return scripts_toys.script("scripts/build_time.py")


TIMINGS = {"preset": "paper", "device": "cpu", "wall_seconds": 600.0, "cpu_seconds": 60.0,
           "chapters": {"api": {"seconds": 0.0, "cached": True}, "table1": {"seconds": 120.0, "cached": False,
                                                                            "waited": 60.0}},
           "stages": [{"runs": 2, "new": 2, "chapters": ["table1"], "seconds": 300.0}],
           "runs": {"models": 2.0, "cpu_seconds": 1200.0, "epochs": 40.0, "failed": 2.0},
           "runs_by_chapter": {"table1": {"models": 2.0, "cpu_seconds": 1200.0, "epochs": 40.0, "failed": 2.0}},
           "failed_runs": [{"reason": "truncated back-propagation: the gradient stops short"},
                           {"reason": "truncated back-propagation: the gradient stops short"}],
           "unsettled_runs": []}


def _build(tmp_path: Path) -> Path:
    (tmp_path / "_build" / "executed").mkdir(parents=True)
    (tmp_path / "_build" / "executed" / "timings.json").write_text(json.dumps(TIMINGS))
    render = reported.number(480.0, "camera sweep: CPU seconds to render the clips", unit="s")
    dev = reported.number(120.0, "the floor path's development clips: CPU seconds to render", unit="s")
    (tmp_path / "_build" / "results.json").write_text(results.dumps(
        [("usercamera.sweep.render_cpu_s", render), ("usercamera.sweep.floor_render_cpu_s", dev)], preset="paper"))
    return tmp_path / "_build" / "executed" / "timings.json"


def test_the_sweep_renders_and_the_runs_bound_a_cold_builds_wall_time(tmp_path, capsys):
    assert _script().main([str(_build(tmp_path)), "--cores", "2"]) == 0
    out = capsys.readouterr().out
    assert "renders: sweep 8.0 CPU-min, floor development clips 2.0 CPU-min" in out
    assert "training and renders: 30.0 CPU-min: a cold build needs at least 15 min of wall on 2 cores" in out
    assert "table1 2.0 (+1.0)" in out and "api" not in out, "cached pages are not listed"
    assert "waits for runs: 1, 5.0 min in all" in out
    assert "failed runs: 2\n  2 x truncated back-propagation\n" in out


def test_without_results_the_renders_are_said_missing(tmp_path, capsys):
    timings = _build(tmp_path)
    (tmp_path / "_build" / "results.json").unlink()
    assert _script().main([str(timings)]) == 0
    out = capsys.readouterr().out
    assert "sweep renders: not in the results" in out and "needs at least 10 min of wall on 2 cores" in out


@pytest.mark.parametrize("args, named", [(["missing.json"], "missing.json"), (["results"], "timings"),
                                         (["timings", "--cores", "0"], "--cores 0"),
                                         (["timings", "--results", "missing.json"], "missing.json")])
def test_what_is_not_a_build_is_one_line_and_exit_2(tmp_path, capsys, args, named):
    timings = _build(tmp_path)
    paths = {"timings": str(timings), "results": str(tmp_path / "_build" / "results.json"),
             "missing.json": str(tmp_path / "missing.json")}
    assert _script().main([paths.get(a, a) for a in args]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and named in err
