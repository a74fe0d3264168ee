"""The tracker's error model fitted to error series (``study.methods.tracker_model``): on series drawn from the
model itself the fit recovers the parameters they were drawn with; lost frames count only while the object is in
view."""

from __future__ import annotations

import json

import numpy as np
import pytest

from study.core.errors import DataError
from study.methods import tracker_model
from study.simulate import observe
from study.simulate.observe import TrackerNoise


def landings(n: int, T: int = 90, seed: int = 0) -> np.ndarray:
    """(n, T) bool contact flags: in the air until a random frame, then on the ground, with a short bounce for some."""
    rng = np.random.default_rng(seed)
    t = np.arange(T)[None, :]
    land = rng.integers(15, T - 15, n)[:, None]
    bounce = (t >= land + 3) & (t < land + 3 + rng.integers(0, 6, n)[:, None])  # up again for a few frames
    return (t >= land) & ~bounce


def drawn(model: TrackerNoise, n: int = 300, T: int = 90, lost: float = 0.05,
          seed: int = 1) -> list[tracker_model.ErrorSeries]:
    """``n`` series drawn from ``model``, a share ``lost`` of their frames lost (NaN)."""
    rng = np.random.default_rng(seed)
    contact = landings(n, T, seed)
    e = model.draw(contact, rng)
    e[rng.random(e.shape) < lost] = np.nan
    return [tracker_model.ErrorSeries(e[i], contact[i], np.ones(T, bool)) for i in range(n)]


@pytest.mark.parametrize("model", [
    TrackerNoise(flight=0.023, contact=0.008, offset=0.008, rho=0.84),  # the current tracker
    TrackerNoise(flight=0.004, contact=0.003, offset=0.002, rho=0.5),  # a better one
    TrackerNoise(flight=0.01, contact=0.01, offset=0.0, rho=0.0),  # white noise
])
def test_the_fit_recovers_the_parameters_it_was_drawn_with(model):
    f = tracker_model.fit(drawn(model), bootstrap=60)
    for name in ("flight", "contact", "rho"):
        assert getattr(f.model, name) == pytest.approx(getattr(model, name), rel=0.06, abs=0.03 if name == "rho" else 0)
        assert f.intervals[name].lo <= getattr(f.model, name) <= f.intervals[name].hi
    assert f.model.offset == pytest.approx(model.offset, abs=0.15 * model.flight + 1e-4)
    assert f.model.band == observe.CONTACT_BAND and f.drop == pytest.approx(0.05, abs=0.005)
    c = landings(300)
    both = np.array([(~c[:, :-1] & ~c[:, 1:]).mean(), (c[:, :-1] & c[:, 1:]).mean()])
    expected = np.sqrt((both * [model.step_sd() ** 2, model.step_sd(in_contact=True) ** 2]).sum() / both.sum())
    assert f.step_sd == pytest.approx(expected, rel=0.1), "the frame-to-frame error, mostly within one state"


def test_the_fit_corrects_for_each_video_s_mean_removed():
    """With strong correlation, a video's mean takes part of the varying error: the plain pooled statistics
    understate the levels and the autocorrelation, and overstate the offset; the fit does not."""
    model = TrackerNoise(flight=0.02, contact=0.02, offset=0.01, rho=0.95)
    f = tracker_model.fit(drawn(model, n=400, lost=0.0), bootstrap=0)
    assert f.pooled_sd < 0.9 * 0.02 and f.lag1 < 0.93
    assert f.model.flight == pytest.approx(0.02, rel=0.06) and f.model.rho == pytest.approx(0.95, abs=0.01)
    assert f.model.offset == pytest.approx(0.01, abs=0.0025)
    plain = np.sqrt(np.mean([np.nanmean(s.error) ** 2 for s in drawn(model, n=400, lost=0.0)]))
    assert plain > 0.013, "the videos' plain mean errors hold much of the correlated noise"


def test_white_noise_overstates_a_correlated_tracker_s_frame_to_frame_error():
    f = tracker_model.fit(drawn(TrackerNoise(flight=0.023, contact=0.008, offset=0.008, rho=0.84)), bootstrap=0)
    assert 1.8 < f.white_overstates < 3.0
    w = tracker_model.fit(drawn(TrackerNoise.white(0.01), lost=0.0), bootstrap=0)
    assert w.white_overstates == pytest.approx(1.0, abs=0.05)


def test_lost_frames_count_only_while_the_object_is_in_view():
    T = 40
    e = np.full(T, 0.001) * np.sin(np.arange(T))
    e[30:] = np.nan  # the object has left the picture: the tracker sees nothing
    e[5] = np.nan  # lost in view
    view = np.arange(T) < 30
    s = tracker_model.ErrorSeries(e, np.zeros(T, bool), view)
    f = tracker_model.fit([s, s], bootstrap=0)
    assert f.drop == pytest.approx(1 / 30) and f.n_frames == 2 * 29


def test_a_fit_without_contact_frames_gives_both_states_one_level():
    contact = np.zeros((200, 60), bool)
    e = TrackerNoise(flight=0.01, contact=0.01, rho=0.6).draw(contact, np.random.default_rng(3))
    f = tracker_model.fit([tracker_model.ErrorSeries(x, c, np.ones(60, bool)) for x, c in zip(e, contact)], bootstrap=0)
    assert f.model.flight == f.model.contact == pytest.approx(0.01, rel=0.06) and f.n_contact == 0


def test_error_series_of_heights_reads_contact_from_the_truth():
    true = np.array([1.0, 0.5, 0.103, 0.1, 0.1])
    tracked = true + np.array([0.01, np.nan, -0.01, 0.0, 0.002])
    s = tracker_model.ErrorSeries.of(tracked, true)
    assert s.contact.tolist() == [False, False, True, True, True] and s.measured.tolist() == [1, 0, 1, 1, 1]
    np.testing.assert_allclose(s.error[[0, 2, 4]], [0.01, -0.01, 0.002])
    with pytest.raises(DataError, match="error series"):
        tracker_model.ErrorSeries.of(tracked[:3], true)


def test_a_fit_needs_consecutive_measured_frames():
    e = np.full(10, np.nan)
    e[::2] = 0.01 * np.arange(5)
    with pytest.raises(DataError, match="consecutive"):
        tracker_model.fit([tracker_model.ErrorSeries(e, np.zeros(10, bool), np.ones(10, bool))])
    with pytest.raises(DataError, match="no error series"):
        tracker_model.fit([])


def test_the_fit_reads_back_from_its_file_and_gives_the_fitted_observation():
    f = tracker_model.fit(drawn(TrackerNoise(flight=0.02, contact=0.01, offset=0.005, rho=0.7), n=60), bootstrap=20)
    back = tracker_model.TrackerFit.from_json(json.loads(json.dumps(f.to_json())))
    assert back == f
    ob = f.observation()
    assert ob.tracker == f.model and ob.drop == f.drop and ob.noise == 0.0
