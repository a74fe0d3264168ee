"""The simulation settings checked against physics (see the data chapter for the same checks as figures)."""

import dataclasses
import math

import mujoco
import numpy as np
import pytest

from study.core.errors import ConfigError
from study.simulate import checks, synth
from study.simulate.contact import penetration_bound


@pytest.fixture(scope="module")
def high_launches(smoke_cfg):
    """Launches from 12-15 m: no contact within the one second the free-flight checks simulate."""
    high = smoke_cfg.replace(launch=synth.LaunchPrior(height=(12.0, 15.0)))
    return synth.sample_launch(high.launch, 6, np.random.default_rng(1))


def test_free_flight_follows_the_parabola(smoke_cfg, high_launches):
    """Air off, the staggered start: on the analytic parabola to rounding over 1 s."""
    qpos, qvel = high_launches
    errors = [checks.free_flight_error(smoke_cfg, qpos[i], qvel[i], duration=1.0) for i in range(6)]
    assert max(errors) < 1e-9


def test_free_flight_without_staggering_sags_by_g_t_dt_over_2(smoke_cfg, high_launches):
    """The naive start (the launch velocity given as it is) traces the parabola of v - g dt / 2: more
    than 1 mm off after 1 s at our step, which is why synthesis staggers the velocity."""
    qpos, qvel = high_launches
    errors = [checks.free_flight_error(smoke_cfg, qpos[i], qvel[i], duration=1.0, staggered=False) for i in range(6)]
    assert min(errors) > 1e-3
    assert max(errors) == pytest.approx(synth.GRAVITY * 1.0 * smoke_cfg.timestep / 2, rel=0.01)


@pytest.mark.parametrize("label", [0, 1])
def test_restitution_from_bounce_heights_matches_the_value_set(smoke_cfg, label):
    """Flat drops from several heights and masses: every bounce's sqrt(h2 / h1) within 0.05 of e."""
    prior = smoke_cfg.prior(label)
    for e in np.linspace(*prior.restitution, 4):
        for drop, mass in [(0.6, prior.mass[0]), (1.0, prior.mass[1]), (1.4, math.sqrt(prior.mass[0] * prior.mass[1]))]:
            measured = checks.restitution_from_drops(smoke_cfg, e, drop=drop, mass=mass, bounces=3)
            assert len(measured) >= 1, f"e={e:.2f} drop={drop}: no bounce measured"
            assert np.all(np.abs(measured - e) < 0.05), (e, drop, mass, measured)


def test_halving_the_timestep_changes_restitution_by_less_than_0_02(smoke_cfg):
    conv = checks.convergence(smoke_cfg, np.array([0.1, 0.3, 0.5, 0.7, 0.85]))
    assert np.all(np.abs(conv["dt"] - conv["dt/2"]) < 0.02), conv


@pytest.fixture(scope="module")
def traces(smoke_cfg):
    """Four throws per class from the smoke prior, 8 s each, every step recorded."""
    cfg = smoke_cfg.replace(duration=8.0)
    params = synth.sample_split(cfg, 0, "train")
    picks = [0, 1, 2, 3, 8, 9, 10, 11]
    return cfg, params, [checks.trace(cfg, params, i) for i in picks]


def test_objects_come_to_rest(traces):
    _, _, ts = traces
    for tr in ts:
        assert tr.speed[-900:].max() < 0.01  # below 1 cm/s for the last half second


def test_penetration_stays_within_its_bound_and_under_2_cm(traces):
    cfg, _, ts = traces
    bound = penetration_bound(cfg.max_impact_speed(), cfg.stiffness)
    assert bound < 0.02
    assert max(tr.depth.max() for tr in ts) <= bound


