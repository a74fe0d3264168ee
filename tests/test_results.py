"""Intervals, reported numbers and their names, the results file and `study results --compare`."""

from __future__ import annotations

import json
from dataclasses import dataclass
from typing import Literal

import numpy as np
import pytest

from study import cli
from study.book import results
from study.core import ticket
from study.core.errors import ConfigError, DataError
from study.learn.metrics import Interval, at_chance, bootstrap_accuracy, wilson
from study.report import reported, text, verdicts


def test_wilson_interval_of_a_known_binomial_case():
    """Wilson (1927) for 14 of 20 at 95 %: [0.481, 0.855] (the standard tables); 20 of 20 keeps an upper 1."""
    iv = wilson(14, 20)
    assert iv.value == 0.7 and iv.lo == pytest.approx(0.4810, abs=5e-4) and iv.hi == pytest.approx(0.8545, abs=5e-4)
    full = wilson(20, 20)
    assert full.hi == 1.0 and full.lo == pytest.approx(0.8389, abs=5e-4)
    none = wilson(0, 1000)  # a build with no miss must hold its own 0 (comparing two builds relies on it)
    assert none.lo == 0.0 and none.contains(0.0) and none.hi == pytest.approx(0.00383, abs=5e-5)
    assert wilson(1000, 1000).hi == 1.0 and wilson(1000, 1000).contains(1.0)
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


def test_a_number_cannot_carry_a_typed_verdict():
    diff = Interval(0.03, 0.01, 0.05, "d")
    with pytest.raises(ConfigError, match="Decision"):
        reported.number(diff, "gap", decision="reproduced")
    with pytest.raises(ConfigError, match="Decision"):
        reported.Verdict("reproduced", "Table 1")
    with pytest.raises(ConfigError, match="decision="):
        reported.number(1.2, "time", unit="s", paper=1.0)  # the rule compares fractions
    n = reported.number(diff, "gap", decision=verdicts.order(diff, 1))
    assert n.verdict == "reproduced" and n.decision.kind == "order" and n.paper is None
    small = reported.number(Interval(0.9, 0.85, 0.95, "w"), "light", paper=0.93, margin=verdicts.Margin(n_paper=20))
    assert small.decision.n_paper == 20 and small.verdict == "reproduced"
    assert reported.count(3, "runs").exact and reported.count(3, "runs").unit == "count"


@dataclass(frozen=True)
class _Rendered(reported.Reported):
    light: reported.Number
    heavy: reported.Number | None = None


@dataclass(frozen=True)
class _Chapter(reported.Reported):
    CHAPTER = "realworld"
    rendered: _Rendered
    gaps: dict[Literal["gap", "other"], reported.Number]
    figure5: reported.Verdict
    real_heavy: reported.Verdict = reported.named("real.heavy")
    cells: dict[str, reported.Number] = reported.named("cell_{key}", default_factory=dict)


def _chapter() -> _Chapter:
    gap = Interval(0.02, -0.01, 0.05, "d")
    return _Chapter(_Rendered(reported.number(Interval(0.8, 0.78, 0.82, "w"), "light", paper=0.81)),
                    {"gap": reported.number(gap, "gap", decision=verdicts.order(gap, 1), signed=True)},
                    reported.Verdict(verdicts.qualitative("tracked heights rise and fall as the paper's"), "Figure 5"),
                    reported.Verdict(verdicts.not_comparable("no public footage of heavy objects"), "real cubes"),
                    {"a": reported.count(14, "videos")})


def test_a_chapter_tree_names_its_numbers_and_reads_back_from_the_results_file(tmp_path, monkeypatch):
    ch = _chapter()
    names = [name for name, _ in ch.entries()]
    assert names == ["realworld.rendered.light", "realworld.gaps.gap", "realworld.figure5", "realworld.real.heavy",
                     "realworld.cell_a"]
    part = tmp_path / "part.json"
    monkeypatch.setenv(ticket.ENV, str(ticket.Ticket(results=str(part)).write(tmp_path / "ticket.json")))
    assert results.write_part("realworld", ch.entries()) == part
    out = results.merge([part, tmp_path / "absent.json"], tmp_path / "build.json", "smoke")
    body = json.loads(out.read_text())
    assert body["format"] == "study.results/2" and len(body["numbers"]) == 3 and len(body["verdicts"]) == 2
    loaded = results.load(out)
    assert loaded["realworld.gaps.gap"].verdict == "inconclusive" and loaded["realworld.cell_a"].decision is None
    assert results.recompute(loaded) == []
    back = _Chapter.read(loaded)
    assert back == ch and back.rendered.heavy is None, "the same typed tree, an absent optional number as None"
    missing = {k: v for k, v in loaded.items() if k != "realworld.figure5"}
    with pytest.raises(reported.MissingResult, match="realworld.figure5.*chapter 'realworld'"):
        _Chapter.read(missing)
    body["numbers"][0]["verdict"] = "differs"  # a verdict edited by hand no longer follows from its inputs
    (tmp_path / "edited.json").write_text(json.dumps(body))
    with pytest.raises(DataError, match="decide 'reproduced'"):
        results.load(tmp_path / "edited.json")


