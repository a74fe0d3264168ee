"""What every simulator of the study shares: the class priors and the launch, the config of a data set, the sampling
of a split's throws, and the staggered start that makes free flight exact. It imports neither simulator, so each
data set's key hashes the code of its own engine (``study.simulate.synth`` chooses the engine).

Each class is a prior over physical parameters (:class:`ClassPrior`); the launch prior is shared, so only the
object's physics tells the classes apart.
"""

from __future__ import annotations

import dataclasses
import json
import math
from dataclasses import dataclass, field
from typing import Any, Literal, get_args

import mujoco
import numpy as np

from study import CLASSES
from study.core import cache, presets
from study.core.errors import ConfigError, check_range
from study.simulate import data
from study.simulate.contact import damping_for_restitution
from study.simulate.scene import Shape

GRAVITY = 9.81
"""m/s^2, MuJoCo's default |gravity|."""
Engine = Literal["mujoco", "bullet"]
"""The physics engines a data set can be simulated with."""
ENGINES: tuple[Engine, ...] = get_args(Engine)
SLEEP_STEPS = mujoco.mjMINAWAKE
"""Consecutive steps an object's speeds must stay under the sleep tolerance before MuJoCo puts it to sleep."""


def max_sleep_tolerance(timestep: float) -> float:
    """Largest sleep tolerance, m/s, that cannot put a thrown object to sleep in mid-air at this timestep (s).

    MuJoCo puts a body to sleep when its speeds stay under the tolerance for :data:`SLEEP_STEPS`
    steps, in the air as on the ground. At the apex of a throw without spin the vertical speed
    crosses the band (-tol, tol) in 2 tol / (g dt) steps; we allow half of :data:`SLEEP_STEPS`.
    """
    return SLEEP_STEPS / 4 * GRAVITY * timestep


@dataclass(frozen=True)
class ClassPrior:
    """Prior over one class's physical parameters: each a ``(low, high)`` range, sampled uniformly
    (mass log-uniformly). Sources for the ranges are given in the book's data chapter.

    Example::

        import dataclasses
        cfg = study.SynthConfig.preset("smoke")
        lighter = dataclasses.replace(cfg.light, mass=(0.05, 0.2))   # kg
        ds = study.dataset(cfg.replace(light=lighter), seed=0)
    """

    mass: tuple[float, float]
    """kg, log-uniform."""
    restitution: tuple[float, float]
    """Coefficient of restitution of a flat drop on the ground, dimensionless, uniform."""
    friction: tuple[float, float]
    """Sliding (Coulomb) friction coefficient against the ground, dimensionless, uniform."""

    def validate(self, where: str) -> None:
        """Raise :class:`ConfigError` naming the field if a range is empty or out of physical bounds."""
        for name, (lo_ok, hi_ok) in {"mass": (1e-3, 1e4), "restitution": (0.0, 1.0), "friction": (0.0, 2.0)}.items():
            lo, hi = getattr(self, name)
            check_range(f"{where}.{name}[0]", lo, lo_ok, hi_ok, lo_open=name == "mass")
            check_range(f"{where}.{name}[1]", hi, lo, hi_ok)


LIGHT = ClassPrior(mass=(0.1, 0.6), restitution=(0.35, 0.75), friction=(0.3, 0.7))
"""Light, safe to pass over, as a 20 cm box: an empty cardboard or plastic box, a foam block (density
12.5-75 kg/m^3; sources in the data chapter)."""
LIGHT_BALLS = ClassPrior(mass=(0.05, 0.5), restitution=(0.45, 0.85), friction=(0.3, 0.8))
"""The light prior of the study's first builds, taken from balls (tennis, golf, hollow plastic): kept to
compare Table 1 under both priors."""
HEAVY = ClassPrior(mass=(3.0, 25.0), restitution=(0.1, 0.5), friction=(0.4, 0.7))
"""Heavy, must avoid: a wooden block, a brick, a gas cylinder (density 375-3125 kg/m^3 as a 20 cm box)."""


