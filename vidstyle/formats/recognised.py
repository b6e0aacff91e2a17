"""Recognised per-frame labels (what ``vidstyle recognize`` writes): the owner of that JSON.

A labels file (:mod:`vidstyle.formats.labels`) of ``kind`` ``"vidstyle.recognised_labels"``,
``schema_version`` 2, with what the recogniser adds::

    {"kind": "vidstyle.recognised_labels", "schema_version": 2,
     "video": ..., "fps": 20, "classes": [...],
     "labels": [...],            # smoothed labels, one per frame
     "confidence": [...],        # smoothed confidence in [0, 1], one per frame (required)
     "raw": [...],               # labels before smoothing, one per frame (each in classes)
     "raw_confidence": [...],    # one per frame, in [0, 1]
     "smoothing": "viterbi", "smoothing_window": 6, "model": "model.joblib", "features": "x.npz"}

Schema 1 (no ``kind``) files of older runs still load; there ``raw`` and the confidences are optional.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from typing import Any

import numpy as np

from ._base import FormatError, read_json_document, write_json_document
from .framelabels import SCHEMA_VERSION, FrameLabels, check_length, opt_str, parse_common

KIND = "vidstyle.recognised_labels"
_KNOWN = ("kind", "schema_version", "video", "bvh", "fps", "classes", "labels", "confidence", "performer", "view",
          "transitions", "events", "segments", "chain", "raw", "raw_confidence", "smoothing", "smoothing_window",
          "model", "features")


@dataclass
class RecognisedLabels(FrameLabels):
    raw: list[str] | None = None
    raw_confidence: np.ndarray | None = None
    smoothing: str | None = None
    smoothing_window: int | None = None
    model: str | None = None
    features: str | None = None

    kind = KIND

    def to_dict(self) -> dict[str, Any]:
        doc = super().to_dict()
        if self.raw is not None:
            doc["raw"] = list(self.raw)
        if self.raw_confidence is not None:
            doc["raw_confidence"] = [float(x) for x in np.asarray(self.raw_confidence, float)]
        for key in ("smoothing", "smoothing_window", "model", "features"):
            if getattr(self, key) is not None:
                doc[key] = getattr(self, key)
        return doc


def parse_recognised(doc: Any, path: str | os.PathLike | None = None) -> RecognisedLabels:
    f, kw = parse_common(doc, path, (KIND, "vidstyle.labels"))
    v2 = doc.get("kind") == KIND
    n = len(kw["labels"])
    if v2 and kw["confidence"] is None:
        raise FormatError(path, "confidence", "missing (one number in [0, 1] per frame)")
    raw = None
    if doc.get("raw") is not None or v2:
        raw = f.list("raw", min_len=n, max_len=n)
        known = set(kw["classes"])
        for i, x in enumerate(raw):
            if not isinstance(x, str) or x not in known:
                raise FormatError(path, f"raw[{i}]", f"{x!r} is not one of the classes"[:200])
    raw_conf = f.array("raw_confidence", shape=(n,), required=v2) if (v2 or doc.get("raw_confidence") is not None) else None
    if raw_conf is not None and raw_conf.size and (raw_conf.min() < 0 or raw_conf.max() > 1):
        raise FormatError(path, "raw_confidence", "values must lie in [0, 1]")
    window = f.int("smoothing_window", required=False, min=1) if doc.get("smoothing_window") is not None else None
    extra = {k: v for k, v in doc.items() if k not in _KNOWN}
    return RecognisedLabels(**kw, extra=extra, path="" if path is None else str(path), raw=raw, raw_confidence=raw_conf,
                            smoothing=opt_str(f, "smoothing"), smoothing_window=window, model=opt_str(f, "model"),
                            features=opt_str(f, "features"))


def read_recognised(path: str | os.PathLike, n_frames: int | None = None) -> RecognisedLabels:
    track = parse_recognised(read_json_document(path), path)
    if n_frames is not None:
        check_length(track, n_frames)
    return track


def write_recognised(path: str | os.PathLike, track: RecognisedLabels) -> None:
    doc = track.to_dict()
    parse_recognised(doc, path)
    write_json_document(path, doc)


__all__ = ["KIND", "SCHEMA_VERSION", "RecognisedLabels", "parse_recognised", "read_recognised", "write_recognised"]
