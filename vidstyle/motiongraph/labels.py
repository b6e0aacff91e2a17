"""Action labels of mocap clips: whole clips or frame ranges, from JSON or CSV.

Accepted label files (``--labels``, repeatable):

* **demo labels JSON** (``mocap/<take>.labels.json``)::

      {"bvh": "mocap/<take>.bvh", "fps": 60, "classes": [...],
       "labels": ["Guard", "Guard", "Jab", ...],            # one class name per mocap frame
       "events": [{"label": "Jab", "start": 12, "end": 19}, ...]}

  Per-frame ``labels`` win; otherwise ``events`` (``end`` exclusive) label frame ranges. The clip is the
  BVH whose file name matches ``bvh``. A ``<take>.labels.json`` beside a BVH is used automatically.
* **CMU index** ``clips.csv`` (``file,subject,trial,description,frames,fps``): every clip gets the action
  whose keyword appears first in its description (table :data:`CMU_KEYWORDS`), ``other`` if none does.
* **label CSV** ``file,label[,start,end]``: whole clip, or frames ``start`` (inclusive) to ``end``
  (exclusive) in the BVH's own frame numbers; later rows override earlier ones.

Frame numbers always refer to the BVH file as written (frame 0 = first MOTION line).
"""

from __future__ import annotations

import csv
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import InputError

UNLABELLED = "unlabelled"

#: CMU description keyword -> action. The action whose keyword occurs earliest in the description wins
#: ("playground - climb, ..., jump down" is a climb; "walk on uneven terrain" a walk).
CMU_KEYWORDS: dict[str, tuple[str, ...]] = {
    "walk": ("walk", "stride"),
    "run": ("run", "jog"),
    "jump": ("jump", "hop", "leap"),
    "punch": ("punch", "strike", "box"),
    "dance": ("dance", "pirouette", "arabesque"),
    "basketball": ("basketball", "dribble"),
    "climb": ("climb",),
    "swordplay": ("sword",),
}


def cmu_action(description: str) -> str:
    """Action of a CMU clip description (see :data:`CMU_KEYWORDS`)."""
    text = description.lower()
    best, best_pos = "other", len(text) + 1
    for action, words in CMU_KEYWORDS.items():
        for word in words:
            m = re.search(r"\b" + re.escape(word), text)
            if m and m.start() < best_pos:
                best, best_pos = action, m.start()
    return best


@dataclass
class LabelSpec:
    """Labels of one clip: a default for the whole clip and/or per-frame overrides (native frames)."""

    whole: str | None = None
    ranges: list[tuple[int, int | None, str]] = field(default_factory=list)  # start, end (excl.), label
    per_frame: list[str] | None = None

    def frame_labels(self, n_frames: int) -> list[str]:
        out = [self.whole or UNLABELLED] * n_frames
        for start, end, label in self.ranges:
            for f in range(max(start, 0), min(n_frames if end is None else end, n_frames)):
                out[f] = label
        if self.per_frame is not None:
            for f in range(min(n_frames, len(self.per_frame))):
                out[f] = self.per_frame[f]
        return out


class _AnyClass:
    """Every label is a class (event lists without a class list)."""

    def __contains__(self, item) -> bool:
        return True


def _key(path: str | Path) -> str:
    return Path(str(path)).name.lower().removesuffix(".bvh")


class LabelBook:
    """Labels of many clips, keyed by BVH file name (without directory and ``.bvh``)."""

    def __init__(self) -> None:
        self.specs: dict[str, LabelSpec] = {}

    def spec(self, clip: str | Path) -> LabelSpec:
        return self.specs.setdefault(_key(clip), LabelSpec())

    def has(self, clip: str | Path) -> bool:
        return _key(clip) in self.specs

    def load(self, path: str | Path) -> "LabelBook":
        path = Path(path)
        if not path.is_file():
            raise InputError(f"{path}: label file not found")
        if path.suffix.lower() == ".json":
            self._load_json(path)
        elif path.suffix.lower() == ".csv":
            self._load_csv(path)
        else:
            raise InputError(f"{path}: labels must be .json or .csv")
        return self

    def _load_json(self, path: Path) -> None:
        from ..formats import FormatError, read_json_document
        from ..formats.labels import parse_labels, parse_segment

        data = read_json_document(path)
        items = data if isinstance(data, list) else [data]
        for i, item in enumerate(items):
            where = f"[{i}]" if isinstance(data, list) else None
            if not isinstance(item, dict) or not isinstance(item.get("bvh"), str):
                raise FormatError(path, where, "expected an object with 'bvh' and 'labels' or 'events'")
            spec = self.spec(item["bvh"])
            if "label" in item:
                if not isinstance(item["label"], str):
                    raise FormatError(path, f"{where or ''}label", "expected a class name")
                spec.whole = item["label"]
            if item.get("labels") is not None:  # a labels file (vidstyle.formats.labels) of the take
                track = parse_labels(item, path)
                spec.per_frame = track.labels
                events = track.events or []
            else:
                raw = item.get("events") or []
                if not isinstance(raw, list):
                    raise FormatError(path, "events", "expected a list")
                events = [parse_segment(ev, path, f"events[{k}]", 1 << 62, _AnyClass()) for k, ev in enumerate(raw)]
            for ev in events:
                spec.ranges.append((ev.start, ev.end, ev.label))

    def _load_csv(self, path: Path) -> None:
        with open(path, newline="", encoding="utf-8") as f:
            rows = list(csv.DictReader(f))
        if not rows:
            raise InputError(f"{path}: no rows")
        cols = set(rows[0])
        if {"file", "description"} <= cols:
            for r in rows:
                self.spec(r["file"]).whole = cmu_action(r["description"] or "")
            return
        if not {"file", "label"} <= cols:
            raise InputError(f"{path}: expected columns file,label[,start,end] or a CMU clips.csv")
        for i, r in enumerate(rows, start=2):
            spec = self.spec(r["file"])
            start, end = (r.get("start") or "").strip(), (r.get("end") or "").strip()
            if not start and not end:
                spec.whole = r["label"]
                continue
            try:
                spec.ranges.append((int(start or 0), int(end) if end else None, r["label"]))
            except ValueError:
                raise InputError(f"{path}: line {i}: start/end must be integers") from None

    def frame_labels(self, clip: str | Path, n_frames: int) -> list[str]:
        spec = self.specs.get(_key(clip))
        return spec.frame_labels(n_frames) if spec else [UNLABELLED] * n_frames


def resample_labels(labels: list[str], src_fps: float, dst_fps: float, n_dst: int, first: int = 0) -> list[str]:
    """Labels at ``dst_fps`` by nearest source frame; ``first`` = source frame at destination time 0."""
    t = np.arange(n_dst) / dst_fps
    src = np.clip(np.rint(t * src_fps).astype(int) + first, 0, len(labels) - 1)
    return [labels[i] for i in src]