@dataclass(frozen=True)
class LaunchPrior:
    """Prior over the state at the moment recording starts; the same for both classes."""

    height: tuple[float, float] = (0.6, 1.5)
    """Height of the centre above the ground, metres (a car's boot to a lorry's bed), uniform."""
    horizontal_speed: tuple[float, float] = (0.0, 4.0)
    """Speed in the ground plane, m/s, uniform; the direction is uniform on the circle."""
    vertical_speed: tuple[float, float] = (-1.0, 2.0)
    """Vertical velocity, m/s (up positive), uniform."""
    spin: float = 2 * math.pi
    """Each component of the angular velocity is uniform in [-spin, spin], rad/s."""

    def validate(self, shape: Shape) -> None:
        """Raise :class:`ConfigError` if a range is empty or the object could start in the ground."""
        check_range("LaunchPrior.height[0]", self.height[0], shape.bounding_radius, 20.0)
        check_range("LaunchPrior.height[1]", self.height[1], self.height[0], 20.0)
        check_range("LaunchPrior.horizontal_speed[0]", self.horizontal_speed[0], 0.0, 30.0)
        check_range("LaunchPrior.horizontal_speed[1]", self.horizontal_speed[1], self.horizontal_speed[0], 30.0)
        check_range("LaunchPrior.vertical_speed[0]", self.vertical_speed[0], -30.0, 30.0)
        check_range("LaunchPrior.vertical_speed[1]", self.vertical_speed[1], self.vertical_speed[0], 30.0)
        check_range("LaunchPrior.spin", self.spin, 0.0, 100.0)


