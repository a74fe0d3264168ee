"""The Bullet scene (study.simulate.bullet) checked against physics and against MuJoCo's launch, as
tests/test_physics.py checks the MuJoCo scene."""

import dataclasses
import math

import mujoco
import numpy as np
import pybullet
import pytest

from study.core.errors import ConfigError
from study.simulate import bullet, measure, synth
from study.simulate.scene import Shape


@pytest.fixture(scope="module")
def cfg(smoke_cfg):
    """The smoke config without air (Bullet has none)."""
    return smoke_cfg.replace(air=False)


def split(cfg: synth.SynthConfig, seed: int = 0) -> dict[str, np.ndarray]:
    """The throws of ``synth.sample_split(cfg, seed, "train")`` (same random streams, light then heavy)
    without MuJoCo's contact damping, whose calibration Bullet does not need and which takes seconds."""
    parts = []
    for label, name in enumerate(("light", "heavy")):
        rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(0, label)))
        objects = synth.sample_objects(cfg.prior(name), cfg.n_train, rng)
        qpos, qvel = synth.sample_launch(cfg.launch, cfg.n_train, rng)
        parts.append({"label": np.full(cfg.n_train, label), **objects, "qpos0": qpos, "qvel0": qvel})
    return {k: np.concatenate([p[k] for p in parts]) for k in parts[0]}


@pytest.fixture(scope="module")
def high_launches(cfg):
    """Launches from 12-15 m: no contact within the one second the free-flight checks simulate."""
    high = cfg.replace(launch=synth.LaunchPrior(height=(12.0, 15.0)))
    return synth.sample_launch(high.launch, 6, np.random.default_rng(1))


def test_inertia_is_a_uniform_solid_box_as_in_mujoco(cfg):
    mass = 2.5
    expected = synth.build_model(cfg, mass, 100.0, 0.5).body_inertia[1]
    a, b, c = (2 * s for s in cfg.shape.size)
    assert expected == pytest.approx(mass / 12 * np.array([b * b + c * c, a * a + c * c, a * a + b * b]), rel=1e-12)
    assert bullet.inertia(cfg.shape, mass) == pytest.approx(expected, rel=1e-12)


def test_the_scene_has_the_documented_contact_settings(cfg):
    """Both rigid bodies (body type 1), as in Blender. Ground: lateral friction 1, no rolling or spinning
    friction, so each contact value is the object's; object: MuJoCo's rolling (0.0001 m) and torsional
    (0.005 m) friction. (pybullet reports no restitution for rigid bodies; the drops measure it.)"""
    with bullet.client() as cid:
        body = bullet.build(cid, cfg.shape, mass=2.0, restitution=0.3, friction=0.6)
        ground = next(b for b in range(pybullet.getNumBodies(physicsClientId=cid)) if b != body)
        info = pybullet.getDynamicsInfo(body, -1, physicsClientId=cid)
        ground_info = pybullet.getDynamicsInfo(ground, -1, physicsClientId=cid)
    mass, lateral, _, _, _, _, rolling, spinning = info[:8]
    assert (mass, lateral, rolling, spinning) == pytest.approx((2.0, 0.6, 1e-4, 5e-3))
    assert info[10] == ground_info[10] == 1
    assert (ground_info[0], ground_info[1], ground_info[6], ground_info[7]) == (0.0, 1.0, 0.0, 0.0)  # static


def test_free_flight_follows_the_parabola(cfg, high_launches):
    """With the staggered start Bullet's semi-implicit Euler is exact for constant gravity: every step of
    1 s on ``p0 + v0 t - g t^2 / 2`` to rounding (1e-9 m; the error without the stagger is g dt t / 2, 2 cm)."""
    qpos, qvel = high_launches
    for i in range(len(qpos)):
        pos, _ = bullet.flight(cfg, qpos[i], qvel[i], 1.0)
        t = bullet.TIMESTEP * np.arange(1, len(pos) + 1)[:, None]
        exact = qpos[i, :3] + qvel[i, :3] * t + np.array([0.0, 0.0, -synth.GRAVITY / 2]) * t**2
        assert pos[:, 2].min() > 5.0  # far from the ground: no contact
        assert np.abs(pos - exact).max() < 1e-9
    # the naive start (Bullet given the launch velocity as it is) sags by g dt t / 2: 2 cm after 1 s
    naive = qvel[0] - np.array([0.0, 0.0, synth.GRAVITY * bullet.TIMESTEP / 2, 0.0, 0.0, 0.0])
    pos, _ = bullet.flight(cfg, qpos[0], naive, 1.0)
    t = bullet.TIMESTEP * np.arange(1, len(pos) + 1)
    exact_z = qpos[0, 2] + qvel[0, 2] * t - synth.GRAVITY / 2 * t**2
    assert np.abs(pos[:, 2] - exact_z).max() == pytest.approx(synth.GRAVITY * bullet.TIMESTEP * 1.0 / 2, rel=0.01)


