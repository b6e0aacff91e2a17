"""The pose stage's ``poses.json`` as what matching needs: per frame, (15, 2) points and a viewpoint."""

from __future__ import annotations

import logging
import os
from dataclasses import dataclass

import numpy as np

from ..formats.poses import UNKNOWN, read_poses

log = logging.getLogger(__name__)


@dataclass
class FramePose:
    frame: int
    viewpoint: str  # a view name (front/left/right/back) or degrees, relative to the character's facing
    points: np.ndarray  # (15, 2) x = column, y = row, in KEYPOINTS order
    scores: np.ndarray  # (15,)


def viewpoint_of(f) -> str:
    """The viewpoint matching uses: the named view, else the azimuth in degrees when the file has one."""
    if f.viewpoint == UNKNOWN and f.azimuth is not None:
        return f"{float(f.azimuth):g}"
    return str(f.viewpoint)


def read_frame_poses(path: str | os.PathLike) -> tuple[str, list[FramePose]]:
    """(video, frames) of a ``poses.json`` (read by its owner, :func:`vidstyle.formats.poses.read_poses`).
    Frames without a pose (``missing``) are skipped with a warning naming them."""
    doc = read_poses(path)
    missing = [f for f in doc.frames if not f.found]
    if missing:
        log.warning("%s: %d of %d frames have no pose and are skipped (e.g. frame %d: %s)", path, len(missing),
                    len(doc.frames), missing[0].frame, missing[0].missing)
    return str(doc.video), [FramePose(int(f.frame), viewpoint_of(f), f.xy.copy(), f.scores.copy())
                            for f in doc.frames if f.found]
