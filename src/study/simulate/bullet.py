"""The study's throws in Bullet (pybullet), the engine behind Blender's rigid-body physics the paper used.

Same scene as :mod:`study.simulate.scene` -- ground z = 0, one free object of ``cfg.shape``, gravity
9.81 m/s^2 down, no air -- and the same output as :func:`study.simulate.synth.simulate`: the centre's
world position at the frame times, ``(n, T, 3)`` float64 metres, frame 0 the launch.

Choices, each checked by ``tests/test_bullet.py``:

* **Bodies.** The object and the ground are ``btRigidBody``s (``useMaximalCoordinates``), as in
  Blender, not pybullet's default multibodies, so their contact is Bullet's rigid-body
  sequential-impulse contact. The ground is a static 200 m x 200 m x 2 m box whose top face is
  z = 0, not pybullet's ``GEOM_PLANE``: the plane's contact generator adds one manifold point per
  step, so a flat box first lands on a single corner and its measured restitution changes by 0.1-0.2
  as the step halves (never converging); box-box contact gives the whole face at once. Blender has
  no infinite plane either.
  Linear and angular damping are set to 0 explicitly: there is no air.
* **Time step.** :data:`TIMESTEP` = 1/240 s, eight steps per 1/30 s frame, each a ``stepSimulation``
  call with no sub-stepping of its own. Blender's default since 2.91, 10 substeps per 1/24 s frame,
  is the same rate; its older 60 steps per second is coarse (a 4.4 m/s impact moves 7 cm, a third of
  the box, in a step). The measured restitution is converged at 1/240 s: halving the step changes it
  by < 0.02 (a test; by < 0.005 over most of the range). A 10 s throw takes about 0.07 s of one core.
* **Solver.** Bullet's sequential-impulse solver with exactly :data:`SOLVER_ITERATIONS` iterations a
  step (pybullet's default number; its early exit on a small residual is off, for without it the
  four corners of a flat landing get unequal impulses and the box starts spinning, up to several
  rad/s by the third bounce), deterministic pair ordering, and Bullet's defaults otherwise: its
  penetration recovery too (pybullet's contact ERP, folded into the velocity), which is what makes
  the set ``restitution`` differ from the measured one (below). Of 16 throws from the priors, 14 are
  within 1 mm of themselves with 100 iterations and two tumbling ones within 7 cm; with 20
  iterations it is up to 9 cm, with Blender's 10 up to 27 cm.
* **Sleeping.** Off: Bullet's deactivation (0.8 m/s and 1 rad/s for 2 s) is far coarser than MuJoCo's
  5 mm/s and could freeze an object that is still sliding slowly; Blender's default leaves it off too.
* **Launch.** Position as given; MuJoCo's quaternion (w, x, y, z) -> Bullet's (x, y, z, w); linear
  velocity (world frame) as given; angular velocity rotated from MuJoCo's body frame to Bullet's world
  frame. Bullet's integrator is semi-implicit Euler like MuJoCo's (v += g dt, then x += v dt), so the
  velocity is staggered by ``+g dt / 2`` exactly as :func:`study.simulate.synth.staggered_qvel` does:
  free flight then follows ``p0 + v0 t - g t^2 / 2`` to rounding.
* **Restitution.** Bullet's ``restitution`` (object's value times the ground's, 1) sets the
  outgoing normal speed, and the penetration recovery adds more, the deeper the object got in the
  step of impact: a 20 cm box set to 0.4 measures ``e = sqrt(h1 / h0)`` = 0.431 (0.1 -> 0.109, 0.7 ->
  0.735, 0.95 -> 0.986, 1 -> 1.036: energy gained), and single drops scatter by about +-0.035 around
  the mean with the impact phase. As :mod:`study.simulate.contact` does for MuJoCo, we measure flat
  drops (no spin, 1 m of the lowest point, :data:`PHASES` impact phases averaged) on
  :data:`RESTITUTION_GRID`, keep the increasing part below 1 and invert it by interpolation
  (:func:`restitution_setting`).
* **Friction.** Bullet multiplies the two bodies' lateral frictions; the ground's is 1, so the
  contact's is the object's. A box sliding on a face decelerates at ``mu g`` for that value to 0.2 %;
  that is measured too, on :data:`FRICTION_GRID`, and inverted the same way (:func:`friction_setting`).
  The grid stops at 0.9: from mu = 1 a sliding 20 cm cube tips over. Rolling and spinning friction
  (Bullet combines each with the other body's lateral friction, ``r_a f_b + r_b f_a``) are the
  object's only, 0.0001 m and 0.005 m: MuJoCo's scene's rolling and torsional values, which in both
  engines bound the torque per contact point at coefficient x normal force.
"""

