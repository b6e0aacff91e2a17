"""The 15 body keypoints AugMG compares (the pose stage's keypoints), from a CMU-layout motion.

Until :mod:`vidstyle.mocap.keypoints` (the pose stage's definition) exists on this branch, this module
is the one place that maps the CMU 31-joint skeleton onto them; :func:`keypoint_positions` prefers the
pose stage's function when it is importable, so both stages always agree.
"""

from __future__ import annotations

import numpy as np

KEYPOINTS: tuple[str, ...] = (
    "head_top", "neck", "pelvis",
    "left_shoulder", "left_elbow", "left_wrist", "right_shoulder", "right_elbow", "right_wrist",
    "left_hip", "left_knee", "left_ankle", "right_hip", "right_knee", "right_ankle",
)
KP = {n: i for i, n in enumerate(KEYPOINTS)}

#: keypoint -> CMU joint (head_top is the Head joint's End Site)
CMU_JOINT = {
    "neck": "Neck", "pelvis": "Hips",
    "left_shoulder": "LeftArm", "left_elbow": "LeftForeArm", "left_wrist": "LeftHand",
    "right_shoulder": "RightArm", "right_elbow": "RightForeArm", "right_wrist": "RightHand",
    "left_hip": "LeftUpLeg", "left_knee": "LeftLeg", "left_ankle": "LeftFoot",
    "right_hip": "RightUpLeg", "right_knee": "RightLeg", "right_ankle": "RightFoot",
}

#: connected keypoints (the 2D "bones" whose angles are compared): the 10-part body model's segments
#: plus the shoulder and hip girdles
BONES: tuple[tuple[str, str], ...] = (
    ("neck", "head_top"), ("pelvis", "neck"),
    ("neck", "left_shoulder"), ("left_shoulder", "left_elbow"), ("left_elbow", "left_wrist"),
    ("neck", "right_shoulder"), ("right_shoulder", "right_elbow"), ("right_elbow", "right_wrist"),
    ("pelvis", "left_hip"), ("left_hip", "left_knee"), ("left_knee", "left_ankle"),
    ("pelvis", "right_hip"), ("right_hip", "right_knee"), ("right_knee", "right_ankle"),
)
BONE_INDEX = np.array([(KP[a], KP[b]) for a, b in BONES])


def keypoint_positions(motion) -> np.ndarray:
    """(F, 15, 3) world positions of :data:`KEYPOINTS` for a CMU-layout motion."""
    from ..mocap import end_site_positions, forward_kinematics

    pos, mats = forward_kinematics(motion)
    names = motion.skeleton.names
    out = np.empty((motion.n_frames, len(KEYPOINTS), 3))
    for k, joint in CMU_JOINT.items():
        out[:, KP[k]] = pos[:, names.index(joint)]
    owners, ends = end_site_positions(motion, mats, pos)
    head = names.index("Head")
    out[:, KP["head_top"]] = ends[:, owners.index(head)] if head in owners else pos[:, head]
    return out


def keypoints_from_joints(joints: np.ndarray, names) -> np.ndarray:
    """(F, 15, D) keypoints picked from per-joint arrays (F, J, D) of a CMU-layout skeleton (e.g. a
    render sidecar's ``joints2d``); head_top falls back to the Head joint (sidecars hold joints only)."""
    names = list(names)
    out = np.empty(joints.shape[:1] + (len(KEYPOINTS),) + joints.shape[2:], dtype=np.float64)
    for k, joint in CMU_JOINT.items():
        out[:, KP[k]] = joints[:, names.index(joint)]
    out[:, KP["head_top"]] = joints[:, names.index("Head")]
    return out
