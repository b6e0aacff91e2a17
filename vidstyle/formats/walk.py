"""The labels of a synthesised motion (``vidstyle synthesize`` writes ``<out>.labels.json`` beside the BVH):
the owner of that JSON.

It is a labels file (:mod:`vidstyle.formats.labels`, ``kind`` ``"vidstyle.labels"``, schema 2), so
``build-graph`` and every labels reader take it as the per-frame labels of the BVH, with what the walk
adds; ``n`` is the number of frames of the BVH::

    {"kind": "vidstyle.labels", "schema_version": 2,
     "bvh": "p00.bvh", "fps": 30, "classes": [...],
     "labels": [...],                  # n: the action the sequence asked for at each frame
     "events": [{"label": "Jab", "start": 0, "end": 14}, ...],   # the sequence's steps, end exclusive
     "source_labels": [...],           # n: the label of the graph frame played (may be "unlabelled")
     "source_clip": [...],             # n: the mocap clip it comes from
     "source_frame": [...],            # n: frame index in that clip (>= 0)
     "graph_frame": [...],             # n: frame index in the motion graph (>= 0)
     "transition": [...],              # n: index of the edge taken into this frame, -1 inside a clip
     "transitions_used": [...],        # edge indices, in walk order (>= 0)
     "transition_kinds": [...],        # one per used edge: PLAYBACK | BLEND | ENHANCEMENT
     "transition_segments": [...],     # one per used edge: stored segment id of an enhancement, else -1
     "cost": 12.5,                     # the walk's planner cost (a number or null)
     "foot_lock": {"enabled": true, ...},   # what foot locking did (an object)
     "planner": {...}}                 # the planner's parameters (an object)

Files of older runs (no ``kind``) still load (labels schema 1).
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from typing import Any

from ._base import Fields, FormatError, check_int, header, read_json_document, write_json_document
from .labels import KIND, SCHEMA_VERSION, FrameLabels, check_length, parse_labels

#: the walk's own per-frame lists (each of the BVH's length)
_PER_FRAME_STR = ("source_labels", "source_clip")
_PER_FRAME_INT = {"source_frame": 0, "graph_frame": 0, "transition": -1}
EDGE_KINDS = ("PLAYBACK", "BLEND", "ENHANCEMENT")


@dataclass
class WalkLabels:
    """A synthesised motion's labels (``track``) and the walk record (``doc``: the validated document)."""

    track: FrameLabels
    doc: dict[str, Any]
    path: str = ""

    @property
    def n_frames(self) -> int:
        return self.track.n_frames

    def to_dict(self) -> dict[str, Any]:
        return dict(self.doc)


def parse_walk_labels(doc: Any, path: str | os.PathLike | None = None) -> WalkLabels:
    """Validate a synthesised motion's labels document; see the module docstring."""
    track = parse_labels(doc, path)
    if track.bvh is None:
        raise FormatError(path, "bvh", "missing (the labels of a synthesised motion name its BVH)")
    f = Fields(doc, path)
    n = track.n_frames
    def per_frame(key: str) -> list:
        vals = f.list(key)
        if len(vals) != n:
            raise FormatError(path, key, f"{len(vals)} entries but 'labels' has {n} frames")
        return vals

    for key in _PER_FRAME_STR:
        per_frame(key)
        f.str_list(key, nonempty_items=False)
    for key, lo in _PER_FRAME_INT.items():
        for i, v in enumerate(per_frame(key)):
            check_int(v, path, f"{key}[{i}]", lo)
    used = f.list("transitions_used")
    for i, v in enumerate(used):
        check_int(v, path, f"transitions_used[{i}]", 0)
    for key in ("transition_kinds", "transition_segments"):
        if len(f.list(key)) != len(used):
            raise FormatError(path, key, f"{len(doc[key])} entries but {len(used)} transitions_used")
    kinds = doc["transition_kinds"]
    for i, v in enumerate(kinds):
        if v not in EDGE_KINDS:
            raise FormatError(path, f"transition_kinds[{i}]", f"{v!r} is not one of {', '.join(EDGE_KINDS)}"[:200])
    for i, v in enumerate(doc["transition_segments"]):
        check_int(v, path, f"transition_segments[{i}]", -1)
    if doc.get("cost") is not None:
        f.number("cost")
    for key in ("foot_lock", "planner"):
        if doc.get(key) is not None:
            f.sub(key)
    return WalkLabels(track, dict(doc), "" if path is None else str(path))


def read_walk_labels(path: str | os.PathLike, n_frames: int | None = None) -> WalkLabels:
    """Read and validate a synthesised motion's labels; ``n_frames``: the frames of its BVH."""
    walk = parse_walk_labels(read_json_document(path), path)
    if n_frames is not None:
        check_length(walk.track, n_frames, "the BVH")
    return walk


def write_walk_labels(path: str | os.PathLike, walk: WalkLabels | dict) -> None:
    """Validate ``walk`` (as its reader would) and write it atomically; a dict is given the labels header."""
    doc = walk.to_dict() if isinstance(walk, WalkLabels) else dict(walk)
    doc = {**header(KIND, SCHEMA_VERSION), **{k: v for k, v in doc.items() if k not in ("kind", "schema_version")}}
    parse_walk_labels(doc, path)
    write_json_document(path, doc)
