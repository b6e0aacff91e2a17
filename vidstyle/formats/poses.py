"""``poses.json``: 2D poses of chosen frames of a video (written by ``vidstyle pose``).

Schema (``kind`` = ``"vidstyle.poses"``, ``schema_version`` = 3; versions 1 and 2 still load)::

    {"kind": "vidstyle.poses", "schema_version": 3,
     "video": "clip.mp4",                       # the input video, as given
     "backend": "ps" | "blazepose",
     "keypoints": ["head_top", "neck", ...],    # the 15 names of vidstyle.formats.keypoints.KEYPOINTS, in order
     "params": {"scales": [1.0, 1.2, 1.4]},     # optional: the backend's inference settings
     "frames": [{"frame": 12,                   # decoded frame index (vidstyle.video.VideoReader)
                 "viewpoint": "front",          # front | left | right | back | unknown (nobody found)
                 "azimuth": -35.0,              # optional: degrees of the camera about the performer
                                                # (0 = facing the camera, +90 = their left side)
                 "viewpoint_scores": {"front": 0.9, "left": 0.05, ...},   # finite numbers, per viewpoint
                 "points": [[x, y, score], ...],                           # 15 rows, keypoints order
                 "world": [[x, y, z], ...]},    # optional (version 3): 15 rows, metres, see below
                {"frame": 13, "points": null, "missing": "performer not found"},   # no pose: a reason
                ...]}

``x`` is the column and ``y`` the row, in pixels of the input video (integer values at pixel centres);
``score`` in [0, 1] is the backend's confidence in that keypoint. A frame without the performer has
``"points": null`` and a ``"missing"`` reason, never made-up points (in memory: NaN points, viewpoint
``"unknown"``, :attr:`PoseFrame.found` false). Version 1 wrote such frames as the image centre with
score 0 and viewpoint ``"unknown"``; they are read as missing ("nobody found"). Frames are unique and
in increasing order.

``world`` (version 3, optional, only on frames with a pose; written by the ``blazepose`` backend, never
by ``ps``): the backend's own 3D estimate of the same 15 keypoints in metres, in its camera-aligned,
hip-centred frame: x to the image's right, y down, z away from the camera, origin at the midpoint of
BlazePose's hips (so ``pelvis`` is about 0). Only the directions of the axes are the camera's; the scale
is metric from BlazePose's body model, not from the camera. In memory :attr:`PoseFrame.world`, (15, 3)
or ``None``. Every value is finite.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field

import numpy as np

from ._base import (
    Fields,
    FormatError,
    check_array,
    check_header,
    check_leaves,
    header,
    read_json_document,
    write_json_document,
)
from .keypoints import KEYPOINTS

KIND = "vidstyle.poses"
SCHEMA_VERSION = 3
VERSIONS = (1, 2, 3)
BACKENDS = ("ps", "blazepose")
VIEWPOINTS = ("front", "left", "right", "back")
UNKNOWN = "unknown"
#: the largest |coordinate| of a world keypoint, metres (hip-centred: a body is within about 2.5 m)
MAX_WORLD_M = 100.0


@dataclass
class PoseFrame:
    """One frame's pose: ``points`` (15, 3) = x (column), y (row), score."""

    frame: int
    viewpoint: str
    points: np.ndarray
    viewpoint_scores: dict[str, float] = field(default_factory=dict)
    azimuth: float | None = None
    """degrees of the camera about the performer (0 = facing it, +90 = their left side), if known"""
    missing: str | None = None
    """why there is no pose (points are then NaN and the viewpoint ``"unknown"``)"""
    world: np.ndarray | None = None
    """(15, 3) the backend's 3D keypoints, metres, camera-aligned and hip-centred (x right, y down, z away
    from the camera), if it gives them (blazepose); ``None`` otherwise and on frames without a pose"""

    def __post_init__(self) -> None:
        self.points = np.asarray(self.points, dtype=np.float64)
        if self.world is not None:
            self.world = np.asarray(self.world, dtype=np.float64)

    @classmethod
    def none(cls, frame: int, reason: str) -> PoseFrame:
        """A frame without the performer."""
        return cls(int(frame), UNKNOWN, np.full((len(KEYPOINTS), 3), np.nan), {}, None, reason)

    @property
    def found(self) -> bool:
        return self.missing is None

    @property
    def xy(self) -> np.ndarray:
        return self.points[:, :2]

    @property
    def scores(self) -> np.ndarray:
        return self.points[:, 2]


@dataclass
class Poses:
    video: str
    backend: str
    frames: list[PoseFrame]
    keypoints: tuple[str, ...] = KEYPOINTS
    params: dict = field(default_factory=dict)

    def frame(self, index: int) -> PoseFrame:
        for f in self.frames:
            if f.frame == index:
                return f
        raise KeyError(f"no pose for frame {index}")

    def to_document(self) -> dict:
        validate_poses(self, None)
        return {
            **header(KIND, SCHEMA_VERSION),
            "video": self.video,
            "backend": self.backend,
            "keypoints": list(self.keypoints),
            **({"params": dict(self.params)} if self.params else {}),
            "frames": [_frame_document(f) for f in self.frames],
        }


def _frame_document(f: PoseFrame) -> dict:
    if not f.found:
        return {"frame": int(f.frame), "points": None, "missing": f.missing}
    doc = {"frame": int(f.frame), "viewpoint": f.viewpoint}
    if f.azimuth is not None:
        doc["azimuth"] = round(float(f.azimuth), 2)
    doc["viewpoint_scores"] = {k: float(v) for k, v in f.viewpoint_scores.items()}
    doc["points"] = [[round(float(x), 3), round(float(y), 3), round(float(s), 4)] for x, y, s in f.points]
    if f.world is not None:
        doc["world"] = [[round(float(v), 5) for v in row] for row in f.world]
    return doc


