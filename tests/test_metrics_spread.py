"""Spread between data sets: the t interval over seeds, the hierarchical bootstrap, the between-data-set share."""

from __future__ import annotations

import numpy as np
import pytest

from study.core.errors import ConfigError
from study.learn.metrics import (
    between_share,
    bootstrap_accuracy,
    hierarchical_bootstrap,
    t_interval,
)


def test_t_interval_against_a_hand_computation():
    iv = t_interval([0.7, 0.75, 0.8])  # mean 0.75, sd 0.05, t(2, 0.975) = 4.303: 4.303 * 0.05 / sqrt(3) = 0.1242
    assert iv.value == pytest.approx(0.75)
    assert iv.hi - iv.value == pytest.approx(0.1242, abs=1e-4) and iv.value - iv.lo == pytest.approx(0.1242, abs=1e-4)
    assert "Student-t" in iv.method and "3 values" in iv.method
    assert t_interval([0.7, 0.75, 0.8], level=0.9).hi < iv.hi
    one = t_interval([0.8])
    assert one.value == one.lo == one.hi == 0.8 and "no interval" in one.method
    with pytest.raises(ConfigError, match="t_interval"):
        t_interval([])
    with pytest.raises(ConfigError, match="finite"):
        t_interval([0.7, float("nan")])


def _data_sets(accuracies, seeds=5, throws=2000, seed=0) -> list[np.ndarray]:
    rng = np.random.default_rng(seed)
    return [rng.random((seeds, throws)) < a for a in accuracies]


def test_the_hierarchical_bootstrap_holds_the_spread_between_data_sets():
    disagree = _data_sets((0.70, 0.80, 0.90))
    agree = _data_sets((0.80, 0.80, 0.80), seed=1)
    h_dis, h_agr = hierarchical_bootstrap(disagree), hierarchical_bootstrap(agree)
    one = bootstrap_accuracy(disagree[1])  # one data set's interval: its seeds and test throws only
    width = lambda iv: iv.hi - iv.lo  # noqa: E731
    assert h_dis.value == pytest.approx(np.mean([c.mean() for c in disagree]))
    assert width(h_dis) > 5 * width(one)  # the data sets' 10-point spread dominates
    assert h_dis.lo < 0.75 and h_dis.hi > 0.85
    # data sets that agree: about one data set's width (sqrt(5/9) = 0.75 of it in expectation: three times
    # the throws, with the test sets' noise counted twice), nowhere near the width when they disagree
    ratio = width(h_agr) / width(bootstrap_accuracy(agree[0]))
    assert 0.5 < ratio < 1.1
    assert "3 data sets" in h_dis.method
    assert hierarchical_bootstrap(disagree) == h_dis  # seeded: the same interval every time
    assert hierarchical_bootstrap(disagree, seed=1) != h_dis


def test_the_hierarchical_bootstrap_takes_data_sets_of_different_sizes():
    rng = np.random.default_rng(2)
    sets = [rng.random((3, 500)) < 0.6, rng.random((5, 1500)) < 0.9, rng.random(800) < 0.75]  # one run: (n,)
    iv = hierarchical_bootstrap(sets, n_boot=500)
    assert iv.lo < iv.value < iv.hi and iv.value == pytest.approx(np.mean([s.mean() for s in sets]))
    with pytest.raises(ConfigError, match="no data sets"):
        hierarchical_bootstrap([])
    with pytest.raises(ConfigError, match="data set 1"):
        hierarchical_bootstrap([sets[0], np.zeros((2, 0), bool)])


def _runs(groups: list[list[int]], throws: int = 10) -> list[np.ndarray]:
    """Data sets whose runs got exactly the given numbers of ``throws`` right."""
    return [np.array([np.arange(throws) < k for k in g]) for g in groups]


def test_between_share_of_identical_far_apart_and_a_hand_worked_unbalanced_design():
    same = between_share(_runs([[6, 7, 8], [6, 7, 8], [6, 7, 8]]))
    assert same["share"] == 0.0 and same["between_sd"] == 0.0 and same["within_sd"] == pytest.approx(0.1)
    apart = between_share([np.full((4, 1000), False), np.full((3, 1000), True)])  # 0 % and 100 %, no spread within
    assert apart["share"] == 1.0 and apart["within_sd"] == 0.0
    assert between_share([np.full((2, 10), True), np.full((3, 10), True)])["share"] == 0.0  # no spread at all
    far = between_share(_runs([[100, 101, 99], [500, 501, 499], [900, 899, 901]], throws=1000))
    assert far["share"] > 0.999 and far["between_sd"] == pytest.approx(0.4, abs=0.01)
    # groups A = (0.5, 0.7), B = (0.8, 0.9, 1.0): N = 5, means 0.6 and 0.9, grand mean 0.78;
    # MS_between = 2 (0.18)^2 + 3 (0.12)^2 = 0.108, MS_within = 0.04 / 3 = 1/75,
    # n0 = (5 - 13/5) / 1 = 2.4, sigma_b^2 = (0.108 - 1/75) / 2.4 = 71/1800, share = 71/95
    hand = between_share(_runs([[5, 7], [8, 9, 10]]))
    assert hand["share"] == pytest.approx(71 / 95)
    assert hand["between_sd"] == pytest.approx((71 / 1800) ** 0.5)
    assert hand["within_sd"] == pytest.approx((1 / 75) ** 0.5)
    assert "random-effects" in hand["method"] and set(hand) == {"share", "between_sd", "within_sd", "method"}
    # means 0.6 and 0.65 with a wide within spread: MS_between < MS_within, truncated at 0
    assert between_share(_runs([[2, 10], [3, 10]]))["share"] == 0.0
    with pytest.raises(ConfigError, match="two or more"):
        between_share(_runs([[5, 6, 7]]))
    with pytest.raises(ConfigError, match="two or more"):
        between_share(_runs([[5], [6]]))