def test_files_of_the_first_format_still_load_under_todays_names(tmp_path):
    old = {"format": "study.results/1", "preset": "paper", "numbers": [
        {"name": "motion.lstm_positions.air_on.exact", "value": 0.7, "lo": 0.68, "hi": 0.72, "method": "bootstrap",
         "chapter": "motion", "what": "peephole LSTM, positions", "unit": "fraction", "paper": None, "verdict": None,
         "source": {"best": "lstm_velocity"}, "decision": None},
        {"name": "table1.verdict", "value": float("nan"), "lo": float("nan"), "hi": float("nan"), "method": "verdict",
         "chapter": "table1", "what": "Table 1", "unit": "verdict", "paper": None, "verdict": "qualitative",
         "source": {}, "decision": {"rule": "qualitative", "criterion": "x"}}]}
    (tmp_path / "old.json").write_text(json.dumps(old))
    again = results.load(tmp_path / "old.json")
    assert set(again) == {"motion.peephole_positions.air_on.exact", "table1.verdict"}
    assert again["motion.peephole_positions.air_on.exact"].source == {"best": "peephole_velocity"}
    assert isinstance(again["table1.verdict"], reported.Verdict) and again["table1.verdict"].verdict == "qualitative"
    old["numbers"][1]["verdict"] = "reproduced"
    old["numbers"][1]["decision"] = None  # a verdict without the inputs it was decided from
    (tmp_path / "bad.json").write_text(json.dumps(old))
    with pytest.raises(DataError, match="without the inputs"):
        results.load(tmp_path / "bad.json")


def write_build(path, numbers: dict[str, tuple[float, float, float]]) -> None:
    """A results file as the builder writes it."""
    leaves = []
    for name, (v, lo, hi) in numbers.items():
        iv = Interval(v, lo, hi, "bootstrap")
        leaves.append((f"table1.{name}", reported.number(iv, name, paper=0.81 if name == "xyz" else None,
                                                         decision=verdicts.order(iv, +1) if name == "gap" else None)))
    path.write_text(results.dumps(leaves, preset="paper"))


def test_results_file_round_trip_and_compare(tmp_path, capsys):
    a, b = tmp_path / "a.json", tmp_path / "b.json"
    write_build(a, {"xyz": (0.80, 0.78, 0.82), "z": (0.78, 0.76, 0.80), "gap": (0.02, 0.0, 0.04)})
    write_build(b, {"xyz": (0.90, 0.88, 0.92), "z": (0.70, 0.68, 0.72), "only_b": (0.5, 0.4, 0.6)})
    loaded = results.load(a)
    assert loaded["table1.xyz"].verdict == "reproduced" and loaded["table1.xyz"].paper == 0.81
    assert loaded["table1.xyz"].decision.kind == "number" and loaded["table1.gap"].verdict == "inconclusive"
    c = results.compare(loaded, results.load(b))
    assert [m.name for m in c.moved] == ["table1.xyz", "table1.z"]
    assert c.only_a == ["table1.gap"] and c.only_b == ["table1.only_b"]
    assert c.verdicts == [("table1.xyz", "reproduced", "differs")]
    assert cli.main(["results", str(a), "--compare", str(b)]) == 0
    out = capsys.readouterr().out
    assert "MOVED table1.z" in out and "VERDICT table1.xyz: reproduced  vs  differs" in out
    assert "2 of 2 shared numbers moved" in out and "1 verdicts differ" in out
    assert cli.main(["results", str(a)]) == 0
    assert "table1.xyz: 80.0 % [78.0, 82.0]  paper 81.0 %  reproduced" in capsys.readouterr().out


def test_results_outside_the_builder_write_nothing(monkeypatch):
    monkeypatch.delenv(ticket.ENV, raising=False)
    assert results.write_part("x", [("x.n", reported.count(3, "n"))]) is None


def test_a_chapter_executed_inside_another_writes_nothing_to_that_ones_results(tmp_path, monkeypatch):
    """The tutorial re-runs the data chapter through papermill; the nested kernel inherits the tutorial's ticket.
    Before the ticket named its chapter, the nested run wrote the data chapter's numbers (another seed, the smoke
    preset) into the tutorial's part, and the merge let them replace the data chapter's own."""
    part = tmp_path / "tutorial.json"
    monkeypatch.setenv(ticket.ENV, str(ticket.Ticket(chapter="tutorial", results=str(part)).write(tmp_path / "t.json")))
    assert results.write_part("data", [("data.n", reported.count(3, "n"))]) is None and not part.exists()
    assert results.write_part("tutorial", [("tutorial.n", reported.count(4, "n"))]) == part


