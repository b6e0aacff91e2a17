"""Small built-in motions for tests, benchmarks and examples of the renderer (no data files needed).

:func:`humanoid_skeleton` is a symmetric humanoid in a T-pose (facing +Z, +Y up, about 1.75 m tall in
metres), named either CMU-style (``LeftUpLeg``, ``LeftForeArm`` ...) or joint-style (``l_hip``,
``l_knee`` ...). :func:`sample_motion` animates it with a gentle walk-like swing of arms and legs.
"""

from __future__ import annotations

import numpy as np

from ..mocap import Motion, Skeleton

# (CMU-style name, joint-style name, parent index, offset in metres)
_LAYOUT = [
    ("Hips", "pelvis", -1, (0.0, 0.0, 0.0)),
    ("LeftUpLeg", "l_hip", 0, (0.09, -0.05, 0.0)),
    ("LeftLeg", "l_knee", 1, (0.0, -0.43, 0.0)),
    ("LeftFoot", "l_ankle", 2, (0.0, -0.43, 0.0)),
    ("LeftToeBase", "l_toe", 3, (0.0, -0.05, 0.14)),
    ("RightUpLeg", "r_hip", 0, (-0.09, -0.05, 0.0)),
    ("RightLeg", "r_knee", 5, (0.0, -0.43, 0.0)),
    ("RightFoot", "r_ankle", 6, (0.0, -0.43, 0.0)),
    ("RightToeBase", "r_toe", 7, (0.0, -0.05, 0.14)),
    ("Spine", "spine", 0, (0.0, 0.16, 0.0)),
    ("Spine1", "chest", 9, (0.0, 0.16, 0.0)),
    ("Neck", "neck", 10, (0.0, 0.2, 0.0)),
    ("Head", "head", 11, (0.0, 0.1, 0.0)),
    ("LeftShoulder", "l_collar", 10, (0.03, 0.15, 0.0)),
    ("LeftArm", "l_shoulder", 13, (0.16, 0.0, 0.0)),
    ("LeftForeArm", "l_elbow", 14, (0.29, 0.0, 0.0)),
    ("LeftHand", "l_wrist", 15, (0.25, 0.0, 0.0)),
    ("RightShoulder", "r_collar", 10, (-0.03, 0.15, 0.0)),
    ("RightArm", "r_shoulder", 17, (-0.16, 0.0, 0.0)),
    ("RightForeArm", "r_elbow", 18, (-0.29, 0.0, 0.0)),
    ("RightHand", "r_wrist", 19, (-0.25, 0.0, 0.0)),
]
_END_SITES = {"Head": (0.0, 0.13, 0.0), "LeftHand": (0.09, 0.0, 0.0), "RightHand": (-0.09, 0.0, 0.0),
              "LeftToeBase": (0.0, 0.0, 0.05), "RightToeBase": (0.0, 0.0, 0.05)}


def humanoid_skeleton(style: str = "cmu") -> Skeleton:
    """Symmetric T-pose humanoid; ``style`` ``"cmu"`` or ``"joint"`` picks the naming convention."""
    if style not in ("cmu", "joint"):
        raise ValueError(f"style must be 'cmu' or 'joint', got {style!r}")
    col = 0 if style == "cmu" else 1
    names = [row[col] for row in _LAYOUT]
    parents = [row[2] for row in _LAYOUT]
    offsets = [row[3] for row in _LAYOUT]
    ends = {names.index(row[col]): np.array(_END_SITES[row[0]]) for row in _LAYOUT if row[0] in _END_SITES}
    return Skeleton(names, np.array(parents), np.array(offsets, dtype=float), end_sites=ends)


def sample_motion(n_frames: int = 40, fps: float = 20.0, style: str = "cmu", speed: float = 0.8,
                  arm_drop_deg: float = 65.0) -> Motion:
    """A symmetric-start walk-like motion: arms lowered from the T-pose and swinging, legs swinging,
    knees bending, the root moving along +Z at ``speed`` m/s. Frame 0 is left-right symmetric."""
    sk = humanoid_skeleton(style)
    F = int(n_frames)
    t = np.arange(F) / fps
    phase = np.sin(2 * np.pi * 1.0 * t)
    ang = np.zeros((F, sk.n_joints, 3))  # intrinsic ZYX Euler angles (degrees)
    idx = {row[0]: i for i, row in enumerate(_LAYOUT)}
    ang[:, idx["LeftArm"], 0] = -arm_drop_deg
    ang[:, idx["RightArm"], 0] = arm_drop_deg
    ang[:, idx["LeftArm"], 1] = 25 * phase  # swing forward/back (about Y once lowered... roughly)
    ang[:, idx["RightArm"], 1] = 25 * phase
    ang[:, idx["LeftForeArm"], 1] = -20 - 10 * phase
    ang[:, idx["RightForeArm"], 1] = 20 - 10 * phase
    ang[:, idx["LeftUpLeg"], 2] = -25 * phase
    ang[:, idx["RightUpLeg"], 2] = 25 * phase
    ang[:, idx["LeftLeg"], 2] = 30 * np.maximum(phase, 0)
    ang[:, idx["RightLeg"], 2] = 30 * np.maximum(-phase, 0)
    root = np.zeros((F, 3))
    root[:, 1] = 0.95 + 0.015 * np.abs(phase)
    root[:, 2] = speed * t
    return Motion.from_euler(sk, ang, root, fps, order="ZYX")
