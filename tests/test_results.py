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


def test_a_paper_number_is_reproduced_inside_the_margin_and_differs_wholly_outside():
    m = results.margin(0.81)  # 3 points + 1.96 sqrt(0.81 0.19 / 1000) = 3 + 2.43 points
    assert m == pytest.approx(0.03 + 1.96 * (0.81 * 0.19 / 1000) ** 0.5) and m == pytest.approx(0.0543, abs=1e-4)
    assert results.margin(1.0) == results.DELTA  # no sampling error at 100 %
    inside = results.number(0.81, Interval(0.80, 0.78, 0.82, "x"))
    assert inside.verdict == "reproduced"
    assert inside.inputs == {"rule": "number", "paper": 0.81, "lo": 0.78, "hi": 0.82, "delta": 0.03, "n_paper": 1000}
    assert results.number(0.81, Interval(0.90, 0.87, 0.93, "x")).verdict == "differs"  # wholly above p + M
    assert results.number(0.81, Interval(0.70, 0.67, 0.74, "x")).verdict == "differs"  # wholly below p - M
    edge = results.number(0.81, Interval(0.86, 0.84, 0.88, "x"))  # straddles p + M = 0.8643
    assert edge.verdict == "inconclusive"
    assert results.number(0.81, Interval(0.81, 0.70, 0.92, "x")).verdict == "inconclusive"  # wider than the margin
    twenty = results.number(0.81, Interval(0.80, 0.78, 0.82, "x"), results.Rule(delta=0.0, n_paper=20))
    assert twenty.inputs["n_paper"] == 20 and twenty.inputs["delta"] == 0.0
    with pytest.raises(ConfigError, match="fraction"):
        results.number(81, Interval(0.80, 0.78, 0.82, "x"))
    with pytest.raises(ConfigError, match="finite"):
        results.number(0.81, Interval(float("nan"), float("nan"), float("nan"), "x"))
    with pytest.raises(ConfigError, match="Rule.delta"):
        results.Rule(delta=-0.01)
    with pytest.raises(ConfigError, match="n_paper"):
        results.Rule(n_paper=0)


def test_a_claimed_order_against_the_interval_of_the_difference():
    d = lambda lo, hi: Interval((lo + hi) / 2, lo, hi, "d")  # noqa: E731
    assert results.order(d(0.01, 0.05), +1).verdict == "reproduced"
    assert results.order(d(0.005, 0.02), +1).verdict == "reproduced"  # the order holds, if by little
    assert results.order(d(-0.08, -0.04), +1).verdict == "differs"  # the other order
    assert results.order(d(-0.01, 0.02), +1).verdict == "differs"  # wholly inside [-3, 3] points: no difference
    assert results.order(d(-0.01, 0.05), +1).verdict == "inconclusive"  # straddles 0, reaches past delta
    assert results.order(d(-0.05, -0.01), -1).verdict == "reproduced"  # A falls below B, as claimed
    assert results.order(d(0.04, 0.08), -1).verdict == "differs"
    assert results.order(d(-0.05, 0.01), -1).verdict == "inconclusive"
    assert results.order(d(0.01, 0.05), +1).inputs == {"rule": "order", "sign": 1, "lo": 0.01, "hi": 0.05,
                                                        "delta": 0.03, "in_points": True}
    with pytest.raises(ConfigError, match="sign"):
        results.order(d(0.01, 0.05), 2)


def test_an_order_of_counts_or_seconds_takes_no_margin_in_points():
    """A difference of bounces or seconds is judged on the side of 0 alone, at the book's δ and at any other."""
    d = lambda lo, hi: Interval((lo + hi) / 2, lo, hi, "d")  # noqa: E731
    tiny = results.order(d(0.001, 0.02), +1, in_points=False)  # 0.001 to 0.02 s: inside ±δ, yet above 0
    assert tiny.verdict == "reproduced" and tiny.inputs["delta"] == 0.0 and tiny.inputs["in_points"] is False
    near_zero = results.order(d(-0.01, 0.02), +1, in_points=False)
    assert near_zero.verdict == "inconclusive"  # in points it would be "differs": wholly inside ±3 points
    assert results.order(d(-0.01, 0.02), +1).verdict == "differs"
    for k in (0.015, 0.06, 0.5):  # the summary's δ/2 and 2δ, and more, leave it alone
        assert results.decide(near_zero.inputs, delta=k) == "inconclusive"
        assert results.decide(tiny.inputs, delta=k) == "reproduced"
    assert results.decide(results.order(d(-0.01, 0.02), +1).inputs, delta=0.005) == "inconclusive"
    old = {"rule": "order", "sign": 1, "lo": -0.01, "hi": 0.02, "delta": 0.03}  # stored before the field existed
    assert results.decide(old) == "differs" and results.decide(old, delta=0.005) == "inconclusive"


