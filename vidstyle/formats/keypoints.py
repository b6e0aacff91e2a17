"""The names of the 15 keypoints of the 2D pose stage, in the order every file uses (``poses.json``,
models, metrics). A format-level constant: :mod:`vidstyle.mocap.keypoints` (where the keypoints sit on a
skeleton) and :mod:`vidstyle.formats.poses` both take it from here."""

from __future__ import annotations

KEYPOINTS: tuple[str, ...] = (
    "head_top", "neck", "pelvis",
    "left_shoulder", "right_shoulder", "left_elbow", "right_elbow", "left_wrist", "right_wrist",
    "left_hip", "right_hip", "left_knee", "right_knee", "left_ankle", "right_ankle",
)
