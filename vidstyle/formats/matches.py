"""``matches.json``: the library poses that best match each annotated video frame (``vidstyle match-pose``).

Schema (``kind`` = ``"vidstyle.matches"``, ``schema_version`` 1)::

    {"kind": "vidstyle.matches", "schema_version": 1,
     "poses": "poses.json",                  # the 2D poses that were matched
     "video": "videos/p00_perf0_front.mp4",  # the poses' video ("" when unknown)
     "library": ["lib/clips/a.bvh", ...],    # every clip indexed
     "params": {"k": 10, "n_views": 12, "elevation_deg": 10.0, "stride": 3, "coherence": false, ...},
     "frames": [{"frame": 118,               # video frame index (0-based, decoded order)
                 "viewpoint_deg": 2.0,       # azimuth relative to the character's facing that was searched
                 "candidates": [{"clip": "lib/clips/a.bvh", "time": 1.35, "cost": 0.21}, ...]}]}

``candidates`` are best first; ``time`` is seconds into the clip (frame = round(time * clip fps));
``cost`` is the matching cost (non-negative; lower is better).
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field

from ._base import Fields, check_header, header, read_json_document, write_checked

KIND = "vidstyle.matches"
SCHEMA_VERSION = 1


@dataclass
class Candidate:
    clip: str
    time: float
    cost: float


@dataclass
class FrameMatches:
    frame: int
    viewpoint_deg: float
    candidates: list[Candidate]


@dataclass
class Matches:
    poses: str
    video: str
    library: list[str]
    params: dict
    frames: list[FrameMatches] = field(default_factory=list)

    def to_dict(self) -> dict:
        return {**header(KIND, SCHEMA_VERSION), "poses": self.poses, "video": self.video,
                "library": list(self.library), "params": dict(self.params),
                "frames": [{"frame": f.frame, "viewpoint_deg": f.viewpoint_deg,
                            "candidates": [{"clip": c.clip, "time": c.time, "cost": c.cost} for c in f.candidates]}
                           for f in self.frames]}


def _parse(doc, path) -> Matches:
    check_header(doc, path, KIND, (SCHEMA_VERSION,))
    top = Fields(doc, path)
    library = top.str_list("library")
    params = top.get("params")
    if not isinstance(params, dict):
        raise top.fail("params", "expected an object")
    frames = []
    for i, raw in enumerate(top.list("frames")):
        f = Fields(raw, path, f"frames[{i}]")
        cands = []
        for j, rc in enumerate(f.list("candidates")):
            c = Fields(rc, path, f"frames[{i}].candidates[{j}]")
            cands.append(Candidate(c.str("clip", nonempty=True), c.number("time", min=0.0), c.number("cost", min=0.0)))
        frames.append(FrameMatches(f.int("frame", min=0), f.number("viewpoint_deg"), cands))
    return Matches(top.str("poses"), top.str("video"), library, params, frames)


def read_matches(path: str | os.PathLike) -> Matches:
    """Read and validate ``path``; :class:`FormatError` names the file and the field."""
    return _parse(read_json_document(path), path)


def write_matches(path: str | os.PathLike, matches: Matches) -> None:
    """Validate ``matches`` (as the reader would) and write it atomically."""
    write_checked(path, matches.to_dict(), _parse, "matches")
