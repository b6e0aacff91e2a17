"""Transition clips (placement: :mod:`vidstyle.mocap.placement`): linear root interpolation, slerp of joint rotations, C^1 blend weight."""

from __future__ import annotations

import numpy as np


def blend_weight(p: np.ndarray | float, k: int) -> np.ndarray:
    """Weight of the *departing* clip at blend frame ``p`` (0..k-1) of a k-frame transition:
    ``alpha(p) = 2 u^3 - 3 u^2 + 1`` with ``u = (p + 1) / k``.

    ``alpha(-1) = 1`` (the frame before the blend is the departing clip), ``alpha(k-1) = 0`` (the last
    blend frame is the arriving clip) and ``alpha'`` vanishes at both ends, so the weight joins the
    constant weights before and after with a continuous first derivative (C^1). (The thesis prints
    ``+3 u^2``, which gives alpha(k-1) = 6.)
    """
    u = (np.asarray(p, dtype=np.float64) + 1.0) / k
    return 2.0 * u**3 - 3.0 * u**2 + 1.0


def slerp(q0: np.ndarray, q1: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Spherical interpolation of unit quaternions (..., 4) along the shorter arc; ``t`` broadcasts over
    the leading axes (0 gives q0, 1 gives q1)."""
    q0 = np.asarray(q0, dtype=np.float64)
    q1 = np.asarray(q1, dtype=np.float64)
    t = np.asarray(t, dtype=np.float64)[..., None]
    dot = np.sum(q0 * q1, axis=-1, keepdims=True)
    q1 = np.where(dot < 0, -q1, q1)
    dot = np.abs(dot)
    omega = np.arccos(np.clip(dot, -1.0, 1.0))
    so = np.sin(omega)
    small = so < 1e-6
    safe = np.where(small, 1.0, so)
    a = np.where(small, 1.0 - t, np.sin((1.0 - t) * omega) / safe)
    b = np.where(small, t, np.sin(t * omega) / safe)
    out = a * q0 + b * q1
    return out / np.linalg.norm(out, axis=-1, keepdims=True)


def blend_frames(
    rot_a: np.ndarray, root_a: np.ndarray, rot_b: np.ndarray, root_b: np.ndarray, k: int,
    ramp: int | None = None, start: int = 0,
) -> tuple[np.ndarray, np.ndarray]:
    """The k frames of a transition between placed frames A (departing) and B (arriving, already aligned
    onto A): roots linearly, every joint rotation by slerp, both with weight ``1 - alpha(p)`` on B.

    ``ramp`` / ``start``: the weight moves from A to B over frames ``start .. start + ramp - 1`` only
    (``alpha(p - start)`` of a ``ramp``-frame blend; A before, B after); default the whole ``k``."""
    r = k if ramp is None else int(ramp)
    if not (1 <= r and 0 <= start and start + r <= k):
        raise ValueError(f"ramp/start: frames {start} .. {start + r - 1} must lie inside the {k}-frame blend")
    t = 1.0 - blend_weight(np.clip(np.arange(k) - start, -1, r - 1), r)
    root = root_a * (1.0 - t)[:, None] + root_b * t[:, None]
    rot = slerp(rot_a, rot_b, np.broadcast_to(t[:, None], rot_a.shape[:2]))
    return rot, root
