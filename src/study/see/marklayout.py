"""The floor marks the study draws and looks for: their paint, size and layout about a throw (no detection here,
so what renders them does not depend on how they are found: ``study.see.marks`` finds them)."""

from __future__ import annotations

import numpy as np

MARK_HSV: tuple[tuple[int, int, int], tuple[int, int, int]] = ((140, 90, 60), (170, 255, 255))
"""The marks' colour range, HSV on OpenCV's scale (H 0-179): magenta, clear of every object colour the tracker
knows (``study.see.config.COLORS``: red wraps 170-8) and of grey, white and wood floors (low saturation)."""
MARK_RGBA = (0.8, 0.1, 0.7, 1.0)
"""The paint the renders give the marks (hue about 152 of 180 on OpenCV's scale)."""
MARK_DIAMETER = 0.15
"""Metres: the rendered marks' size, a disc of paper a user can lay flat (seen from 0.6 m up at 4 m it is about
20 x 4 pixels at 640 x 360)."""
LAYOUT = np.array([[-1.0, -0.75], [1.0, -0.75], [1.0, 0.75], [-1.0, 0.75], [-0.5, -0.75], [0.25, 0.75]])
"""Metres on the floor about the throw's middle: a 2 m x 1.5 m rectangle's corners and one mark on each long side,
off their middles so that no turn or mirror of the layout is the layout (``study.see.marks.match`` needs that)."""
