"""Keyframes for keyframe-to-keyframe synthesis (``vidstyle synthesize --keyframes K.json``): the owner of
that JSON.

Schema (``kind`` ``"vidstyle.keyframes"``, ``schema_version`` 1; a file without ``kind`` and
``schema_version`` is read as schema 1, so a hand-written file needs only the list)::

    {"kind": "vidstyle.keyframes", "schema_version": 1,      # optional header
     "keyframes": [                                          # at least 2, times strictly increasing
        {"clip": "mocap/02_05.bvh",   # BVH file holding the pose (relative paths: from this file's folder)
         "frame": 120,                # frame index in that clip, as the file numbers them (>= 0)
         "time": 0.0},                # seconds in the output (>= 0); the first keyframe is output frame 0
        {"clip": "mocap/02_01.bvh", "frame": 40, "time": 1.5}, ...]}

Each consecutive pair is in-betweened; the output passes through every keyframe's pose (joint rotations
and root height) at its time, rounded to the output's frame rate. No other keys are allowed in a
keyframe (a misspelt key is an error, not a silently ignored field). Whether ``frame`` exists in the clip
is checked when the clip is read (:mod:`vidstyle.inbetween.keyframes`).
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ._base import Fields, FormatError, check_header, header, read_json_document, write_json_document

KIND = "vidstyle.keyframes"
SCHEMA_VERSION = 1
KEYS = ("clip", "frame", "time")


@dataclass(frozen=True)
class Keyframe:
    clip: str
    frame: int
    time: float

    def to_dict(self) -> dict[str, Any]:
        return {"clip": self.clip, "frame": self.frame, "time": self.time}


@dataclass
class Keyframes:
    keyframes: list[Keyframe]
    path: str = ""

    def clip_path(self, k: Keyframe) -> Path:
        """``k.clip`` resolved against the folder of the file it was read from."""
        p = Path(k.clip)
        return p if p.is_absolute() or not self.path else Path(self.path).parent / p

    def to_dict(self) -> dict[str, Any]:
        return {**header(KIND, SCHEMA_VERSION), "keyframes": [k.to_dict() for k in self.keyframes]}


def parse_keyframes(doc: Any, path: str | os.PathLike | None = None) -> Keyframes:
    """Validate a keyframes document (see the module docstring); every problem is a :class:`FormatError`."""
    check_header(doc, path, KIND, (SCHEMA_VERSION,), legacy=True)
    f = Fields(doc, path)
    items = f.list("keyframes", min_len=2)
    out: list[Keyframe] = []
    for i, raw in enumerate(items):
        k = Fields(raw, path, f"keyframes[{i}]")
        extra = sorted(set(k.obj) - set(KEYS))
        if extra:
            raise k.fail(None, f"unknown key {extra[0]!r} (a keyframe has {', '.join(KEYS)})"[:200])
        clip = k.str("clip", nonempty=True)
        if "\x00" in clip:
            raise k.fail("clip", "contains a NUL character")
        frame = k.int("frame", min=0)
        time = k.number("time", min=0.0, max=1e6)
        if out and not time > out[-1].time:
            raise k.fail("time", f"{time:g} s is not after keyframe {i - 1}'s {out[-1].time:g} s (times must increase)")
        out.append(Keyframe(clip, frame, time))
    return Keyframes(out, "" if path is None else str(path))


def read_keyframes(path: str | os.PathLike) -> Keyframes:
    return parse_keyframes(read_json_document(path), path)


def write_keyframes(path: str | os.PathLike, keyframes: Keyframes | dict) -> None:
    """Validate (as the reader would) and write atomically, with the header."""
    doc = keyframes.to_dict() if isinstance(keyframes, Keyframes) else dict(keyframes)
    doc = {**header(KIND, SCHEMA_VERSION), **{k: v for k, v in doc.items() if k not in ("kind", "schema_version")}}
    try:
        parse_keyframes(doc, path)
    except FormatError as e:
        raise ValueError(f"invalid keyframes: {e.field}: {e.problem}") from None
    write_json_document(path, doc)
