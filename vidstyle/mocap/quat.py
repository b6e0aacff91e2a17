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


def _qmul_parts(a: tuple, b: tuple) -> tuple:
    """:func:`qmul` on quaternions given as 4 components, each an array or the float ``0.0``.

    The same expression in the same order as :func:`qmul`, so every result is bit-equal to qmul's on
    the stacked quaternions (an exact zero component multiplies as ``0.0`` and adds as ``0.0``, scalar
    or array alike); products of two zero components stay Python floats and cost nothing.
    """
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return (
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
        aw * bw - ax * bx - ay * by - az * bz,
    )


def intrinsic_euler_parts(seq: str, angles_deg: np.ndarray) -> tuple:
    """The 4 components (x, y, z, w) of :func:`from_intrinsic_euler`, angles given axis first.

    ``angles_deg``: ``(len(seq), ...)`` in degrees. Each component is an array of shape ``...`` (or the
    float ``0.0`` where it is exactly zero, e.g. for a one-axis sequence). Contiguous arrays throughout
    (no strided quaternion slices), the products composed with :func:`_qmul_parts`.
    """
    half = np.deg2rad(np.asarray(angles_deg, dtype=np.float64)) * 0.5
    out = None
    for k, axis in enumerate(seq.upper()):
        q = [0.0, 0.0, 0.0, np.cos(half[k])]
        q[_AXIS[axis]] = np.sin(half[k])
        out = tuple(q) if out is None else _qmul_parts(out, tuple(q))
    if out is None:
        out = (0.0, 0.0, 0.0, 1.0)
    return out


def from_intrinsic_euler(seq: str, angles_deg: np.ndarray) -> np.ndarray:
    """Quaternions of intrinsic rotations about the axes of ``seq`` (e.g. "ZYX": R = Rz Ry Rx).

    ``angles_deg``: ``(..., len(seq))`` in degrees. Equal to
    ``Rotation.from_euler(seq.upper(), angles, degrees=True).as_quat()`` up to sign.
    """
    angles_deg = np.asarray(angles_deg, dtype=np.float64)
    parts = intrinsic_euler_parts(seq, np.ascontiguousarray(np.moveaxis(angles_deg, -1, 0)))
    out = np.empty(angles_deg.shape[:-1] + (4,))
    for i, part in enumerate(parts):
        out[..., i] = part
    return out


def continuous_quaternions(q: np.ndarray) -> np.ndarray:
    """Flip signs along the frame axis so consecutive quaternions of a joint lie in one hemisphere."""
    if q.shape[0] < 2:
        return q.copy()
    step = np.where(np.sum(q[1:] * q[:-1], axis=-1) < 0, -1.0, 1.0)  # (F-1, J)
    sign = np.concatenate([np.ones((1,) + step.shape[1:]), np.cumprod(step, axis=0)])
    return q * sign[..., None]