def test_the_launch_matches_mujocos_in_flight(cfg, high_launches):
    """The same spinning launches in MuJoCo (its own step, staggered) and Bullet: after 0.5 s the centres
    agree to 1e-9 m and the orientations to 1e-9 (a body-frame spin given to Bullet as world-frame
    would be off by order 1)."""
    qpos, qvel = high_launches
    params = {"mass": np.ones(len(qpos)), "damping": np.full(len(qpos), 100.0), "friction": np.full(len(qpos), 0.5),
              "qpos0": qpos, "qvel0": qvel}
    for i in range(len(qpos)):
        assert np.abs(qvel[i, 3:]).max() > 0.5  # the check means something only with spin
        m, d = synth.initial_data(cfg, params, i)
        for _ in range(int(round(0.5 / m.opt.timestep))):
            mujoco.mj_step(m, d)
        assert d.ncon == 0
        pos, quat = bullet.flight(cfg, qpos[i], qvel[i], 0.5)
        assert np.abs(pos[-1] - d.qpos[:3]).max() < 1e-9
        assert min(np.abs(quat[-1] - d.qpos[3:7]).max(), np.abs(quat[-1] + d.qpos[3:7]).max()) < 1e-9


def test_launch_state_converts_the_conventions():
    """A quarter turn about z: MuJoCo's (w, x, y, z) becomes Bullet's (x, y, z, w); body-frame spin about
    body x is world-frame spin about world y; the vertical velocity gains g dt / 2."""
    h = math.sqrt(0.5)
    pos, orn, lin, ang = bullet.launch_state(np.array([1.0, 2.0, 3.0, h, 0.0, 0.0, h]),
                                             np.array([0.5, 0.0, -1.0, 2.0, 0.0, 0.0]), timestep=0.01)
    assert pos == [1.0, 2.0, 3.0]
    assert orn == pytest.approx([0.0, 0.0, h, h])
    assert lin == pytest.approx([0.5, 0.0, -1.0 + synth.GRAVITY * 0.005])
    assert ang == pytest.approx([0.0, 2.0, 0.0])


def test_the_calibration_tables_cover_the_priors(cfg):
    """Bullet's ``restitution`` is not the measured one (a 20 cm box set to 0.4 rebounds at about 0.43 off
    the box ground); both tables increase and reach every class's range."""
    setting, e = bullet.restitution_table(cfg.shape)
    assert np.all(np.diff(e) > 0) and np.all(np.diff(setting) > 0)
    assert float(np.interp(0.4, setting, e)) == pytest.approx(0.43, abs=0.02)
    lo, hi = bullet.restitution_range(cfg.shape)
    mu_setting, mu = bullet.friction_table(cfg.shape)
    for prior in (synth.LIGHT, synth.HEAVY, synth.LIGHT_BALLS):
        assert lo <= prior.restitution[0] and prior.restitution[1] <= hi
        assert mu[0] <= prior.friction[0] and prior.friction[1] <= mu[-1]