from __future__ import annotations

import functools
import importlib.metadata
import math
import multiprocessing
import os
from collections.abc import Iterator
from concurrent.futures import ProcessPoolExecutor
from contextlib import contextmanager

import numpy as np

from study import CLASSES
from study.core.errors import ConfigError
from study.core.progress import Progress
from study.simulate.config import GRAVITY, SynthConfig, staggered_qvel
from study.simulate.scene import Shape
from study.simulate.trace import Trace


def _import_quietly():
    """pybullet, imported and connected once with the 'pybullet build time' line its C code prints on the first
    connection kept off the caller's standard output (where ``study synth`` prints the data set's path, and a
    chapter its cells' output)."""
    import ctypes
    import os
    import sys

    sys.stdout.flush()
    saved = os.dup(1)
    try:
        with open(os.devnull, "w") as null:
            os.dup2(null.fileno(), 1)
            import pybullet as module

            module.disconnect(module.connect(module.DIRECT))  # the first connection prints it
            ctypes.CDLL(None).fflush(None)  # C's buffered line goes to the null device, not to the later stdout
    finally:
        os.dup2(saved, 1)
        os.close(saved)
    return module


pybullet = _import_quietly()

SHAPES = ("box",)
"""The shapes the Bullet scene supports. A sphere's and a cylinder's flat-drop restitution do not
converge at :data:`TIMESTEP` (halving the step changes it by 0.08 and 0.12), so they are refused."""
TIMESTEP = 1.0 / 240.0
"""Bullet's step, seconds (eight per 1/30 s frame); see the module docstring."""
SOLVER_ITERATIONS = 50
"""Sequential-impulse iterations per step."""
RESTITUTION_VELOCITY_THRESHOLD = 0.2
"""m/s: Bullet applies restitution only to impacts faster than this (its default); slower ones stick."""
ROLLING_FRICTION = 1e-4
"""Rolling friction, metres (torque bound per newton of normal force): MuJoCo's scene's value."""
SPINNING_FRICTION = 5e-3
"""Torsional (spinning) friction, metres: MuJoCo's scene's value."""
GROUND_HALF_EXTENTS = (100.0, 100.0, 1.0)
"""Half-extents of the static ground box, metres; its top face is z = 0."""
CHUNK = 16
"""Throws per unit of work in :func:`simulate` (one private client each, and a worker's share)."""

CALIBRATION_DROP = 1.0
"""Release height of the lowest point above the ground in calibration drops, metres."""
PHASES = 8
"""Calibration drops per setting, released at heights that spread the impact evenly over one step."""
RESTITUTION_GRID = tuple(float(r) for r in np.round(np.linspace(0.0, 1.0, 41), 6))
"""Bullet restitution settings at which the calibration measures the restitution."""
SLIDE_SPEED = 3.0
"""Launch speed of the sliding box in friction calibration, m/s."""
FRICTION_GRID = tuple(float(f) for f in np.round(np.linspace(0.0, 0.9, 19), 6))
"""Bullet lateral-friction settings at which the calibration measures the sliding deceleration."""

DESCRIPTION = (
    f"Bullet (pybullet {importlib.metadata.version('pybullet')}, headless) simulates the same box as a rigid body "
    f"on a static box whose top is the ground, with no air, in steps of 1/{round(1 / TIMESTEP)} s "
    f"({round(1 / (30 * TIMESTEP))} per frame at 30 fps, Blender's default rate since 2.91) and exactly "
    f"{SOLVER_ITERATIONS} solver iterations a step, never putting a resting object to sleep. Each launch is "
    "converted from MuJoCo's conventions (quaternion order, spin in the body frame) and staggered half a step, "
    "as MuJoCo's is, so that free flight follows the exact parabola. Bullet's restitution setting is not the "
    "measured one (its penetration recovery adds some bounce: a box set to 0.4 rebounds at 0.43), so the setting "
    "for each object is read off a table of measured flat drops, as MuJoCo's contact damping is; its friction "
    "setting is the Coulomb coefficient to 0.2 %, and rolling and torsional friction are MuJoCo's."
)
"""One paragraph on how the Bullet scene is set up, for the book."""


