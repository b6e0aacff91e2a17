"""The pose stage's ``poses.json`` as what matching needs: per frame, (15, 2) points and a viewpoint."""

from __future__ import annotations

import os
from dataclasses import dataclass

import numpy as np

from ..formats.poses import read_poses


@dataclass
class FramePose:
    frame: int
    viewpoint: str  # a view name (front/left/right/back) or degrees, relative to the character's facing
    points: np.ndarray  # (15, 2) x = column, y = row, in KEYPOINTS order
    scores: np.ndarray  # (15,)


def read_frame_poses(path: str | os.PathLike) -> tuple[str, list[FramePose]]:
    """(video, frames) of a ``poses.json`` (read by its owner, :func:`vidstyle.formats.poses.read_poses`)."""
    doc = read_poses(path)
    return str(doc.video), [FramePose(int(f.frame), str(f.viewpoint), f.xy.copy(), f.scores.copy())
                            for f in doc.frames]
