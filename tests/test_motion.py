"""The chapter *What the motion allows*: its pieces (the camera columns, the learners' configs, the best-learner
rule, the ceiling) on arrays, and its computation on fake run records, models and MiniRocket fits written into a
fresh cache (nothing trains)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from fake_runs import cache_models, cache_records, cache_rocket

from study.book import results
from study.chapters import motion
from study.learn.config import TrainConfig
from study.learn.metrics import Interval, bootstrap_accuracy
from study.methods import camera
from study.methods.tracker import TrackerError
from study.report.text import pct, pct_ci, seeds_ci
from study.runs import Runner, paper, stats
from study.simulate import synth
from study.simulate.observe import Observation, TrackerNoise

pytestmark = pytest.mark.filterwarnings("ignore::RuntimeWarning")

MODEL = TrackerNoise(flight=0.02, contact=0.008, offset=0.006, rho=0.84)
CAL = Observation(tracker=MODEL, drop=0.05)
"""The calibrated tracker as ``calibration.observation`` gives it: the fitted error model and its lost frames."""
WHITE = TrackerError(noise_px=1.02, noise_m=0.0141, drop=0.05, n_frames=100, metres_per_pixel=0.0138)


def test_the_columns_come_from_the_camera_model():
    cols = camera.columns(CAL)
    assert [(c.air, c.name) for c in cols] == [(a, n) for a in (True, False) for n in ("exact", "near", "calibrated", "far")]
    near = next(c for c in cols if c.name == "near")
    far = next(c for c in cols if c.name == "far")
    one_px = lambda d: 2 * d * math.tan(math.radians(22.5)) / 1080  # noqa: E731
    assert near.noise == pytest.approx(one_px(4.0)) and far.noise == pytest.approx(one_px(55.0))
    cal = next(c for c in cols if c.name == "calibrated")
    assert cal.tracker == MODEL and cal.noise == pytest.approx(np.hypot(0.006, 0.02)), "its error in flight"
    assert near.tracker is None and far.tracker is None, "the reference columns stay white"
    assert cal.observation() == Observation(tracker=MODEL, drop=0.05) and near.observation().tracker is None
    assert all(c.drop == (0.0 if c.noise is None else CAL.drop) for c in cols), "lost frames in every observed one"
    assert "3.1 mm" in near.label and "42.2 mm" in far.label and "20.0 mm in flight" in cols[2].label
    assert "autocorrelation 0.84" in cols[2].label and "offset 6.0 mm" in cols[2].label
    assert [c.key for c in cols[3:5]] == ["air_on.far", "air_off.exact"] and cols[6].heading == "air off, tracker"
    white = camera.columns(WHITE)[2]  # a TrackerError: its white noise
    assert white.tracker is None and white.noise == 0.0141 and "white noise of 14.1 mm" in white.label


def test_the_calibrated_column_draws_correlated_noise_and_the_reference_columns_white():
    from study.simulate.data import Dataset, Split

    x = np.zeros((400, 60, 3))
    x[:, :, 2] = 1.0  # in flight throughout
    ds = Dataset(train=Split(x, np.zeros(400, int), {}), test=Split(x, np.zeros(400, int), {}), fps=30.0)
    near, cal = camera.columns(Observation(tracker=MODEL))[1:3]
    lag1 = lambda e: np.corrcoef(e[:, :-1].ravel(), e[:, 1:].ravel())[0, 1]  # noqa: E731
    e_cal, e_near = cal.inputs(ds, 60)[1][:, :, 2] - 1.0, near.inputs(ds, 60)[1][:, :, 2] - 1.0
    assert lag1(e_cal) > 0.8 and abs(lag1(e_near)) < 0.05
    assert np.std(np.diff(e_cal, axis=1)) == pytest.approx(MODEL.step_sd(), rel=0.05)


def test_each_network_trains_on_the_condition_it_is_tested_on():
    base = {n: TrainConfig(dims="xyz") for n in motion.NETWORKS + ("peephole_exact_trained",)}
    exact, observed = camera.columns(CAL)[0], camera.columns(CAL)[2]
    assert set(motion.network_configs(base, exact)) == set(motion.NETWORKS), "no exact-trained row where all are exact"
    cfgs = motion.network_configs(base, observed)
    c = cfgs["peephole_positions"]
    assert c.observe == "fixed" and c.observe_noise == MODEL.flight and c.observe_rho == MODEL.rho
    assert c.observe_offset == MODEL.offset and c.observe_contact_ratio == pytest.approx(0.4)
    assert c.observe_drop == CAL.drop and c.dims == "z"
    near = motion.network_configs(base, camera.columns(CAL)[1])["peephole_positions"]
    assert (near.observe_rho, near.observe_offset, near.observe_contact_ratio) == (0.0, 0.0, 1.0), "white"
    assert cfgs["peephole_exact_trained"].observe == "exact"
    plan = motion.plan({True: "on", False: "off"}, base, camera.columns(CAL), (0, 1, 2))
    assert [r for r, _, _ in plan] == ["on"] * 4 + ["off"] * 4 and all(test for _, _, test in plan)
    assert sum(len(c) for _, c, _ in plan) == 3 * (2 * 3 + 6 * 4), "3 seeds: 3 nets per exact column, 4 observed"


def test_each_column_chooses_a_network_rate_among_its_grid_by_mean_validation():
    from types import SimpleNamespace

    class Runs(list):
        def val_accuracies(self):
            return np.array([r.val_accuracy for r in self])

    class Fake:  # the GRU picked 0.003 on exact positions; through a noisy camera 2 of its 3 seeds stay at chance
        def __init__(self, val, loss=None):
            self.val, self.loss = val, loss or {lr: 0.6 for lr in val}

        def train_runs(self, cfg, dims, seeds, desc=""):
            return Runs(SimpleNamespace(val_accuracy=self.val[cfg.lr][s], val_loss=self.loss[cfg.lr]) for s in seeds)

    gru = TrainConfig(cell="gru", lr=3e-3, inputs="velocity")
    cands = motion.candidates(gru, {"gru": (1e-3, 3e-3)})
    assert [c.lr for c in cands] == [3e-3, 1e-3], "the grid's pick first"
    assert motion.chosen(Fake({3e-3: (0.52, 0.74, 0.51), 1e-3: (0.73, 0.69, 0.73)}), cands, (0, 1, 2)).lr == 1e-3
    assert motion.chosen(Fake({3e-3: (0.99, 0.55, 0.55), 1e-3: (0.70, 0.71, 0.72)}), cands, (0, 1, 2)).lr == 1e-3, \
        "the mean, not the best seed"
    even = {3e-3: (0.7, 0.7, 0.7), 1e-3: (0.7, 0.7, 0.7)}
    assert motion.chosen(Fake(even), cands, (0, 1, 2)).lr == 3e-3, "a tie keeps the grid's pick"
    assert motion.chosen(Fake(even, {3e-3: 0.6, 1e-3: 0.5}), cands, (0, 1, 2)).lr == 1e-3, "then the lower loss"


def test_the_runs_a_column_turned_down_are_marked_unless_another_row_uses_them():
    base = {"peephole_positions": TrainConfig(), "peephole_velocity": TrainConfig(inputs="velocity"),
            "gru_velocity": TrainConfig(cell="gru", inputs="velocity"),
            "peephole_exact_trained": TrainConfig()}  # never chosen again: Table 1's network as it is
    cols = camera.columns(CAL)
    rates = {"gru": (1e-3, 3e-3), "peephole": (1e-3, 3e-3)}
    plan = motion.plan({True: "on", False: "off"}, base, cols, (0, 1, 2), rates)
    gru = [c for _, batch, _ in plan for c in batch if c.cell == "gru"]
    assert {c.lr for c in gru} == {1e-3, 3e-3} and len(gru) == 8 * 3 * 2, "every column, both rates"
    trained_exact = [c for _, batch, _ in plan for c in batch if c.cell == "peephole" and c.observe == "exact"]
    assert len(trained_exact) == 2 * 2 * 3 * 2 + 6 * 3, "the exact-trained row at its own rate only"
    picked = {(n, c.key): base[n].lr for c in cols for n in motion.network_configs(base, c)}
    picked["gru_velocity", "air_on.far"] = 3e-3  # this column turned the grid's pick (0.001) down
    picked["peephole_positions", "air_off.exact"] = 3e-3  # ... and here, but the row trained exact uses 0.001
    down = motion.turned_down(base, cols, (0, 1, 2), rates, picked)
    far = [c for c in down[True] if c.cell == "gru" and c.lr == 1e-3]
    assert len(far) == 3 and {c.observe_noise for c in far} == {cols[3].noise}, "the far column's three seeds"
    assert not [c for c in down[False] if c.observe == "exact" and c.lr == 1e-3 and c.cell == "peephole"], \
        "a run the row trained exact uses is not turned down"
    assert len(down[True]) == 3 * 4 * 3, "3 rows, 4 columns, 3 seeds: one rate turned down each"
    assert len(down[False]) == 3 * 4 * 3 - 3, "less the air-off exact column's 0.001, which the row trained exact uses"


def test_the_page_says_which_column_chose_which_rate(m):
    assert m.rates_moved == "no column chose another rate than its grid's"
    key = m.columns[3].key
    entries = {**m.entries, ("gru_velocity", key): dataclasses.replace(m.entries["gru_velocity", key], lr=1e-4)}
    moved = dataclasses.replace(m, entries=entries).rates_moved
    assert moved == f"the {motion.NAMES['gru_velocity']}: lr 0.0001 in {m.columns[3].heading}"


def test_the_learners_are_the_peephole_lstm_by_name_never_lstm():
    assert not any(n.startswith("lstm") for n in motion.LEARNERS)
    assert set(motion.NAMES) == set(motion.LEARNERS) and "peephole_exact_trained" not in motion.SHOWN


def test_the_best_learner_is_tied_when_the_paired_difference_spans_zero():
    rng = np.random.default_rng(0)
    truth = rng.random((3, 2000)) < 0.8
    col = camera.columns(CAL)[0]
    same = [motion.Entry("physics", col, truth), motion.Entry("rule", col, truth.copy())]
    assert motion.best_of(same).tied
    worse = truth & (rng.random((3, 2000)) < 0.8)
    clear = motion.best_of([motion.Entry("physics", col, worse), motion.Entry("minirocket", col, truth)])
    assert clear.best == "minirocket" and clear.next == "physics"
    assert not clear.tied and clear.difference.lo > 0


def test_the_ceiling_of_a_column_knows_the_mass_only_with_air():
    cfg = synth.SynthConfig.preset("paper")
    on, off = camera.columns(CAL)[0], camera.columns(CAL)[4]
    assert camera.column_ceiling(cfg, on) == 1.0 and 0.5 < camera.column_ceiling(cfg, off) < 1.0


def test_seeds_agree_unless_one_interval_misses_another():
    iv = lambda v: Interval(v, v - 0.01, v + 0.01, "x")  # noqa: E731
    assert stats.intervals_agree([iv(0.70), iv(0.71), iv(0.715)])
    assert not stats.intervals_agree([iv(0.70), iv(0.71), iv(0.85)]), "a seed that trained where others stalled"


def test_every_seed_and_a_t_interval_beside_the_bootstrap():
    c = np.array([[1, 1, 0, 1], [1, 0, 0, 1]], bool)
    text = seeds_ci(c)
    assert text.startswith("62.5 % [") and "; t [" in text and text.endswith("75.0 · 50.0")
    assert seeds_ci(c[:1]) == pct_ci(bootstrap_accuracy(c[0])), "one seed: no t-interval"
    dv = stats.mean_difference(np.full(50, 3.0), np.full(40, 1.0))
    assert dv.value == 2.0 and dv.lo == dv.hi == 2.0


def test_a_column_draws_the_same_noise_for_every_engine_and_its_own_per_column():
    from study.simulate.data import Dataset, Split

    rng = np.random.default_rng(0)
    split = lambda: Split(rng.random((4, 40, 3)), np.array([0, 1, 0, 1]), {})  # noqa: E731
    ds = Dataset(train=split(), test=split(), fps=30.0)
    cols = camera.columns(CAL)
    exact, cal_on, cal_off = cols[0], cols[2], cols[6]
    assert all(np.array_equal(a, b) for a, b in zip(exact.inputs(ds, 30), (ds.train.x[:, :30], ds.test.x[:, :30])))
    a, b = cal_off.inputs(ds, 30), cal_off.inputs(ds, 30)
    assert np.array_equal(a[1], b[1], equal_nan=True), "the same column draws the same noise"
    assert not np.array_equal(a[1], cal_on.inputs(ds, 30)[1], equal_nan=True), "air on and off draw apart"


# ---------------------------------------------------------------------------------------------
# The chapter's computation, on a cache of fake runs

PERFECT = "air_on.far"
"""The column where the fake MiniRocket gets every test throw right: it must be that column's best learner."""


