"""Key poses, the pose feature, and pinning a motion to its two key poses.

A :class:`Keypose` is one frame on the library's skeleton: local joint rotations ``(J, 4)`` (x, y, z, w) and
the root position ``(3,)``, optionally with the frame one step before it (``previous``, at the library's
frame rate) or after it (``following``) for a velocity feature.

Heading: the yaw of the root joint's local +Z axis (``atan2(z_x, z_z)``, the angle of
:class:`~vidstyle.mocap.placement.Placement`). The pose feature removes it, so poses facing any
direction compare equal (Molina Tanco & Hilton 2000, section 3.2: the model is invariant to where the
action faces).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

from ..mocap.placement import Placement, yaw_quat
from ..mocap.quat import qmul
from ..motiongraph.blend import slerp


@dataclass
class Keypose:
    rotations: np.ndarray  # (J, 4)
    root: np.ndarray  # (3,)
    previous: Keypose | None = None
    following: Keypose | None = None  # the frame one step after (velocity of an end key without a previous)

    def placed(self, placement: Placement) -> Keypose:
        r, p = placement.apply_frames(self.rotations[None], self.root[None])
        prev = None if self.previous is None else self.previous.placed(placement)
        nxt = None if self.following is None else self.following.placed(placement)
        return Keypose(r[0], p[0], prev, nxt)


def headings(root_rotations: np.ndarray) -> np.ndarray:
    """(F,) yaw of the root's local +Z axis for root quaternions (F, 4)."""
    z = Rotation.from_quat(root_rotations.reshape(-1, 4)).apply([0.0, 0.0, 1.0])
    return np.arctan2(z[:, 0], z[:, 2])


def placement_onto(rot_from: np.ndarray, root_from: np.ndarray, rot_to: np.ndarray, root_to: np.ndarray) -> Placement:
    """The yaw + floor placement that puts a frame (root quaternion ``rot_from`` (4,), root ``root_from``)
    onto another's heading and horizontal root position."""
    theta = float(headings(rot_to[None])[0] - headings(rot_from[None])[0])
    turned = Placement(theta).apply_points(root_from)
    return Placement(theta, float(root_to[0] - turned[0]), float(root_to[2] - turned[2]))


def pose_features(rotations: np.ndarray, root_positions: np.ndarray, leg: float, height_weight: float) -> np.ndarray:
    """(F, 3J + 1): angle-axis vectors of every joint's local rotation (the root's with its heading
    removed), then the root height in leg lengths times ``height_weight``."""
    F, J, _ = rotations.shape
    root = qmul(yaw_quat(-headings(rotations[:, 0])), rotations[:, 0])
    q = rotations.copy()
    q[:, 0] = root
    rv = Rotation.from_quat(q.reshape(-1, 4)).as_rotvec().reshape(F, 3 * J)
    h = root_positions[:, 1:2] / max(leg, 1e-12) * height_weight
    return np.concatenate([rv, h], axis=1)


#: where the root goes between the keys: ``library`` (the synthesised motion's own root path, displaced onto
#: the keys) or ``hermite`` (a cubic Hermite curve through the two keys' root positions with their velocities)
ROOT_PATHS = ("library", "hermite")


def key_velocity(key: Keypose, chord: np.ndarray, at_end: bool) -> np.ndarray:
    """The root velocity (per frame step) at a key: from ``following`` (an end key) or ``previous``,
    else ``chord`` (the other key's root minus this one's, per frame of the gap: no bend at this end)."""
    if at_end and key.following is not None:
        return key.following.root - key.root
    if key.previous is not None:
        return key.root - key.previous.root
    if key.following is not None:
        return key.following.root - key.root
    return chord


def hermite_root(start: Keypose, end: Keypose, n_frames: int) -> np.ndarray:
    """(n_frames, 3) root positions from ``start`` to ``end`` (both included) on the cubic Hermite curve with
    the keys' root velocities (:func:`key_velocity`): C1 with the motion around each key, where a straight
    line (LERP) bends at both. Keys moving at the chord's constant velocity give the straight line."""
    T = n_frames - 1
    if T < 1:
        return start.root[None].copy()
    chord = (end.root - start.root) / T
    v0 = key_velocity(start, chord, at_end=False) * T
    v1 = key_velocity(end, chord, at_end=True) * T
    s = np.linspace(0.0, 1.0, n_frames)[:, None]
    s2, s3 = s * s, s * s * s
    out = ((2 * s3 - 3 * s2 + 1) * start.root + (s3 - 2 * s2 + s) * v0 + (-2 * s3 + 3 * s2) * end.root
           + (s3 - s2) * v1)
    out[0], out[-1] = start.root, end.root
    return out


