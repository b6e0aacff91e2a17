"""Shared helpers for the annotate tests: numbered videos (constant and variable rate) and a running server."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from vidstyle.annotate.server import Running, new_session
from vidstyle.annotate.session import Store, open_videos
from vidstyle.video import write_video
from vidstyle.video.numbered import numbered_frame

CLASSES = ["Jab", "Hook", "Guard"]


def numbered_video(path: Path, n: int = 60, fps: float = 25.0, vfr: bool = False, size=(160, 120), seed: int = 0) -> Path:
    frames = (numbered_frame(i, *size) for i in range(n))
    times = None
    if vfr:
        rng = np.random.default_rng(seed)
        times = np.concatenate([[0.0], np.cumsum(rng.choice([1 / 50, 1 / 25, 1 / 12.5, 0.07], n - 1))])
    return write_video(frames, path, fps, times=times)


def session(videos, annotations: Path, classes=CLASSES, overlays=None, max_body=1 << 20):
    vids = open_videos(videos)
    return new_session(vids, Store(annotations, vids, list(classes)), overlays, max_body=max_body)


def running(videos, annotations: Path, **kw) -> Running:
    return Running(session(videos, annotations, **kw))
