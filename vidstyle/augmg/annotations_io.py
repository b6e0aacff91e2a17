"""Transition marks of an annotations file (:mod:`vidstyle.formats.annotations`) as AugMG uses them."""

from __future__ import annotations

import os
from pathlib import Path


def read_marks(path: str | os.PathLike) -> list[dict]:
    """Every transition mark: ``{"video": <video file stem>, "path", "fps", "frame", "from", "to", "status",
    "candidates": [{"clip", "time", "status"}]}`` (frames are 0-based decoded indices)."""
    from ..formats.annotations import read_annotations

    ann = read_annotations(path)
    out = []
    for v in ann.videos:
        for t in v.transitions:
            out.append({"video": Path(v.path).stem, "path": v.path, "fps": float(v.fps), "frame": t.frame,
                        "from": t.from_action,
                        "to": t.to_action, "status": t.status,
                        "candidates": [{"clip": c.clip, "time": c.time, "status": c.status} for c in t.candidates]})
    return out