# --------------------------------------------------------------------------- the scene


@contextmanager
def client() -> Iterator[int]:
    """A private headless pybullet client, disconnected on exit."""
    cid = pybullet.connect(pybullet.DIRECT)
    try:
        yield cid
    finally:
        pybullet.disconnect(cid)


def check_shape(shape: Shape) -> None:
    """Raise :class:`ConfigError` naming the shape unless it is valid and in :data:`SHAPES`."""
    shape.validate("SynthConfig.shape")
    if shape.kind not in SHAPES:
        raise ConfigError(
            f"SynthConfig.shape.kind = {shape.kind!r} has no Bullet scene (its flat-drop restitution does not converge "
            f"as the step halves); allowed: {', '.join(SHAPES)}"
        )


def _collision_shape(shape: Shape, cid: int) -> int:
    check_shape(shape)
    return pybullet.createCollisionShape(pybullet.GEOM_BOX, halfExtents=list(shape.size), physicsClientId=cid)


def build(cid: int, shape: Shape, *, mass: float, restitution: float, friction: float,
          timestep: float = TIMESTEP) -> int:
    """Reset client ``cid`` to the scene with one object and return the object's body id.

    ``restitution`` and ``friction`` are Bullet's settings (see :func:`restitution_setting`,
    :func:`friction_setting`), ``mass`` kg, ``timestep`` s. The object starts at rest at the origin;
    the inertia is Bullet's for a uniform solid of the shape.
    """
    pybullet.resetSimulation(physicsClientId=cid)
    pybullet.setGravity(0.0, 0.0, -GRAVITY, physicsClientId=cid)
    pybullet.setPhysicsEngineParameter(
        fixedTimeStep=timestep, numSubSteps=0, numSolverIterations=SOLVER_ITERATIONS,
        solverResidualThreshold=0.0, deterministicOverlappingPairs=1,
        restitutionVelocityThreshold=RESTITUTION_VELOCITY_THRESHOLD, physicsClientId=cid,
    )
    ground_shape = pybullet.createCollisionShape(pybullet.GEOM_BOX, halfExtents=list(GROUND_HALF_EXTENTS),
                                                 physicsClientId=cid)
    ground = pybullet.createMultiBody(0.0, ground_shape, basePosition=[0.0, 0.0, -GROUND_HALF_EXTENTS[2]],
                                      useMaximalCoordinates=True, physicsClientId=cid)
    pybullet.changeDynamics(ground, -1, restitution=1.0, lateralFriction=1.0, rollingFriction=0.0,
                            spinningFriction=0.0, physicsClientId=cid)
    body = pybullet.createMultiBody(float(mass), _collision_shape(shape, cid), useMaximalCoordinates=True,
                                    physicsClientId=cid)
    pybullet.changeDynamics(
        body, -1, restitution=float(restitution), lateralFriction=float(friction), rollingFriction=ROLLING_FRICTION,
        spinningFriction=SPINNING_FRICTION, linearDamping=0.0, angularDamping=0.0,
        activationState=pybullet.ACTIVATION_STATE_DISABLE_SLEEPING, physicsClientId=cid,
    )
    return body


def inertia(shape: Shape, mass: float = 1.0) -> np.ndarray:
    """Bullet's principal moments of inertia of the object, (3,) kg m^2 about the centre (body axes)."""
    with client() as cid:
        body = build(cid, shape, mass=mass, restitution=0.5, friction=0.5)
        return np.array(pybullet.getDynamicsInfo(body, -1, physicsClientId=cid)[2])


# --------------------------------------------------------------------------- the launch


