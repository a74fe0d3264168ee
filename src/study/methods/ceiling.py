"""The best any classifier can do, computed exactly from the two class priors.

Without air the simulated contact is mass-invariant, so a throw's trajectory depends on its class only
through the restitution and friction drawn from the class's prior (and on the launch, drawn from one prior
for both classes). A classifier told each throw's true restitution and friction therefore knows at least as
much as any classifier of its trajectory, and the best such classifier is the Bayes rule: the class with the
larger prior-weighted density. Its accuracy bounds every learner of the air-off data::

    ceiling = integral of max(pi_light p_light(e, mu), pi_heavy p_heavy(e, mu)) de dmu

Every parameter of a :class:`~study.simulate.synth.ClassPrior` is uniform (mass uniform in its logarithm), so
each density is constant on a box and the integral is a finite sum: cut each axis at every box edge, and add
up, cell by cell, the cell's volume times the larger of the two weighted densities. No fitting, no sampling.

With air, the drag makes the mass visible, and the classes' mass ranges do not overlap: the same sum over
(restitution, friction, log mass) then gives the ceiling of the air-on data, 1 when they do not overlap.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Mapping, Sequence

import numpy as np

from study.core.errors import ConfigError
from study.simulate.synth import ClassPrior, SynthConfig

PARAMETERS = ("restitution", "friction", "mass")
"""What a prior draws; the mass is uniform in its logarithm."""
Box = Mapping[str, tuple[float, float]]
"""A prior as the box it is uniform on: parameter -> (low, high), the mass as its log."""


def box(prior: ClassPrior, names: Sequence[str]) -> dict[str, tuple[float, float]]:
    """The box on which ``prior`` is uniform in the parameters ``names`` (log mass for the mass)."""
    out = {}
    for n in names:
        if n not in PARAMETERS:
            raise ConfigError(f"parameter {n!r} is not one a class prior draws; use some of {PARAMETERS}")
        lo, hi = getattr(prior, n)
        out[n] = (math.log(lo), math.log(hi)) if n == "mass" else (float(lo), float(hi))
    return out


def bayes_accuracy(light: Box, heavy: Box, heavy_share: float = 0.5) -> float:
    """The accuracy of the Bayes rule between two uniform priors on the boxes ``light`` and ``heavy`` (the
    same parameters), with ``heavy_share`` of the throws heavy: exact (see the module docstring)."""
    if set(light) != set(heavy) or not light:
        raise ConfigError(f"the two priors must be boxes in the same parameters, not {sorted(light)} and {sorted(heavy)}")
    if not 0 < heavy_share < 1:
        raise ConfigError(f"heavy_share = {heavy_share!r}; it must lie in (0, 1)")
    names = sorted(light)
    for b in (light, heavy):
        for n in names:
            if not b[n][1] > b[n][0]:
                raise ConfigError(f"prior range {n} = {b[n]}: the high end must exceed the low end")
    weight = {"light": (1 - heavy_share) / math.prod(light[n][1] - light[n][0] for n in names),
              "heavy": heavy_share / math.prod(heavy[n][1] - heavy[n][0] for n in names)}
    cuts = [sorted({*light[n], *heavy[n]}) for n in names]  # every box edge, axis by axis
    total = 0.0
    for cell in itertools.product(*(list(zip(c[:-1], c[1:])) for c in cuts)):
        mid = [(a + b) / 2 for a, b in cell]
        inside = {k: all(b[n][0] <= m <= b[n][1] for n, m in zip(names, mid)) for k, b in (("light", light), ("heavy", heavy))}
        best = max((weight[k] for k in weight if inside[k]), default=0.0)
        total += best * math.prod(b - a for a, b in cell)
    return total


def exact_ceiling(cfg: SynthConfig, names: Sequence[str] = ("restitution", "friction"), heavy_share: float = 0.5) -> float:
    """The ceiling of a data set of ``cfg``'s priors for a classifier that knows ``names`` of every throw:
    (restitution, friction) bound every learner without air; with the mass too, with air."""
    return bayes_accuracy(box(cfg.light, names), box(cfg.heavy, names), heavy_share)


def bayes_labels(cfg: SynthConfig, params: Mapping[str, np.ndarray], names: Sequence[str] = ("restitution", "friction"),
                 heavy_share: float = 0.5) -> np.ndarray:
    """The Bayes rule's labels (n,) for throws with the parameters ``params`` (name -> (n,)): heavy (1) where the
    heavy prior's weighted density is the larger (ties: light). What :func:`exact_ceiling` integrates."""
    values = {n: np.log(params[n]) if n == "mass" else np.asarray(params[n], float) for n in names}
    dens = []
    for share, prior in ((1 - heavy_share, cfg.light), (heavy_share, cfg.heavy)):
        b = box(prior, names)
        inside = np.all([(values[n] >= b[n][0]) & (values[n] <= b[n][1]) for n in names], axis=0)
        dens.append(np.where(inside, share / math.prod(b[n][1] - b[n][0] for n in names), 0.0))
    return (dens[1] > dens[0]).astype(np.int64)
