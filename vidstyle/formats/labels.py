"""Per-frame action labels of one video (or one mocap take): the owner of the labels JSON.

Schema (``kind`` ``"vidstyle.labels"``, ``schema_version`` 2; files without ``kind`` and
``schema_version`` are schema 1 and still load)::

    {"kind": "vidstyle.labels", "schema_version": 2,
     "video": "videos/p03_perf0_front.mp4",   # the labelled video (or "bvh": "mocap/<take>.bvh")
     "fps": 20,                                # frame rate of the labels (> 0)
     "classes": ["Jab", ..., "Guard", "Step"], # unique names; schema 1 may omit it (then: sorted labels)
     "labels": ["Guard", "Guard", "Jab", ...], # one class name per frame, each in "classes"
     # optional:
     "confidence": [0.9, ...],                 # one finite number in [0, 1] per frame
     "performer": "p03", "view": "front",
     "transitions": [12, 40, ...],             # frames whose label differs from the previous frame's
     "events": [{"label": "Jab", "start": 12, "end": 19}, ...],    # end exclusive, 0 <= start < end <= frames
     "segments": [...same shape as events...], "chain": ["Jab", ...]}

Other keys are carried along unchanged (``extra``). Frame ``i`` of ``labels`` is frame ``i`` of the
video as decoded (:mod:`vidstyle.video`). Recognised labels (``vidstyle recognize``) are a sibling kind,
see :mod:`vidstyle.formats.recognised`; :func:`read_labels` reads both.
"""

from __future__ import annotations

import os
from typing import Any

from ._base import header, read_json_document, write_json_document
from .framelabels import (
    KIND,
    KNOWN_KEYS,
    SCHEMA_VERSION,
    VERSIONS,
    FrameLabels,
    LabelSegment,
    check_length,
    opt_str,
    parse_common,
    parse_segment,
)
from .recognised import KIND as RKIND
from .recognised import parse_recognised

__all__ = [
    "KIND",
    "SCHEMA_VERSION",
    "VERSIONS",
    "FrameLabels",
    "LabelSegment",
    "check_length",
    "opt_str",
    "parse_common",
    "parse_labels",
    "parse_segment",
    "read_labels",
    "write_labels",
]


def parse_labels(doc: Any, path: str | os.PathLike | None = None) -> FrameLabels:
    """Validate a labels document (ground truth or recognised); see the module docstring."""
    if isinstance(doc, dict) and doc.get("kind") == RKIND:
        return parse_recognised(doc, path)
    _, kw = parse_common(doc, path, (KIND,))
    extra = {k: v for k, v in doc.items() if k not in KNOWN_KEYS}
    return FrameLabels(**kw, extra=extra, path="" if path is None else str(path))


def read_labels(path: str | os.PathLike, n_frames: int | None = None) -> FrameLabels:
    """Read and validate a labels file; ``n_frames``: the number of frames it must label."""
    track = parse_labels(read_json_document(path), path)
    if n_frames is not None:
        check_length(track, n_frames)
    return track


def write_labels(path: str | os.PathLike, track: FrameLabels | dict) -> None:
    """Validate ``track`` (as its reader would) and write it atomically. A dict is taken as the document
    (ground-truth labels) and given the current header."""
    if isinstance(track, dict):
        doc = {**header(KIND, SCHEMA_VERSION), **{k: v for k, v in track.items() if k not in ("kind", "schema_version")}}
    else:
        doc = track.to_dict()
    parse_labels(doc, path)
    write_json_document(path, doc)