def rotate(quat_wxyz: np.ndarray, v: np.ndarray) -> np.ndarray:
    """``v`` (3,) rotated by the unit quaternion (w, x, y, z): body frame -> world frame."""
    w, u = quat_wxyz[0], np.asarray(quat_wxyz[1:4], float)
    v = np.asarray(v, float)
    t = 2.0 * np.cross(u, v)
    return v + w * t + np.cross(u, t)


def launch_state(qpos: np.ndarray, qvel: np.ndarray, timestep: float = TIMESTEP) -> tuple[list, list, list, list]:
    """Bullet's base state for a MuJoCo launch: position (m), orientation (x, y, z, w), linear velocity
    (world, m/s) and angular velocity (world, rad/s).

    ``qpos`` (7,) [x, y, z, quaternion w, x, y, z]; ``qvel`` (6,) [linear world m/s, angular body rad/s].
    The linear velocity is staggered by :func:`study.simulate.synth.staggered_qvel` for Bullet's step.
    """
    qpos, qvel = np.asarray(qpos, float), staggered_qvel(qvel, timestep)
    quat = qpos[3:7] / np.linalg.norm(qpos[3:7])
    return (qpos[:3].tolist(), [quat[1], quat[2], quat[3], quat[0]], qvel[:3].tolist(),
            rotate(quat, qvel[3:6]).tolist())


def _launch(cid: int, body: int, qpos: np.ndarray, qvel: np.ndarray, timestep: float) -> None:
    pos, orn, lin, ang = launch_state(qpos, qvel, timestep)
    pybullet.resetBasePositionAndOrientation(body, pos, orn, physicsClientId=cid)
    pybullet.resetBaseVelocity(body, lin, ang, physicsClientId=cid)


def steps_per_frame(fps: float, timestep: float = TIMESTEP) -> int:
    """Bullet steps per recorded frame; :class:`ConfigError` unless ``timestep`` divides ``1 / fps``."""
    ratio = 1.0 / (fps * timestep)
    if abs(ratio - round(ratio)) > 1e-6 or round(ratio) < 1:
        raise ConfigError(f"Bullet timestep {timestep!r} s does not divide the frame period 1/{fps:g} s of "
                          f"SynthConfig.fps; use an fps that divides {1 / timestep:g}, or timestep 1/(fps * n)")
    return int(round(ratio))


# --------------------------------------------------------------------------- simulation


def _settings(cfg: SynthConfig, params: dict[str, np.ndarray], timestep: float) -> tuple[np.ndarray, np.ndarray]:
    """Bullet's restitution and friction settings for every throw of ``params``, (n,) each."""
    return (restitution_setting(params["restitution"], cfg.shape, timestep=timestep),
            friction_setting(params["friction"], cfg.shape, timestep=timestep))


def _check_config(cfg: SynthConfig) -> None:
    if cfg.air:
        raise ConfigError("SynthConfig.air = True: the Bullet scene has no air; simulate cfg.replace(air=False) "
                          "and compare it with MuJoCo's air-off data")


def simulate(cfg: SynthConfig, params: dict[str, np.ndarray], *, timestep: float = TIMESTEP, processes: int = 1,
             progress: bool = False, desc: str = "simulating (bullet)") -> np.ndarray:
    """Simulate every throw of a split's ``params`` (:func:`study.simulate.synth.sample_split`) in Bullet.

    Uses (n,) ``mass`` kg, ``restitution`` (the measured flat-drop e wanted), ``friction`` (Coulomb
    mu), ``qpos0`` (n, 7) and ``qvel0`` (n, 6) as MuJoCo does; ``damping`` is MuJoCo's alone. ``cfg``
    gives the shape, duration and frame rate and must have ``air=False``; ``cfg.timestep`` and
    ``cfg.sleep_tolerance`` are MuJoCo's. Returns (n, T, 3) float64 centre positions, metres, at
    ``k / cfg.fps`` for k < T = ``cfg.n_frames``; frame 0 is the launch position. Throws are independent
    (each in a freshly reset world), so ``processes > 1`` worker processes give the same bits as one;
    the result is bitwise reproducible.
    """
    _check_config(cfg)
    spf = steps_per_frame(cfg.fps, timestep)
    if not isinstance(processes, int) or isinstance(processes, bool) or processes < 1:
        raise ConfigError(f"processes = {processes!r} must be a positive integer")
    n = len(params["mass"])
    restitution, friction = _settings(cfg, params, timestep)
    throws = [(float(params["mass"][i]), float(restitution[i]), float(friction[i]), np.asarray(params["qpos0"][i]),
               np.asarray(params["qvel0"][i])) for i in range(n)]
    job = functools.partial(_simulate_throws, cfg.shape, cfg.n_frames, spf, timestep)
    chunks = [throws[i : i + CHUNK] for i in range(0, n, CHUNK)]
    out = np.empty((n, cfg.n_frames, 3))
    with Progress(desc, total=n, show=progress, unit="traj") as bar:
        if processes == 1:
            results: Iterator[np.ndarray] = map(job, chunks)
            pool = None
        else:
            # fork: spawned workers would re-import the caller's script, which then needs a __main__ guard
            pool = ProcessPoolExecutor(max_workers=processes, mp_context=multiprocessing.get_context("fork"))
            results = pool.map(job, chunks)
        try:
            for j, x in enumerate(results):
                out[j * CHUNK : j * CHUNK + len(x)] = x
                bar.update(len(x))
        finally:
            if pool is not None:
                pool.shutdown(cancel_futures=True)
    return out


