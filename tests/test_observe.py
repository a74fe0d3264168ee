"""The observation model: each function's statistics, its composition, and its bad inputs."""

from __future__ import annotations

import numpy as np
import pytest

from study.core.errors import ConfigError, TrajectoryError
from study.learn.config import TrainConfig
from study.learn.inputs import observation, observe_fields
from study.simulate import observe


def parabolas(n: int = 50, T: int = 90, fps: float = 30.0, seed: int = 0) -> np.ndarray:
    """Smooth trajectories (n, T, 3): free flight of random throws, no ground (for exact interpolation tests)."""
    rng = np.random.default_rng(seed)
    t = np.arange(T) / fps
    p0 = rng.uniform(-1, 1, (n, 1, 3)) + np.array([0, 0, 3.0])
    v0 = rng.uniform(-2, 2, (n, 1, 3))
    x = p0 + v0 * t[None, :, None]
    x[:, :, 2] -= 0.5 * 9.81 * t**2 / 4
    return x


def test_noise_has_the_size_asked_for_and_only_on_the_height():
    x = parabolas(200)
    y = observe.noise(x, 0.01, np.random.default_rng(1))
    d = y - x
    assert np.std(d[:, :, 2]) == pytest.approx(0.01, rel=0.02) and abs(np.mean(d[:, :, 2])) < 5e-4
    assert (d[:, :, :2] == 0).all()
    per = observe.noise(x, np.linspace(0, 0.02, 200), np.random.default_rng(1))
    assert np.std((per - x)[:10, :, 2]) < np.std((per - x)[-10:, :, 2])  # one size per trajectory
    assert (observe.noise(x, 0.0, np.random.default_rng(1)) == x).all()


def test_dropped_frames_are_the_share_asked_for_and_filled_linearly():
    rng = np.random.default_rng(2)
    x = parabolas(100)
    y = observe.drop(x, 0.3, rng)
    changed = np.abs(y - x).max(axis=2) > 1e-12
    # On a straight line linear interpolation is exact; on these parabolas it is not: the lost frames
    # are the ones that moved. About 30 % of the frames (the first one is never lost).
    assert changed[:, 0].sum() == 0 and changed.mean() == pytest.approx(0.3 * 89 / 90, abs=0.02)
    line = np.broadcast_to(np.linspace(0, 1, 90)[None, :, None], (5, 90, 3))
    y = observe.drop(line, 0.3, np.random.default_rng(3))
    # Interpolated frames lie on the line; lost frames at the very end cannot be interpolated and hold
    # the last frame the tracker has, so compare all but the last few.
    np.testing.assert_allclose(y[:, :80], line[:, :80], atol=1e-12)


def test_fill_runs_fills_short_gaps_and_splits_at_long_ones():
    v = np.arange(12, dtype=float)[:, None]
    measured = np.ones(12, bool)
    measured[[3, 6, 7, 8, 9]] = False
    filled, seg = observe.fill_runs(v, measured, max_gap=2)
    assert filled[3, 0] == 3.0 and seg.tolist() == [0] * 6 + [-1] * 4 + [1, 1]


def test_camera_rate_resamples_a_smooth_curve_to_tolerance():
    fps = 120.0
    x = parabolas(20, T=361, fps=fps)  # 3 s at 120 fps
    at30 = x[:, ::4]
    for camera in (120.0, 60.0, 30.0):
        y = observe.camera_rate(x, fps, camera, out_fps=30.0)
        assert y.shape == at30.shape
        np.testing.assert_allclose(y, at30, atol=1e-12)  # a frame the camera has is the frame itself
    y15 = observe.camera_rate(x, fps, 15.0, out_fps=30.0)
    # between two 15 fps frames the parabola is interpolated linearly: error g' dt^2 / 8 at most
    assert np.abs(y15 - at30).max() == pytest.approx(9.81 / 4 * (1 / 15) ** 2 / 8, rel=0.05)
    with pytest.raises(ConfigError, match="camera_fps = 45"):
        observe.camera_rate(x, fps, 45.0)


