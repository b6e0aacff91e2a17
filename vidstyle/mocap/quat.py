"""Small vectorised quaternion helpers (scalar-last ``(x, y, z, w)``, as scipy's ``Rotation``).

scipy's ``Rotation`` is the reference and is used wherever it is fast enough; these exist for the hot
path of BVH parsing, where ``Rotation.from_euler`` costs more than reading the numbers
(tests check every function here against scipy).
"""

from __future__ import annotations

import numpy as np

_AXIS = {"X": 0, "Y": 1, "Z": 2}


def qmul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Hamilton product ``a * b`` (rotation b first, then a), broadcasting over leading axes."""
    ax, ay, az, aw = np.moveaxis(a, -1, 0)
    bx, by, bz, bw = np.moveaxis(b, -1, 0)
    return np.stack(
        [
            aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
            aw * bw - ax * bx - ay * by - az * bz,
        ],
        axis=-1,
    )


def from_intrinsic_euler(seq: str, angles_deg: np.ndarray) -> np.ndarray:
    """Quaternions of intrinsic rotations about the axes of ``seq`` (e.g. "ZYX": R = Rz Ry Rx).

    ``angles_deg``: ``(..., len(seq))`` in degrees. Equal to
    ``Rotation.from_euler(seq.upper(), angles, degrees=True).as_quat()`` up to sign.
    """
    half = np.deg2rad(np.asarray(angles_deg, dtype=np.float64)) * 0.5
    out = None
    for k, axis in enumerate(seq.upper()):
        q = np.zeros(half.shape[:-1] + (4,))
        q[..., _AXIS[axis]] = np.sin(half[..., k])
        q[..., 3] = np.cos(half[..., k])
        out = q if out is None else qmul(out, q)
    if out is None:
        out = np.zeros(half.shape[:-1] + (4,))
        out[..., 3] = 1.0
    return out


def continuous_quaternions(q: np.ndarray) -> np.ndarray:
    """Flip signs along the frame axis so consecutive quaternions of a joint lie in one hemisphere."""
    if q.shape[0] < 2:
        return q.copy()
    step = np.where(np.sum(q[1:] * q[:-1], axis=-1) < 0, -1.0, 1.0)  # (F-1, J)
    sign = np.concatenate([np.ones((1,) + step.shape[1:]), np.cumprod(step, axis=0)])
    return q * sign[..., None]
