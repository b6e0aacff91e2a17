"""``reconstruction.json``: what ``vidstyle reconstruct`` found for each video frame, beside the BVH it wrote.

Schema (``kind`` = ``"vidstyle.reconstruction"``, ``schema_version`` 1)::

    {"kind": "vidstyle.reconstruction", "schema_version": 1,
     "video": "clip.mp4",                    # the reconstructed video ("" when unknown)
     "poses": "clip.poses.json",             # the 2D poses used ("" when estimated in the run)
     "bvh": "clip.bvh",                      # the motion written (library skeleton, library units)
     "fps": 20.0, "size": [160, 120],        # the video's frame rate (> 0) and size in pixels (> 0)
     "library": ["lib/a.bvh", ...],          # every library clip, in index order (non-empty)
     "params": {...},                        # the reconstructor's parameters
     "camera": {"K": [[fx, 0, cx], [0, fy, cy], [0, 0, 1]],   # intrinsics (finite, fx, fy > 0)
                "elevation_deg": 10.0,       # pitch of the camera (down), degrees in [-90, 90]
                "height": 25.3},             # the camera's height above the floor (finite; library units)
     "frames": [{"frame": 0,                 # video frame (0, 1, 2, ...: one entry per frame, in order)
                 "observed": true,           # the frame had a pose (false: bridged from its neighbours)
                 "azimuth_deg": 12.5,        # camera about the performer (0 = they face it, +90 = their left)
                 "label": "Jab",             # the matched library frames' label ("" when none)
                 "contacts": [true, false],  # left / right foot planted
                 "neighbours": [{"clip": 0, "frame": 120, "weight": 0.4}, ...]}]}
                                             # blended library frames: clip index into "library", the
                                             # clip's frame, weight in [0, 1]; empty when not observed

The motion's world: +Y up, the floor at Y = 0, the camera at ``(0, height, 0)`` looking along +Z (pitched
down by ``elevation_deg``).
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field

import numpy as np

from ._base import Fields, check_header, header, read_json_document, write_checked

KIND = "vidstyle.reconstruction"
SCHEMA_VERSION = 1


@dataclass
class Neighbour:
    clip: int
    frame: int
    weight: float


@dataclass
class ReconstructedFrame:
    frame: int
    observed: bool
    azimuth_deg: float
    label: str
    contacts: tuple[bool, bool]
    neighbours: list[Neighbour] = field(default_factory=list)


@dataclass
class ReconstructionRecord:
    video: str
    poses: str
    bvh: str
    fps: float
    size: tuple[int, int]
    library: list[str]
    params: dict
    K: np.ndarray
    elevation_deg: float
    camera_height: float
    frames: list[ReconstructedFrame] = field(default_factory=list)

    def to_dict(self) -> dict:
        return {**header(KIND, SCHEMA_VERSION), "video": self.video, "poses": self.poses, "bvh": self.bvh,
                "fps": float(self.fps), "size": [int(self.size[0]), int(self.size[1])], "library": list(self.library),
                "params": dict(self.params),
                "camera": {"K": np.asarray(self.K, dtype=float).tolist(), "elevation_deg": float(self.elevation_deg),
                           "height": float(self.camera_height)},
                "frames": [{"frame": f.frame, "observed": bool(f.observed), "azimuth_deg": float(f.azimuth_deg),
                            "label": f.label, "contacts": [bool(f.contacts[0]), bool(f.contacts[1])],
                            "neighbours": [{"clip": n.clip, "frame": n.frame, "weight": float(n.weight)}
                                           for n in f.neighbours]} for f in self.frames]}


def parse_reconstruction(doc, path) -> ReconstructionRecord:
    """Validate a parsed document; :class:`~vidstyle.formats.FormatError` names the file and the field."""
    check_header(doc, path, KIND, (SCHEMA_VERSION,))
    top = Fields(doc, path)
    library = top.str_list("library", min_len=1)
    params = top.get("params")
    if not isinstance(params, dict):
        raise top.fail("params", "expected an object")
    size = top.list("size")
    if len(size) != 2 or not all(isinstance(s, int) and not isinstance(s, bool) and s > 0 for s in size):
        raise top.fail("size", "expected [width, height], two integers > 0")
    cam = top.sub("camera")
    K = cam.array("K", shape=(3, 3))
    if not (K[0, 0] > 0 and K[1, 1] > 0):
        raise cam.fail("K", "focal lengths must be > 0")
    elevation = cam.number("elevation_deg", min=-90.0, max=90.0)
    height = cam.number("height")
    frames = []
    for i, raw in enumerate(top.list("frames")):
        f = Fields(raw, path, f"frames[{i}]")
        frame = f.int("frame", min=0)
        if frame != i:
            raise f.fail("frame", f"expected {i} (one entry per video frame, in order)")
        contacts = f.list("contacts")
        if len(contacts) != 2 or not all(isinstance(c, bool) for c in contacts):
            raise f.fail("contacts", "expected [left, right], two booleans")
        neighbours = []
        for j, rn in enumerate(f.list("neighbours")):
            n = Fields(rn, path, f"frames[{i}].neighbours[{j}]")
            clip = n.int("clip", min=0, max=len(library) - 1)
            neighbours.append(Neighbour(clip, n.int("frame", min=0), n.number("weight", min=0.0, max=1.0)))
        frames.append(ReconstructedFrame(frame, f.bool("observed"), f.number("azimuth_deg"), f.str("label"),
                                         (contacts[0], contacts[1]), neighbours))
    return ReconstructionRecord(top.str("video"), top.str("poses"), top.str("bvh"),
                                top.number("fps", positive=True),
                                (size[0], size[1]), library, params, K, elevation, height, frames)


def read_reconstruction(path: str | os.PathLike) -> ReconstructionRecord:
    """Read and validate ``path``."""
    return parse_reconstruction(read_json_document(path), path)


def write_reconstruction(path: str | os.PathLike, record: ReconstructionRecord | dict) -> None:
    """Validate and write atomically."""
    doc = record.to_dict() if isinstance(record, ReconstructionRecord) else record
    write_checked(path, doc, parse_reconstruction, "reconstruction")