def test_perspective_of_a_level_camera_recovers_heights_in_the_plane_it_faces():
    t = np.arange(90) / 30.0
    x = np.zeros((10, 90, 3))
    x[:, :, 0] = np.linspace(-1, 1, 10)[:, None] * t  # across the view
    x[:, :, 2] = 0.1 + np.abs(np.sin(3 * t))[None] * np.linspace(0.2, 1.2, 10)[:, None]  # bounces, 0.1-1.3 m
    y = observe.perspective(x, observe.Camera(distance=4.0, elevation=0.0))
    assert (y[:, :, :2] == 0).all()
    np.testing.assert_allclose(y[:, :, 2], x[:, :, 2], atol=0.02)  # the small error: depth varies with x
    towards = x.copy()
    towards[:, :, 0] = np.linspace(0, 1, 90)  # across the view overall, but 1.5 m towards the camera and back
    towards[:, :, 1] = -1.5 * np.sin(np.pi * t / t[-1])
    z = observe.perspective(towards, observe.Camera(distance=4.0, elevation=20.0))[:, :, 2]
    assert np.abs(z - towards[:, :, 2]).max() > 0.1  # a camera from above mistakes depth for height


def test_height_scale_and_composition():
    x = parabolas(10)
    assert np.allclose(observe.height_scale(x, 2.0)[:, :, 2] - 0.1, 2 * (x[:, :, 2] - 0.1))
    ob = observe.Observation(noise=0.005, drop=0.1, camera_fps=15.0, height_factor=1.1)
    a = ob.apply(x, 30.0, np.random.default_rng(5))
    b = ob.apply(x, 30.0, np.random.default_rng(5))
    assert a.shape == x.shape and (a == b).all(), "seeded: the same observation twice"
    assert (observe.Observation().apply(x, 30.0, np.random.default_rng(0)) == x).all(), "the default is exact"
    r = observe.randomised(x, 30.0, np.random.default_rng(6))
    assert r.shape == x.shape and np.isfinite(r).all() and (r[:, :, :2] == 0).all()


@pytest.mark.parametrize("call, match", [
    (lambda x, g: observe.noise(x, -0.01, g), "noise sigma"),
    (lambda x, g: observe.drop(x, 1.0, g), "drop share"),
    (lambda x, g: observe.drop(x, -0.1, g), "drop share"),
    (lambda x, g: observe.perspective(x, observe.Camera(kind="fisheye")), "Camera.kind"),
    (lambda x, g: observe.height_scale(x, 0.0), "height scale"),
    (lambda x, g: observe.Observation(noise=-1.0).apply(x, 30.0, g), "Observation.noise"),
    (lambda x, g: observe.Observation(drop=1.5).apply(x, 30.0, g), "Observation.drop"),
])
def test_bad_parameters_name_themselves(call, match):
    with pytest.raises(ConfigError, match=match):
        call(parabolas(2), np.random.default_rng(0))


def test_bad_trajectories():
    with pytest.raises(TrajectoryError, match="shape"):
        observe.noise(np.zeros((3, 4)), 0.01, np.random.default_rng(0))
    x = parabolas(2)
    x[0, 3, 2] = np.nan
    with pytest.raises(TrajectoryError, match="NaN"):
        observe.drop(x, 0.1, np.random.default_rng(0))


def test_turned_across_view_turns_each_throw_to_cross_the_camera():
    x = parabolas(20)
    turned = observe.turned_across_view(x)
    d = turned[:, -1, :2] - turned[:, 0, :2]
    np.testing.assert_allclose(d[:, 1], 0, atol=1e-12)
    assert (d[:, 0] >= 0).all()
    np.testing.assert_allclose(np.linalg.norm(d, axis=1), np.linalg.norm(x[:, -1, :2] - x[:, 0, :2], axis=1))
    np.testing.assert_allclose(turned[:, :, 2], x[:, :, 2])  # heights untouched


# ---------------------------------------------------------------------------------------------
# The tracker's error model: a per-throw offset, AR(1) noise, one level in flight and one in contact


def landings(n: int, T: int = 90, seed: int = 0) -> np.ndarray:
    """(n, T) bool contact flags: each throw in the air until a random frame, then on the ground."""
    land = np.random.default_rng(seed).integers(10, T - 10, n)
    return np.arange(T)[None, :] >= land[:, None]


def test_in_contact_is_a_band_above_the_rest_height():
    z = np.array([0.099, 0.1, 0.104, 0.106, 0.5])
    assert observe.in_contact(z).tolist() == [True, True, True, False, False]
    assert observe.in_contact(z, rest_height=0.2, band=0.0).tolist() == [True] * 4 + [False]


