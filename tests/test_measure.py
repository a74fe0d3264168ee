"""The one bounce detector (study.simulate.measure.bounces) and the other measurements on trajectories."""

import numpy as np
import pytest

from study.simulate import measure


def bouncing(e: float = 0.7, h0: float = 1.0, fps: float = 30.0, seconds: float = 3.0) -> np.ndarray:
    """Exact heights (T,) of a ball dropped from h0 with restitution e (no air), sampled at fps."""
    g = 9.81
    t = np.arange(int(seconds * fps)) / fps
    z = np.empty_like(t)
    start, v = 0.0, 0.0  # time of the flight's start, upward speed at that start
    fall = np.sqrt(2 * h0 / g)
    for i, ti in enumerate(t):
        while True:
            if start == 0.0 and ti < fall:
                z[i] = h0 - g * ti**2 / 2
                break
            if start == 0.0:
                start, v = fall, e * g * fall
            flight = 2 * v / g
            if ti < start + flight or v < 1e-3:
                s = ti - start
                z[i] = max(0.0, v * s - g * s**2 / 2)
                break
            start, v = start + flight, e * v
    return z


def test_bounces_of_an_exact_bouncing_ball():
    z = bouncing(e=0.7, h0=1.0)
    b = measure.bounces(z)
    g, fall = 9.81, np.sqrt(2 / 9.81)
    v1 = 0.7 * g * fall
    touchdowns = np.cumsum([fall, 2 * v1 / g, 2 * 0.7 * v1 / g, 2 * 0.49 * v1 / g])
    # Each impact is the frame nearest the touch-down. Rebounds below 2 cm (e^2k h0 < 0.02) are none;
    # a rebound just above 2 cm may be seen at 30 fps as a rise just under it.
    rebounds = 0.7 ** (2 * np.arange(1, 12))
    assert np.sum(rebounds >= 0.03) <= len(b.impacts) <= np.sum(rebounds >= 0.02)
    np.testing.assert_allclose(b.impacts[:4] / 30.0, touchdowns, atol=1.5 / 30)
    np.testing.assert_allclose(z[b.apexes[:3]], 0.7 ** (2 * np.arange(1, 4)), rtol=0.05)
    assert measure.bounce_count(z) == len(b.impacts)


def test_a_slide_a_rocking_box_and_a_rising_launch_are_no_bounces():
    t = np.arange(90) / 30
    landing = np.maximum(1.0 - 4.9 * t**2, 0.1)  # falls, lands, stays
    rocking = landing + 0.015 * np.abs(np.sin(8 * t)) * (t > 0.5)  # 1.5 cm wiggles on the ground
    launch = 0.6 + 2.0 * t - 4.9 * t**2  # thrown up: rises 20 cm before it falls
    for z in (landing, rocking, np.maximum(launch, 0.1)):
        assert measure.bounce_count(z) == 0
    assert measure.bounce_count(rocking, min_rise=0.01) > 0  # the threshold is what rules the wiggles out


def test_bounce_count_shapes_and_first_contact():
    z = np.stack([bouncing(0.7), bouncing(0.2)])
    counts = measure.bounce_count(z)
    assert counts.shape == (2,) and counts.dtype == np.int64 and counts[0] > counts[1] >= 0
    assert isinstance(measure.bounce_count(z[0]), int)
    first = measure.first_contact(z[0])
    assert first == int(np.argmin(z[0][:20]))
    assert measure.first_contact(np.linspace(1, 0, 10)) is None  # a fall that never turns


@pytest.mark.parametrize("rise", [0.02, 0.05])
def test_a_tracked_jitter_below_the_threshold_is_no_bounce(rise):
    rng = np.random.default_rng(0)
    resting = 0.1 + rng.normal(0, rise / 10, 300)  # a resting object, as a tracker sees it
    assert measure.bounce_count(resting, rise) == 0
    clean = measure.bounces(bouncing(0.8), rise)
    noisy = measure.bounces(bouncing(0.8) + rng.normal(0, rise / 10, 90), rise)
    big = int(np.sum(bouncing(0.8)[clean.apexes] >= 3 * rise))  # rebounds well above the threshold
    np.testing.assert_allclose(noisy.impacts[:big], clean.impacts[:big], atol=1)