def test_a_number_reported_by_two_parts_is_refused_not_replaced(tmp_path, monkeypatch):
    parts = []
    for chapter, value in (("data", 3), ("tutorial", 5)):
        part = tmp_path / f"{chapter}.json"
        monkeypatch.setenv(ticket.ENV, str(ticket.Ticket(results=str(part)).write(tmp_path / f"{chapter}.t.json")))
        results.write_part(chapter, [("data.n", reported.count(value, "n"))])
        parts.append(part)
    with pytest.raises(DataError, match=r"data\.n is also reported by .*data\.json") as err:
        results.merge(parts, tmp_path / "build.json", "smoke")
    assert "--only data" in str(err.value) and "--only tutorial" in str(err.value), "either may be the stale one"
    assert not (tmp_path / "build.json").exists()


def test_bad_results_files(tmp_path, capsys):
    with pytest.raises(DataError, match="no such file"):
        results.load(tmp_path / "none.json")
    (tmp_path / "bad.json").write_text("{not json")
    with pytest.raises(DataError, match="cannot be read"):
        results.load(tmp_path / "bad.json")
    (tmp_path / "other.json").write_text(json.dumps({"format": "something/1"}))
    assert cli.main(["results", str(tmp_path / "other.json")]) == 2
    assert "not a study.results/2 file" in capsys.readouterr().err


@pytest.mark.slow  # trains the smoke Table 1 on the PyTorch loop
def test_rebuild_check_writes_table1_on_the_other_backend(tmp_path, monkeypatch):
    import dataclasses
    import subprocess
    import sys
    from pathlib import Path

    from study import runs as experiments

    cfg = experiments.preset("smoke").base_config()
    mean = reported.number(Interval(0.6, 0.5, 0.7, "x"), "mean", config=dataclasses.asdict(cfg))
    (tmp_path / "build.json").write_text(results.dumps([("table1.z.mean", mean)], preset="smoke"))
    script = Path(__file__).resolve().parents[1] / "scripts" / "rebuild_check.py"
    proc = subprocess.run([sys.executable, str(script), "--results", str(tmp_path / "build.json"), "--backend", "torch",
                           "--preset", "smoke", "--data-dir", str(tmp_path / "data"), "--workers", "1",
                           "--out", str(tmp_path / "torch.json")], capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr[-2000:]
    again = results.load(tmp_path / "torch.json")
    assert {"table1.z.mean", "table1.xyz.mean", "table1.z.validation_pick", "table1.xyz.validation_pick"} <= set(again)
    metas = [json.loads(f.read_text()) for f in (tmp_path / "data" / "models").glob("*/meta.json")]
    assert len(metas) == 4 and {m["backend"] for m in metas} == {"torch"}, "trained on the PyTorch loop"


def test_numbers_print_as_the_chapters_print_them():
    n = reported.Number(0.013, 0.00761, 0.0221, "Wilson")
    assert text.fmt(n) == "1.3 % [0.8, 2.2]"  # percentages to a tenth of a point, not 3 digits
    assert text.fmt(reported.count(14, "videos")) == "14"
    assert text.fmt_value(0.0141, "m") == "0.0141 m"
    assert text.fmt(reported.number(Interval(0.005, -0.009, 0.02, "d"), signed=True)) == "+0.5 points [-0.9, +2.0]"
    assert text.fmt(reported.Verdict(verdicts.qualitative("by eye"), "x")) == "qualitative"


@pytest.mark.slow  # executes the data chapter in a scratch book
def test_rebuild_check_reexecutes_whole_chapters_into_a_results_file(tmp_path):
    import subprocess
    import sys
    from pathlib import Path

    script = Path(__file__).resolve().parents[1] / "scripts" / "rebuild_check.py"
    proc = subprocess.run([sys.executable, str(script), "--chapters", "data", "--preset", "smoke", "--data-dir",
                           str(tmp_path / "data"), "--out", str(tmp_path / "again.json")],
                          capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr[-2000:]
    again = results.load(tmp_path / "again.json")
    assert again and all(n.startswith("data.") for n in again), "the chapter's own numbers, as the book names them"
    assert list((tmp_path / "data").glob("synth-*.npz")), "into the data folder it was given"
    bad = subprocess.run([sys.executable, str(script), "--chapters", "nonesuch", "--out", str(tmp_path / "x.json")],
                         capture_output=True, text=True, timeout=120)
    assert bad.returncode == 2 and "no chapter nonesuch" in bad.stderr
