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
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ._base import Fields, FormatError, check_header, header, read_json_document, write_json_document

KIND = "vidstyle.labels"
SCHEMA_VERSION = 2
VERSIONS = (1, 2)

#: keys with a meaning (validated); everything else goes to ``extra``
_KNOWN = ("kind", "schema_version", "video", "bvh", "fps", "classes", "labels", "confidence", "performer", "view",
          "transitions", "events", "segments", "chain")


@dataclass
class Segment:
    """A run of frames ``start`` (inclusive) to ``end`` (exclusive) with one ``label``."""

    label: str
    start: int
    end: int

    def to_dict(self) -> dict:
        return {"label": self.label, "start": self.start, "end": self.end}


@dataclass
class FrameLabels:
    """One class name per frame. ``classes`` is the label vocabulary; ``labels[i]`` is in it."""

    labels: list[str]
    classes: tuple[str, ...]
    fps: float = 20.0
    video: str | None = None
    bvh: str | None = None
    performer: str | None = None
    view: str | None = None
    confidence: np.ndarray | None = None  # (frames,) in [0, 1]
    transitions: list[int] | None = None
    events: list[Segment] | None = None
    segments: list[Segment] | None = None
    chain: list[str] | None = None
    extra: dict[str, Any] = field(default_factory=dict)
    path: str = ""  # where it was read from ("" when built in memory)

    kind = KIND

    def __post_init__(self) -> None:
        self.classes = tuple(self.classes)
        self.labels = list(self.labels)

    @property
    def n_frames(self) -> int:
        return len(self.labels)

    def indices(self) -> np.ndarray:
        """(frames,) int64 index of every frame's label in ``classes``."""
        index = {c: i for i, c in enumerate(self.classes)}
        return np.fromiter((index[x] for x in self.labels), dtype=np.int64, count=len(self.labels))

    def source(self) -> str:
        return self.video or self.bvh or ""

    def to_dict(self) -> dict[str, Any]:
        doc: dict[str, Any] = {**header(self.kind, SCHEMA_VERSION)}
        for key in ("video", "bvh", "performer", "view"):
            if getattr(self, key) is not None:
                doc[key] = getattr(self, key)
        doc["fps"] = self.fps
        doc["classes"] = list(self.classes)
        doc["labels"] = list(self.labels)
        if self.confidence is not None:
            doc["confidence"] = [float(x) for x in np.asarray(self.confidence, float)]
        if self.transitions is not None:
            doc["transitions"] = [int(x) for x in self.transitions]
        for key in ("events", "segments"):
            if getattr(self, key) is not None:
                doc[key] = [s.to_dict() for s in getattr(self, key)]
        if self.chain is not None:
            doc["chain"] = list(self.chain)
        for k, v in self.extra.items():
            doc.setdefault(k, v)
        return doc


def parse_common(doc: Any, path: str | os.PathLike | None, kinds: tuple[str, ...]) -> tuple[Fields, dict]:
    """Header and the fields every labels kind shares; returns the checked values as keyword arguments."""
    if isinstance(doc, dict) and doc.get("kind") in kinds:
        check_header(doc, path, doc["kind"], VERSIONS)
        version = doc["schema_version"]
    else:
        version = check_header(doc, path, kinds[0], VERSIONS, legacy=True)
    f = Fields(doc, path)
    labels = f.list("labels", min_len=1)
    for i, x in enumerate(labels):
        if not isinstance(x, str):
            raise FormatError(path, f"labels[{i}]", f"expected a class name, got {x!r}"[:200])
    if version == 1 and not f.has("classes"):
        classes = sorted(set(labels))
    else:
        classes = f.str_list("classes", unique=True, min_len=1)
    known = set(classes)
    for i, x in enumerate(labels):
        if x not in known:
            raise FormatError(path, f"labels[{i}]", f"{x!r} is not one of the classes ({', '.join(classes)})"[:300])
    n = len(labels)
    fps = f.number("fps", required=version >= 2, default=20.0, positive=True)
    kw: dict[str, Any] = {"labels": labels, "classes": tuple(classes), "fps": fps}
    for key in ("video", "bvh", "performer", "view"):
        kw[key] = _opt_str(f, key)
    if version >= 2 and kinds[0] == KIND and kw["video"] is None and kw["bvh"] is None:
        raise FormatError(path, "video", "missing (a labels file names its video, or its mocap take as 'bvh')")
    conf = f.array("confidence", shape=(n,), required=False) if doc.get("confidence") is not None else None
    if conf is not None and conf.size and (conf.min() < 0 or conf.max() > 1):
        raise FormatError(path, "confidence", "values must lie in [0, 1]")
    kw["confidence"] = conf
    if doc.get("transitions") is not None:
        tr = f.list("transitions")
        kw["transitions"] = [_check_frame(t, path, f"transitions[{i}]", n) for i, t in enumerate(tr)]
    for key in ("events", "segments"):
        if doc.get(key) is not None:
            kw[key] = [_segment(s, path, f"{key}[{i}]", n, known) for i, s in enumerate(f.list(key))]
    if doc.get("chain") is not None:
        kw["chain"] = f.str_list("chain")
    return f, kw


def _opt_str(f: Fields, key: str) -> str | None:
    if f.obj.get(key) is None:
        return None
    return f.str(key)


def _check_frame(v: Any, path, name: str, n: int) -> int:
    from ._base import check_int

    return check_int(v, path, name, 0, max(n - 1, 0))


def _segment(obj: Any, path, name: str, n: int, classes: set[str]) -> Segment:
    s = Fields(obj, path, name)
    label = s.str("label")
    if label not in classes:
        raise FormatError(path, f"{name}.label", f"{label!r} is not one of the classes"[:200])
    start = s.int("start", min=0, max=n)
    end = s.int("end", min=0, max=n)
    if end <= start:
        raise FormatError(path, f"{name}.end", f"must be greater than start ({start}), got {end}")
    return Segment(label, start, end)


def parse_labels(doc: Any, path: str | os.PathLike | None = None) -> FrameLabels:
    """Validate a labels document (ground truth or recognised); see the module docstring."""
    from .recognised import KIND as RKIND
    from .recognised import parse_recognised

    if isinstance(doc, dict) and doc.get("kind") == RKIND:
        return parse_recognised(doc, path)
    _, kw = parse_common(doc, path, (KIND,))
    extra = {k: v for k, v in doc.items() if k not in _KNOWN}
    return FrameLabels(**kw, extra=extra, path="" if path is None else str(path))


def read_labels(path: str | os.PathLike, n_frames: int | None = None) -> FrameLabels:
    """Read and validate a labels file; ``n_frames``: the number of frames it must label."""
    track = parse_labels(read_json_document(path), path)
    if n_frames is not None:
        check_length(track, n_frames)
    return track


def check_length(track: FrameLabels, n_frames: int, what: str = "the video") -> None:
    if track.n_frames != n_frames:
        raise FormatError(track.path or None, "labels", f"{track.n_frames} labels but {what} has {n_frames} frames")


def write_labels(path: str | os.PathLike, track: FrameLabels | dict) -> None:
    """Validate ``track`` (as its reader would) and write it atomically. A dict is taken as the document
    (ground-truth labels) and given the current header."""
    if isinstance(track, dict):
        doc = {**header(KIND, SCHEMA_VERSION), **{k: v for k, v in track.items() if k not in ("kind", "schema_version")}}
    else:
        doc = track.to_dict()
    parse_labels(doc, path)
    write_json_document(path, doc)