def test_the_draw_has_the_statistics_of_its_parameters():
    contact = landings(4000)
    m = observe.TrackerNoise(flight=0.02, contact=0.008, offset=0.006, rho=0.8)
    e = m.draw(contact, np.random.default_rng(1))
    assert e.shape == contact.shape
    offsets = observe.TrackerNoise(offset=0.006).draw(contact, np.random.default_rng(2))
    assert (offsets == offsets[:, :1]).all(), "an offset is one draw per throw"
    assert offsets[:, 0].std() == pytest.approx(0.006, rel=0.05)
    u = observe.TrackerNoise(flight=0.02, contact=0.008, rho=0.8).draw(contact, np.random.default_rng(3))
    assert u[~contact].std() == pytest.approx(0.02, rel=0.03) and u[contact].std() == pytest.approx(0.008, rel=0.03)
    both = ~contact[:, :-1] & ~contact[:, 1:]
    a, b = u[:, :-1][both], u[:, 1:][both]
    assert np.corrcoef(a, b)[0, 1] == pytest.approx(0.8, abs=0.01)
    assert np.std(b - a) == pytest.approx(m.step_sd(), rel=0.03)
    assert m.step_sd() == pytest.approx(0.02 * np.sqrt(0.4))
    rest = contact[:, :-1] & contact[:, 1:]
    assert np.std(np.diff(e, axis=1)[rest]) == pytest.approx(m.step_sd(in_contact=True), rel=0.03)
    assert e[~contact].std() == pytest.approx(m.position_sd(), rel=0.03), "offset and flight add in quadrature"
    assert e[contact].std() == pytest.approx(m.position_sd(in_contact=True), rel=0.03)


def test_white_noise_is_the_special_case():
    x = parabolas(30)
    sigma = 0.012
    white = observe.TrackerNoise.white(sigma)
    assert (white.offset, white.rho, white.flight, white.contact) == (0.0, 0.0, sigma, sigma)
    np.testing.assert_array_equal(observe.tracker_noise(x, white, np.random.default_rng(4)),
                                  observe.noise(x, sigma, np.random.default_rng(4)))
    a = observe.Observation(tracker=white, drop=0.1).apply(x, 30.0, np.random.default_rng(5))
    b = observe.Observation(noise=sigma, drop=0.1).apply(x, 30.0, np.random.default_rng(5))
    np.testing.assert_array_equal(a, b)
    correlated = observe.Observation(tracker=observe.TrackerNoise(flight=sigma, contact=sigma, rho=0.5))
    assert not np.array_equal(correlated.apply(x, 30.0, np.random.default_rng(5))[:, :, 2], b[:, :, 2])


def test_an_observation_draws_the_contact_level_where_the_exact_object_rests():
    x = np.zeros((200, 60, 3))
    x[:, :30, 2] = 1.0  # in the air for 30 frames, then at rest on the ground
    x[:, 30:, 2] = observe.REST_HEIGHT
    ob = observe.Observation(tracker=observe.TrackerNoise(flight=0.03, contact=0.005))
    e = ob.apply(x, 30.0, np.random.default_rng(6))[:, :, 2] - x[:, :, 2]
    assert e[:, :30].std() == pytest.approx(0.03, rel=0.05) and e[:, 30:].std() == pytest.approx(0.005, rel=0.05)


def test_train_config_fields_round_trip_the_tracker_model():
    m = observe.TrackerNoise(flight=0.02, contact=0.008, offset=0.006, rho=0.84)
    ob = observe.Observation(tracker=m, drop=0.03)
    cfg = TrainConfig(observe="fixed", **observe_fields(ob))
    cfg.check()
    back = observation(cfg)
    assert back.drop == 0.03 and back.tracker.contact == pytest.approx(m.contact)
    assert (back.tracker.flight, back.tracker.offset, back.tracker.rho) == (m.flight, m.offset, m.rho)
    white = TrainConfig(observe="fixed", **observe_fields(observe.Observation(noise=0.01)))
    fields = (white.observe_noise, white.observe_offset, white.observe_rho, white.observe_contact_ratio)
    assert fields == (0.01, 0, 0, 1)
    assert observation(white).tracker == observe.TrackerNoise.white(0.01)


