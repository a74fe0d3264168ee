"""scripts/build_time.py adds the renders' CPU (kept beside the clips) to the runs' and bounds the build's wall time by
the cores; an unreadable timings file is one line and exit 2."""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

SCRIPT = Path(__file__).resolve().parents[1] / "scripts" / "build_time.py"


def _script():
    spec = importlib.util.spec_from_file_location("build_time", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


TIMINGS = {"preset": "paper", "device": "cpu", "wall_seconds": 600.0, "cpu_seconds": 60.0,
           "chapters": {"api": {"seconds": 0.0, "cached": True}, "table1": {"seconds": 120.0, "cached": False,
                                                                            "waited": 60.0}},
           "runs": {"models": 2.0, "cpu_seconds": 1200.0, "epochs": 40.0, "failed": 1.0},
           "runs_by_chapter": {"table1": {"models": 2.0, "cpu_seconds": 1200.0, "epochs": 40.0, "failed": 1.0}},
           "failed_runs": [{"reason": "designed"}], "unsettled_runs": []}


def test_the_renders_and_the_runs_bound_the_wall_time(tmp_path, capsys):
    clips = tmp_path / "data" / "realworld" / "sweep-x"
    clips.mkdir(parents=True)
    (clips / "RENDER_SECONDS.json").write_text(json.dumps({"a.mp4": {"cpu_s": 300.0, "wall_s": 310.0},
                                                           "b.mp4": {"cpu_s": 300.0, "wall_s": 290.0}}))
    (tmp_path / "timings.json").write_text(json.dumps(TIMINGS))
    assert _script().main([str(tmp_path / "timings.json"), "--data-dir", str(tmp_path / "data"), "--cores", "2"]) == 0
    out = capsys.readouterr().out
    assert "renders: 10.0 CPU-min in 1 folders: realworld/sweep-x 10.0" in out
    assert "training and renders alone: 30.0 CPU-min, at least 15 min of wall on 2 cores" in out
    assert "table1 2.0 (+1.0)" in out and "api" not in out.split("\n")[1], "cached pages are not listed"
    assert "failed runs 1: 1 x designed" in out


def test_an_unreadable_timings_file_is_one_line_and_exit_2(tmp_path, capsys):
    assert _script().main([str(tmp_path / "missing.json")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "missing.json" in err and "timings.json" in err