@pytest.mark.parametrize("label", [0, 1])
def test_restitution_of_flat_drops_matches_the_request(cfg, label):
    """Flat drops over the class's whole restitution range, from several heights and with the class's
    lightest, heaviest and middle mass: every bounce's sqrt(h2 / h1) (bounces of 5 mm or more) within
    0.05 of the e asked for."""
    prior = cfg.prior(label)
    for e in np.linspace(*prior.restitution, 4):
        setting = float(bullet.restitution_setting(e, cfg.shape))
        for drop, mass in [(0.6, prior.mass[0]), (1.0, prior.mass[1]), (1.4, math.sqrt(prior.mass[0] * prior.mass[1]))]:
            h = bullet.flat_drops(cfg.shape, setting, drop, mass=mass, bounces=3)[0]
            h = h[h >= 0.005]
            measured = np.sqrt(h[1:] / h[:-1])
            assert len(measured) >= 1, f"e={e:.2f} drop={drop}: no bounce measured"
            assert np.all(np.abs(measured - e) < 0.05), (e, drop, mass, measured)


def test_energy_never_rises_in_flat_drops(cfg):
    for e in (0.35, 0.75):
        h = bullet.flat_drops(cfg.shape, float(bullet.restitution_setting(e, cfg.shape)), 1.0, bounces=4)[0]
        h = h[h > 0]
        assert len(h) >= 3 and np.all(np.diff(h) < 0), h


def test_halving_the_timestep_changes_restitution_by_less_than_0_02(cfg):
    e = np.array([0.1, 0.3, 0.5, 0.75])
    setting = bullet.restitution_setting(e, cfg.shape)
    at_dt = bullet.measured_restitution(cfg.shape, setting)
    at_half = bullet.measured_restitution(cfg.shape, setting, timestep=bullet.TIMESTEP / 2)
    assert np.abs(at_dt - e).max() < 0.005  # the table inverts as it should
    assert np.abs(at_dt - at_half).max() < 0.02, (at_dt, at_half)


def test_sliding_friction_decelerates_at_mu_g(cfg):
    """A box sliding on a face across both priors' friction range slows at mu g within 1 %; Bullet's own
    setting is that mu already (the calibration changes it by < 0.5 %)."""
    mu = np.linspace(0.3, 0.7, 5)
    setting = bullet.friction_setting(mu, cfg.shape)
    assert setting == pytest.approx(mu, rel=5e-3)
    decel = bullet.slide_deceleration(cfg.shape, setting, mass=5.0)
    assert decel == pytest.approx(mu * synth.GRAVITY, rel=0.01)


def test_bullet_multiplies_the_lateral_frictions(cfg):
    """Why the ground's friction is 1: with 0.5 there, an object set to 0.8 slides at 0.4 g."""
    with bullet.client() as cid:
        body = bullet.build(cid, cfg.shape, mass=1.0, restitution=0.0, friction=0.8)
        ground = next(b for b in range(pybullet.getNumBodies(physicsClientId=cid)) if b != body)
        pybullet.changeDynamics(ground, -1, lateralFriction=0.5, physicsClientId=cid)
        bullet._launch(cid, body, np.array([0.0, 0.0, 0.1, 1.0, 0.0, 0.0, 0.0]), np.array([3.0, 0, 0, 0, 0, 0]),
                       bullet.TIMESTEP)
        speeds = []
        for _ in range(60):  # the first steps settle the contact; the slope is measured after them
            pybullet.stepSimulation(physicsClientId=cid)
            speeds.append(pybullet.getBaseVelocity(body, physicsClientId=cid)[0][0])
        v0, v1 = speeds[10], speeds[58]
    assert (v0 - v1) / (48 * bullet.TIMESTEP) == pytest.approx(0.4 * synth.GRAVITY, rel=0.01)


@pytest.fixture(scope="module")
def thrown(cfg):
    """Four light and four heavy 10 s throws from the study's priors, simulated in Bullet."""
    c = cfg.replace(duration=10.0, n_train=4)
    params = split(c)
    return c, params, bullet.simulate(c, params)


def test_simulate_returns_frames_from_the_launch(thrown):
    c, params, x = thrown
    assert x.shape == (8, c.n_frames, 3) and x.dtype == np.float64
    assert np.array_equal(x[:, 0], params["qpos0"][:, :3])
    assert np.all(x[:, :, 2] > c.shape.size[2] - 0.03)  # never through the ground


def test_thrown_objects_come_to_rest(thrown):
    """Both priors: below 5 cm/s (frame to frame) for the whole last second, on a face."""
    c, _, x = thrown
    assert measure.speeds(x, c.fps)[:, -int(c.fps):].max() < 0.05
    assert x[:, -1, 2] == pytest.approx(c.shape.rest_height, abs=1e-3)
    assert np.abs(x[:, -1] - x[:, -int(3 * c.fps)]).max() < 1e-4  # awake: creeps by microns a second at most


