"""The decision functions: operating point, rates, curves, calibration, time to clear; and bad inputs."""

import math

import numpy as np
import pytest

from study.core.errors import ConfigError
from study.experiments import decide


@pytest.fixture
def scores():
    rng = np.random.default_rng(0)
    y = np.repeat([0, 1], 5000)
    p = np.clip(np.where(y == 1, rng.beta(5, 2, 10000), rng.beta(2, 5, 10000)), 0, 1)
    return p, y


def test_the_threshold_meets_the_target_miss_rate(scores):
    p, y = scores
    for target in (0.01, 0.05, 0.2):
        t = decide.threshold_for_miss_rate(p, y, target)
        misses = np.mean(p[y == 1] < t)
        assert misses <= target and misses > target - 2 / 5000  # as high as the target allows
    r = decide.rates(p, y, decide.threshold_for_miss_rate(p, y, 0.01))
    assert r["miss"].value <= 0.01 and r["miss"].lo <= r["miss"].value <= r["miss"].hi
    assert 0 < r["false_alarm"].value < 1  # the price of a low miss rate


@pytest.mark.parametrize("target", [0, 1, -0.1, 1.5, float("nan"), "1%"])
def test_a_target_outside_0_1_is_refused(scores, target):
    p, y = scores
    with pytest.raises(ConfigError, match="target miss rate"):
        decide.threshold_for_miss_rate(p, y, target)


def test_an_empty_set_or_one_without_heavy_objects_is_refused():
    with pytest.raises(ConfigError, match="empty"):
        decide.threshold_for_miss_rate(np.array([]), np.array([]), 0.01)
    with pytest.raises(ConfigError, match="no heavy"):
        decide.threshold_for_miss_rate(np.array([0.2, 0.4]), np.array([0, 0]), 0.01)
    with pytest.raises(ConfigError, match=r"\[0, 1\]"):
        decide.rates(np.array([1.5]), np.array([1]), 0.5)


def test_roc_and_precision_recall_of_perfect_and_random_scores():
    y = np.repeat([0, 1], 500)
    fpr, tpr = decide.roc(np.where(y == 1, 0.9, 0.1), y)
    assert decide.auc(fpr, tpr) == pytest.approx(1.0)
    rng = np.random.default_rng(1)
    fpr, tpr = decide.roc(rng.random(1000), y)
    assert decide.auc(fpr, tpr) == pytest.approx(0.5, abs=0.05)
    recall, precision = decide.precision_recall(rng.random(1000), y)
    assert recall[-1] == 1.0 and precision[-1] == pytest.approx(0.5)


def test_calibration_error_and_temperature_scaling():
    rng = np.random.default_rng(2)
    true_p = rng.random(20000)
    y = (rng.random(20000) < true_p).astype(int)
    assert decide.expected_calibration_error(true_p, y) < 0.02  # calibrated by construction
    overconfident = decide.scaled(true_p, 1 / 3)  # logits three times too large
    assert decide.expected_calibration_error(overconfident, y) > 0.1
    t = decide.fit_temperature(overconfident, y)
    assert t == pytest.approx(3.0, rel=0.1)
    assert decide.expected_calibration_error(decide.scaled(overconfident, t), y) < 0.02
    with pytest.raises(ConfigError, match="temperature"):
        decide.scaled(true_p, 0.0)


def test_time_to_clear():
    p = np.array([[0.9, 0.5, 0.2, 0.1], [0.9, 0.9, 0.9, 0.9], [0.1, 0.9, 0.9, 0.9]])
    thr = np.array([0.3, 0.3, 0.3, 0.3])
    assert decide.time_to_clear(p, thr).tolist() == [2, -1, 0]
    with pytest.raises(ConfigError, match="thresholds"):
        decide.time_to_clear(p, thr[:2])
    assert math.isfinite(decide.fit_temperature(np.array([0.2, 0.8]), np.array([0, 1])))


def test_clearing_thresholds_bound_the_cumulative_miss_rate():
    rng = np.random.default_rng(3)
    n, T = 4000, 30
    y = np.repeat([0, 1], n // 2)
    drift = np.linspace(0, 2, T)[None, :] * np.where(y == 1, 1, -1)[:, None]  # evidence grows with time
    p = 1 / (1 + np.exp(-(drift + rng.standard_normal((n, T)))))
    thr = decide.clearing_thresholds(p, y, 0.01)
    ever = decide.time_to_clear(p[y == 1], thr) >= 0
    assert ever.mean() <= 0.01  # a heavy object cleared at any frame is a miss
    cleared = decide.time_to_clear(p[y == 0], thr)
    assert (cleared >= 0).mean() > 0.5 and np.median(cleared[cleared >= 0]) > 0
    per_frame = np.array([decide.threshold_for_miss_rate(p[:, t], y, 0.01) for t in range(T)])
    assert (decide.time_to_clear(p[y == 1], per_frame) >= 0).mean() > 0.01  # per-frame 1 % is not enough
