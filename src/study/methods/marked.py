"""A throw's scene with floor marks in view: flat magenta discs (``study.see.marks``) at measured positions on the
floor, drawn by the renderer and touched by nothing, so the throw is bitwise the one synthesis simulates
(``tests/test_marks.py`` checks it). The book's own renders keep their plain floor: the tracker's error model is
fitted on them."""

from __future__ import annotations

import mujoco
import numpy as np

from study.see.marklayout import MARK_DIAMETER, MARK_RGBA
from study.simulate.scene import scene_xml

THICKNESS = 0.001
"""Metres: a mark's height above the floor (paper), low enough that the object's centre never sees it."""


def with_marks(model_xml: str, points: np.ndarray, diameter: float = MARK_DIAMETER,
               rgba: tuple[float, float, float, float] = MARK_RGBA) -> mujoco.MjModel:
    """The scene ``model_xml`` (MJCF) compiled with a disc of ``diameter`` metres at each floor point ``points``
    (k, 2) metres; the discs collide with nothing."""
    spec = mujoco.MjSpec.from_string(model_xml)
    for k, (x, y) in enumerate(np.asarray(points, np.float64)):
        spec.worldbody.add_geom(name=f"mark{k}", type=mujoco.mjtGeom.mjGEOM_CYLINDER,
                                size=[diameter / 2, THICKNESS / 2, 0.0], pos=[float(x), float(y), THICKNESS / 2],
                                rgba=list(rgba), contype=0, conaffinity=0)
    return spec.compile()


def throw_xml(cfg, params: dict[str, np.ndarray], i: int) -> str:
    """The MJCF of throw ``i`` of a split's ``params``: the scene ``study.simulate.mujoco_sim.build_model``
    compiles for it (``cfg`` a ``study.simulate.synth.SynthConfig``)."""
    return scene_xml(cfg.shape, mass=float(params["mass"][i]), damping=float(params["damping"][i]),
                     stiffness=cfg.stiffness, friction=float(params["friction"][i]), timestep=cfg.timestep,
                     air=cfg.air, sleep_tolerance=cfg.sleep_tolerance)
