"""Physics checks of the simulation settings, shared by the tests (which assert them) and the data
chapter (which plots them): free flight against the analytic parabola, restitution from bounce
heights against the value set, penetration against its bound, energy between flights, rest, the
timestep convergence of the measured restitution, and what letting resting objects sleep changes.
"""

from __future__ import annotations

import time

import mujoco
import numpy as np

from study.simulate import measure
from study.simulate.config import GRAVITY, SynthConfig, staggered_qvel
from study.simulate.contact import (
    damping_for_restitution,
    drop_test,
    measured_restitution,
)
from study.simulate.mujoco_sim import build_model, initial_data, simulate
from study.simulate.trace import Trace


def free_flight_error(cfg: SynthConfig, qpos0: np.ndarray, qvel0: np.ndarray, duration: float = 1.0,
                      staggered: bool = True) -> float:
    """Largest distance, metres, between simulated and analytic free-flight centre positions.

    Air off and the object launched high enough that it cannot reach the ground in ``duration``
    seconds (asserted); compares every step with ``p0 + v0 t - g t^2 / 2``. ``staggered=False`` gives
    MuJoCo the launch velocity as it is, instead of :func:`staggered_qvel` (the naive start).
    """
    m = build_model(cfg.replace(air=False), mass=1.0, damping=100.0, friction=0.5)
    d = mujoco.MjData(m)
    d.qpos[:] = qpos0
    d.qvel[:] = staggered_qvel(qvel0, m.opt.timestep) if staggered else qvel0
    worst = 0.0
    for k in range(1, int(round(duration / m.opt.timestep)) + 1):
        mujoco.mj_step(m, d)
        assert d.ncon == 0, "free-flight check touched the ground; launch higher"
        t = k * m.opt.timestep
        exact = qpos0[:3] + qvel0[:3] * t + np.array([0.0, 0.0, -GRAVITY * t * t / 2])
        worst = max(worst, float(np.linalg.norm(d.qpos[:3] - exact)))
    return worst


def restitution_from_drops(cfg: SynthConfig, restitution: float, *, drop: float = 1.0, mass: float = 1.0, bounces: int = 3) -> np.ndarray:
    """Restitutions ``sqrt(h[i+1] / h[i])`` of successive apexes of a flat drop (no air, no spin).

    Heights are of the lowest point above the ground; bounces lower than 5 mm are left out (the
    contact's 1 mm impedance width and the frame of a nearly resting object dominate there).
    """
    b = float(damping_for_restitution(restitution, cfg.shape, stiffness=cfg.stiffness, timestep=cfg.timestep))
    h = drop_test(cfg.shape, b, stiffness=cfg.stiffness, timestep=cfg.timestep, drop=drop, mass=mass, bounces=bounces)
    h = h[h >= 0.005]
    return np.sqrt(h[1:] / h[:-1])


def trace(cfg: SynthConfig, params: dict[str, np.ndarray], i: int, duration: float | None = None) -> Trace:
    """Simulate trajectory ``i`` of a split's ``params`` step by step and record diagnostics."""
    m, d = initial_data(cfg, params, i)
    n = int(round((duration or cfg.duration) / m.opt.timestep))
    mass, inertia = float(m.body_mass[1]), m.body_inertia[1].copy()
    t, pos, speed = np.empty(n), np.empty((n, 3)), np.empty(n)
    contact, depth, energy = np.zeros(n, bool), np.zeros(n), np.empty(n)
    for k in range(n):
        mujoco.mj_step(m, d)
        t[k], pos[k] = d.time, d.qpos[:3]
        v, w = d.qvel[:3], d.qvel[3:6]
        speed[k] = np.linalg.norm(v)
        energy[k] = mass * GRAVITY * d.qpos[2] + 0.5 * mass * v @ v + 0.5 * w @ (inertia * w)
        if d.ncon:
            contact[k] = True
            depth[k] = max(0.0, -min(d.contact[j].dist for j in range(d.ncon)))
    return Trace(t=t, pos=pos, speed=speed, in_contact=contact, depth=depth, energy=energy)


def convergence(cfg: SynthConfig, restitutions: np.ndarray) -> dict[str, np.ndarray]:
    """Measured first-bounce restitution at the config's timestep and at half of it, same damping.

    Returns ``{"set": e, "dt": measured at dt, "dt/2": measured at dt/2}``, each (k,).
    """
    dt = cfg.timestep
    b = damping_for_restitution(np.asarray(restitutions), cfg.shape, stiffness=cfg.stiffness, timestep=dt)
    at = lambda step: np.array([measured_restitution(cfg.shape, x, stiffness=cfg.stiffness, timestep=step) for x in b])  # noqa: E731
    return {"set": np.asarray(restitutions, float), "dt": at(dt), "dt/2": at(dt / 2)}


def sleep_effect(
    cfg: SynthConfig, params: dict[str, np.ndarray], idx, *, threads: int = 1
) -> dict[str, np.ndarray | float]:
    """Trajectories ``idx`` of a split's ``params`` simulated with the config's sleeping and with none.

    Returns per trajectory (each (n,)): ``max_diff``, the largest distance between the two centre
    positions over the record, metres; ``first_diff``, the first frame time at which they differ at
    all, seconds (nan if never); ``time_to_rest`` of the awake trajectory
    (``study.simulate.measure.features``), seconds; ``last_speed_asleep``, ``last_speed_awake``, the largest
    frame-to-frame speed in the last second of each record, m/s. And ``seconds_asleep``,
    ``seconds_awake``: wall time of each simulation on ``threads`` threads.
    """
    sub = {k: v[np.asarray(idx)] for k, v in params.items()}
    runs = {}
    for name, c in (("asleep", cfg), ("awake", cfg.replace(sleep_tolerance=0.0))):
        start = time.perf_counter()
        runs[name] = simulate(c, sub, threads=threads, progress=False)
        runs[f"seconds_{name}"] = time.perf_counter() - start
    dist = np.linalg.norm(runs["asleep"] - runs["awake"], axis=-1)  # (n, T)
    t = np.arange(cfg.n_frames) / cfg.fps
    last_second = -int(round(cfg.fps))
    differs = dist > 0
    return {
        "max_diff": dist.max(axis=1),
        "first_diff": np.where(differs.any(axis=1), t[np.argmax(differs, axis=1)], np.nan),
        "time_to_rest": measure.features(runs["awake"], cfg.fps)["time_to_rest"],
        "last_speed_asleep": measure.speeds(runs["asleep"], cfg.fps)[:, last_second:].max(axis=1),
        "last_speed_awake": measure.speeds(runs["awake"], cfg.fps)[:, last_second:].max(axis=1),
        "seconds_asleep": runs["seconds_asleep"],
        "seconds_awake": runs["seconds_awake"],
    }