@dataclass(frozen=True)
class SynthConfig:
    """Everything that determines a dataset, with the seed. Build one with :meth:`preset`.

    Example::

        cfg = study.SynthConfig.preset("smoke").replace(duration=2.0)
        ds = study.dataset(cfg, seed=1)
    """

    n_train: int = 1000
    """Training trajectories per class."""
    n_test: int = 1000
    """Test trajectories per class."""
    duration: float = 10.0
    """Recorded length of each trajectory, seconds."""
    fps: float = 30.0
    """Camera frame rate at which positions are recorded, frames per second."""
    timestep: float = 1 / 1800
    """Simulation step, seconds; must divide the frame period (chosen by the convergence check)."""
    stiffness: float = 2.5e5
    """Contact stiffness k of MuJoCo's direct solref, 1/s^2 (about 6 ms contacts; see the book)."""
    air: bool = True
    """Air drag and added mass through MuJoCo's ellipsoid fluid model (air at 20 C)."""
    sleep_tolerance: float = 5e-3
    """Speed below which MuJoCo puts a resting object to sleep (its position frozen), m/s; 0 keeps it awake."""
    shape: Shape = field(default_factory=Shape)
    """The object's shape, the same for every trajectory (a 20 cm cube by default)."""
    light: ClassPrior = LIGHT
    """Prior of the light (label 0, safe to pass over) class."""
    heavy: ClassPrior = HEAVY
    """Prior of the heavy (label 1, must avoid) class."""
    launch: LaunchPrior = field(default_factory=LaunchPrior)
    """Prior of the launch state, shared by both classes."""
    engine: Engine = "mujoco"
    """The physics engine that simulates the throws: 'mujoco' (the study's), or 'bullet' (the paper's, through
    Blender: ``study.simulate.bullet``; no air, the same sampled objects and launches)."""

    @classmethod
    def preset(cls, name: str) -> SynthConfig:
        """The config of a preset (its sizes in ``study.core.presets.SIZES``): ``'paper'``, the paper's size (1000
        train + 1000 test per class, 10 s); ``'smoke'``, a few short throws."""
        return cls(**presets.sizes(name, "data"))

    def replace(self, **changes: Any) -> SynthConfig:
        """A copy with ``changes`` applied, validated."""
        cfg = dataclasses.replace(self, **changes)
        cfg.validate()
        return cfg

    @property
    def steps_per_frame(self) -> int:
        """Simulation steps per recorded frame."""
        return int(round(1.0 / (self.fps * self.timestep)))

    @property
    def n_frames(self) -> int:
        """T, frames per trajectory (the first is the launch state)."""
        return int(round(self.duration * self.fps))

    def prior(self, label: int | str) -> ClassPrior:
        """The prior of a class, by label (0, 1) or name ('light', 'heavy')."""
        if label in (0, "light"):
            return self.light
        if label in (1, "heavy"):
            return self.heavy
        raise ConfigError(f"unknown class {label!r}; allowed: 0/'light', 1/'heavy'")

    def max_impact_speed(self) -> float:
        """Bound on the normal speed of any point of the object at impact, m/s (drag ignored)."""
        vz = max(abs(self.launch.vertical_speed[0]), abs(self.launch.vertical_speed[1]))
        fall = math.sqrt(vz**2 + 2 * GRAVITY * self.launch.height[1])
        return fall + math.sqrt(3) * self.launch.spin * self.shape.bounding_radius

    def validate(self) -> None:
        """Raise :class:`ConfigError` naming the field and its allowed range for any bad value."""
        for name in ("n_train", "n_test"):
            v = getattr(self, name)
            if not isinstance(v, int) or isinstance(v, bool) or not 1 <= v <= 1_000_000:
                raise ConfigError(f"SynthConfig.{name} = {v!r} must be an integer in [1, 1000000]")
        check_range("SynthConfig.duration", self.duration, 0.0, 120.0, lo_open=True)
        check_range("SynthConfig.fps", self.fps, 1.0, 1000.0)
        check_range("SynthConfig.timestep", self.timestep, 1e-5, 0.01)
        check_range("SynthConfig.stiffness", self.stiffness, 1e3, 1e7)
        check_range("SynthConfig.sleep_tolerance", self.sleep_tolerance, 0.0, 0.05)
        limit = max_sleep_tolerance(self.timestep)
        if self.sleep_tolerance > limit:
            raise ConfigError(
                f"SynthConfig.sleep_tolerance = {self.sleep_tolerance!r} m/s: at the apex of a throw the vertical speed "
                f"stays under it for {2 * self.sleep_tolerance / (GRAVITY * self.timestep):.1f} steps of "
                f"{self.timestep:.3g} s, and MuJoCo puts a body to sleep, in mid-air too, after {SLEEP_STEPS}; allowed "
                f"at this timestep: at most {limit:.4f} m/s, or 0 (never asleep)"
            )
        ratio = 1.0 / (self.fps * self.timestep)
        if abs(ratio - round(ratio)) > 1e-6:
            raise ConfigError(
                f"SynthConfig.timestep = {self.timestep!r} s does not divide the frame period 1/{self.fps:g} s; "
                f"use 1/(fps * n) for an integer n"
            )
        if self.n_frames < 2:
            raise ConfigError(f"SynthConfig.duration = {self.duration!r} s gives fewer than 2 frames at {self.fps:g} fps")
        resolution = math.sqrt(self.stiffness) * self.timestep
        if resolution > 0.3:
            raise ConfigError(
                f"sqrt(SynthConfig.stiffness) * SynthConfig.timestep = {resolution:.3f} exceeds 0.3: the contact is "
                f"under-resolved and can gain energy; lower the timestep or the stiffness"
            )
        if self.engine not in ENGINES:
            raise ConfigError(f"SynthConfig.engine = {self.engine!r} is unknown; use one of {', '.join(ENGINES)}")
        if self.engine == "bullet" and self.air:
            raise ConfigError("SynthConfig.air = True with engine 'bullet': Bullet has no air drag; set air=False "
                              "(the comparison is with MuJoCo's air-off data of the same throws)")
        self.shape.validate("SynthConfig.shape")
        self.light.validate("SynthConfig.light")
        self.heavy.validate("SynthConfig.heavy")
        self.launch.validate(self.shape)

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON-able dict (tuples as lists)."""
        return json_roundtrip(dataclasses.asdict(self))

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> SynthConfig:
        """Inverse of :meth:`to_dict`; raises :class:`ConfigError` on unknown or missing fields.

        A dict without ``sleep_tolerance`` is from a file written before sleeping existed, when every
        object stayed awake: it reads as ``sleep_tolerance=0``; one without ``engine``, from before Bullet,
        was simulated by MuJoCo.
        """
        try:
            d = {"sleep_tolerance": 0.0, "engine": "mujoco", **d}
            tup = lambda v: tuple(v) if isinstance(v, list) else v  # noqa: E731
            return cls(
                **{k: v for k, v in d.items() if k not in ("shape", "light", "heavy", "launch")},
                shape=Shape(**{k: tup(v) for k, v in d["shape"].items()}),
                light=ClassPrior(**{k: tup(v) for k, v in d["light"].items()}),
                heavy=ClassPrior(**{k: tup(v) for k, v in d["heavy"].items()}),
                launch=LaunchPrior(**{k: tup(v) for k, v in d["launch"].items()}),
            )
        except (KeyError, TypeError) as e:
            raise ConfigError(f"not a SynthConfig: {e}") from None


def json_roundtrip(obj: Any) -> Any:
    """``obj`` as JSON would give it back (tuples become lists)."""
    return json.loads(cache.canonical_json(obj))


def sample_objects(prior: ClassPrior, n: int, rng: np.random.Generator) -> dict[str, np.ndarray]:
    """Draw ``n`` objects' parameters: ``mass`` (kg), ``restitution``, ``friction``, each (n,) float64."""
    log_mass = rng.uniform(math.log(prior.mass[0]), math.log(prior.mass[1]), n)
    return {
        "mass": np.exp(log_mass),
        "restitution": rng.uniform(*prior.restitution, n),
        "friction": rng.uniform(*prior.friction, n),
    }