def _val(c) -> float:
    return 0.7 + 0.1 * (c.seed == 0)


def _loss(c) -> float:
    """Seed 1 of an observed column never leaves the plateau (a coin's loss): those runs failed to train. (Not the
    exact columns' runs: some of them are grid runs, whose losses choose the grid's winner.)"""
    return 0.69 if c.seed == 1 and c.observe != "exact" else 0.45


@pytest.fixture(scope="module")
def m(tmp_path_factory) -> motion.Motion:
    runner = Runner.open("smoke", data_dir=tmp_path_factory.mktemp("data"))
    p = runner.preset
    for cell in ("peephole", "gru"):
        cache_records(runner, paper.grid_configs(p, cell), test=False, val_score=_val)
    cache_records(runner, paper.grid_configs(p, "peephole", "velocity"), test=False, val_score=_val)
    cfgs = motion.configs(runner)
    cols = camera.columns(CAL)
    on = {True: runner, False: runner.air_off()}
    for r, batch, _ in motion.plan(on, cfgs, cols, p.grid_seeds):
        cache_records(r, batch, val_score=_val, val_loss=_loss)
        cache_models(r, batch)
    T = cfgs["peephole_positions"].n_frames(runner.fps)
    for c in cols:
        r = on[c.air]
        x_train, x_test = c.inputs(r.dataset, T)
        y = np.asarray(r.dataset.test.y)
        for s in p.grid_seeds:
            labels = y if c.key == PERFECT else np.zeros_like(y)  # perfect, or every throw called light
            cache_rocket(r, "z", T, s, {"test": x_test}, {"test": labels}, None if c.noise is None else x_train)
    return motion.compute(runner, calibrated=CAL)


