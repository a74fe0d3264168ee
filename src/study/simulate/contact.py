"""Contact calibration: from the restitution we want to the MuJoCo contact damping that gives it.

MuJoCo's direct ``solref = (-k, -b)`` makes the contact a spring-damper in constraint space:
reference acceleration ``a = -b v - k d r`` (d the ``solimp`` impedance). The linear damped-oscillator
formula ``e = exp(-pi z / sqrt(1 - z^2))``, ``z = b / (2 sqrt(k))``, is only a guide: the measured
restitution comes out higher, more so at high damping. So we *measure*: drop the object flat, with no
spin and no air, and take ``e = sqrt(h1 / h0)`` from the release height and the first apex (heights of
the lowest point above the ground), averaged over drops whose impacts fall at different points of a
time step (a single drop varies by up to +-0.04 with that phase at our step). A table of damping -> measured e, computed once per (shape,
stiffness, timestep), is inverted by monotone interpolation.

The contact model is mass-invariant (MuJoCo works in constraint space), so the table holds for any
mass; the tests check that, and check the table against drops from other heights.
"""

from __future__ import annotations

import functools
import math
import os

import mujoco
import numpy as np
from mujoco import rollout

from study.core.errors import ConfigError
from study.simulate.scene import Shape, compile_scene

CALIBRATION_DROP = 1.0
"""Release height of the lowest point above the ground in calibration drops, metres."""
PHASES = 8
"""Calibration drops per damping value, released 0.3 mm apart so that the impact falls at evenly spread
points within a simulation step (about 2.5 mm of travel at impact); the table holds their mean."""
DAMPING_GRID = tuple(float(b) for b in np.concatenate([np.linspace(0, 100, 5), np.linspace(130, 1210, 25)]))
"""Contact damping values b (1/s) at which the calibration measures the restitution."""
SOLIMP_DMIN = 0.95
"""Smallest constraint impedance of the scene's ``solimp`` (its first number); bounds penetration."""


def linear_restitution(damping: float, stiffness: float) -> float:
    """Restitution of a linear spring-damper (the textbook guide, not what MuJoCo gives), dimensionless."""
    zeta = damping / (2.0 * math.sqrt(stiffness))
    return math.exp(-math.pi * zeta / math.sqrt(1.0 - zeta**2)) if zeta < 1.0 else 0.0


def flat_drops(
    shape: Shape,
    damping: np.ndarray,
    drop: np.ndarray,
    *,
    stiffness: float,
    timestep: float,
    mass: float = 1.0,
    bounces: int = 1,
) -> np.ndarray:
    """Drop the object flat (no spin, no air) once per (damping, drop) pair; return apex heights.

    ``damping``, ``drop``: (k,) arrays (1/s, metres of the lowest point above the ground).
    Returns (k, bounces + 1) metres: ``[drop, h1, h2, ...]``, the lowest point's height at release and
    at the apex of each flight after a bounce; 0 once it stops bouncing. Runs as one ``mujoco.rollout``.
    A flat box touches the ground exactly when its lowest point would go below it, so flights are the
    stretches where the centre is above its resting height.
    """
    damping, drop = np.broadcast_arrays(np.asarray(damping, float), np.asarray(drop, float))
    models = [
        compile_scene(shape, mass=mass, damping=b, stiffness=stiffness, friction=0.5, timestep=timestep, air=False)
        for b in damping
    ]
    rest = shape.rest_height
    state = mujoco.mjtState.mjSTATE_FULLPHYSICS
    x0 = np.zeros((len(models), mujoco.mj_stateSize(models[0], state)))
    x0[:, 3] = rest + drop  # layout: time, qpos (x, y, z, quaternion), qvel
    x0[:, 4] = 1.0
    fall = math.sqrt(2 * drop.max() / 9.81)
    nstep = int((2 * fall * bounces + 0.1) / timestep)  # enough to pass the last apex wanted
    datas = [mujoco.MjData(models[0]) for _ in range(os.cpu_count() or 1)]
    states, _ = rollout.rollout(models, datas, x0, nstep=nstep)
    height = states[:, :, 3] - rest
    out = np.zeros((len(models), bounces + 1))
    out[:, 0] = drop
    for i, h in enumerate(height):
        flying = h > 0
        # a flight after a bounce starts where contact ends: flying now, not flying one step earlier
        starts = np.flatnonzero(flying[1:] & ~flying[:-1]) + 1
        for j, s in enumerate(starts[:bounces]):
            stop = np.flatnonzero(~flying[s:])
            out[i, j + 1] = h[s : s + stop[0]].max() if len(stop) else h[s:].max()
    return out


