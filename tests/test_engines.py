"""The chapter *Another engine*: its pieces (the throw-by-throw agreement, whether a learner transfers) on arrays,
and its computation on fake run records, models and MiniRocket fits written into a fresh cache (nothing trains).
The engine's physics is tests/test_bullet.py's."""

from __future__ import annotations

import numpy as np
import pytest

from fake_runs import cache_models, cache_records, cache_rocket
from study.book import results
from study.experiments import Runner, engines, motion, paper
from study.experiments.tracker import TrackerError
from study.learn.metrics import Interval
from study.simulate import measure, synth

pytestmark = pytest.mark.filterwarnings("ignore::RuntimeWarning")

CAL = TrackerError(noise_px=1.02, noise_m=0.0141, drop=0.05, n_frames=100, metres_per_pixel=0.0138)


def test_engine_agreement_is_throw_by_throw():
    t = np.arange(90) / 30.0
    z = 0.1 + np.abs(np.sin(2 * t)) * np.exp(-t)  # a few decaying hops
    a = np.zeros((2, 90, 3))
    a[..., 2] = z
    b = a.copy()
    b[1, :, 0] = np.linspace(0, 1.5, 90)  # the second throw travels 1.5 m further in the other engine
    d = engines.agreement(a, b, 30.0, rest_height=0.1)
    assert set(d) == set(engines.AGREEMENT)
    assert d["bounces"].tolist() == [0, 0] and d["first_rebound"].tolist() == [0, 0]
    assert d["distance"][0] == 0 and d["distance"][1] == pytest.approx(1.5)
    apex = int(measure.bounces(z).apexes[0])
    assert engines.first_rebound(a[:1, :, 2], 0.1)[0] == pytest.approx(z[apex] - 0.1) and z[apex] - 0.1 > 0.05


def test_the_agreement_is_reported_as_each_class_median():
    y = np.array([0, 0, 0, 1, 1])
    diff = {k: np.array([1.0, 2.0, 9.0, -1.0, -3.0]) for k in engines.AGREEMENT}
    numbers, table = engines.agreement_numbers(diff, y)
    assert numbers["bounces"]["light"].value == 2.0 and numbers["bounces"]["heavy"].value == -2.0
    assert numbers["bounces"]["light"].unit == "count" and numbers["time_to_rest"]["heavy"].unit == "s"
    assert numbers["distance"]["light"].what == "median of Bullet minus MuJoCo, horizontal distance, m, light"
    assert len(table.rows) == 2 * len(engines.AGREEMENT) and table.rows[0]["same"] == "0 %"


def test_a_learner_transfers_only_when_every_difference_lies_inside_the_margin():
    iv = lambda lo, hi: Interval((lo + hi) / 2, lo, hi, "x")  # noqa: E731
    assert engines.outcome({"mujoco": iv(-0.01, 0.01), "bullet": iv(-0.02, 0.02)}) == "transfers"
    assert engines.outcome({"mujoco": iv(-0.01, 0.01), "bullet": iv(-0.2, -0.05)}) == "loses"
    assert engines.outcome({"mujoco": iv(-0.01, 0.01), "bullet": iv(-0.2, 0.05)}) == "unclear"
    assert engines.outcome({"mujoco": iv(-0.02, 0.02)}, delta=0.01) == "unclear", "at a smaller margin"


def test_the_engines_are_synths_and_the_learners_are_named_as_in_the_motion_chapter():
    assert engines.ENGINES is synth.ENGINES and engines.ENGINES[0] == "mujoco"
    assert all(engines.NAMES[n] == motion.NAMES[n] for n in engines.LEARNERS)
    assert not any(n.startswith("lstm") for n in engines.LEARNERS)


# ---------------------------------------------------------------------------------------------
# The chapter's computation, on a cache of fake runs


def _score(c) -> float:
    """Test accuracy of a fake run: seed 1 the best on the test split."""
    return 0.6 + 0.1 * (c.dims == "xyz") + 0.15 * (c.seed == 1)


def _val(c) -> float:
    """Validation accuracy: seed 0 the best there, so validation and the test split disagree on the best run."""
    return 0.7 + 0.1 * (c.seed == 0)


