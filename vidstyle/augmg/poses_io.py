"""Reading the pose stage's ``poses.json`` into what matching needs.

The owner of the format is ``vidstyle.formats.poses`` (the pose stage); when it is importable it reads
the file. Until then this module validates the documented schema itself (issue 13): ``kind``,
``schema_version``, ``video``, ``backend``, ``keypoints`` (the 15 names), ``frames``: a list of
``{"frame", "viewpoint", "viewpoint_scores", "points": [[x, y, score], ...]}``.
"""

from __future__ import annotations

import os
from dataclasses import dataclass

import numpy as np

from ..formats._base import Fields, FormatError, check_array, read_json_document
from .keypoints import KEYPOINTS


@dataclass
class FramePose:
    frame: int
    viewpoint: str  # a view name (front/left/right/back) or degrees, relative to the character's facing
    points: np.ndarray  # (15, 2) x = column, y = row, in KEYPOINTS order
    scores: np.ndarray  # (15,)


def read_frame_poses(path: str | os.PathLike) -> tuple[str, list[FramePose]]:
    """(video, frames) of a ``poses.json``; keypoints reordered to :data:`.keypoints.KEYPOINTS`."""
    try:
        from ..formats.poses import read_poses  # the owner module, once the pose stage has landed
    except ImportError:
        read_poses = None
    if read_poses is not None:
        doc = read_poses(path)
        names = list(doc.keypoints)
        order = [names.index(k) for k in KEYPOINTS]
        out = []
        for f in doc.frames:
            pts = np.asarray(f.points, dtype=np.float64)
            out.append(FramePose(int(f.frame), str(f.viewpoint), pts[order, :2], pts[order, 2]))
        return str(doc.video), out
    doc = read_json_document(path)
    top = Fields(doc, path)
    if top.str("kind") != "vidstyle.poses":
        raise FormatError(path, "kind", f"expected 'vidstyle.poses', got {doc.get('kind')!r}")
    names = top.str_list("keypoints", unique=True)
    missing = [k for k in KEYPOINTS if k not in names]
    if missing:
        raise FormatError(path, "keypoints", f"missing {', '.join(missing)}")
    order = [names.index(k) for k in KEYPOINTS]
    out = []
    for i, raw in enumerate(top.list("frames")):
        f = Fields(raw, path, f"frames[{i}]")
        pts = check_array(f.get("points"), path, f"frames[{i}].points", (len(names), 3))
        view = f.get("viewpoint")
        if not isinstance(view, (str, int, float)) or isinstance(view, bool):
            raise f.fail("viewpoint", "expected a view name or degrees")
        out.append(FramePose(f.int("frame", min=0), str(view), pts[order, :2], pts[order, 2]))
    return top.str("video"), out