def validate_poses(p: Poses, path: str | os.PathLike | None) -> None:
    """Raise :class:`FormatError` if ``p`` breaks the schema (used by the writer, before writing)."""
    if not isinstance(p.video, str) or not p.video:
        raise FormatError(path, "video", "must be a non-empty string")
    if p.backend not in BACKENDS:
        raise FormatError(path, "backend", f"{p.backend!r} is not one of {', '.join(BACKENDS)}")
    if tuple(p.keypoints) != KEYPOINTS:
        raise FormatError(path, "keypoints", f"must be exactly {', '.join(KEYPOINTS)}")
    if not isinstance(p.params, dict):
        raise FormatError(path, "params", "must be an object")
    check_leaves(p.params, path, "params")
    last = -1
    for i, f in enumerate(p.frames):
        where = f"frames[{i}]"
        if isinstance(f.frame, bool) or not isinstance(f.frame, (int, np.integer)) or f.frame < 0:
            raise FormatError(path, f"{where}.frame", f"expected a frame index >= 0, got {f.frame!r}")
        if f.frame <= last:
            raise FormatError(path, f"{where}.frame", f"frame {f.frame} is not after frame {last} (unique, increasing)")
        last = int(f.frame)
        if f.missing is not None:
            if not isinstance(f.missing, str) or not f.missing.strip() or len(f.missing) > 200:
                raise FormatError(path, f"{where}.missing", "must be a short non-empty reason")
            if f.world is not None:
                raise FormatError(path, f"{where}.world", "a frame without a pose has no world keypoints")
            continue
        if f.azimuth is not None and not (isinstance(f.azimuth, (int, float, np.floating)) and np.isfinite(f.azimuth)
                                          and -360.0 <= f.azimuth <= 360.0):
            raise FormatError(path, f"{where}.azimuth", f"must be finite degrees in [-360, 360], got {f.azimuth!r}")
        if f.viewpoint not in VIEWPOINTS + (UNKNOWN,):
            raise FormatError(path, f"{where}.viewpoint", f"{f.viewpoint!r} is not one of "
                              f"{', '.join(VIEWPOINTS + (UNKNOWN,))}")
        for k, v in f.viewpoint_scores.items():
            if k not in VIEWPOINTS:
                raise FormatError(path, f"{where}.viewpoint_scores.{k}", "not a viewpoint name")
            if not np.isfinite(v):
                raise FormatError(path, f"{where}.viewpoint_scores.{k}", f"must be a finite number, got {v}")
        pts = check_array(f.points, path, f"{where}.points", (len(KEYPOINTS), 3))
        if np.any(pts[:, 2] < 0) or np.any(pts[:, 2] > 1):
            raise FormatError(path, f"{where}.points", "scores (third column) must lie in [0, 1]")
        if f.world is not None:
            w = check_array(f.world, path, f"{where}.world", (len(KEYPOINTS), 3))
            if np.abs(w).max() > MAX_WORLD_M:
                raise FormatError(path, f"{where}.world", f"values must lie within +-{MAX_WORLD_M:g} m of the hips")


def read_poses(path: str | os.PathLike) -> Poses:
    """Read and validate a ``poses.json``; :class:`FormatError` (one line naming the file) otherwise."""
    return parse_poses(read_json_document(path), path)


def parse_poses(doc, path: str | os.PathLike | None = None) -> Poses:
    """:class:`Poses` of a parsed ``poses.json`` document (``path``: for messages)."""
    version = check_header(doc, path, KIND, VERSIONS)
    top = Fields(doc, path)
    video = top.str("video", nonempty=True)
    backend = top.str("backend", choices=BACKENDS)
    kps = top.str_list("keypoints")
    if tuple(kps) != KEYPOINTS:
        raise top.fail("keypoints", f"must be exactly {', '.join(KEYPOINTS)}")
    frames = []
    for i, item in enumerate(top.list("frames")):
        f = Fields(item, path, f"frames[{i}]")
        index = f.int("frame", min=0)
        if version >= 2 and f.has("points") and f.obj["points"] is None:
            frames.append(PoseFrame.none(index, f.str("missing", nonempty=True)))
            continue
        scores_f = f.sub("viewpoint_scores")
        scores = {k: scores_f.number(k) for k in scores_f.obj}
        viewpoint = f.str("viewpoint")
        points = f.array("points", (len(KEYPOINTS), 3))
        azimuth = f.number("azimuth") if version >= 2 and f.has("azimuth") else None
        world = f.array("world", (len(KEYPOINTS), 3)) if version >= 3 and f.has("world") else None
        if version == 1 and viewpoint == UNKNOWN and not np.any(np.asarray(points)[:, 2] > 0):
            frames.append(PoseFrame.none(index, "nobody found"))  # version 1's stand-in for no pose
            continue
        frames.append(PoseFrame(index, viewpoint, points, scores, azimuth, world=world))
    params = top.sub("params").obj if "params" in doc else {}
    p = Poses(video, backend, frames, tuple(kps), dict(params))
    validate_poses(p, path)
    return p


def write_poses(path: str | os.PathLike, poses: Poses) -> None:
    """Validate ``poses`` and write it atomically."""
    validate_poses(poses, path)
    write_json_document(path, poses.to_document())
