"""A pinhole camera in the world: from pixels to rays and back, and an object's height from its image and its depth.

A single camera sees directions, not distances: a pixel (u, v) is a ray, and where along it the object is (its
*depth*, the distance along the camera's view axis) must come from elsewhere. Given the depth, the camera's
position, tilt and focal length turn an image position into a world point, hence a height:
:meth:`Camera.heights`. A rendered throw's camera is the scene's (``study.see.render.camera``); its depth is known
from the render. Without a known depth, a plane the object is assumed to move in gives one
(:meth:`Camera.plane_depth`), with an error that grows with how far the object leaves that plane.

Conventions: world z up, metres; pixels u to the right and v down, the centre of the top-left pixel at (0, 0)
(OpenCV's image moments, ``study.see.render``'s truth); the camera's axes as MuJoCo's (x right, y up, looking
along -z).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from study.core.errors import ConfigError, check_range


@dataclass(frozen=True)
class Camera:
    """A pinhole camera without lens distortion."""

    position: tuple[float, float, float]
    """The camera's centre in the world, metres."""
    rotation: tuple[float, ...]
    """The 3 x 3 matrix whose columns are the camera's x (right), y (up) and z (backwards) axes in world
    coordinates, row by row (9 numbers)."""
    focal: float
    """Focal length, pixels (the same for both axes: square pixels)."""
    width: int
    """Image width, pixels."""
    height: int
    """Image height, pixels."""

    def validate(self) -> None:
        """Raise :class:`ConfigError` for a malformed camera."""
        if len(self.position) != 3 or len(self.rotation) != 9:
            raise ConfigError(f"Camera: position {self.position!r} needs 3 numbers and rotation 9 (a 3 x 3 matrix)")
        r = self.matrix
        if not np.allclose(r.T @ r, np.eye(3), atol=1e-6):
            raise ConfigError("Camera.rotation: the matrix is not orthonormal (its columns are the camera's axes)")
        check_range("Camera.focal (pixels)", self.focal, 0.0, 1e6, lo_open=True)
        check_range("Camera.width", self.width, 1, 1e5)
        check_range("Camera.height", self.height, 1, 1e5)

    @property
    def matrix(self) -> np.ndarray:
        """(3, 3) float64: the camera's axes as columns, in world coordinates."""
        return np.asarray(self.rotation, np.float64).reshape(3, 3)

    def rays(self, u: np.ndarray, v: np.ndarray) -> np.ndarray:
        """(n, 3) world directions through pixels ``u``, ``v`` (n,), each scaled to unit depth: the world point
        at depth ``d`` on pixel i's ray is ``position + d * rays[i]``."""
        u, v = np.asarray(u, np.float64), np.asarray(v, np.float64)
        cam = np.stack([(u + 0.5 - self.width / 2) / self.focal, -(v + 0.5 - self.height / 2) / self.focal,
                        -np.ones_like(u)], axis=-1)
        return cam @ self.matrix.T

    def depth_of(self, points: np.ndarray) -> np.ndarray:
        """(n,) depth of world points (n, 3) metres: their distance along the view axis, metres."""
        return -((np.asarray(points, np.float64) - self.position) @ self.matrix)[..., 2]

    def project(self, points: np.ndarray) -> np.ndarray:
        """(n, 2) pixel positions u, v of world points (n, 3) metres in front of the camera."""
        rel = (np.asarray(points, np.float64) - self.position) @ self.matrix
        d = -rel[..., 2]
        return np.stack([self.width / 2 + self.focal * rel[..., 0] / d - 0.5,
                         self.height / 2 - self.focal * rel[..., 1] / d - 0.5], axis=-1)

    def heights(self, u: np.ndarray, v: np.ndarray, depth: float | np.ndarray) -> np.ndarray:
        """(n,) world height z, metres, of an object seen at pixels ``u``, ``v`` (n,) at ``depth`` metres (a number,
        or (n,) one per frame); NaN where the pixel is NaN."""
        return self.position[2] + np.asarray(depth, np.float64) * self.rays(u, v)[..., 2]

    def plane_depth(self, u: np.ndarray, v: np.ndarray, point: tuple[float, float, float],
                    normal: tuple[float, float, float]) -> np.ndarray:
        """(n,) depth at which each pixel's ray meets the plane through ``point`` with ``normal`` (world, metres):
        the depth of an object assumed to move in that plane (NaN for a ray parallel to it)."""
        r = self.rays(u, v)
        n = np.asarray(normal, np.float64)
        along = r @ n
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(np.abs(along) > 1e-12, (np.asarray(point, np.float64) - self.position) @ n / along, np.nan)
