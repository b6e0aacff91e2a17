"""What the page draws over a video besides the user's own marks: the actions ``recognize`` found, the 2D
poses of ``pose`` and the library poses ``match-pose`` matched to them. Each is mapped onto the video's
decoded frame indices here, once, so the page only ever deals in decoded indices.

Schemas read:

* recognised labels (``vidstyle recognize``): ``{"video", "fps", "classes", "labels": [one per working
  frame], "confidence"?: [one per working frame]}``; working frame ``k`` is decoded frame ``working_indices(timestamps, fps)[k]`` and covers the
  decoded frames up to the next working frame;
* poses: :mod:`vidstyle.formats.poses` (``points`` x = column, y = row in the video's pixels);
* matches (issue 14): ``{"kind": "vidstyle.matches", "schema_version", "video", "frames": [{"frame",
  "candidates": [{"clip", "time", "cost"}]}]}`` - a small reader of its own, as the owner module
  (``vidstyle/formats/matches.py``) is on the ``augmg`` branch, not this one; it ignores the other fields.

A file applies to the session video whose path (resolved, else file name) equals its ``video`` field; with
a single video in the session it applies to that one.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np

from ..formats import FormatError
from ..video import working_indices

#: skeleton drawn for the 15 keypoints of the pose stage (pairs of names)
EDGES = [("head_top", "neck"), ("neck", "pelvis"), ("neck", "left_shoulder"), ("neck", "right_shoulder"),
         ("left_shoulder", "left_elbow"), ("left_elbow", "left_wrist"), ("right_shoulder", "right_elbow"),
         ("right_elbow", "right_wrist"), ("pelvis", "left_hip"), ("pelvis", "right_hip"),
         ("left_hip", "left_knee"), ("left_knee", "left_ankle"), ("right_hip", "right_knee"),
         ("right_knee", "right_ankle")]


def _match_video(doc_video: str | None, videos, path) -> Any:
    if len(videos) == 1 and not doc_video:
        return videos[0]
    if doc_video:
        dv = Path(doc_video)
        for v in videos:
            try:
                if dv.resolve() == v.path:
                    return v
            except OSError:
                pass
        named = [v for v in videos if v.path.name == dv.name]
        if len(named) == 1:
            return named[0]
    if len(videos) == 1:
        return videos[0]
    raise FormatError(path, "video", f"{doc_video!r} is none of the videos given to annotate")


def read_labels_overlay(path: str | os.PathLike, videos) -> tuple[str, dict]:
    """(video id, {"classes", "spans": [{start, end, action}] in decoded frames, half-open, and, when the
    file has confidences, "starts": the first decoded frame of each working frame, "confidence": one per
    working frame}), read by the owner module :func:`vidstyle.formats.recognised.read_recognised` (plain
    labels files load too)."""
    from ..formats.recognised import read_recognised

    track = read_recognised(path)
    labels, classes, fps = track.labels, list(track.classes), track.fps
    v = _match_video(track.video, videos, path)
    src = working_indices(v.reader.info.timestamps, fps)
    if len(src) != len(labels):
        # recognize labels its features' frames; a features file at another rate than the video's
        raise FormatError(path, "labels", f"{len(labels)} labels, but {v.path.name} has {len(src)} frames at "
                                          f"{fps} fps")
    bounds = np.append(src, v.frames)
    spans: list[dict] = []
    for k, lab in enumerate(labels):
        s, e = int(bounds[k]), int(bounds[k + 1])
        if spans and spans[-1]["action"] == lab and spans[-1]["end"] == s:
            spans[-1]["end"] = e
        else:
            spans.append({"start": s, "end": e, "action": lab})
    out = {"classes": classes, "spans": spans, "file": Path(path).name}
    if track.confidence is not None:
        # the page shows the confidence of the working frame holding the current decoded frame
        out["starts"] = [int(x) for x in src]
        out["confidence"] = [round(float(c), 3) for c in np.asarray(track.confidence, float)]
    return v.id, out


def read_poses_overlay(path: str | os.PathLike, videos) -> tuple[str, dict]:
    """(video id, {"keypoints", "edges", "frames": {index: {"viewpoint", "points"}}}), read by the owner
    module :func:`vidstyle.formats.poses.read_poses`."""
    from ..formats.poses import read_poses

    poses = read_poses(path)
    names = list(poses.keypoints)
    v = _match_video(poses.video or None, videos, path)
    frames = {}
    for i, fr in enumerate(poses.frames):
        if fr.frame >= v.frames:
            raise FormatError(path, f"frames[{i}].frame", f"frame {fr.frame} is past the end of {v.path.name} "
                                                          f"({v.frames} frames)")
        if not fr.found:  # no pose there: nothing to draw (never fake points)
            continue
        frames[str(fr.frame)] = {"viewpoint": fr.viewpoint, "points": np.round(fr.points, 2).tolist()}
    edges = [[names.index(a), names.index(b)] for a, b in EDGES if a in names and b in names]
    return v.id, {"keypoints": names, "edges": edges, "frames": frames, "file": Path(path).name}


def read_matches_overlay(path: str | os.PathLike, videos) -> tuple[str, dict]:
    """(video id, {"frames": {index: [{"clip", "time", "cost"}, ...]}}), read by the owner module
    :func:`vidstyle.formats.matches.read_matches`."""
    from ..formats.matches import read_matches

    m = read_matches(path)
    v = _match_video(m.video or None, videos, path)
    frames = {}
    for i, fr in enumerate(m.frames):
        if fr.frame >= v.frames:
            raise FormatError(path, f"frames[{i}].frame", f"frame {fr.frame} is past the end of {v.path.name} "
                                                          f"({v.frames} frames)")
        frames[str(fr.frame)] = [{"clip": c.clip, "time": c.time, "cost": c.cost} for c in fr.candidates]
    return v.id, {"frames": frames, "file": Path(path).name}


def load_overlays(videos, labels=(), poses=(), matches=()) -> dict[str, dict]:
    """Per video id: {"recognized"?, "poses"?, "matches"?}."""
    out: dict[str, dict] = {v.id: {} for v in videos}
    for key, reader, files in (("recognized", read_labels_overlay, labels), ("poses", read_poses_overlay, poses),
                               ("matches", read_matches_overlay, matches)):
        for p in files:
            vid, data = reader(p, videos)
            if key in out[vid]:
                raise FormatError(p, None, f"a second {key} file for video {vid}")
            out[vid][key] = data
    return out
