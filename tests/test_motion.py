"""The pieces of the chapters on what the motion allows and on another engine: the camera columns, the
learners' configs, the best-learner rule, the engines' throw-by-throw agreement, the seeds' agreement."""

from __future__ import annotations

import math

import numpy as np
import pytest

from study.book import tables
from study.experiments import engines, motion, stats
from study.learn.config import TrainConfig
from study.learn.metrics import Interval, bootstrap_accuracy
from study.simulate import measure

CAL = {"noise_px": 1.02, "noise_m": 0.0141, "drop": 0.05, "n_frames": 100, "metres_per_pixel": 0.0138}


def test_the_columns_come_from_the_camera_model():
    cols = motion.columns(CAL)
    assert [(c.air, c.name) for c in cols] == [(a, n) for a in (True, False) for n in ("exact", "near", "calibrated", "far")]
    near = next(c for c in cols if c.name == "near")
    far = next(c for c in cols if c.name == "far")
    one_px = lambda d: 2 * d * math.tan(math.radians(22.5)) / 1080  # noqa: E731
    assert near.noise == pytest.approx(one_px(4.0)) and far.noise == pytest.approx(one_px(55.0))
    assert next(c for c in cols if c.name == "calibrated").noise == CAL["noise_m"]
    assert all(c.drop == (0.0 if c.noise is None else CAL["drop"]) for c in cols), "lost frames in every observed one"
    assert "3.1 mm" in near.label and "42.2 mm" in far.label and "1.02 px" in cols[2].label


def test_each_network_trains_on_the_condition_it_is_tested_on():
    base = {n: TrainConfig(dims="xyz") for n in motion.NETWORKS + ("lstm_exact_trained",)}
    exact, observed = motion.columns(CAL)[0], motion.columns(CAL)[2]
    assert set(motion.network_configs(base, exact)) == set(motion.NETWORKS), "no exact-trained row where all are exact"
    cfgs = motion.network_configs(base, observed)
    assert cfgs["lstm_positions"].observe == "fixed" and cfgs["lstm_positions"].observe_noise == CAL["noise_m"]
    assert cfgs["lstm_positions"].observe_drop == CAL["drop"] and cfgs["lstm_positions"].dims == "z"
    assert cfgs["lstm_exact_trained"].observe == "exact"
    plan = motion.plan({True: "on", False: "off"}, base, motion.columns(CAL), (0, 1, 2))
    assert [r for r, _, _ in plan] == ["on"] * 4 + ["off"] * 4 and all(test for _, _, test in plan)
    assert sum(len(c) for _, c, _ in plan) == 3 * (2 * 3 + 6 * 4), "3 seeds: 3 nets per exact column, 4 observed"


def test_the_best_learner_is_tied_when_the_paired_difference_spans_zero():
    rng = np.random.default_rng(0)
    truth = rng.random((3, 2000)) < 0.8
    col = motion.columns(CAL)[0]
    same = [motion.Cell("a", col, truth), motion.Cell("b", col, truth.copy())]
    assert motion.best_of(same)["tied"]
    worse = truth & (rng.random((3, 2000)) < 0.8)
    clear = motion.best_of([motion.Cell("weak", col, worse), motion.Cell("strong", col, truth)])
    assert clear["best"] == "strong" and not clear["tied"] and clear["difference"].lo > 0


def test_the_ceiling_of_a_column_knows_the_mass_only_with_air():
    from study.simulate import synth

    cfg = synth.SynthConfig.preset("paper")
    on, off = motion.columns(CAL)[0], motion.columns(CAL)[4]
    assert motion.column_ceiling(cfg, on) == 1.0 and 0.5 < motion.column_ceiling(cfg, off) < 1.0


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


def test_seeds_agree_unless_one_interval_misses_another():
    iv = lambda v: Interval(v, v - 0.01, v + 0.01, "x")  # noqa: E731
    assert stats.intervals_agree([iv(0.70), iv(0.71), iv(0.715)])
    assert not stats.intervals_agree([iv(0.70), iv(0.71), iv(0.85)]), "a seed that trained where others stalled"


def test_every_seed_and_a_t_interval_beside_the_bootstrap():
    c = np.array([[1, 1, 0, 1], [1, 0, 0, 1]], bool)
    text = tables.seeds_ci(c)
    assert text.startswith("62.5 % [") and "; t [" in text and text.endswith("75.0 · 50.0")
    assert tables.seeds_ci(c[:1]) == tables.pct_ci(bootstrap_accuracy(c[0])), "one seed: no t-interval"
    dv = stats.mean_difference(np.full(50, 3.0), np.full(40, 1.0))
    assert dv.value == 2.0 and dv.lo == dv.hi == 2.0


def test_a_column_draws_the_same_noise_for_every_engine_and_its_own_per_column():
    from study.simulate.data import Dataset, Split

    rng = np.random.default_rng(0)
    split = lambda: Split(rng.random((4, 40, 3)), np.array([0, 1, 0, 1]), {})  # noqa: E731
    ds = Dataset(train=split(), test=split(), fps=30.0)
    cols = motion.columns(CAL)
    exact, cal_on, cal_off = cols[0], cols[2], cols[6]
    assert all(np.array_equal(a, b) for a, b in zip(exact.inputs(ds, 30), (ds.train.x[:, :30], ds.test.x[:, :30])))
    a, b = cal_off.inputs(ds, 30), cal_off.inputs(ds, 30)
    assert np.array_equal(a[1], b[1], equal_nan=True), "the same column draws the same noise"
    assert not np.array_equal(a[1], cal_on.inputs(ds, 30)[1], equal_nan=True), "air on and off draw apart"