@pytest.fixture(scope="module")
def e(tmp_path_factory) -> engines.AnotherEngine:
    runner = Runner.open("smoke", data_dir=tmp_path_factory.mktemp("data"))
    p = runner.preset
    cache_records(runner, paper.grid_configs(p, "peephole"), test=False, val_score=_val)
    cache_records(runner, paper.grid_configs(p, "peephole", "velocity"), test=False, val_score=_val)
    cfgs = engines.configs(runner)
    cols = engines.columns(CAL)
    runners = {eng: runner.in_engine(eng) for eng in synth.ENGINES}
    for r, batch, _ in engines.plan(runners, cfgs, cols, p.grid_seeds, p.seeds):
        cache_records(r, batch, _score, val_score=_val)
        cache_models(r, [c for c in batch if c.dims == "z"])
    T = cfgs["peephole_positions"].n_frames(runner.fps)
    for c in cols:
        data = {eng: c.inputs(r.dataset, T) for eng, r in runners.items()}
        tests = {eng: x for eng, (_, x) in data.items()}
        for eng, r in runners.items():
            y = {o: np.asarray(runners[o].dataset.test.y) for o in runners}
            # trained in Bullet: right on every Bullet throw, wrong on every MuJoCo one; trained in MuJoCo: right
            labels = {o: y[o] if eng == "mujoco" or o == "bullet" else 1 - y[o] for o in runners}
            for s in p.grid_seeds:
                cache_rocket(r, "z", T, s, tests, labels, None if c.noise is None else data[eng][0])
    return engines.compute(runner, tracker=CAL)


def test_every_number_keeps_its_name_and_reads_back_from_the_results_file(e, tmp_path):
    names = [name for name, _ in e.numbers.entries()]
    assert len(names) == len(set(names)) == 8 + 4 * 2 * 4 + 1 + 4 * 2 * 2 + 2 * 2 * 2
    assert {"engine.agreement.bounces.light", "engine.cross.peephole_positions.exact.mujoco_to_bullet",
            "engine.cross.rule.calibrated.bullet_to_bullet", "engine.ceiling",
            "engine.transfer.peephole_velocity.calibrated.bullet", "engine.table1.xyz.paper_way",
            "engine.table1.z.mean", "engine.table1_mujoco_air_off.z.paper_way"} <= set(names)
    f = tmp_path / "results.json"
    f.write_text(results.dumps(e.numbers.entries()))
    assert engines.Numbers.read(results.load(f)) == e.numbers


def test_table1_in_each_engine_is_the_run_validation_picks_never_the_best_test_run(e):
    for eng, rows in (("bullet", e.numbers.table1), ("mujoco", e.numbers.table1_mujoco_air_off)):
        for d in ("xyz", "z"):
            runs = e.in_engine[eng].where(dims=d)
            assert rows[d].paper_way.source == {"seed": 0}, "validation prefers seed 0"
            assert rows[d].paper_way.value == pytest.approx(runs.one(seed=0).accuracy)
            assert rows[d].paper_way.value < max(runs.accuracies()), "seed 1 is better on the test split"
            assert rows[d].mean.value == pytest.approx(runs.accuracies().mean())
            assert (rows[d].paper_way.paper == paper.TABLE1[d]) == (eng == "bullet")
            assert (rows[d].paper_way.verdict is not None) == (eng == "bullet"), "against the paper in Bullet only"
    assert e.engine_table1.rows[0]["verdict"] == f"**{e.numbers.table1['xyz'].paper_way.verdict}**"


def test_what_a_learner_loses_when_the_engine_changes(e):
    for view in engines.VIEWS:
        moved = e.numbers.transfer["minirocket"][view]
        assert moved["bullet"].value == -1.0 and moved["mujoco"].value == 0.0 and moved["bullet"].signed
        assert e.outcomes["minirocket", view] == "loses"
        cross = e.numbers.cross["minirocket"][view]
        assert cross["bullet_to_bullet"].value == 1.0 and cross["bullet_to_mujoco"].value == 0.0
    assert e.transfer_summary.startswith(f"Of {len(engines.LEARNERS) * 2} learners and conditions")
    lost = [r for r in e.transfer_table.rows if r["learner"] == engines.NAMES["minirocket"]]
    assert all(r["says"] == engines.OUTCOME_WORDS["loses"] for r in lost)


def test_every_learner_is_trained_in_one_engine_and_tested_in_both(e):
    assert len(e.entries) == len(engines.LEARNERS) * len(e.columns) * 4
    for x in e.entries:
        assert x.correct.shape[0] == (1 if x.learner == "rule" else 2)
        if x.learner in engines.NETWORKS:
            assert x.failed == e.numbers.cross[x.learner][x.column.name][f"{x.train}_to_{x.test}"].source["failed"]
    assert e.numbers.ceiling.value == pytest.approx(motion.column_ceiling(synth.SynthConfig.preset("smoke"),
                                                                          e.columns[0]))
    assert set(e.agreement) == set(engines.AGREEMENT) and len(e.test_y) == len(e.agreement["bounces"])
    assert e.checks.flight_error.max() < 1e-6 and set(e.checks.rebound) == set(engines.DROPS)
