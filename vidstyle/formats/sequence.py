"""A generated action sequence (``vidstyle generate``): the owner of ``kind`` ``"vidstyle.sequence"``.

Schema (``schema_version`` 1)::

    {"kind": "vidstyle.sequence", "schema_version": 1,
     "style": "style/p03.json", "model": "a" | "b" | "bigram", "seed": 0,
     "fps": 20.0,                      # frame rate of the durations (> 0)
     "start": "Jab",                   # == events[0].action
     "length": 40,                     # == len(events), >= 1
     "events": [{"action": "Jab", "duration_frames": 14, "start_frame": 0}, ...]}
                                       # duration >= 1; start_frame = sum of the previous durations

``--format text`` is the actions separated by spaces (thesis Table 4), ``--format csv`` the table
``index,action,duration_frames,start_frame``; :func:`format_sequence` writes all three.
"""

from __future__ import annotations

import csv
import io
import json
import os
from dataclasses import dataclass, field
from typing import Any

from ._base import Fields, FormatError, check_header, header, read_json_document, write_json_document

KIND = "vidstyle.sequence"
SCHEMA_VERSION = 1
FORMATS = ("text", "json", "csv")


@dataclass
class SequenceEvent:
    action: str
    duration_frames: int
    start_frame: int

    def to_dict(self) -> dict:
        return {"action": self.action, "duration_frames": self.duration_frames, "start_frame": self.start_frame}


@dataclass
class ActionSequence:
    events: list[SequenceEvent]
    fps: float
    style: str | None = None
    model: str | None = None
    seed: int | None = None
    extra: dict[str, Any] = field(default_factory=dict)
    path: str = ""

    kind = KIND

    @classmethod
    def from_events(cls, events: list[dict], fps: float, **meta) -> ActionSequence:
        """From ``{"action", "duration_frames"[, "start_frame"]}`` dicts; start frames are back to back."""
        out, t = [], 0
        for e in events:
            out.append(SequenceEvent(str(e["action"]), int(e["duration_frames"]), t))
            t += int(e["duration_frames"])
        return cls(out, float(fps), **meta)

    def actions(self) -> list[str]:
        return [e.action for e in self.events]

    def to_dict(self) -> dict[str, Any]:
        doc = {**header(KIND, SCHEMA_VERSION), "style": self.style, "model": self.model,
               "start": self.events[0].action if self.events else None, "length": len(self.events),
               "seed": self.seed, "fps": self.fps, "events": [e.to_dict() for e in self.events]}
        return {**doc, **{k: v for k, v in self.extra.items() if k not in doc}}


def parse_sequence(doc: Any, path: str | os.PathLike | None = None) -> ActionSequence:
    check_header(doc, path, KIND, (SCHEMA_VERSION,))
    f = Fields(doc, path)
    fps = f.number("fps", positive=True)
    events = []
    t = 0
    for i, e in enumerate(f.list("events", min_len=1)):
        ef = Fields(e, path, f"events[{i}]")
        action = ef.str("action", nonempty=True)
        dur = ef.int("duration_frames", min=1)
        start = ef.int("start_frame", required=False, default=t, min=0)
        if start != t:
            raise FormatError(path, ef.name("start_frame"), f"expected {t} (the sum of the previous durations), got {start}")
        events.append(SequenceEvent(action, dur, start))
        t += dur
    if f.has("length") and f.int("length") != len(events):
        raise FormatError(path, "length", f"{doc['length']} but there are {len(events)} events")
    if doc.get("start") is not None and f.str("start") != events[0].action:
        raise FormatError(path, "start", f"{doc['start']!r} but the first event is {events[0].action!r}")
    model = None if doc.get("model") is None else f.str("model")
    style = None if doc.get("style") is None else f.str("style")
    seed = None if doc.get("seed") is None else f.int("seed")
    extra = {k: v for k, v in doc.items()
             if k not in ("kind", "schema_version", "style", "model", "start", "length", "seed", "fps", "events")}
    return ActionSequence(events, fps, style, model, seed, extra, "" if path is None else str(path))


def read_sequence(path: str | os.PathLike) -> ActionSequence:
    return parse_sequence(read_json_document(path), path)


def write_sequence(path: str | os.PathLike, seq: ActionSequence) -> None:
    doc = seq.to_dict()
    parse_sequence(doc, path)
    write_json_document(path, doc)


def format_sequence(seq: ActionSequence, fmt: str) -> str:
    """The sequence as ``text`` (actions separated by spaces), ``csv`` or ``json`` (the file's text)."""
    if fmt == "json":
        doc = seq.to_dict()
        parse_sequence(doc)
        return json.dumps(doc, indent=2, allow_nan=False) + "\n"
    if fmt == "csv":
        buf = io.StringIO()
        w = csv.writer(buf, lineterminator="\n")
        w.writerow(["index", "action", "duration_frames", "start_frame"])
        for i, e in enumerate(seq.events):
            w.writerow([i, e.action, e.duration_frames, e.start_frame])
        return buf.getvalue()
    if fmt == "text":
        return " ".join(seq.actions()) + "\n"
    raise ValueError(f"format: one of {', '.join(FORMATS)}, got {fmt!r}")
