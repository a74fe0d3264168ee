"""Can a car tell a must-avoid object from a safe-to-pass one by its motion alone?

A reproduction of Fathollahi & Kasturi, arXiv:1609.00361, as a package:

- ``study.synth``: MuJoCo trajectories of light (bouncy) and heavy (sliding) objects.
- ``study.book``: execute the chapters with papermill and build the Jupyter Book.

Submodules are imported on demand (``from study import synth``) so that ``import study`` stays cheap.
"""

import os

# Headless rendering by default: MuJoCo reads MUJOCO_GL when it is first imported, which any submodule
# may do (set MUJOCO_GL=osmesa, or glfw with a display, before importing study to choose otherwise).
os.environ.setdefault("MUJOCO_GL", "egl")

__version__ = "0.1.0"

CLASSES: tuple[str, str] = ("light", "heavy")
"""Class names by label: 0 = light (bounces; safe to pass over), 1 = heavy (slides; must avoid)."""
