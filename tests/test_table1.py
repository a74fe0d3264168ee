"""The chapter Table 1's computation, on run records written into a fresh cache (nothing trains)."""

from __future__ import annotations

import pytest

from fake_runs import cache_records
from study.book import results
from study.experiments import Runner, paper, table1

pytestmark = pytest.mark.filterwarnings("ignore::RuntimeWarning")


def _score(c) -> float:
    """Test accuracy of a fake run: X, Y, Z above Z, velocity above both; seed 1 the best on the test split."""
    return 0.6 + 0.1 * (c.dims == "xyz") + 0.2 * (c.inputs == "velocity") + 0.15 * (c.seed == 1)


def _val(c) -> float:
    """Validation accuracy: seed 0 the best there, so validation and the test split disagree on the best run."""
    return 0.7 + 0.1 * (c.seed == 0)


@pytest.fixture(scope="module")
def t1(tmp_path_factory) -> table1.Table1:
    runner = Runner.open("smoke", data_dir=tmp_path_factory.mktemp("data"))
    p = runner.preset
    for cell in p.cells:
        cache_records(runner, paper.grid_configs(p, cell), _score, test=False, val_score=_val)
    cache_records(runner, paper.grid_configs(p, "peephole", "velocity"), _score, test=False, val_score=_val)
    g = table1.grid_search(runner)
    cache_records(runner, [c for _, c in paper.protocol_plan(g.config, p)], _score, test=False, val_score=_val)
    cache_records(runner, paper.seed_configs(g.config, p.seeds) + paper.seed_configs(g.velocity_config, p.seeds)
                  + paper.ablation_configs(g.winners, p), _score, val_score=_val)
    for s in p.data_seeds[1:]:
        o = runner.with_data_seed(s)
        cache_records(o, paper.seed_configs(g.config, p.grid_seeds) + paper.seed_configs(g.velocity_config, p.grid_seeds),
                      _score, val_score=_val)
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
    for key in table1.PROTOCOL_KEYS:
        assert f"table1.protocol.{key}.z.val_mean" in names and f"table1.protocol.{key}.xyz.stalled" in names
    assert {"table1.verdict", "table1.xyz_minus_z", "table1.velocity.xyz_minus_z", "table1.grid.failed_runs",
            "table1.ablation.peephole.mean", "table1.ablation.peephole_minus_gru"} <= set(names)
    f = tmp_path / "results.json"
    f.write_text(results.dumps(t1.numbers.entries()))
    assert table1.Numbers.read(results.load(f)) == t1.numbers


def test_counts_and_sentences(t1):
    assert t1.grid_runs == 4 * 4, "2 points x 2 seeds in each of 4 grids (three cells and the velocity network)"
    assert t1.numbers.grid.failed_runs.unit == "count"
    assert t1.n_params > 0 and t1.n_data == 2
    assert "X, Y, Z" in t1.clip_gain and t1.vel_order in ("trails", "beats", "cannot be told apart from")
    assert len(t1.table1.rows) == 4 and t1.table1.markdown().count("\n") == 5
