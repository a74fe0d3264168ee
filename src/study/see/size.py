"""The object's size as a camera sees it: one number, the diameter of a disc with the object's mean silhouette.

A tracker measures a blob's equivalent-disc diameter, pixels. For a ball that is its diameter at any orientation;
a box or a cylinder shows a different silhouette at each orientation, so the size that matches the blob on average
is that of its *mean* silhouette: by Cauchy's formula a convex body's projected area, averaged over orientations,
is a quarter of its surface, so the disc's diameter is ``sqrt(surface / pi)`` (1.38 edges for a cube).
"""

from __future__ import annotations

import math

from study.core.errors import TrajectoryError


def apparent_size(kind: str, size: tuple[float, ...]) -> float:
    """The diameter, metres, of the disc with the mean silhouette area of a ``kind`` ('sphere': ``(diameter,)``;
    'box': its three edges; 'cylinder': ``(diameter, height)``), all in metres.

    >>> round(apparent_size("box", (0.2, 0.2, 0.2)), 4)
    0.2764
    """
    if kind == "sphere":
        return float(size[0])
    if kind == "box":
        a, b, c = size
        return math.sqrt(2 * (a * b + b * c + c * a) / math.pi)
    if kind == "cylinder":
        d, h = size
        return math.sqrt((math.pi * d * d / 2 + math.pi * d * h) / math.pi)
    raise TrajectoryError(f"apparent_size: kind {kind!r} is unknown; use 'sphere', 'box' or 'cylinder'")
