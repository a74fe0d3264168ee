"""Intervals, verdicts, the results file and `study results --compare`."""

from __future__ import annotations

import json

import numpy as np
import pytest

from study import cli
from study.book import results
from study.core.errors import ConfigError, DataError
from study.learn.metrics import Interval, at_chance, bootstrap_accuracy, wilson


def test_wilson_interval_of_a_known_binomial_case():
    """Wilson (1927) for 14 of 20 at 95 %: [0.481, 0.855] (the standard tables); 20 of 20 keeps an upper 1."""
    iv = wilson(14, 20)
    assert iv.value == 0.7 and iv.lo == pytest.approx(0.4810, abs=5e-4) and iv.hi == pytest.approx(0.8545, abs=5e-4)
    full = wilson(20, 20)
    assert full.hi == 1.0 and full.lo == pytest.approx(0.8389, abs=5e-4)
    with pytest.raises(ConfigError, match="trials"):
        wilson(3, 0)


def test_bootstrap_interval_covers_like_the_binomial_and_widens_with_seeds():
    rng = np.random.default_rng(0)
    correct = rng.random(2000) < 0.8
    iv = bootstrap_accuracy(correct)
    w = wilson(int(correct.sum()), 2000)
    assert iv.value == correct.mean()
    assert iv.lo == pytest.approx(w.lo, abs=0.004) and iv.hi == pytest.approx(w.hi, abs=0.004)
    assert bootstrap_accuracy(correct) == iv  # seeded: the same interval every time
    spread = np.stack([rng.random(2000) < p for p in (0.70, 0.75, 0.80, 0.85, 0.90)])  # five seeds that disagree
    same = np.stack([correct] * 5)
    assert (bootstrap_accuracy(spread).hi - bootstrap_accuracy(spread).lo) > 2 * (iv.hi - iv.lo)
    assert bootstrap_accuracy(same).hi - bootstrap_accuracy(same).lo == pytest.approx(iv.hi - iv.lo, abs=0.004)
    assert "5 seeds" in bootstrap_accuracy(spread).method


def test_at_chance():
    assert at_chance(0.52, 400) and at_chance(0.40, 400) and not at_chance(0.60, 400)


def test_verdicts():
    iv = Interval(0.80, 0.78, 0.82, "x")
    assert results.verdict(0.81, iv) == "reproduced" and results.verdict(0.85, iv) == "differs"
    assert results.combine(["reproduced", "reproduced"]) == "reproduced"
    assert results.combine(["differs", "differs"]) == "differs"
    assert results.combine(["reproduced", "differs"]) == "mixed"
    assert results.claim_verdict(Interval(0.03, 0.01, 0.05, "d"), +1) == "reproduced"
    assert results.claim_verdict(Interval(0.01, -0.01, 0.03, "d"), +1) == "differs"
    with pytest.raises(ConfigError):
        results.combine(["maybe"])


def write_build(path, numbers: dict[str, tuple[float, float, float]], monkeypatch) -> None:
    """A results file as the builder writes it: one chapter's part, merged."""
    part = path.parent / f"{path.stem}-part.json"
    monkeypatch.setenv(results.ENV, str(part))
    r = results.Results("table1")
    for name, (v, lo, hi) in numbers.items():
        r.add(name, Interval(v, lo, hi, "bootstrap"), paper=0.81 if name == "xyz" else None)
    r.save()
    results.merge([part], path, "paper")


def test_results_file_round_trip_and_compare(tmp_path, monkeypatch, capsys):
    a, b = tmp_path / "a.json", tmp_path / "b.json"
    write_build(a, {"xyz": (0.80, 0.78, 0.82), "z": (0.78, 0.76, 0.80), "gap": (0.02, 0.0, 0.04)}, monkeypatch)
    write_build(b, {"xyz": (0.81, 0.79, 0.83), "z": (0.70, 0.68, 0.72), "only_b": (0.5, 0.4, 0.6)}, monkeypatch)
    loaded = results.load(a)
    assert loaded["table1.xyz"].verdict == "reproduced" and loaded["table1.xyz"].paper == 0.81
    pairs, only_a, only_b = results.compare(loaded, results.load(b))
    assert [m.name for m in pairs if m.moved] == ["table1.z"]
    assert only_a == ["table1.gap"] and only_b == ["table1.only_b"]
    assert cli.main(["results", str(a), "--compare", str(b)]) == 0
    out = capsys.readouterr().out
    assert "MOVED table1.z" in out and "table1.xyz" not in out
    assert "1 of 2 shared numbers moved" in out
    assert cli.main(["results", str(a)]) == 0
    assert "table1.xyz: 80.0 % [78.0, 82.0]  paper 81.0 %  reproduced" in capsys.readouterr().out


def test_results_outside_the_builder_write_nothing(monkeypatch):
    monkeypatch.delenv(results.ENV, raising=False)
    r = results.Results("x")
    r.add("n", 3, unit="count")
    assert r.save() is None


def test_bad_results_files(tmp_path, capsys):
    with pytest.raises(DataError, match="no such file"):
        results.load(tmp_path / "none.json")
    (tmp_path / "bad.json").write_text("{not json")
    with pytest.raises(DataError, match="cannot be read"):
        results.load(tmp_path / "bad.json")
    (tmp_path / "other.json").write_text(json.dumps({"format": "something/1"}))
    assert cli.main(["results", str(tmp_path / "other.json")]) == 2
    assert "not a study.results/1 file" in capsys.readouterr().err


@pytest.mark.slow  # trains the smoke Table 1 on the PyTorch loop
def test_rebuild_check_writes_table1_on_the_other_backend(tmp_path, monkeypatch):
    import dataclasses
    import subprocess
    import sys
    from pathlib import Path

    from study import experiments

    cfg = experiments.preset("smoke").base_config()
    part = tmp_path / "part.json"
    monkeypatch.setenv(results.ENV, str(part))
    r = results.Results("table1")
    r.add("z.mean", Interval(0.6, 0.5, 0.7, "x"), config=dataclasses.asdict(cfg))
    r.save()
    results.merge([part], tmp_path / "build.json", "smoke")
    script = Path(__file__).resolve().parents[1] / "scripts" / "rebuild_check.py"
    proc = subprocess.run([sys.executable, str(script), "--results", str(tmp_path / "build.json"), "--backend", "torch",
                           "--preset", "smoke", "--data-dir", str(tmp_path / "data"), "--workers", "1",
                           "--out", str(tmp_path / "torch.json")], capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr[-2000:]
    again = results.load(tmp_path / "torch.json")
    assert {"table1.z.mean", "table1.xyz.mean", "table1.z.best", "table1.xyz.best"} <= set(again)
    metas = [json.loads(f.read_text()) for f in (tmp_path / "data" / "models").glob("*/meta.json")]
    assert len(metas) == 4 and {m["backend"] for m in metas} == {"torch"}, "trained on the PyTorch loop"


def test_numbers_print_as_the_chapters_print_them():
    n = results.Number("decision.exact.miss", 0.013, 0.00761, 0.0221, "Wilson", "decision")
    assert results.fmt(n) == "1.3 % [0.8, 2.2]"  # percentages to a tenth of a point, not 3 digits
    assert results.fmt(results.Number("x.count", 14, 14, 14, "count", "table1", unit="count")) == "14"
    assert results.fmt_value(0.0141, "m") == "0.0141 m"