def test_every_number_keeps_its_name_and_reads_back_from_the_results_file(m, tmp_path):
    names = [name for name, _ in m.numbers.entries()]
    assert len(names) == len(set(names)) == 3 + 3 + 3 * 8 + 6 + 3 * 8 + 1 + 2 * 8
    views = [c.key for c in camera.columns(CAL)]
    for learner in ("peephole_positions", "peephole_velocity", "gru_velocity", "minirocket", "physics", "rule"):
        assert all(f"motion.{learner}.{v}" in names for v in views)
    assert "motion.peephole_exact_trained.air_on.near" in names
    assert "motion.peephole_exact_trained.air_on.exact" not in names, "trained exact and tested exact: Table 1's"
    assert {"motion.ceiling.air_off", "motion.ceiling.air_on", "motion.ceiling.air_off_restitution",
            "motion.noise.calibrated", "motion.failed_runs", "motion.best.air_off.far.lead",
            "motion.best.air_on.exact.gap_to_ceiling"} <= set(names)
    f = tmp_path / "results.json"
    f.write_text(results.dumps(m.numbers.entries()))
    back = motion.Numbers.read(results.load(f))
    assert back == m.numbers and back.best["air_on"]["far"].learner == "minirocket"


def test_each_entry_is_what_its_learner_got_right(m):
    n = len(m.entries["physics", "air_on.exact"].correct[0])
    for (learner, key), e in m.entries.items():
        seeded = learner not in ("physics", "rule")
        assert e.correct.shape == ((2, n) if seeded else (1, n)), (learner, key)
        source = m.numbers.learners[learner][e.column.air_key][e.column.name].source
        assert source["seeds"] == ([0, 1] if seeded else []) and source["failed"] == e.failed
        network = learner in motion.NETWORKS or learner == "peephole_exact_trained"
        assert source.get("lr") == e.lr and (e.lr is not None) == network, "a network's rate is in its source"
    assert m.entries["minirocket", PERFECT].correct.all()
    assert m.entries["rule", "air_off.exact"].feature in camera.RULE_FEATURES
    assert all(m.entries[n, "air_on.exact"].val == pytest.approx(0.75) for n in motion.NETWORKS), "mean of 0.8, 0.7"