def test_simulate_is_deterministic_and_throws_are_independent(thrown, monkeypatch):
    """Bitwise the same again, alone as in a batch, and in two worker processes as in one."""
    c, params, x = thrown
    idx = [2, 6]
    assert np.array_equal(bullet.simulate(c, {k: v[idx] for k, v in params.items()}), x[idx])
    monkeypatch.setattr(bullet, "CHUNK", 1)  # one throw per unit of work, so both workers get some
    idx = [1, 5, 7]
    assert np.array_equal(bullet.simulate(c, {k: v[idx] for k, v in params.items()}, processes=2), x[idx])


def test_energy_never_rises_between_flights_without_friction(cfg):
    """Frictionless tumbling throws: each flight's energy at most the previous one's (+0.1 %), and a
    flight's energy constant to rounding."""
    c = cfg.replace(duration=4.0, light=synth.ClassPrior((0.1, 0.6), (0.35, 0.75), (0.0, 0.0)),
                    heavy=synth.ClassPrior((3.0, 25.0), (0.1, 0.5), (0.0, 0.0)))
    params = split(c)
    for i in [0, 1, 8, 9]:
        tr = bullet.trace(c, params, i)
        e = tr.flight_energies()
        assert len(e) >= 2
        assert np.all(np.diff(e) <= 1e-3 * e[0]), e
        first = np.flatnonzero(tr.in_contact)[0]  # the launch flight; the velocity after it is the contact's
        assert np.ptp(tr.energy[: first - 1]) < 1e-9 * tr.energy[0]


@pytest.fixture(scope="module")
def traces(cfg):
    """Two light and two heavy 6 s throws from the study's priors, every step recorded."""
    c = cfg.replace(duration=6.0)
    params = split(c)
    return c, [bullet.trace(c, params, i) for i in [0, 3, 8, 11]]


def test_energy_never_rises_between_flights_with_friction(traces):
    """Unlike MuJoCo's soft contact (tests/test_physics.py, xfail), Bullet's impulses never gave a tumbling
    box energy in these throws."""
    for tr in traces[1]:
        e = tr.flight_energies()
        assert len(e) >= 2
        assert np.all(np.diff(e) <= 1e-3 * e[0]), e


def test_penetration_stays_within_one_step_of_travel(traces):
    """Bullet resolves contact after the fact: an impact can sink in by what a point travels in one step
    at the fastest impact the launch prior allows (3 cm here), and no deeper."""
    c, ts = traces
    bound = c.max_impact_speed() * bullet.TIMESTEP
    assert bound < 0.035
    assert max(tr.depth.max() for tr in ts) <= bound


def test_bad_input_is_refused_by_name(cfg):
    params = split(cfg)
    one = {k: v[:1] for k, v in params.items()}
    with pytest.raises(ConfigError, match="kind = 'cone'"):
        bullet.simulate(dataclasses.replace(cfg, shape=Shape("cone", (0.1,))), one)  # past SynthConfig's own check
    with pytest.raises(ConfigError, match="'sphere'.*allowed: box"):
        bullet.simulate(cfg.replace(shape=Shape("sphere", (0.1,))), one)
    lo, hi = bullet.restitution_range(cfg.shape)
    with pytest.raises(ConfigError, match=rf"restitution 0\.999 .*\[{lo:.3f}, {hi:.3f}\]"):
        bullet.simulate(cfg, {**one, "restitution": np.array([0.999])})
    with pytest.raises(ConfigError, match=r"friction 1\.500 .*\[0\.000, 0\.90"):
        bullet.simulate(cfg, {**one, "friction": np.array([1.5])})
    with pytest.raises(ConfigError, match="restitution"):
        bullet.restitution_setting(np.nan, cfg.shape)
    with pytest.raises(ConfigError, match="SynthConfig.air"):
        bullet.simulate(cfg.replace(air=True), one)
    with pytest.raises(ConfigError, match="SynthConfig.fps"):
        bullet.simulate(cfg.replace(fps=25.0), one)
