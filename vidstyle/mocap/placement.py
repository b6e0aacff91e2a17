"""The one yaw + floor placement helper: a rotation by ``theta`` about the vertical (+Y) axis followed by
a horizontal translation ``(x0, 0, z0)``.

``R_y(theta)`` turns +Z towards +X: ``x -> x cos + z sin``, ``z -> -x sin + z cos`` (the rotation by
``theta`` about +Y; a character facing angle ``a`` faces angle ``a + theta`` afterwards, see
:meth:`vidstyle.mocap.Motion.facing_angles`). Everything that turns or places motion on the floor uses
this: motion-graph alignment (Kovar's closed form returns one), walk placement, ``Motion.normalize_facing``.

>>> P = Placement(0.5, 1.0, -2.0)
>>> import numpy as np
>>> bool(np.allclose(P.inverse().apply_points(P.apply_points(np.ones(3))), 1.0))
True
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .quat import qmul


def yaw_quat(theta: np.ndarray | float) -> np.ndarray:
    """Quaternion(s) (x, y, z, w) of a rotation by ``theta`` about +Y."""
    theta = np.asarray(theta, dtype=np.float64)
    out = np.zeros(theta.shape + (4,))
    out[..., 1] = np.sin(theta / 2)
    out[..., 3] = np.cos(theta / 2)
    return out


@dataclass(frozen=True)
class Placement:
    """``T(p) = R_y(theta) p + (x0, 0, z0)``."""

    theta: float = 0.0
    x0: float = 0.0
    z0: float = 0.0

    @classmethod
    def from_array(cls, a) -> Placement:
        """From ``(theta, x0, z0)``."""
        a = np.asarray(a, dtype=np.float64).reshape(3)
        return cls(float(a[0]), float(a[1]), float(a[2]))

    def as_array(self) -> np.ndarray:
        return np.array([self.theta, self.x0, self.z0])

    @property
    def offset(self) -> np.ndarray:
        return np.array([self.x0, self.z0])

    def apply_points(self, points: np.ndarray) -> np.ndarray:
        """(..., 3) points moved by ``T``."""
        c, s = math.cos(self.theta), math.sin(self.theta)
        p = np.asarray(points, dtype=np.float64)
        out = p.copy()
        out[..., 0] = c * p[..., 0] + s * p[..., 2] + self.x0
        out[..., 2] = -s * p[..., 0] + c * p[..., 2] + self.z0
        return out

    def apply_frames(self, rotations: np.ndarray, root_positions: np.ndarray, root: int = 0) -> tuple[np.ndarray, np.ndarray]:
        """Frames ``rotations`` (F, J, 4) and ``root_positions`` (F, 3) moved by ``T``: only the root joint's
        rotation and the root position change. Returns new arrays."""
        rot = np.array(rotations, dtype=np.float64, copy=True)
        rot[:, root] = qmul(np.broadcast_to(yaw_quat(self.theta), rot[:, root].shape), rot[:, root])
        return rot, self.apply_points(root_positions)

    def then(self, other: Placement) -> Placement:
        """``self o other``: apply ``other`` first, then ``self``."""
        x, z = self.apply_points(np.array([other.x0, 0.0, other.z0]))[[0, 2]]
        return Placement(self.theta + other.theta, float(x), float(z))

    def inverse(self) -> Placement:
        c, s = math.cos(-self.theta), math.sin(-self.theta)
        return Placement(-self.theta, -(c * self.x0 + s * self.z0), -(-s * self.x0 + c * self.z0))

    @classmethod
    def facing(cls, facing_angle: float, root_position: np.ndarray, angle: float = 0.0, origin: bool = True) -> Placement:
        """The placement that turns a character facing ``facing_angle`` (radians) to face ``angle``
        about the vertical through its root, and (``origin``) moves that root above the world origin."""
        r = np.asarray(root_position, dtype=np.float64)
        turn = cls(angle - facing_angle)
        pivot = np.array([r[0], 0.0, r[2]])
        # rotate about the pivot: T(p) = R (p - pivot) + pivot, then optionally - pivot
        moved = turn.apply_points(-pivot) + (0.0 if origin else pivot)
        return cls(turn.theta, float(moved[0]), float(moved[2]))


def inverse_placements(theta, x0, z0) -> np.ndarray:
    """(n, 3) ``Placement(t, x, z).inverse().as_array()`` of every ``(t, x, z)``, the same numbers to the
    bit (the sines and cosines by :mod:`math`, as :meth:`Placement.inverse`, the rest element-wise in the
    same order) without an object per placement."""
    theta = np.asarray(theta, dtype=np.float64).reshape(-1)
    x0 = np.asarray(x0, dtype=np.float64).reshape(-1)
    z0 = np.asarray(z0, dtype=np.float64).reshape(-1)
    c = np.array([math.cos(-t) for t in theta.tolist()], dtype=np.float64)
    s = np.array([math.sin(-t) for t in theta.tolist()], dtype=np.float64)
    return np.stack([-theta, -(c * x0 + s * z0), -(-s * x0 + c * z0)], axis=1).reshape(-1, 3)