def test_qualitative_and_not_comparable_rows_and_combining_verdicts():
    nc = results.not_comparable("the paper tests on real video of heavy objects; none is public")
    q = results.qualitative("both classes' heights fall and bounce as in the paper's Figure 3")
    assert nc.verdict == "not comparable" and nc.inputs["reason"].startswith("the paper tests")
    assert q.verdict == "qualitative" and q.inputs == {"rule": "qualitative", "criterion": q.inputs["criterion"]}
    assert results.decide(nc.inputs) == "not comparable" and results.decide(q.inputs, delta=0.5) == "qualitative"
    with pytest.raises(ConfigError, match="reason"):
        results.not_comparable("")
    c = results.combine
    assert c(["reproduced", "reproduced"]) == "reproduced" and c(["differs", "differs"]) == "differs"
    assert c(["reproduced", "differs"]) == c(["reproduced", "inconclusive"]) == c(["differs", "mixed"]) == "mixed"
    assert c(["inconclusive", "inconclusive"]) == "inconclusive"
    assert c(["reproduced", "qualitative", "not comparable"]) == "reproduced"  # set aside when numbers exist
    assert c(["qualitative", "not comparable"]) == "qualitative" and c(["not comparable"]) == "not comparable"
    with pytest.raises(ConfigError):
        c(["maybe"])
    with pytest.raises(ConfigError):
        c([])
    yes = results.number(0.81, Interval(0.80, 0.78, 0.82, "x"))
    no = results.number(0.78, Interval(0.70, 0.67, 0.72, "x"))
    both = results.combined([yes, no, nc])
    assert both.verdict == "mixed" and both.inputs == {"rule": "combined", "parts": [yes.inputs, no.inputs, nc.inputs]}
    assert results.combined([yes, q]).verdict == "reproduced"
    with pytest.raises(ConfigError, match="Decision"):
        results.combined(["reproduced"])


def test_every_verdict_is_decided_again_from_its_inputs_and_at_another_margin():
    iv = lambda lo, hi: Interval((lo + hi) / 2, lo, hi, "x")  # noqa: E731
    decisions = [results.number(0.81, iv(0.78, 0.82)), results.number(0.81, iv(0.87, 0.93)),
                 results.number(0.81, iv(0.84, 0.88)), results.order(iv(0.01, 0.05), 1),
                 results.order(iv(-0.01, 0.02), 1), results.order(iv(-0.01, 0.05), -1),
                 results.not_comparable("different in kind"), results.qualitative("by eye")]
    decisions.append(results.combined(decisions[:3]))
    for d in decisions:
        assert results.decide(d.inputs) == d.verdict
        assert results.decide(json.loads(json.dumps(d.inputs))) == d.verdict  # as the results file stores them
    # borderline: [0.84, 0.865] straddles 0.81 + M (0.8643) at delta = 3 points; inside it at 6, outside at 1.5
    border = results.number(0.81, iv(0.84, 0.865))
    assert border.verdict == "inconclusive"
    assert results.decide(border.inputs, delta=2 * results.DELTA) == "reproduced"
    assert results.decide(results.number(0.81, iv(0.85, 0.87)).inputs, delta=results.DELTA / 2) == "differs"
    no_diff = results.order(iv(-0.02, 0.025), 1)  # inside [-3, 3] points: no difference
    assert no_diff.verdict == "differs" and results.decide(no_diff.inputs, delta=results.DELTA / 2) == "inconclusive"
    assert results.decide(decisions[-1].inputs, delta=2 * results.DELTA) == "mixed"
    with pytest.raises(ConfigError, match="rule"):
        results.decide({"rule": "by hand", "verdict": "reproduced"})
    with pytest.raises(ConfigError, match="malformed"):
        results.decide({"rule": "number", "paper": 0.81})
    with pytest.raises(ConfigError, match="does not follow"):
        results.Decision("reproduced", border.inputs)  # a verdict cannot be typed beside its inputs


def test_no_chapter_can_type_a_verdict(monkeypatch):
    r = results.Results("table1")
    with pytest.raises(ConfigError, match="Decision"):
        r.verdict("verdict", "reproduced", what="Table 1")
    with pytest.raises(ConfigError, match="verdict_= is gone"):
        r.add("xyz_minus_z", Interval(0.03, 0.01, 0.05, "d"), verdict_="reproduced")
    with pytest.raises(ConfigError, match="Decision"):
        r.add("xyz_minus_z", Interval(0.03, 0.01, 0.05, "d"), decision="reproduced")
    with pytest.raises(ConfigError, match="decision="):
        r.add("time", 1.2, unit="s", paper=1.0)  # the rule compares fractions
    diff = Interval(0.03, 0.01, 0.05, "d")
    n = r.add("xyz_minus_z", diff, decision=results.order(diff, 1))
    assert n.verdict == "reproduced" and n.decision["rule"] == "order" and n.paper is None
    v = r.verdict("verdict", results.combined([results.number(0.81, Interval(0.8, 0.78, 0.82, "x"))]), what="Table 1")
    assert v.verdict == "reproduced" and v.decision["rule"] == "combined" and results.fmt(v) == "(verdict)"
    small = r.add("rendered.light", Interval(0.9, 0.85, 0.95, "w"), paper=0.93, rule=results.Rule(n_paper=20))
    assert small.decision["n_paper"] == 20 and small.verdict == "reproduced"
    assert results.recompute(r.numbers) == []


