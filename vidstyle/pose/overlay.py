"""Keypoints drawn over video frames, for a person to check a pose file (``vidstyle pose --overlay DIR``)."""

from __future__ import annotations

import os

import numpy as np

from ..formats.keypoints import KEYPOINTS
from ..formats.poses import PoseFrame

#: skeleton edges drawn (keypoint names)
EDGES = (("head_top", "neck"), ("neck", "pelvis"), ("neck", "left_shoulder"), ("neck", "right_shoulder"),
         ("left_shoulder", "left_elbow"), ("left_elbow", "left_wrist"), ("right_shoulder", "right_elbow"),
         ("right_elbow", "right_wrist"), ("pelvis", "left_hip"), ("pelvis", "right_hip"), ("left_hip", "left_knee"),
         ("left_knee", "left_ankle"), ("right_hip", "right_knee"), ("right_knee", "right_ankle"))
LEFT, RIGHT, CENTRE = (60, 200, 60), (60, 60, 230), (230, 200, 40)  # BGR


def draw_pose(frame: np.ndarray, pose: PoseFrame, min_score: float = 0.3) -> np.ndarray:
    """A copy of ``frame`` (BGR) with the pose's keypoints and bones (left green, right red) and its
    viewpoint written in a corner; a frame without a pose gets its reason instead."""
    import cv2

    img = np.ascontiguousarray(frame).copy()
    if img.ndim == 2:
        img = cv2.cvtColor(img, cv2.COLOR_GRAY2BGR)
    h = img.shape[0]
    thick = max(1, round(h / 300))
    if not pose.found:
        cv2.putText(img, str(pose.missing), (8, 8 + 14 * thick), cv2.FONT_HERSHEY_SIMPLEX, 0.45 * thick, (0, 0, 255),
                    thick, cv2.LINE_AA)
        return img
    idx = {k: i for i, k in enumerate(KEYPOINTS)}
    pts = pose.points
    for a, b in EDGES:
        pa, pb = pts[idx[a]], pts[idx[b]]
        if min(pa[2], pb[2]) < min_score:
            continue
        colour = LEFT if "left" in b else RIGHT if "right" in b else CENTRE
        cv2.line(img, (round(pa[0]), round(pa[1])), (round(pb[0]), round(pb[1])), colour, thick, cv2.LINE_AA)
    for k, (x, y, s) in zip(KEYPOINTS, pts):
        if s >= min_score:
            colour = LEFT if k.startswith("left") else RIGHT if k.startswith("right") else CENTRE
            cv2.circle(img, (round(x), round(y)), thick + 1, colour, -1, cv2.LINE_AA)
    label = pose.viewpoint + ("" if pose.azimuth is None else f" ({pose.azimuth:+.0f} deg)")
    cv2.putText(img, label, (8, 8 + 14 * thick), cv2.FONT_HERSHEY_SIMPLEX, 0.45 * thick, (255, 255, 255), thick,
                cv2.LINE_AA)
    return img


def write_overlays(video: str | os.PathLike, poses, out_dir: str | os.PathLike) -> int:
    """``<out_dir>/<frame>.jpg`` for every frame of ``poses`` (a :class:`~vidstyle.formats.poses.Poses`),
    streamed one frame at a time; returns how many were written. ``out_dir`` is made if missing (and
    removed again, when empty, if this fails); temporaries a killed run left for these frames are swept."""
    import cv2

    from ..fileio import atomic_path, output_dir
    from ..video import VideoReader

    n = 0
    names = [f"{int(pf.frame):06d}.jpg" for pf in poses.frames]
    with VideoReader(video) as reader, output_dir(out_dir, names) as out:
        for pf in poses.frames:
            img = draw_pose(np.asarray(reader.frame(int(pf.frame))), pf)
            ok, buf = cv2.imencode(".jpg", img, [cv2.IMWRITE_JPEG_QUALITY, 90])
            with atomic_path(out / f"{int(pf.frame):06d}.jpg") as tmp:
                tmp.write_bytes(buf.tobytes())
            n += 1
    return n
