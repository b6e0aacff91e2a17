"""Atomic video writing with OpenCV (mp4 'mp4v', or avi 'MJPG')."""

from __future__ import annotations

import os
from collections.abc import Iterable
from pathlib import Path

import cv2
import numpy as np

from ..errors import InputError
from ..fileio import atomic_path

CODECS = {".mp4": "mp4v", ".m4v": "mp4v", ".mov": "mp4v", ".avi": "MJPG"}


class VideoSink:
    """Frame-by-frame writer to an already chosen (temporary) path; size fixed by the first frame."""

    def __init__(self, path: str | os.PathLike, fps: float, suffix: str | None = None) -> None:
        self.path = Path(path)
        suffix = (suffix or self.path.suffix).lower()
        if suffix not in CODECS:
            raise InputError(f"{path}: video must end in {', '.join(CODECS)} (got {suffix or 'no suffix'!r})")
        if not fps > 0:
            raise InputError(f"fps must be positive, got {fps}")
        self.fourcc = cv2.VideoWriter_fourcc(*CODECS[suffix])
        self.fps = float(fps)
        self.writer: cv2.VideoWriter | None = None
        self.size: tuple[int, int] | None = None
        self.count = 0

    def write(self, frame: np.ndarray) -> None:
        frame = np.asarray(frame)
        if frame.ndim != 3 or frame.shape[2] != 3 or frame.dtype != np.uint8:
            raise ValueError(f"frames must be (H, W, 3) uint8 BGR, got {frame.shape} {frame.dtype}")
        H, W = frame.shape[:2]
        if self.writer is None:
            self.size = (W, H)
            self.writer = cv2.VideoWriter(str(self.path), self.fourcc, self.fps, (W, H))
            if not self.writer.isOpened():
                raise InputError(f"{self.path}: OpenCV cannot open a video writer for this file")
        elif (W, H) != self.size:
            raise ValueError(f"frame size {W}x{H} differs from the first frame's {self.size[0]}x{self.size[1]}")
        self.writer.write(np.ascontiguousarray(frame))
        self.count += 1

    def close(self) -> None:
        if self.writer is not None:
            self.writer.release()
            self.writer = None


def write_video(frames: Iterable[np.ndarray] | np.ndarray, path: str | os.PathLike, fps: float) -> Path:
    """Write (F, H, W, 3) uint8 BGR frames (or any iterable of frames) to ``path`` atomically.

    ``.mp4`` uses OpenCV's 'mp4v' codec, ``.avi`` Motion-JPEG. Raises :class:`InputError` for an
    unsupported suffix or when no frame is given.
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in CODECS:
        raise InputError(f"{path}: video must end in {', '.join(CODECS)} (got {suffix or 'no suffix'!r})")
    with atomic_path(path) as tmp:
        sink = VideoSink(tmp, fps, suffix)
        try:
            for frame in frames:
                sink.write(frame)
        finally:
            sink.close()
        if sink.count == 0:
            raise InputError(f"{path}: no frames to write")
    return path


def read_video(path: str | os.PathLike) -> np.ndarray:
    """All frames of a video as (F, H, W, 3) uint8 BGR (for tests and small clips)."""
    cap = cv2.VideoCapture(str(path))
    if not cap.isOpened():
        raise InputError(f"{path}: OpenCV cannot open this video")
    frames = []
    try:
        while True:
            ok, frame = cap.read()
            if not ok:
                break
            frames.append(frame)
    finally:
        cap.release()
    if not frames:
        raise InputError(f"{path}: no frames could be read")
    return np.stack(frames)
