"""The certification split: throws that neither training, early stopping nor a grid search has seen, simulated
once from the data set's priors, on which a threshold is certified (``study.methods.operating.certified_threshold``):
the decision chapter's operating points and the cannot-tell band of a recommended model's answers."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from study.simulate import synth

if TYPE_CHECKING:
    from study.runs.runner import Runner

SEED = 500
"""The certification split is simulated from the data set's seed plus this (throws no other split holds)."""


def config(runner: Runner) -> synth.SynthConfig:
    """The certification split's synthesis: the study's priors and scene, ``preset.certify_per_class`` throws of
    each class (its test split; a training split of one), as long as Table 1's input and two frames more."""
    T = runner.table1_config().n_frames(runner.fps)
    return runner.synth_config.replace(duration=(T + 2) / runner.fps, n_train=1, n_test=runner.preset.certify_per_class)


def split(runner: Runner) -> tuple[np.ndarray, np.ndarray]:
    """The certification split, exact: ``(x, y)``, x (m, T + 2, 3) float32 metres (T: Table 1's input in frames),
    y (m,) 1 = heavy. Simulated once and cached, from seed :data:`SEED` above the data set's."""
    seed = int(runner.dataset.meta["seed"]) + SEED
    throws = synth.dataset(config(runner), seed, data_dir=runner.data_dir, progress=False).test
    return throws.x, np.asarray(throws.y)