def test_the_failed_runs_count_each_network_run_once(m):
    assert m.n_runs == 8 * 3 * 2, "8 columns, 3 networks, 2 seeds; the exact-trained row is Table 1's runs again"
    failed = sum(e.failed for (n, _), e in m.entries.items() if n in motion.NETWORKS)
    assert m.n_failed == failed == m.numbers.failed_runs.value and m.numbers.failed_runs.unit == "count"


def test_each_columns_best_learner_is_the_highest_mean_and_its_lead_is_paired(m):
    for c in m.columns:
        here = {n: e for (n, k), e in m.entries.items() if k == c.key}
        best = m.numbers.best[c.air_key][c.name]
        assert here[best.learner].correct.mean() == max(e.correct.mean() for e in here.values())
        assert best.tied == (best.lead.lo <= 0 <= best.lead.hi) and best.lead.signed
        assert best.gap_to_ceiling.value == pytest.approx(m.ceilings[c.key] - here[best.learner].correct.mean())
    perfect = m.numbers.best["air_on"]["far"]
    assert perfect.learner == "minirocket" and not perfect.tied and perfect.gap_to_ceiling.value == 0.0
    for key in ("air_on.exact", "air_off.exact", "air_on.calibrated", "air_off.calibrated"):
        assert f"the {motion.NAMES[m.leads[key].best]} at" in m.answer