def _simulate_throws(shape: Shape, n_frames: int, spf: int, timestep: float,
                     throws: list[tuple[float, float, float, np.ndarray, np.ndarray]]) -> np.ndarray:
    """Centre positions (len(throws), n_frames, 3) of throws ``(mass, restitution setting, friction
    setting, qpos0, qvel0)``, one freshly reset world each, in one private client."""
    out = np.empty((len(throws), n_frames, 3))
    with client() as cid:
        for i, (mass, restitution, friction, qpos0, qvel0) in enumerate(throws):
            body = build(cid, shape, mass=mass, restitution=restitution, friction=friction, timestep=timestep)
            _launch(cid, body, qpos0, qvel0, timestep)
            out[i, 0] = qpos0[:3]
            for k in range(1, n_frames):
                for _ in range(spf):
                    pybullet.stepSimulation(physicsClientId=cid)
                out[i, k] = pybullet.getBasePositionAndOrientation(body, physicsClientId=cid)[0]
    return out


def _step_states(cid: int, body: int, n_steps: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Step ``n_steps`` times: per-step position (N, 3), orientation (N, 4) x, y, z, w, linear and angular
    velocity (N, 3) each, world frame, as Bullet stores them (the velocity half a step behind)."""
    pos, orn = np.empty((n_steps, 3)), np.empty((n_steps, 4))
    lin, ang = np.empty((n_steps, 3)), np.empty((n_steps, 3))
    for k in range(n_steps):
        pybullet.stepSimulation(physicsClientId=cid)
        pos[k], orn[k] = pybullet.getBasePositionAndOrientation(body, physicsClientId=cid)
        lin[k], ang[k] = pybullet.getBaseVelocity(body, physicsClientId=cid)
    return pos, orn, lin, ang


def flight(cfg: SynthConfig, qpos0: np.ndarray, qvel0: np.ndarray, duration: float, *,
           timestep: float = TIMESTEP) -> tuple[np.ndarray, np.ndarray]:
    """One throw (mass 1 kg, mid-prior contact settings) stepped for ``duration`` s: per-step centre
    positions (N, 3) metres and orientations (N, 4) as MuJoCo's quaternion (w, x, y, z), the k-th after
    k + 1 steps. For the free-flight and launch-conversion checks."""
    with client() as cid:
        body = build(cid, cfg.shape, mass=1.0, restitution=0.5, friction=0.5, timestep=timestep)
        _launch(cid, body, qpos0, qvel0, timestep)
        pos, orn, _, _ = _step_states(cid, body, int(round(duration / timestep)))
    return pos, orn[:, [3, 0, 1, 2]]


def trace(cfg: SynthConfig, params: dict[str, np.ndarray], i: int, duration: float | None = None, *,
          timestep: float = TIMESTEP) -> Trace:
    """Throw ``i`` of ``params`` step by step, with the diagnostics of :class:`study.simulate.trace.Trace`.

    Speed and energy use the velocity at the position's time, the mean of Bullet's velocities over the
    steps before and after it (each is the velocity of a step, half a step away from the positions):
    with it semi-implicit Euler conserves ``m g z + m v^2 / 2`` in free flight exactly, where the stored
    velocity would show a steady loss of ``m g^2 dt / 2`` per second; at rest it is 0. Energy:
    m g z + translational + rotational kinetic, joules. A step is in contact when Bullet's manifold has
    any point (it keeps points up to a few mm apart); depth is the deepest penetration, metres.
    """
    _check_config(cfg)
    restitution, friction = _settings(cfg, {k: params[k][i : i + 1] for k in ("restitution", "friction")}, timestep)
    mass = float(params["mass"][i])
    n = int(round((duration or cfg.duration) / timestep))
    with client() as cid:
        body = build(cid, cfg.shape, mass=mass, restitution=restitution[0], friction=friction[0], timestep=timestep)
        moments = np.array(pybullet.getDynamicsInfo(body, -1, physicsClientId=cid)[2])
        _launch(cid, body, params["qpos0"][i], params["qvel0"][i], timestep)
        pos, orn = np.empty((n + 1, 3)), np.empty((n + 1, 4))
        lin, ang = np.empty((n + 1, 3)), np.empty((n + 1, 3))
        contact, depth = np.zeros(n + 1, bool), np.zeros(n + 1)
        for k in range(n + 1):  # one step more, for the velocity after the last position
            pybullet.stepSimulation(physicsClientId=cid)
            pos[k], orn[k] = pybullet.getBasePositionAndOrientation(body, physicsClientId=cid)
            lin[k], ang[k] = pybullet.getBaseVelocity(body, physicsClientId=cid)
            points = pybullet.getContactPoints(bodyA=body, physicsClientId=cid)
            if points:
                contact[k] = True
                depth[k] = max(0.0, -min(pt[8] for pt in points))
    v, w = (lin[:-1] + lin[1:]) / 2, (ang[:-1] + ang[1:]) / 2
    inverse = orn[:-1, [3, 0, 1, 2]] * np.array([1.0, -1.0, -1.0, -1.0])  # (w, x, y, z) of the world -> body turn
    w_body = np.array([rotate(q, x) for q, x in zip(inverse, w)])
    kinetic = 0.5 * mass * np.sum(v * v, axis=1) + 0.5 * np.sum(moments * w_body**2, axis=1)
    energy = mass * GRAVITY * pos[:-1, 2] + kinetic
    return Trace(t=timestep * np.arange(1, n + 1), pos=pos[:-1], speed=np.linalg.norm(v, axis=1),
                 in_contact=contact[:-1], depth=depth[:-1], energy=energy)


# --------------------------------------------------------------------------- calibration


def _apexes(height: np.ndarray, vz: np.ndarray, bounces: int) -> np.ndarray:
    """Apex heights (bounces,) of the flights after each bounce, from per-step heights and vertical
    velocities; 0 where there is no such bounce. A bounce is where the velocity turns upward."""
    up = vz > 0
    starts = np.flatnonzero(up[1:] & ~up[:-1]) + 1
    out = np.zeros(bounces)
    for j, s in enumerate(starts[:bounces]):
        stop = np.flatnonzero(~up[s:])
        end = s + stop[0] + 1 if len(stop) else len(height)
        out[j] = max(0.0, float(height[s:end].max()))
    return out


def flat_drops(shape: Shape, setting: np.ndarray | float, drop: np.ndarray | float, *, timestep: float = TIMESTEP,
               mass: float = 1.0, bounces: int = 1) -> np.ndarray:
    """Drop the object flat (no spin, released at rest) once per (setting, drop) pair; return apex heights.

    ``setting``: Bullet restitution settings; ``drop``: release heights of the lowest point, metres;
    broadcast to (k,). Returns (k, bounces + 1) metres, ``[drop, h1, h2, ...]``: the lowest point's
    height at release and at the apex of each flight after a bounce, 0 once it stops bouncing.
    """
    setting, drop = np.broadcast_arrays(np.atleast_1d(np.asarray(setting, float)),
                                        np.atleast_1d(np.asarray(drop, float)))
    rest = shape.rest_height
    out = np.zeros((len(setting), bounces + 1))
    out[:, 0] = drop
    with client() as cid:
        for i, (r, h) in enumerate(zip(setting, drop)):
            body = build(cid, shape, mass=mass, restitution=r, friction=0.5, timestep=timestep)
            _launch(cid, body, np.array([0.0, 0.0, rest + h, 1.0, 0.0, 0.0, 0.0]), np.zeros(6), timestep)
            fall = math.sqrt(2 * h / GRAVITY)
            pos, _, lin, _ = _step_states(cid, body, int((2 * fall * bounces + 0.1) / timestep))
            out[i, 1:] = _apexes(pos[:, 2] - rest, lin[:, 2], bounces)
    return out


def drop_heights(drop: float, timestep: float = TIMESTEP, phases: int = PHASES) -> np.ndarray:
    """(phases,) release heights, metres, from ``drop`` up by fractions of one step's travel at impact."""
    return drop + math.sqrt(2 * GRAVITY * drop) * timestep * np.arange(phases) / phases


def measured_restitution(shape: Shape, setting: np.ndarray | float, *, timestep: float = TIMESTEP,
                         drop: float = CALIBRATION_DROP, mass: float = 1.0) -> np.ndarray:
    """First-bounce restitution ``sqrt(h1 / h0)`` of flat drops for Bullet restitution ``setting``, the
    mean over :data:`PHASES` impact phases. ``setting``: scalar or (k,); returns the same shape."""
    r = np.atleast_1d(np.asarray(setting, float))
    drops = drop_heights(drop, timestep)
    h = flat_drops(shape, np.repeat(r, PHASES), np.tile(drops, len(r)), timestep=timestep, mass=mass)
    e = np.sqrt(h[:, 1] / h[:, 0]).reshape(len(r), PHASES).mean(axis=1)
    return e if np.ndim(setting) else e[0]


def _increasing(x: np.ndarray, y: np.ndarray, top: float) -> tuple[np.ndarray, np.ndarray]:
    """The table ``(x, y)`` cut at the first point where y stops increasing or passes ``top``."""
    stop = len(y)
    for i in range(1, len(y)):
        if not y[i] > y[i - 1] or y[i] > top:
            stop = i
            break
    return x[:stop], y[:stop]


def restitution_table(shape: Shape, timestep: float = TIMESTEP) -> tuple[np.ndarray, np.ndarray]:
    """``(setting, measured e)`` over :data:`RESTITUTION_GRID`, cut where e stops increasing or exceeds 1
    (the penetration recovery can make a drop rebound higher than it fell). Computed once per
    (shape, timestep)."""
    check_shape(shape)
    return _restitution_table(shape, float(timestep))


@functools.lru_cache(maxsize=16)
def _restitution_table(shape: Shape, timestep: float) -> tuple[np.ndarray, np.ndarray]:
    r = np.array(RESTITUTION_GRID)
    return _increasing(r, measured_restitution(shape, r, timestep=timestep), 1.0)


def restitution_range(shape: Shape, timestep: float = TIMESTEP) -> tuple[float, float]:
    """The flat-drop restitutions the calibration reaches, ``(min, max)``."""
    _, e = restitution_table(shape, timestep)
    return float(e[0]), float(e[-1])


def _invert(name: str, value: np.ndarray | float, table: tuple[np.ndarray, np.ndarray], what: str) -> np.ndarray:
    x, y = table
    value = np.asarray(value, dtype=float)
    lo, hi = float(y[0]), float(y[-1])
    bad = (value < lo) | (value > hi) | ~np.isfinite(value)
    if np.any(bad):
        raise ConfigError(f"{name} {value[bad].ravel()[0]:.3f} is outside what the Bullet calibration reaches, "
                          f"[{lo:.3f}, {hi:.3f}] ({what}); narrow the class prior's {name} range")
    return np.interp(value, y, x)


def restitution_setting(e: np.ndarray | float, shape: Shape, *, timestep: float = TIMESTEP) -> np.ndarray:
    """Bullet restitution setting that gives flat-drop restitution ``e`` (scalar or array, same shape out).

    Raises :class:`ConfigError` naming ``restitution`` if ``e`` is outside :func:`restitution_range`.
    """
    return _invert("restitution", e, restitution_table(shape, timestep), f"flat drops of a {shape.kind}")


def slide_deceleration(shape: Shape, setting: np.ndarray | float, *, speed: float = SLIDE_SPEED,
                       timestep: float = TIMESTEP, mass: float = 1.0) -> np.ndarray:
    """Deceleration, m/s^2, of the object launched along x at ``speed`` m/s while resting on its lowest
    face (no spin), for Bullet lateral-friction ``setting`` (scalar or (k,); same shape out).

    The slope of a straight line fitted to the centre's x velocity over the steps where the bottom still
    slips faster than 20 % of ``speed``, leaving out the first 0.02 s (the contact settling).
    """
    f = np.atleast_1d(np.asarray(setting, float))
    out = np.full(len(f), np.nan)
    rest = shape.rest_height
    n_steps = int((speed / (GRAVITY * max(float(f.min()), 0.05)) + 0.2) / timestep)
    with client() as cid:
        for i, mu in enumerate(f):
            body = build(cid, shape, mass=mass, restitution=0.0, friction=mu, timestep=timestep)
            _launch(cid, body, np.array([0.0, 0.0, rest, 1.0, 0.0, 0.0, 0.0]), np.array([speed, 0, 0, 0, 0, 0.0]),
                    timestep)
            _, _, lin, ang = _step_states(cid, body, n_steps)
            slip = lin[:, 0] + ang[:, 1] * -rest  # x velocity of the bottom centre: v + w x (0, 0, -rest)
            t = timestep * np.arange(1, len(lin) + 1)
            use = (slip > 0.2 * speed) & (t > 0.02)
            if use.sum() >= 5:
                out[i] = -np.polyfit(t[use], lin[use, 0], 1)[0]
    return out if np.ndim(setting) else out[0]


def friction_table(shape: Shape, timestep: float = TIMESTEP) -> tuple[np.ndarray, np.ndarray]:
    """``(setting, measured mu)`` over :data:`FRICTION_GRID`: mu = deceleration / g of a sliding object,
    cut where it stops increasing. Computed once per (shape, timestep)."""
    check_shape(shape)
    return _friction_table(shape, float(timestep))


@functools.lru_cache(maxsize=16)
def _friction_table(shape: Shape, timestep: float) -> tuple[np.ndarray, np.ndarray]:
    f = np.array(FRICTION_GRID)
    mu = np.maximum(slide_deceleration(shape, f, timestep=timestep) / GRAVITY, 0.0)  # setting 0 measures 0 +- 1e-16
    return _increasing(f, mu, math.inf)


def friction_setting(mu: np.ndarray | float, shape: Shape, *, timestep: float = TIMESTEP) -> np.ndarray:
    """Bullet lateral-friction setting that gives sliding friction ``mu`` (scalar or array, same shape out).

    Raises :class:`ConfigError` naming ``friction`` outside the calibrated range.
    """
    return _invert("friction", mu, friction_table(shape, timestep), f"a sliding {shape.kind}")


def check_restitutions(cfg: SynthConfig) -> None:
    """Raise :class:`ConfigError` if a class asks for a restitution Bullet's flat drops cannot give for this
    shape."""
    lo, hi = restitution_range(cfg.shape)
    for name in CLASSES:
        r = cfg.prior(name).restitution
        if r[0] < lo or r[1] > hi:
            raise ConfigError(f"SynthConfig.{name}.restitution = {r!r} leaves Bullet's calibrated range "
                              f"[{lo:.3f}, {hi:.3f}] for this shape; narrow it")


def versions() -> dict[str, str]:
    """The library versions that can change Bullet's numbers."""
    return {"pybullet": importlib.metadata.version("pybullet"), "numpy": np.__version__}


def simulate_split(cfg: SynthConfig, params: dict[str, np.ndarray], threads: int | None, progress: bool,
                   desc: str) -> np.ndarray:
    """A split's throws in Bullet, as ``study.simulate.synth`` asks every engine for them: (n, T, 3) float64
    centre positions, metres, on ``threads`` worker processes (None: one per core)."""
    return simulate(cfg, params, processes=(os.cpu_count() or 1) if threads is None else threads, progress=progress,
                    desc=f"{desc} (Bullet)")