def pin(rotations: np.ndarray, roots: np.ndarray, start: Keypose, end: Keypose,
        root_path: str = "library") -> tuple[np.ndarray, np.ndarray]:
    """Displace a motion (T+1 frames) so that frame 0 is exactly ``start`` and frame T exactly ``end``:
    each joint's rotation is pre-multiplied by the slerp (weight t/T) of the two key corrections
    ``key * frame^-1``; the root (``root_path``, :data:`ROOT_PATHS`) moved by the linear blend of the two
    position errors (``library``) or replaced by :func:`hermite_root` (``hermite``)."""
    if root_path not in ROOT_PATHS:
        raise ValueError(f"root_path must be one of {', '.join(ROOT_PATHS)}, got {root_path!r}")
    T = len(rotations) - 1
    conj = np.array([-1.0, -1.0, -1.0, 1.0])
    d0 = qmul(start.rotations, rotations[0] * conj)
    d1 = qmul(end.rotations, rotations[T] * conj)
    w = np.arange(T + 1) / max(T, 1)
    d = slerp(np.broadcast_to(d0, rotations.shape), np.broadcast_to(d1, rotations.shape),
              np.broadcast_to(w[:, None], rotations.shape[:2]))
    out = qmul(d, rotations)
    if root_path == "hermite":
        root = hermite_root(start, end, T + 1)
    else:
        e0, e1 = start.root - roots[0], end.root - roots[T]
        root = roots + (1.0 - w)[:, None] * e0 + w[:, None] * e1
    out[0], root[0] = start.rotations, start.root
    out[T], root[T] = end.rotations, end.root
    return out, root


def slerp_inbetween(start: Keypose, end: Keypose, n_frames: int, root_path: str = "linear") -> tuple[np.ndarray, np.ndarray]:
    """LAFAN1's LERP+SLERP baseline over ``n_frames`` = T + 1 output frames (both keys included): every
    local rotation by scipy's :class:`~scipy.spatial.transform.Slerp`, the root position linearly
    (``root_path="hermite"``: on :func:`hermite_root` instead, the evaluation's second baseline)."""
    if root_path not in ("linear", "hermite"):
        raise ValueError(f"root_path must be linear or hermite, got {root_path!r}")
    T = n_frames - 1
    w = np.linspace(0.0, 1.0, n_frames)
    J = start.rotations.shape[0]
    # scipy's Slerp between two keys, every joint at once: a * exp(w log(a^-1 b))
    a = Rotation.from_quat(np.broadcast_to(start.rotations, (n_frames, J, 4)).reshape(-1, 4))
    step = (Rotation.from_quat(start.rotations).inv() * Rotation.from_quat(end.rotations)).as_rotvec()
    rot = (a * Rotation.from_rotvec((w[:, None, None] * step[None]).reshape(-1, 3))).as_quat().reshape(n_frames, J, 4)
    root = start.root[None] + w[:, None] * (end.root - start.root)[None]
    if root_path == "hermite":
        root = hermite_root(start, end, n_frames)
    if T >= 1:
        rot[0], rot[T] = start.rotations, end.rotations
    return rot, root


class SlerpInbetweener:
    """SLERP with a root path (:func:`slerp_inbetween`) on the in-betweeners' interface, for the
    evaluation's ``slerp_hermite`` baseline (plain ``slerp`` is the model-free ``None`` of
    :func:`vidstyle.inbetween.keyframes.inbetween_pair`)."""

    def __init__(self, root_path: str = "hermite") -> None:
        self.root_path = root_path

    def get_params(self, deep: bool = True) -> dict:
        return {"root_path": self.root_path}

    def inbetween(self, start: Keypose, end: Keypose, n_frames: int, free_end: bool = False) -> tuple[np.ndarray, np.ndarray]:
        if free_end:
            end = end.placed(placement_onto(end.rotations[0], end.root, start.rotations[0], start.root))
        return slerp_inbetween(start, end, n_frames, self.root_path)
