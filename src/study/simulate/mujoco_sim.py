"""The study's engine: the throws of a split simulated in MuJoCo.

Pipeline: one compiled model per object (same size signature) -> ``mujoco.rollout`` over all cores -> centre
positions sampled at the camera frame rate. :func:`simulate_reference` is the same computation as a plain
``mj_step`` loop; tests require the two to agree bit for bit. The priors, the config and the sampling are
``study.simulate.config``'s; ``study.simulate.synth`` makes data sets with this engine or Bullet.
"""

from __future__ import annotations

import os
from collections.abc import Iterator

import mujoco
import numpy as np
from mujoco import rollout

from study import CLASSES
from study.core.errors import ConfigError
from study.core.progress import Progress
from study.simulate.config import SynthConfig, staggered_qvel
from study.simulate.contact import restitution_range
from study.simulate.scene import compile_scene

STATE = mujoco.mjtState.mjSTATE_FULLPHYSICS


def build_model(cfg: SynthConfig, mass: float, damping: float, friction: float) -> mujoco.MjModel:
    """The compiled scene for one object (SI units)."""
    return compile_scene(
        cfg.shape, mass=mass, damping=damping, stiffness=cfg.stiffness, friction=friction,
        timestep=cfg.timestep, air=cfg.air, sleep_tolerance=cfg.sleep_tolerance,
    )


def initial_data(cfg: SynthConfig, params: dict[str, np.ndarray], i: int) -> tuple[mujoco.MjModel, mujoco.MjData]:
    """Throw ``i`` of a split's ``params`` ready to step: its compiled scene and an ``MjData`` at the launch
    (qpos as sampled, qvel staggered by :func:`staggered_qvel`). Synthesis, the physics checks and the
    renders all start a throw here."""
    m = build_model(cfg, params["mass"][i], params["damping"][i], params["friction"][i])
    d = mujoco.MjData(m)
    d.qpos[:] = params["qpos0"][i]
    d.qvel[:] = staggered_qvel(params["qvel0"][i], m.opt.timestep)
    return m, d


def step_states(model: mujoco.MjModel, data: mujoco.MjData, n_steps: int) -> np.ndarray:
    """Step ``data`` ``n_steps`` times with ``mj_step``: (n_steps + 1, nq) float64 positions, the first the
    initial one. The plain loop that the batched rollout is checked against."""
    out = np.empty((n_steps + 1, model.nq))
    out[0] = data.qpos
    for k in range(n_steps):
        mujoco.mj_step(model, data)
        out[k + 1] = data.qpos
    return out


def _initial_states(pairs: list[tuple[mujoco.MjModel, mujoco.MjData]]) -> np.ndarray:
    """(n, nstate) full physics states (time 0) of the throws set up by :func:`initial_data`."""
    states = np.empty((len(pairs), mujoco.mj_stateSize(pairs[0][0], STATE)))
    for i, (m, d) in enumerate(pairs):
        mujoco.mj_getState(m, d, states[i], STATE)
    return states


def _frames(cfg: SynthConfig, initial: np.ndarray, states: np.ndarray) -> np.ndarray:
    """Centre positions at the frame times from per-step states: (n, T, 3) float64, metres.

    Frame 0 is the launch state; frame k is the state after ``k * steps_per_frame`` steps.
    """
    spf = cfg.steps_per_frame
    pos = np.empty((states.shape[0], cfg.n_frames, 3))
    pos[:, 0] = initial[:, 1:4]  # state layout: time, qpos (x, y, z, quat), qvel
    pos[:, 1:] = states[:, spf - 1 :: spf, 1:4][:, : cfg.n_frames - 1]
    return pos


def _chunks(n: int, size: int) -> Iterator[range]:
    for start in range(0, n, size):
        yield range(start, min(n, start + size))


def simulate(
    cfg: SynthConfig,
    params: dict[str, np.ndarray],
    *,
    threads: int | None = None,
    chunk: int = 32,
    progress: bool = True,
    desc: str = "simulating",
) -> np.ndarray:
    """Simulate every object from its launch state with ``mujoco.rollout`` on ``threads`` threads.

    ``params`` holds (n,) arrays mass, damping, friction and qpos0 (n, 7), qvel0 (n, 6).
    Returns (n, T, 3) float64 centre positions, metres. ``threads=None`` uses every core;
    ``threads=1`` runs the rollout on the calling thread.
    """
    n = len(params["mass"])
    threads = (os.cpu_count() or 1) if threads is None else threads
    nstep = (cfg.n_frames - 1) * cfg.steps_per_frame
    out = np.empty((n, cfg.n_frames, 3))
    with rollout.Rollout(nthread=threads if threads > 1 else 0) as pool, Progress(
        desc, total=n, show=progress, unit="traj"
    ) as bar:
        for idx in _chunks(n, chunk):
            pairs = [initial_data(cfg, params, i) for i in idx]
            models = [m for m, _ in pairs]
            datas = [mujoco.MjData(models[0]) for _ in range(max(threads, 1))]
            initial = _initial_states(pairs)
            states, _ = pool.rollout(models, datas, initial, nstep=nstep)
            out[idx.start : idx.stop] = _frames(cfg, initial, states)
            bar.update(len(idx))
    return out


def simulate_reference(cfg: SynthConfig, params: dict[str, np.ndarray]) -> np.ndarray:
    """The same as :func:`simulate`, as a plain Python loop of ``mj_step``: the reference for tests."""
    n = len(params["mass"])
    out = np.empty((n, cfg.n_frames, 3))
    spf = cfg.steps_per_frame
    for i in range(n):
        states = step_states(*initial_data(cfg, params, i), (cfg.n_frames - 1) * spf)
        out[i] = states[::spf, :3]
    return out


def check_restitutions(cfg: SynthConfig) -> None:
    """Raise :class:`ConfigError` if a class asks for a restitution MuJoCo's contact calibration cannot give at
    this stiffness and timestep."""
    lo, hi = restitution_range(cfg.shape, cfg.stiffness, cfg.timestep)
    for name in CLASSES:
        r = cfg.prior(name).restitution
        if r[0] < lo or r[1] > hi:
            raise ConfigError(
                f"SynthConfig.{name}.restitution = {r!r} leaves the calibrated range [{lo:.3f}, {hi:.3f}] "
                f"for this stiffness and timestep; narrow it"
            )


def versions() -> dict[str, str]:
    """The library versions that can change MuJoCo's numbers."""
    return {"mujoco": mujoco.__version__, "numpy": np.__version__}


def simulate_split(cfg: SynthConfig, params: dict[str, np.ndarray], threads: int | None, progress: bool,
                   desc: str) -> np.ndarray:
    """A split's throws in this engine, as ``study.simulate.synth`` asks every engine for them:
    (n, T, 3) float64 centre positions, metres."""
    return simulate(cfg, params, threads=threads, progress=progress, desc=desc)
