"""The MJCF scene: a ground plane, one rigid object on a free joint, air, a light and a camera.

One function, :func:`scene_xml`, writes the model for one object. Everything the two classes differ
in (mass, contact damping that sets the restitution, sliding friction) is an argument, so a batch of
objects is a list of models with the same size signature, as ``mujoco.rollout`` requires.

Units: SI throughout (metres, kilograms, seconds). The world z axis points up; the ground is z = 0.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco

from study.core.errors import ConfigError, check_range

SHAPES = ("box", "sphere", "cylinder")

AIR_DENSITY = 1.204
"""kg/m^3, dry air at 20 degrees C and sea level (ISO 2533 standard atmosphere, 1.225 at 15 C)."""
AIR_VISCOSITY = 1.81e-5
"""Pa s, dynamic viscosity of air at 20 degrees C."""


@dataclass(frozen=True)
class Shape:
    """The object's shape; kept the same for every trajectory, as in the paper."""

    kind: str = "box"
    """'box', 'sphere' or 'cylinder'."""
    size: tuple[float, ...] = (0.1, 0.1, 0.1)
    """MuJoCo geom size in metres: half-extents (box), (radius,) (sphere), (radius, half-height) (cylinder)."""

    def validate(self, where: str = "Shape") -> None:
        """Raise :class:`ConfigError` for an unknown kind or a non-positive or mis-sized size."""
        if self.kind not in SHAPES:
            raise ConfigError(f"{where}.kind = {self.kind!r} is unknown; allowed: {', '.join(SHAPES)}")
        need = {"box": 3, "sphere": 1, "cylinder": 2}[self.kind]
        if len(self.size) != need:
            raise ConfigError(f"{where}.size = {self.size!r}: a {self.kind} needs {need} numbers (metres)")
        for i, s in enumerate(self.size):
            check_range(f"{where}.size[{i}]", s, 0.005, 2.0)

    @property
    def rest_height(self) -> float:
        """Height of the centre, metres, when resting on its lowest face (box on z-face, cylinder upright)."""
        return float(self.size[-1] if self.kind != "sphere" else self.size[0])

    @property
    def bounding_radius(self) -> float:
        """Radius of the smallest centred sphere that holds the object, metres."""
        if self.kind == "box":
            return float(sum(s * s for s in self.size) ** 0.5)
        if self.kind == "cylinder":
            return float((self.size[0] ** 2 + self.size[1] ** 2) ** 0.5)
        return float(self.size[0])


def scene_xml(
    shape: Shape,
    *,
    mass: float,
    damping: float,
    stiffness: float,
    friction: float,
    timestep: float,
    air: bool = True,
    gravity: bool = True,
    contact: bool = True,
    sleep_tolerance: float = 0.0,
    rgba: tuple[float, float, float, float] = (0.85, 0.35, 0.1, 1.0),
) -> str:
    """MJCF text of the scene with one object.

    Args:
        shape: the object's geometry.
        mass: kg; the inertia is that of a uniform solid of this shape.
        damping: contact damping b of the direct ``solref`` format, 1/s; sets the restitution
            (see ``study.simulate.contact.damping_for_restitution``).
        stiffness: contact stiffness k of the direct ``solref`` format, 1/s^2.
        friction: sliding friction coefficient (dimensionless), used alone thanks to ``priority``.
        timestep: simulation step, seconds.
        air: turn on MuJoCo's ellipsoid fluid model with air's density and viscosity.
        gravity, contact: switch gravity and contacts off for the free-flight check.
        sleep_tolerance: m/s; if > 0, MuJoCo's island sleeping is on: an object whose dof speeds
            (rotations times its size, so also m/s) stay below this for 10 steps is put to sleep,
            its velocity zeroed and its position frozen until something wakes it. 0: always awake.
        rgba: the object's colour (for rendering).
    """
    size = " ".join(f"{float(s)!r}" for s in shape.size)
    mass, damping, stiffness, friction, timestep = map(float, (mass, damping, stiffness, friction, timestep))
    density = AIR_DENSITY if air else 0.0
    viscosity = AIR_VISCOSITY if air else 0.0
    flags = []
    if not gravity:
        flags.append('gravity="disable"')
    if not contact:
        flags.append('contact="disable"')
    sleep = ""
    if sleep_tolerance > 0:
        flags.append('sleep="enable"')
        sleep = f' sleep_tolerance="{float(sleep_tolerance)!r}"'
    flag = f"<flag {' '.join(flags)}/>" if flags else ""
    condim = 3 if friction > 0 else 1  # a zero-width friction pyramid is degenerate: drop friction instead
    r, g, b, a = rgba
    # priority="1" makes the object's solref, solimp and friction the contact's own: no mixing with the floor's.
    # shadowsize 1024, not 2048: in the book's 320x240 renders only a few pixels on shadow edges differ,
    # and each image is drawn about a quarter faster.
    return f"""<mujoco model="throw">
  <option timestep="{timestep!r}" integrator="implicitfast" density="{density}" viscosity="{viscosity}"{sleep}>{flag}</option>
  <visual><global offwidth="1920" offheight="1080"/><quality shadowsize="1024"/></visual>
  <asset>
    <texture name="ground" type="2d" builtin="checker" rgb1="0.32 0.32 0.33" rgb2="0.36 0.36 0.37" width="512" height="512" mark="edge" markrgb="0.9 0.9 0.85"/>
    <material name="ground" texture="ground" texrepeat="8 8" reflectance="0.05"/>
    <texture name="sky" type="skybox" builtin="gradient" rgb1="0.75 0.85 0.95" rgb2="0.95 0.95 0.95" width="256" height="256"/>
  </asset>
  <worldbody>
    <light name="sun" pos="0 0 6" dir="0 0 -1" directional="true" diffuse="0.8 0.8 0.8"/>
    <geom name="ground" type="plane" size="0 0 1" material="ground"/>
    <camera name="side" pos="0 -4 0.6" xyaxes="1 0 0 0 0.1 1" fovy="45"/>
    <camera name="follow" mode="trackcom" pos="0 -3 1" xyaxes="1 0 0 0 0.3 1"/>
    <body name="object" pos="0 0 1">
      <freejoint name="object"/>
      <geom name="object" type="{shape.kind}" size="{size}" mass="{mass!r}" priority="1"
            solref="{-stiffness!r} {-damping!r}" solimp="0.95 0.99 0.001 0.5 2"
            friction="{friction!r} 0.005 0.0001" condim="{condim}" fluidshape="ellipsoid" rgba="{r} {g} {b} {a}"/>
    </body>
  </worldbody>
</mujoco>"""


def compile_scene(shape: Shape, **kwargs) -> mujoco.MjModel:
    """Compile :func:`scene_xml` (same arguments) into a model."""
    return mujoco.MjModel.from_xml_string(scene_xml(shape, **kwargs))