def test_energy_never_rises_between_flights_without_friction(smoke_cfg):
    """Frictionless tumbling throws, air off: each flight's energy at most the previous one's (+0.1 %)."""
    cfg = smoke_cfg.replace(duration=4.0, air=False, light=synth.ClassPrior((0.05, 0.5), (0.45, 0.85), (0.0, 0.0)),
                            heavy=synth.ClassPrior((3.0, 25.0), (0.1, 0.5), (0.0, 0.0)))
    params = synth.sample_split(cfg, 0, "train")
    for i in [0, 1, 8, 9]:
        e = checks.trace(cfg, params, i).flight_energies()
        assert len(e) >= 2
        assert np.all(np.diff(e) <= 1e-3 * e[0]), e


def test_energy_never_rises_in_flat_drops(smoke_cfg):
    """Flat drops with friction (no tangential motion): apex heights, hence energies, strictly fall."""
    for e in (0.45, 0.85):
        h = checks.restitution_from_drops(smoke_cfg, e, bounces=4)
        assert np.all(h <= 1.0)


@pytest.mark.xfail(strict=True, reason=(
    "known limitation, shown in the data chapter: MuJoCo's contact is a spring-damper in constraint "
    "space, and with friction an eccentric impact of a tumbling box can leave it with more energy"))
def test_energy_never_rises_between_flights_with_friction(traces):
    _, _, ts = traces
    for tr in ts:
        e = tr.flight_energies()
        assert np.all(np.diff(e) <= 1e-3 * e[0]), e


@pytest.fixture(scope="module")
def sleep_sample(smoke_cfg):
    """Eight light and eight heavy 3 s throws, simulated with the default sleep tolerance and awake."""
    return checks.sleep_effect(smoke_cfg, synth.sample_split(smoke_cfg, 0, "train"), range(16))


def test_sleeping_changes_nothing_before_an_object_has_come_to_rest(sleep_sample):
    """Asleep and awake runs are bitwise equal until the awake object is at rest; after it, within 1 cm."""
    r = sleep_sample
    assert np.isfinite(r["first_diff"]).sum() >= 4  # objects did fall asleep, so the comparison means something
    assert np.all(np.isnan(r["first_diff"]) | (r["first_diff"] >= r["time_to_rest"])), (r["first_diff"], r["time_to_rest"])
    assert r["max_diff"].max() < 0.01


def test_a_sleeping_object_stays_exactly_where_it_lies(smoke_cfg):
    """Heavy throws at rest: with sleep the last 10 frames are identical; awake, the object still creeps."""
    params = synth.sample_split(smoke_cfg, 0, "train")
    heavy = {k: v[8:12] for k, v in params.items()}
    for cfg, frozen in ((smoke_cfg, True), (smoke_cfg.replace(sleep_tolerance=0.0), False)):
        x = synth.simulate(cfg, heavy, threads=1, progress=False)
        still = [bool(np.all(x[i, -10:] == x[i, -1])) for i in range(len(x))]
        assert still == [frozen] * len(x), (cfg.sleep_tolerance, still)


def test_the_sleep_tolerance_limit_keeps_thrown_objects_awake_at_their_apex(smoke_cfg):
    """MuJoCo sleeps a body in mid-air too: a spinless vertical toss freezes at its apex above the allowed
    tolerance (built unvalidated here), and not at the largest tolerance the config allows."""
    limit = synth.max_sleep_tolerance(smoke_cfg.timestep)
    smoke_cfg.replace(sleep_tolerance=limit)  # allowed
    with pytest.raises(ConfigError, match="sleep_tolerance"):
        smoke_cfg.replace(sleep_tolerance=1.01 * limit)
    for tol, frozen in ((limit, False), (2 * limit, True)):
        m = synth.build_model(dataclasses.replace(smoke_cfg, sleep_tolerance=tol, air=False), 1.0, 100.0, 0.5)
        d = mujoco.MjData(m)
        d.qpos[:3], d.qvel[2] = (0.0, 0.0, 2.0), 1.0
        for _ in range(int(0.25 / m.opt.timestep)):  # the apex is at 0.1 s; the ground is far below
            mujoco.mj_step(m, d)
        assert (d.ntree_awake == 0) == frozen, tol
