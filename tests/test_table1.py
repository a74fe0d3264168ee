"""The chapter Table 1's computation, on run records written into a fresh cache (nothing trains)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from fake_runs import cache_models, cache_records

from study.book import results
from study.chapters import table1
from study.report import verdicts
from study.runs import Runner, paper

pytestmark = pytest.mark.filterwarnings("ignore::RuntimeWarning")


def _score(c) -> float:
    """Test accuracy of a fake run: X, Y, Z above Z, velocity above both, the speed network above the velocity one;
    the rotated training throws above the plain ones; seed 1 the best on the test split."""
    return (0.55 + 0.1 * (c.dims == "xyz") + 0.2 * (c.inputs != "positions") + 0.05 * (c.inputs == "speed")
            + 0.04 * (c.rotate > 0) + 0.15 * (c.seed == 1))


def _val(c) -> float:
    """Validation accuracy: seed 0 the best there, so validation and the test split disagree on the best run; the
    plateau schedule ahead of the constant rate (so the velocity rows move to it)."""
    return 0.7 + 0.1 * (c.seed == 0) + 0.02 * (c.lr_schedule == "plateau")


@pytest.fixture(scope="module")
def t1(tmp_path_factory) -> table1.Table1:
    runner = Runner.open("smoke", data_dir=tmp_path_factory.mktemp("data"))
    p = runner.preset
    for cell in p.cells:
        cache_records(runner, paper.grid_configs(p, cell), _score, test=False, val_score=_val)
    cache_records(runner, paper.grid_configs(p, "peephole", "velocity"), _score, test=False, val_score=_val)
    g = table1.grid_search(runner)
    cache_records(runner, [c for _, c in paper.protocol_plan(g.config, p)] + paper.schedule_configs(g.velocity_config, p),
                  _score, test=False, val_score=_val)
    velocity = dataclasses.replace(g.velocity_config, lr_schedule="plateau")
    speed, rot = table1.speed_config(velocity), table1.rotated_config(g.config)
    cache_records(runner, paper.seed_configs(g.config, p.seeds) + paper.seed_configs(velocity, p.seeds)
                  + paper.seed_configs(speed, p.seeds, ("xyz",)) + paper.seed_configs(rot, p.seeds, ("xyz",))
                  + paper.ablation_configs(g.winners, p), _score, val_score=_val)
    for s in p.data_seeds[1:]:
        o = runner.with_data_seed(s)
        cache_records(o, paper.seed_configs(g.config, p.grid_seeds) + paper.seed_configs(velocity, p.grid_seeds)
                      + paper.seed_configs(speed, p.grid_seeds, ("xyz",)), _score, val_score=_val)
    cache_models(runner, [dataclasses.replace(c, dims="xyz", seed=s) for c in (g.config, velocity, speed, rot)
                          for s in p.seeds])  # untrained: the heading test loads them
    return table1.compute(runner)


def test_the_paper_statistic_is_the_run_validation_picks_never_the_best_test_run(t1):
    for k, d in t1.picked:
        assert set(t1.picked[k, d]) == {0}, "validation prefers seed 0 on every data set"
    z = t1.numbers.rows["z"]
    picked = [runs.where(seed=0)[0].accuracy for runs in t1.seeds["positions"].per_data("z")]
    assert z.paper_way.value == pytest.approx(sum(picked) / len(picked))
    best_test = max(t1.seeds["positions"].first.where(dims="z").accuracies())
    assert z.paper_way.value < best_test, "seed 1 is better on the test split, and is not what the chapter reports"
    assert z.paper_way.paper == paper.TABLE1["z"] and z.paper_way.verdict is not None
    assert t1.numbers.velocity.rows["z"].paper_way.verdict is None, "beyond the paper: no verdict"


def test_the_verdicts_follow_from_the_numbers(t1):
    n = t1.numbers
    both = [n.rows[d].paper_way.verdict for d in table1.ORDER]
    assert n.verdict.verdict == (both[0] if both[0] == both[1] else "mixed")
    assert n.xyz_minus_z.decision.inputs["rule"] == "order" and n.xyz_minus_z.signed
    words = {"reproduced": "as in the paper", "differs": "unlike the paper", "inconclusive": "cannot say"}
    assert words[n.xyz_minus_z.verdict] in t1.claim_text


def test_every_number_keeps_its_name_and_reads_back_from_the_results_file(t1, tmp_path):
    names = [name for name, _ in t1.numbers.entries()]
    for d in ("xyz", "z"):
        for f in ("paper_way", "mean", "mean_t", "across_data", "between_share", "std", "failed"):
            assert f"table1.{d}.{f}" in names and f"table1.velocity.{d}.{f}" in names
        assert f"table1.baseline.{d}" in names and f"table1.lstm_minus_baseline.{d}" in names
    for key in (q.key for q in table1.PROTOCOLS):
        assert f"table1.protocol.{key}.z.val_mean" in names and f"table1.protocol.{key}.xyz.stalled" in names
    assert {"table1.verdict", "table1.xyz_minus_z", "table1.velocity.xyz_minus_z", "table1.grid.failed_runs",
            "table1.ablation.peephole.mean", "table1.ablation.peephole_minus_gru", "table1.speed.xyz.paper_way",
            "table1.speed.xyz_minus_z", "table1.rotated.gain", "table1.flips.speed",
            "table1.velocity.schedule.plateau.swing"} <= set(names)
    f = tmp_path / "results.json"
    f.write_text(results.dumps(t1.numbers.entries()))
    assert table1.Numbers.read(results.load(f)) == t1.numbers


def test_the_velocity_rows_use_the_schedule_validation_prefers(t1):
    assert t1.schedule.chosen == "plateau", "the fake plateau runs validate 2 points higher"
    assert t1.velocity_config.lr_schedule == "plateau" and t1.config.lr_schedule == "constant"
    assert all(r.config.lr_schedule == "plateau" for k in ("velocity", "speed") for r in t1.seeds[k].first)
    sched = t1.numbers.velocity.schedule
    assert sched["plateau"].val_mean.value == pytest.approx(sched["constant"].val_mean.value + 0.02)
    assert sched["constant"].swing.unit == "nats" and "plateau" in t1.schedule_used


def test_a_run_s_swing_is_the_mean_epoch_to_epoch_change_of_its_second_half():
    hist = [{"val_loss": v} for v in (0.9, 0.5, 0.3, 0.2, 1.2, 0.2)]
    assert table1.swing(hist) == pytest.approx((1.0 + 1.0) / 2), "epochs 3..5: 0.2 -> 1.2 -> 0.2"
    assert table1.swing(hist[:1]) == 0.0


def test_the_heading_rows(t1):
    """The speed network's X, Y, Z against the velocity network's Z; the rotated training throws on data set 1; the
    answers that change when a test throw is turned (untrained models here: the speed network's cannot change)."""
    n = t1.numbers
    assert set(n.speed.rows) == {"xyz"} and n.speed.rows["xyz"].paper_way.verdict is None
    assert n.speed.xyz_minus_z.value == pytest.approx(0.125), "speed X, Y, Z (0.9, 1.0) minus velocity Z (0.75, 0.9)"
    assert n.rotated.gain.value == pytest.approx(0.04, abs=0.02) and n.rotated.gain.signed
    assert all(r.config.rotate == table1.ROTATE and r.config.dims == "xyz" for r in t1.seeds["rotated"].first)
    assert not t1.seeds["rotated"].others and not t1.seeds["speed"].per_data("z")[0]
    assert n.flips["speed"].value == 0.0 and set(n.flips) == set(table1.NETWORKS)
    assert "gains" in t1.rot_order and t1.speed_order in ("trails", "beats", "cannot be told apart from")
    assert t1.row("speed", "xyz") is n.speed.rows["xyz"] and t1.row("rotated", "xyz") is None
    assert len(t1.heading_table.rows) == 4 and np.isfinite(n.rotated.mean.value)


def test_counts_and_sentences(t1):
    assert t1.grid_runs == 4 * 4, "2 points x 2 seeds in each of 4 grids (three cells and the velocity network)"
    assert t1.numbers.grid.failed_runs.unit == "count"
    assert t1.n_params > 0 and t1.n_data == 2
    assert "X, Y, Z" in t1.clip_gain and t1.vel_order in ("trails", "beats", "cannot be told apart from")
    assert len(t1.table1.rows) == 6 and t1.table1.markdown().count("\n") == 7, "4 rows, speed and rotated X, Y, Z"


def test_the_figure_has_a_column_per_row_of_table_1_with_every_run_and_the_papers_margin(t1):
    cols = t1.figure
    assert [(c.network, c.dims) for c in cols] == [("positions", "xyz"), ("positions", "z"), ("velocity", "xyz"),
                                                    ("velocity", "z"), ("speed", "xyz"), ("rotated", "xyz")]
    for c in cols:
        assert tuple(c.runs) == tuple(t1.seeds[c.network].per_data(c.dims)) and c.picked == t1.picked[c.network, c.dims]
    xyz = cols[0]
    assert xyz.estimate is t1.numbers.rows["xyz"].paper_way and xyz.paper == paper.TABLE1["xyz"]
    p = paper.TABLE1["xyz"]
    assert xyz.margin == pytest.approx(verdicts.MARGIN.delta + 1.96 * np.sqrt(p * (1 - p) / verdicts.MARGIN.n_paper))
    assert all(c.paper is None and c.margin is None for c in cols[2:]), "beyond the paper: no number to meet"
    assert cols[-1].estimate is t1.numbers.rotated.mean and len(cols[-1].runs) == 1, "data set 1 only"
    assert cols[1].label == "Z only" and cols[4].label == "X, Y, Z\nspeed input"


def test_the_headline_table_and_the_failed_runs_sentence(t1):
    head = t1.headline_table
    assert len(head.rows) == 6 and head.rows[0]["paper"] == "81 %" and head.rows[2]["verdict"] == "beyond the paper"
    assert head.rows[0]["verdict"] == f"**{t1.numbers.rows['xyz'].paper_way.verdict}**"
    assert "data set 1" in head.rows[-1]["ours"] and head.rows[4]["row"] == "X, Y, Z, speed input"
    n = sum(len(r) for c in t1.figure for r in c.runs)
    assert f"Table 1's {n} runs" in t1.failed_runs and f"{t1.grid_runs} grid runs" in t1.failed_runs
    assert (t1.paper_xyz, t1.paper_z) == ("81 %", "78 %")


def test_the_figure_draws_the_papers_band_beside_every_run(t1):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from study.book import figures

    fig = figures.table1_runs(t1.figure)
    left, right = fig.axes
    assert left.get_title().startswith("the paper's network") and right.get_title() == "beyond the paper"
    assert len(left.patches) == 2 and not right.patches, "a margin band for each of the paper's two numbers"
    band = left.patches[0]
    assert band.get_height() == pytest.approx(200 * t1.figure[0].margin)
    assert left.get_ylabel() == "test accuracy (%)"
    n_runs = sum(len(r) for c in t1.figure[:2] for r in c.runs)
    dots = [ln for ln in left.get_lines() if ln.get_marker() in ("o", "x") and ln.get_mfc() != "none"]
    assert len(dots) == n_runs, "every run of the paper's network drawn"
    plt.close(fig)


def test_a_pick_still_climbing_when_its_epochs_ran_out_is_named_not_settled(t1, tmp_path):
    import json

    from fake_runs import record

    from study.core.cache import write_text_atomic
    from study.runs import records

    runner = Runner.open("smoke", data_dir=tmp_path)
    cfg = paper.seed_configs(t1.config, (0,), ("z",))[0]
    cache_records(runner, [cfg])
    assert table1._unsettled(runner, tuple(runner.rows([cfg]))) == (False,), "stopped early: flattened"
    climbing = [{"epoch": e, "val_loss": 0.45, "val_accuracy": 0.5 + 0.02 * e} for e in range(cfg.epochs)]
    for test in (True, False):  # the same run, its budget spent with its validation accuracy still rising
        rec = record(runner.dataset, cfg, test, 0.7) | {"epochs_run": cfg.epochs, "history": climbing}
        write_text_atomic(records.record_path(runner.data_dir, rec["key"]), json.dumps(rec) + "\n")
    assert table1._unsettled(runner, tuple(runner.rows([cfg]))) == (True,)


def test_the_unsettled_picks_sentence_names_each_row_and_data_set(t1):
    assert t1.unsettled_picks.startswith(f"Each of the {5 * t1.n_data} runs validation picks had flattened")
    assert t1.numbers.rows["z"].unsettled_picks.value == 0 and t1.numbers.rows["z"].unsettled_picks.unit == "count"
    late = dataclasses.replace(t1, unsettled={**t1.unsettled, ("positions", "z"): (False, True)})
    z = t1.seeds["positions"].per_data("z")[1].where(seed=t1.picked["positions", "z"][1])[0]
    assert f"1 had not flattened when its {t1.epochs} epochs" in late.unsettled_picks
    assert '"not settled"' in late.unsettled_picks and "*" not in late.unsettled_picks, "glued as text: no Markdown"
    assert f"(Z only, positions, data set 2: {100 * z.accuracy:.1f} %;" in late.unsettled_picks
    assert "the estimate of that row" in late.unsettled_picks


def test_the_findings_say_which_table_1_row_leans_on_an_unsettled_pick():
    from study.book import summary

    assert summary.unsettled_clause({}) == summary.unsettled_clause({"xyz": 0}) == ""
    assert summary.unsettled_clause({"xyz": 0, "z": 1}) == (
        "; of the runs validation picks, 1 behind Z alone had not flattened when its epochs ran out")
    assert summary.unsettled_clause({"xyz": 1, "z": 2}).endswith("1 behind X, Y, Z and 2 behind Z alone had not "
                                                                 "flattened when their epochs ran out")