def test_the_tables_and_sentences(m):
    assert len(m.motion_table.rows) == len(motion.LEARNERS) + 1
    exact_trained = m.motion_table.rows[motion.LEARNERS.index("peephole_exact_trained")]
    positions = m.motion_table.rows[motion.LEARNERS.index("peephole_positions")]
    assert exact_trained["air_on.exact"] == "—" and not exact_trained["air_on.near"].endswith("failed")
    assert positions["air_on.near"].endswith("failed"), "an observed column's seed 1 failed to train: said there"
    assert m.motion_table.rows[-1]["air_on.exact"] == "**100.0 %**"
    assert [r["column"] for r in m.best_table.rows] == [c.heading for c in m.columns]
    assert m.calibrated_model == MODEL.describe() and "lag-1 autocorrelation 0.84" in m.conditions
    assert "ahead of the" in m.best_table.rows[3]["lead"], "the perfect MiniRocket leads its column"
    assert len(m.seed_table.rows) == 8 * 3 + 6 + 8, "every seeded entry: networks, exact-trained, MiniRocket"
    assert m.conditions.count(";") == 3 and m.drop_pct == "5.0" and m.restitution_overlap.count("–") == 1
    assert m.vel_gain_on.startswith(("+", "-")) and m.length_s == 1.0
    assert m.answer.startswith(f"Without air no classifier of these trajectories can beat "
                               f"{pct(m.numbers.ceiling.air_off.value)};")


def test_the_wide_tables_split_by_air_and_keep_every_cell(m):
    for name in ("motion", "gap"):
        whole = getattr(m, f"{name}_table")
        on, off = (getattr(m, f"{name.replace('motion', 'table')}_air_{a}") for a in ("on", "off"))
        assert len(on.columns) == len(off.columns) == 1 + 4, "the learner and four conditions"
        assert on.columns["air_on.exact"] == "exact" and off.columns["air_off.far"].endswith("55 m")
        for half in (on, off):
            assert [r["learner"] for r in half.rows] == [r["learner"] for r in whole.rows]
            assert all(r[k] == w[k] for r, w in zip(half.rows, whole.rows) for k in half.columns)
        assert set(on.columns) | set(off.columns) == set(whole.columns)