def sample_launch(launch: LaunchPrior, n: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """Draw ``n`` launch states: ``qpos`` (n, 7) [x, y, z metres, quaternion w, x, y, z] and
    ``qvel`` (n, 6) [linear m/s in the world frame, angular rad/s in the body frame]."""
    qpos = np.zeros((n, 7))
    qpos[:, 2] = rng.uniform(*launch.height, n)
    euler = rng.uniform(-math.pi, math.pi, (n, 3))  # random Euler angles, as in the paper
    for i in range(n):
        mujoco.mju_euler2Quat(qpos[i, 3:7], euler[i], "xyz")
    speed = rng.uniform(*launch.horizontal_speed, n)
    heading = rng.uniform(-math.pi, math.pi, n)
    qvel = np.zeros((n, 6))
    qvel[:, 0] = speed * np.cos(heading)
    qvel[:, 1] = speed * np.sin(heading)
    qvel[:, 2] = rng.uniform(*launch.vertical_speed, n)
    qvel[:, 3:6] = rng.uniform(-launch.spin, launch.spin, (n, 3))
    return qpos, qvel


def sample_split(cfg: SynthConfig, seed: int, split: str) -> dict[str, np.ndarray]:
    """Parameters and launch states of one split, light then heavy, from disjoint seeds.

    Each (split, class) draws from its own stream ``SeedSequence(seed, spawn_key=(split, class))``,
    so train and test never share random numbers and changing ``n_test`` leaves train unchanged.
    Returns per-trajectory arrays: label, mass, restitution, friction, damping, qpos0, qvel0.
    """
    split_id = data.SPLITS.index(split)
    n = cfg.n_train if split == "train" else cfg.n_test
    parts = []
    for label, name in enumerate(CLASSES):
        rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(split_id, label)))
        objects = sample_objects(cfg.prior(name), n, rng)
        qpos, qvel = sample_launch(cfg.launch, n, rng)
        objects["damping"] = damping_for_restitution(
            objects["restitution"], cfg.shape, stiffness=cfg.stiffness, timestep=cfg.timestep
        )
        parts.append({"label": np.full(n, label, dtype=np.int64), **objects, "qpos0": qpos, "qvel0": qvel})
    return {k: np.concatenate([p[k] for p in parts]) for k in parts[0]}


def staggered_qvel(qvel: np.ndarray, timestep: float) -> np.ndarray:
    """The velocity to give MuJoCo so that free flight follows the launch's exact parabola.

    MuJoCo's (semi-implicit Euler) velocity lives half a step before the position: starting it at the
    launch velocity would trace the parabola of ``v - g dt / 2``, 2.7 mm low after 1 s at our step.
    Starting it at ``v + g dt / 2`` (the true velocity half a step earlier) removes that offset.
    ``qvel``: (..., 6), the last axis [linear world m/s, angular body rad/s].
    """
    out = np.array(qvel, dtype=float, copy=True)
    out[..., 2] += GRAVITY * timestep / 2
    return out


