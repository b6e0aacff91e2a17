"""What every per-frame labels kind shares: :class:`FrameLabels`, :class:`LabelSegment` and the checks of their
common fields. The owners of the two kinds, :mod:`vidstyle.formats.labels` (ground truth, which also reads
recognised files) and :mod:`vidstyle.formats.recognised`, both build on this module.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ._base import Fields, FormatError, check_header, check_int, header

KIND = "vidstyle.labels"
SCHEMA_VERSION = 2
VERSIONS = (1, 2)

#: keys with a meaning (validated); everything else goes to ``extra``
KNOWN_KEYS = ("kind", "schema_version", "video", "bvh", "fps", "classes", "labels", "confidence", "performer", "view",
          "transitions", "events", "segments", "chain")


@dataclass
class LabelSegment:
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
    events: list[LabelSegment] | None = None
    segments: list[LabelSegment] | None = None
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
        kw[key] = opt_str(f, key)
    if version >= 2 and kinds[0] == KIND and kw["video"] is None and kw["bvh"] is None:
        raise FormatError(path, "video", "missing (a labels file names its video, or its mocap take as 'bvh')")
    conf = f.array("confidence", shape=(n,), required=False) if doc.get("confidence") is not None else None
    if conf is not None and conf.size and (conf.min() < 0 or conf.max() > 1):
        raise FormatError(path, "confidence", "values must lie in [0, 1]")
    kw["confidence"] = conf
    if doc.get("transitions") is not None:
        tr = f.list("transitions")
        kw["transitions"] = [check_frame(t, path, f"transitions[{i}]", n) for i, t in enumerate(tr)]
    for key in ("events", "segments"):
        if doc.get(key) is not None:
            kw[key] = [parse_segment(s, path, f"{key}[{i}]", n, known) for i, s in enumerate(f.list(key))]
    if doc.get("chain") is not None:
        kw["chain"] = f.str_list("chain")
    return f, kw


def opt_str(f: Fields, key: str) -> str | None:
    if f.obj.get(key) is None:
        return None
    return f.str(key)


def check_frame(v: Any, path, name: str, n: int) -> int:
    return check_int(v, path, name, 0, max(n - 1, 0))


def parse_segment(obj: Any, path, name: str, n: int, classes: set[str]) -> LabelSegment:
    s = Fields(obj, path, name)
    label = s.str("label")
    if label not in classes:
        raise FormatError(path, f"{name}.label", f"{label!r} is not one of the classes"[:200])
    start = s.int("start", min=0, max=n)
    end = s.int("end", min=0, max=n)
    if end <= start:
        raise FormatError(path, f"{name}.end", f"must be greater than start ({start}), got {end}")
    return LabelSegment(label, start, end)


def check_length(track: FrameLabels, n_frames: int, what: str = "the video") -> None:
    if track.n_frames != n_frames:
        raise FormatError(track.path or None, "labels", f"{track.n_frames} labels but {what} has {n_frames} frames")
