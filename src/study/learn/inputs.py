"""What a run trains on: its validation part carved off the training split, the training part's positions for each
epoch (exact, or observed by a camera; turned about the vertical where the config asks), the normalisation its
first layer stores, and the seeding of a run.
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Iterator

import numpy as np
import torch

from study.core.errors import ConfigError
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


def rotated(x: np.ndarray, degrees: np.ndarray) -> np.ndarray:
    """Trajectories ``x`` (n, T, D >= 2; columns x, y first, metres) each turned about the vertical through the
    origin by its own angle ``degrees`` (n,), counter-clockwise seen from above; the height is left as it is.
    Computed in float64, returned in ``x``'s dtype."""
    a = np.radians(np.asarray(degrees, dtype=np.float64))[:, None]  # (n, 1)
    c, s = np.cos(a), np.sin(a)
    out = np.array(x, dtype=np.float64)
    out[..., 0], out[..., 1] = c * x[..., 0] - s * x[..., 1], s * x[..., 0] + c * x[..., 1]
    return out.astype(x.dtype)


ROTATION_STREAM = 2018
"""Second seed word of a run's rotation draws (``[cfg.seed, 2018]``): a stream of its own, apart from its
observation draws and from the test split's."""


def rotating(view: Callable[[int], torch.Tensor], cfg: TrainConfig) -> Callable[[int], torch.Tensor]:
    """``view`` (the training part's positions (n, T, 3) for an epoch) with every throw turned about the vertical by
    an angle uniform in [-cfg.rotate, cfg.rotate] degrees, drawn afresh every epoch from the run's own stream
    (:data:`ROTATION_STREAM`); epochs come in order, and each draws once."""
    rng = np.random.default_rng([cfg.seed, ROTATION_STREAM])
    drawn: dict[int, torch.Tensor] = {}

    def turned(epoch: int) -> torch.Tensor:
        if epoch not in drawn:
            x = view(epoch).numpy()
            drawn.clear()
            drawn[epoch] = torch.from_numpy(rotated(x, rng.uniform(-cfg.rotate, cfg.rotate, len(x))))
        return drawn[epoch]

    return turned


def observation(cfg: TrainConfig) -> observe.Observation:
    """How a 'fixed' run observes its training split, and an observed run its validation split: the tracker's
    error of the config's ``observe_*`` fields (``observe.TrackerNoise``; white noise where they say so)."""
    return observe.Observation(drop=cfg.observe_drop, tracker=observe.TrackerNoise(
        flight=cfg.observe_noise, contact=cfg.observe_noise * cfg.observe_contact_ratio, offset=cfg.observe_offset,
        rho=cfg.observe_rho))


def observe_fields(ob: observe.Observation) -> dict[str, float]:
    """The ``TrainConfig`` fields that make a run observe as ``ob`` does (its tracker's error, white or modelled,
    and its lost frames; ``ob``'s camera, frame rate and height scale are not a run's): the inverse of
    :func:`observation`."""
    m = ob.tracker or observe.TrackerNoise.white(ob.noise)
    if m.band != observe.CONTACT_BAND or (m.flight == 0 and m.contact > 0):
        raise ConfigError(f"Observation.tracker = {m!r}: a run draws contact within {observe.CONTACT_BAND} m of rest "
                          "and its contact error as a multiple of its flight error (> 0)")
    return {"observe_noise": m.flight, "observe_drop": ob.drop, "observe_offset": m.offset, "observe_rho": m.rho,
            "observe_contact_ratio": m.contact / m.flight if m.flight > 0 else 1.0}


def epoch_inputs(x: np.ndarray, tr: np.ndarray, va: np.ndarray, cfg: TrainConfig,
            fps: float) -> tuple[Callable[[int], torch.Tensor], np.ndarray]:
    """The training part's positions for each epoch (a function of the epoch) and the validation part's, from
    the first frames ``x`` (n, T, 3): exact positions; (``'randomised'``) observed by a random camera, eight
    views cycled; (``'any-camera'``) filmed by cameras anywhere and read by one scale, eight views cycled; or
    (``'fixed'``) observed with the config's tracker error, drawn afresh every epoch. With
    ``cfg.rotate``, each epoch's training positions, once observed, are turned about the vertical
    (:func:`rotating`); the validation part is left as it was thrown."""
    view, x_val = _observed_inputs(x, tr, va, cfg, fps)
    return (rotating(view, cfg) if cfg.rotate else view), x_val


def _observed_inputs(x: np.ndarray, tr: np.ndarray, va: np.ndarray, cfg: TrainConfig,
                     fps: float) -> tuple[Callable[[int], torch.Tensor], np.ndarray]:
    """:func:`epoch_inputs` before any rotation."""
    def inputs(a: np.ndarray) -> np.ndarray:
        return select_inputs(a, cfg.dims, a.shape[1], what="training split")

    if cfg.observe == "exact":
        exact = torch.from_numpy(inputs(x[tr]))
        return lambda epoch: exact, inputs(x[va])
    calibrated = observation(cfg)
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
    if cfg.observe == "any-camera":
        rng = np.random.default_rng([cfg.seed, 2019])
        ranges = observe.AnyCameraRanges(noise=(0.0, 3 * cfg.observe_noise))
        views = [torch.from_numpy(inputs(observe.any_camera(x[tr], fps, rng, ranges))) for _ in range(OBSERVED_VIEWS)]
        return lambda epoch: views[epoch % len(views)], inputs(observe.any_camera(x[va], fps, rng, ranges))
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


