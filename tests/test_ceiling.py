"""The exact ceiling of the class priors: hand-worked cases, and the study's priors against a Monte-Carlo Bayes
estimate drawn the way the data sets draw their objects."""

from __future__ import annotations

import math

import numpy as np
import pytest

from study.core.errors import ConfigError
from study.methods import ceiling
from study.simulate import synth


def test_two_overlapping_intervals_of_equal_width():
    """light U(0, 2), heavy U(1, 3): each is right on its own half, a coin where they overlap: 3/4."""
    assert ceiling.bayes_accuracy({"e": (0, 2)}, {"e": (1, 3)}) == pytest.approx(0.75)


def test_a_narrow_prior_inside_a_wide_one():
    """light U(0, 1) (density 1), heavy U(0, 2) (density 1/2): on (0, 1) light wins, 1/2 of all throws right;
    on (1, 2) only heavy, 1/4 more: 3/4. With a fifth of the throws heavy: on (0, 1) 0.8, on (1, 2) 0.1."""
    assert ceiling.bayes_accuracy({"e": (0, 1)}, {"e": (0, 2)}) == pytest.approx(0.75)
    assert ceiling.bayes_accuracy({"e": (0, 1)}, {"e": (0, 2)}, heavy_share=0.2) == pytest.approx(0.9)


def test_two_dimensions_and_disjoint_priors():
    """Separable in one coordinate only where the other does not matter: the 1-D answer; disjoint: perfect."""
    light, heavy = {"e": (0, 2), "f": (0, 1)}, {"e": (1, 3), "f": (0, 1)}
    assert ceiling.bayes_accuracy(light, heavy) == pytest.approx(0.75)
    assert ceiling.bayes_accuracy({"e": (0, 1)}, {"e": (2, 3)}) == pytest.approx(1.0)
    # overlap only in the corner [1, 2] x [1, 2] of two 2 x 2 squares: a quarter of each, where a coin is right
    assert ceiling.bayes_accuracy({"e": (0, 2), "f": (0, 2)}, {"e": (1, 3), "f": (1, 3)}) == pytest.approx(1 - 0.25 / 2)


def test_bad_priors_are_config_errors():
    with pytest.raises(ConfigError, match="same parameters"):
        ceiling.bayes_accuracy({"e": (0, 1)}, {"f": (0, 1)})
    with pytest.raises(ConfigError, match="high end"):
        ceiling.bayes_accuracy({"e": (1, 1)}, {"e": (0, 1)})
    with pytest.raises(ConfigError, match="heavy_share"):
        ceiling.bayes_accuracy({"e": (0, 1)}, {"e": (0, 1)}, heavy_share=1.0)
    with pytest.raises(ConfigError, match="colour"):
        ceiling.box(synth.LIGHT, ("colour",))


@pytest.mark.parametrize("names", [("restitution", "friction"), ("restitution",), ("restitution", "friction", "mass")])
def test_the_study_priors_agree_with_a_monte_carlo_bayes_estimate(names):
    cfg = synth.SynthConfig.preset("paper")
    exact = ceiling.exact_ceiling(cfg, names)
    n = 40_000
    rng = np.random.default_rng(0)
    right = 0
    for label, prior in enumerate((cfg.light, cfg.heavy)):
        drawn = synth.sample_objects(prior, n, rng)  # as the data sets draw their objects
        right += int((ceiling.bayes_labels(cfg, drawn, names) == label).sum())
    estimate = right / (2 * n)
    assert abs(estimate - exact) < 4 * math.sqrt(exact * (1 - exact) / (2 * n)) + 1e-12
    if "mass" in names:
        assert exact == 1.0, "the classes' mass ranges do not overlap"
    else:
        assert 0.5 < exact < 1.0