def test_decisions_round_trip_through_the_results_file_and_old_files_still_load(tmp_path, monkeypatch):
    part = tmp_path / "part.json"
    monkeypatch.setenv(results.ENV, str(part))
    r = results.Results("realworld")
    r.add("rendered.light", Interval(0.8, 0.78, 0.82, "w"), paper=0.81)
    r.add("gap", Interval(0.02, -0.01, 0.05, "d"), decision=results.order(Interval(0.02, -0.01, 0.05, "d"), 1))
    r.verdict("figure5", results.qualitative("tracked heights rise and fall as the paper's"), what="Figure 5")
    r.verdict("real_heavy", results.not_comparable("no public footage of heavy objects"), what="real cubes")
    r.add("count", 14, unit="count")
    r.save()
    out = results.merge([part], tmp_path / "build.json", "smoke")
    loaded = results.load(out)
    stored = lambda ns: {k: (n.verdict, n.decision) for k, n in ns.items()}  # noqa: E731
    assert stored(loaded) == stored(r.numbers)
    assert loaded["realworld.gap"].verdict == "inconclusive" and loaded["realworld.count"].decision is None
    assert results.recompute(loaded) == []
    body = json.loads(out.read_text())
    assert body["format"] == "study.results/1"
    body["numbers"][0]["verdict"] = "differs"  # a verdict edited by hand no longer follows from its inputs
    (tmp_path / "edited.json").write_text(json.dumps(body))
    assert results.recompute(results.load(tmp_path / "edited.json")) == ["realworld.rendered.light"]
    old = {"format": "study.results/1", "preset": "paper", "numbers": [  # written before decisions were stored
        {"name": "table1.xyz.best", "value": 0.8, "lo": 0.78, "hi": 0.82, "method": "bootstrap", "chapter": "table1",
         "what": "", "unit": "fraction", "paper": 0.81, "verdict": "reproduced", "source": {}},
        {"name": "table1.z.mean", "value": 0.7, "lo": 0.68, "hi": 0.72, "method": "bootstrap", "chapter": "table1"}]}
    (tmp_path / "old.json").write_text(json.dumps(old))
    again = results.load(tmp_path / "old.json")
    assert again["table1.xyz.best"].verdict == "reproduced" and again["table1.xyz.best"].decision is None
    assert results.recompute(again) == ["table1.xyz.best"]  # a verdict without inputs cannot be decided again
    old["numbers"][0]["decision"] = "reproduced"
    (tmp_path / "bad.json").write_text(json.dumps(old))
    with pytest.raises(DataError, match="malformed decision"):
        results.load(tmp_path / "bad.json")


def write_build(path, numbers: dict[str, tuple[float, float, float]], monkeypatch) -> None:
    """A results file as the builder writes it: one chapter's part, merged."""
    part = path.parent / f"{path.stem}-part.json"
    monkeypatch.setenv(results.ENV, str(part))
    r = results.Results("table1")
    for name, (v, lo, hi) in numbers.items():
        iv = Interval(v, lo, hi, "bootstrap")
        r.add(name, iv, paper=0.81 if name == "xyz" else None,
              decision=results.order(iv, +1) if name == "gap" else None)
    r.save()
    results.merge([part], path, "paper")


def test_results_file_round_trip_and_compare(tmp_path, monkeypatch, capsys):
    a, b = tmp_path / "a.json", tmp_path / "b.json"
    write_build(a, {"xyz": (0.80, 0.78, 0.82), "z": (0.78, 0.76, 0.80), "gap": (0.02, 0.0, 0.04)}, monkeypatch)
    write_build(b, {"xyz": (0.81, 0.79, 0.83), "z": (0.70, 0.68, 0.72), "only_b": (0.5, 0.4, 0.6)}, monkeypatch)
    loaded = results.load(a)
    assert loaded["table1.xyz"].verdict == "reproduced" and loaded["table1.xyz"].paper == 0.81
    assert loaded["table1.xyz"].decision["rule"] == "number" and loaded["table1.gap"].verdict == "inconclusive"
    assert results.recompute(loaded) == []
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
