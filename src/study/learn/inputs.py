"""What a run trains on: its validation part carved off the training split, the training part's positions for each
epoch (exact, or observed by a camera), the normalisation its first layer stores, and the seeding of a run.
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Iterator

import numpy as np
import torch

from study.learn.config import TrainConfig, select_inputs
from study.learn.model import Features
from study.learn.trained import THREADS, num_threads
from study.simulate import observe


def split_train_val(n: int, val_fraction: float, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Indices (train, val) of a seeded permutation of ``range(n)``; at least one in each."""
    perm = np.random.default_rng(seed).permutation(n)
    n_val = min(max(1, round(val_fraction * n)), n - 1)
    return np.sort(perm[n_val:]), np.sort(perm[:n_val])


OBSERVED_VIEWS = 8
"""Randomised observations of the training split made once per 'randomised' run and cycled through, epoch by
epoch (drawing a new one every epoch would cost more than the epoch)."""


def epoch_inputs(x: np.ndarray, tr: np.ndarray, va: np.ndarray, cfg: TrainConfig,
            fps: float) -> tuple[Callable[[int], torch.Tensor], np.ndarray]:
    """The training part's positions for each epoch (a function of the epoch) and the validation part's, from
    the first frames ``x`` (n, T, 3): exact positions; (``'randomised'``) observed by a random camera, eight
    views cycled; or (``'fixed'``) observed with the config's tracker error, drawn afresh every epoch."""
    def inputs(a: np.ndarray) -> np.ndarray:
        return select_inputs(a, cfg.dims, a.shape[1], what="training split")

    if cfg.observe == "exact":
        exact = torch.from_numpy(inputs(x[tr]))
        return lambda epoch: exact, inputs(x[va])
    calibrated = observe.Observation(noise=cfg.observe_noise, drop=cfg.observe_drop)
    if cfg.observe == "fixed":
        rng = np.random.default_rng([cfg.seed, 2017])  # a stream of its own: never the test split's draw
        x_val = inputs(calibrated.apply(x[va], fps, rng))
        drawn: dict[int, torch.Tensor] = {}

        def view(epoch: int) -> torch.Tensor:  # epochs come in order: each draws once from the same stream
            if epoch not in drawn:
                drawn.clear()
                drawn[epoch] = torch.from_numpy(inputs(calibrated.apply(x[tr], fps, rng)))
            return drawn[epoch]

        return view, x_val
    rng = np.random.default_rng([cfg.seed, 2016])
    ranges = observe.Randomisation(noise=(0.0, 3 * cfg.observe_noise))
    views = [torch.from_numpy(inputs(observe.randomised(x[tr], fps, rng, ranges))) for _ in range(OBSERVED_VIEWS)]
    return lambda epoch: views[epoch % len(views)], inputs(calibrated.apply(x[va], fps, rng))


def normalisation(x: torch.Tensor, features: Features) -> tuple[np.ndarray, np.ndarray]:
    """The mean and standard deviation (C,) of every channel ``features`` makes of the positions ``x`` (n, T, D),
    float64, a constant channel's std set to 1: what :meth:`Classifier.set_normalisation` stores."""
    raw = features.raw(x.double()).reshape(-1, features.n_channels).numpy()  # (n T, C)
    mean, std = raw.mean(axis=0), raw.std(axis=0)
    return mean, np.where(std > 0, std, 1.0)


@contextlib.contextmanager
def deterministic(seed: int) -> Iterator[None]:
    """Seed torch inside a forked RNG, with deterministic algorithms and ``THREADS`` threads; restore after."""
    det = torch.are_deterministic_algorithms_enabled()
    with torch.random.fork_rng(devices=[]), num_threads(THREADS):
        torch.manual_seed(seed)
        torch.use_deterministic_algorithms(True)
        try:
            yield
        finally:
            torch.use_deterministic_algorithms(det)


