"""Read a whole video as a grayscale float32 volume (frames, height, width) with intensities in [0, 1].

Frames are addressed by index, never by time. Unreadable, empty and truncated input raises
:class:`vidstyle.errors.InputError` naming the file.
"""

from __future__ import annotations

import logging
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import InputError

log = logging.getLogger(__name__)

#: A container may declare one frame more than it decodes (some muxers estimate the count from
#: duration x fps); a larger shortfall means the file is cut off.
FRAME_COUNT_SLACK = 1


@dataclass
class Video:
    frames: np.ndarray
    """float32 (frames, height, width), grayscale in [0, 1]."""
    fps: float
    path: str

    @property
    def shape(self) -> tuple[int, int, int]:
        return tuple(self.frames.shape)  # type: ignore[return-value]


def read_gray(path: str | os.PathLike) -> Video:
    """Decode every frame of ``path`` with OpenCV as grayscale float32 in [0, 1]."""
    import cv2

    path = Path(path)
    if not path.is_file():
        raise InputError(f"{path}: file not found")
    cap = cv2.VideoCapture(str(path))
    try:
        if not cap.isOpened():
            raise InputError(f"{path}: cannot be read as video")
        declared = int(cap.get(cv2.CAP_PROP_FRAME_COUNT) or 0)
        fps = float(cap.get(cv2.CAP_PROP_FPS) or 0.0)
        frames: list[np.ndarray] = []
        while True:
            ok, frame = cap.read()
            if not ok or frame is None:
                break
            if frame.ndim == 3:
                frame = cv2.cvtColor(
                    frame, cv2.COLOR_BGRA2GRAY if frame.shape[2] == 4 else cv2.COLOR_BGR2GRAY
                )
            if frames and frame.shape != frames[0].shape:
                raise InputError(f"{path}: frame {len(frames)} has size {frame.shape}, not {frames[0].shape}")
            frames.append(frame)
    finally:
        cap.release()
    if not frames:
        raise InputError(f"{path}: cannot be read as video (no frame could be decoded)")
    if declared > 0 and len(frames) < declared - FRAME_COUNT_SLACK:
        raise InputError(f"{path}: truncated video (decoded {len(frames)} of {declared} frames)")
    vol = np.stack(frames).astype(np.float32)
    if frames[0].dtype == np.uint16:
        vol *= np.float32(1 / 65535)
    else:
        vol *= np.float32(1 / 255)
    log.debug("%s: %d frames %dx%d at %.3g fps", path, *vol.shape, fps)
    return Video(frames=vol, fps=fps, path=str(path))