@pytest.mark.parametrize("make, match", [
    (lambda: observe.TrackerNoise(rho=1.0).validate(), "TrackerNoise.rho"),
    (lambda: observe.TrackerNoise(flight=-0.01).validate(), "TrackerNoise.flight"),
    (lambda: observe.TrackerNoise(contact=float("nan")).validate(), "TrackerNoise.contact"),
    (lambda: observe.TrackerNoise(offset=-1.0).validate(), "TrackerNoise.offset"),
    (lambda: observe.TrackerNoise(band=-0.001).validate(), "TrackerNoise.band"),
    (lambda: observe.Observation(tracker=observe.TrackerNoise(rho=-1.0)).validate(), "Observation.tracker.rho"),
    (lambda: observe.Observation(noise=0.01, tracker=observe.TrackerNoise.white(0.01)).validate(),
     "Observation.noise"),
])
def test_bad_model_parameters_name_their_field(make, match):
    with pytest.raises(ConfigError, match=match):
        make()


@pytest.mark.parametrize("field, value", [("observe_rho", 1.0), ("observe_rho", -1.5), ("observe_offset", -0.01),
                                          ("observe_contact_ratio", -1.0), ("observe_offset", float("inf"))])
def test_bad_train_config_model_fields_name_themselves(field, value):
    with pytest.raises(ConfigError, match=f"TrainConfig.{field}"):
        TrainConfig(**{field: value}).check()


def test_a_far_square_on_camera_films_the_heights_as_they_are():
    x = parabolas(3)
    for throw in x:
        seen = observe.filmed(throw, observe.AnyCamera(height=1.0, tilt=0.0, yaw=0.0, distance=500.0),
                              rest_height=0.0)
        z = throw[:, 2] - throw[:, 2].min()
        assert np.abs(seen[:, 2] - z).max() < 0.02 and not seen[:, :2].any()


def test_filmed_reads_the_sweeps_camera_as_study_classify_does():
    """The rows and the mean-size scale of :func:`observe.filmed` are the sweep's camera's projection and
    ``read_scale(how='mean')`` on an exact blob: two independent codings of one camera agree."""
    from study.methods import sweep

    throw = observe.turned_across_view(parabolas(1, seed=4))[0]
    shot = sweep.Shot(family="oblique", height=1.7, tilt=30.0, yaw=-40.0, distance=4.0, fov=60.0, width=854,
                      height_px=480, fps=30.0, colour="red", floor=sweep.FLOORS[0], light=0.8)
    cam = sweep.camera(shot, throw)
    v = cam.project(throw)[:, 1]
    blob = cam.focal * 0.2 / cam.depth_of(throw)  # an object 0.2 m across
    scale = 0.2 / np.sqrt(np.mean(blob**2))
    expected = (v.max() - v) * scale + observe.REST_HEIGHT
    seen = observe.filmed(throw, observe.AnyCamera(height=1.7, tilt=30.0, yaw=-40.0, distance=4.0))
    np.testing.assert_allclose(seen[:, 2], expected, atol=1e-9)
    assert np.abs(seen[:, 2] - throw[:, 2]).max() > 0.05, "an oblique camera from above distorts the heights"


def test_any_camera_is_seeded_and_gives_heights_only():
    x = parabolas(6)
    a = observe.any_camera(x, 30.0, np.random.default_rng(3))
    b = observe.any_camera(x, 30.0, np.random.default_rng(3))
    assert np.array_equal(a, b) and a.shape == x.shape and not a[:, :, :2].any() and np.isfinite(a).all()
    assert not np.array_equal(a, observe.any_camera(x, 30.0, np.random.default_rng(4)))


def test_a_camera_the_throw_passes_behind_is_refused_or_moved_back():
    x = parabolas(1)[0]
    assert observe.filmed(x, observe.AnyCamera(distance=0.5, yaw=80.0)) is None
    with pytest.raises(ConfigError, match="AnyCamera.distance"):
        observe.AnyCamera(distance=0.1).validate()
    with pytest.raises(ConfigError, match="any_camera"):
        observe.any_camera(x[None], 30.0, np.random.default_rng(0),
                           observe.AnyCameraRanges(distance=(0.5, 0.5), yaw=(85.0, 85.0), tries=1))
