"""The 15 body keypoints AugMG compares (:mod:`vidstyle.mocap.keypoints`, the pose stage's body
model) and the connected keypoint pairs ("bones") whose 2D angles are matched."""

from __future__ import annotations

import numpy as np

from ..mocap.keypoints import KEYPOINT_INDEX as KP
from ..mocap.keypoints import KEYPOINTS, keypoint_positions

#: connected keypoints: the 10-part body model's segments plus the shoulder and hip girdles
BONES: tuple[tuple[str, str], ...] = (
    ("neck", "head_top"), ("pelvis", "neck"),
    ("neck", "left_shoulder"), ("left_shoulder", "left_elbow"), ("left_elbow", "left_wrist"),
    ("neck", "right_shoulder"), ("right_shoulder", "right_elbow"), ("right_elbow", "right_wrist"),
    ("pelvis", "left_hip"), ("left_hip", "left_knee"), ("left_knee", "left_ankle"),
    ("pelvis", "right_hip"), ("right_hip", "right_knee"), ("right_knee", "right_ankle"),
)
BONE_INDEX = np.array([(KP[a], KP[b]) for a, b in BONES])

__all__ = ["BONES", "BONE_INDEX", "KEYPOINTS", "KP", "keypoint_positions"]