def drop_test(shape: Shape, damping: float, *, stiffness: float, timestep: float, drop: float = CALIBRATION_DROP,
              mass: float = 1.0, bounces: int = 1) -> np.ndarray:
    """Apex heights ``[drop, h1, ...]`` (metres) of one flat drop; see :func:`flat_drops`."""
    return flat_drops(shape, np.array([damping]), np.array([drop]), stiffness=stiffness, timestep=timestep,
                      mass=mass, bounces=bounces)[0]


def measured_restitution(shape: Shape, damping: np.ndarray | float, *, stiffness: float, timestep: float,
                         drop: float = CALIBRATION_DROP, mass: float = 1.0) -> np.ndarray:
    """First-bounce restitution ``sqrt(h1 / h0)``, averaged over :data:`PHASES` impact phases.

    ``damping``: scalar or (k,) 1/s. Returns the same shape, dimensionless.
    """
    b = np.atleast_1d(np.asarray(damping, float))
    drops = drop + 3e-4 * np.arange(PHASES)
    h = flat_drops(shape, np.repeat(b, PHASES), np.tile(drops, len(b)), stiffness=stiffness, timestep=timestep, mass=mass)
    e = np.sqrt(h[:, 1] / h[:, 0]).reshape(len(b), PHASES).mean(axis=1)
    return e if np.ndim(damping) else e[0]


@functools.lru_cache(maxsize=16)
def calibration_table(shape: Shape, stiffness: float, timestep: float) -> tuple[np.ndarray, np.ndarray]:
    """``(damping, restitution)`` arrays over :data:`DAMPING_GRID`, cut where e stops decreasing.

    Beyond critical damping with a coarse step the simulated contact turns unstable and gains energy;
    the table stops at the last point of the monotone decreasing part.
    """
    b = np.array(DAMPING_GRID)
    e = measured_restitution(shape, b, stiffness=stiffness, timestep=timestep)
    stop = len(e)
    for i in range(1, len(e)):
        if not e[i] < e[i - 1] or b[i] * timestep > 1.0:
            stop = i
            break
    return b[:stop], e[:stop]


def restitution_range(shape: Shape, stiffness: float, timestep: float) -> tuple[float, float]:
    """The restitutions the calibration can reach, ``(min, max)``."""
    _, e = calibration_table(shape, stiffness, timestep)
    return float(e[-1]), float(e[0])


def damping_for_restitution(e: np.ndarray | float, shape: Shape, *, stiffness: float, timestep: float) -> np.ndarray:
    """Contact damping b (1/s) that gives restitution ``e`` in a flat drop, by interpolating the table.

    Raises :class:`ConfigError` if ``e`` lies outside what the table covers.
    """
    b, table = calibration_table(shape, stiffness, timestep)
    e = np.asarray(e, dtype=float)
    lo, hi = float(table[-1]), float(table[0])
    if np.any((e < lo) | (e > hi)) or not np.all(np.isfinite(e)):
        bad = e[(e < lo) | (e > hi) | ~np.isfinite(e)].ravel()[0]
        raise ConfigError(
            f"restitution {bad:.3f} is outside the calibrated range [{lo:.3f}, {hi:.3f}] for stiffness "
            f"{stiffness:g} and timestep {timestep:.3g} s; narrow the class prior's restitution range"
        )
    return np.interp(e, table[::-1], b[::-1])


def penetration_bound(impact_speed: float, stiffness: float) -> float:
    """Upper bound on how deep the object sinks into the ground, metres, for a normal impact speed (m/s).

    The undamped spring ``k d`` stops a contact point arriving at speed v within ``v / sqrt(k d)``;
    damping only shortens that. ``d >= SOLIMP_DMIN`` in the scene.
    """
    return impact_speed / math.sqrt(stiffness * SOLIMP_DMIN)
