"""Display orientation: the stream's display matrix (or legacy ``rotate`` tag) as a player applies it.

Phones store portrait video as landscape pictures plus a *display matrix* (FFmpeg's
``AV_PKT_DATA_DISPLAYMATRIX``; the old ``rotate`` metadata tag in MOV/MP4 is turned into one by the
demuxer) that tells a player to rotate and/or mirror the decoded picture. vidstyle shows every consumer
the frame as a player shows it, so pixel coordinates in every artifact are in that displayed frame.

The mapping follows FFmpeg's own ``-autorotate`` (fftools): the rotation angle is
``-round(av_display_rotation_get(M))`` clockwise, normalised to [0, 360); 90 and 270 degrees are
transposes (``clock``, ``cclock`` and their mirrored ``*_flip`` forms, chosen by the sign of ``M[3]``),
180 and 0 degrees are horizontal / vertical flips chosen by the signs of ``M[0]`` and ``M[4]``. A
rotation that is not a multiple of 90 degrees (not made by cameras) is left as decoded, with a warning.
Every one of the eight orientations is a transpose followed by optional flips, so it is exact
(a view of the pixels, no resampling).
"""

from __future__ import annotations

import logging
import math
import struct
from dataclasses import dataclass

import numpy as np

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class Orientation:
    """The displayed frame = the decoded frame, transposed (rows <-> columns) if ``transpose``, then
    mirrored left-right if ``flip_x`` and top-bottom if ``flip_y``."""

    transpose: bool = False
    flip_x: bool = False
    flip_y: bool = False

    @property
    def identity(self) -> bool:
        return not (self.transpose or self.flip_x or self.flip_y)

    def display_size(self, width: int, height: int) -> tuple[int, int]:
        """(width, height) of the displayed frame of a decoded ``width`` x ``height`` frame."""
        return (height, width) if self.transpose else (width, height)

    def coded_size(self, width: int, height: int) -> tuple[int, int]:
        """(width, height) of the decoded frame whose displayed frame is ``width`` x ``height``."""
        return (height, width) if self.transpose else (width, height)

    def apply(self, image: np.ndarray) -> np.ndarray:
        """The displayed frame of a decoded ``image`` (H, W[, C]); the input itself when identity."""
        if self.identity:
            return image
        out = np.swapaxes(image, 0, 1) if self.transpose else image
        if self.flip_x:
            out = out[:, ::-1]
        if self.flip_y:
            out = out[::-1]
        return np.ascontiguousarray(out)

    def describe(self) -> str:
        names = {(False, False, False): "upright", (True, True, False): "rotated 90 deg clockwise",
                 (True, False, True): "rotated 90 deg counter-clockwise", (False, True, True): "rotated 180 deg",
                 (False, True, False): "mirrored left-right", (False, False, True): "mirrored top-bottom",
                 (True, False, False): "transposed", (True, True, True): "anti-transposed"}
        return names[(self.transpose, self.flip_x, self.flip_y)]


UPRIGHT = Orientation()


def parse_display_matrix(data: bytes) -> tuple[int, ...] | None:
    """The nine int32 entries of a display-matrix side-data payload (36 bytes), or ``None``."""
    if data is None or len(data) != 36:
        return None
    return struct.unpack("<9i", bytes(data))


def rotation_of(matrix: tuple[int, ...]) -> float:
    """FFmpeg's ``av_display_rotation_get``: degrees the matrix rotates the frame counter-clockwise."""
    scale0 = math.hypot(matrix[0], matrix[3])
    scale1 = math.hypot(matrix[1], matrix[4])
    if scale0 == 0.0 or scale1 == 0.0:
        return float("nan")
    return -math.degrees(math.atan2(matrix[1] / scale1, matrix[0] / scale0))


def orientation_from_matrix(matrix: tuple[int, ...] | None, where: str = "") -> Orientation:
    """The displayed orientation of a display matrix, as FFmpeg's ``-autorotate`` applies it."""
    if matrix is None:
        return UPRIGHT
    rot = rotation_of(matrix)
    if not math.isfinite(rot):
        log.warning("%sdegenerate display matrix %s ignored", f"{where}: " if where else "", matrix)
        return UPRIGHT
    theta = -round(rot)  # clockwise degrees, as fftools' get_rotation
    theta -= 360 * math.floor(theta / 360 + 0.9 / 360)
    if abs(theta - 90) < 1.0:  # transpose=clock, or cclock_flip when mirrored
        return Orientation(True, False, False) if matrix[3] > 0 else Orientation(True, True, False)
    if abs(theta - 180) < 1.0:
        return Orientation(False, matrix[0] < 0, matrix[4] < 0)
    if abs(theta - 270) < 1.0:  # transpose=cclock, or clock_flip when mirrored
        return Orientation(True, True, True) if matrix[3] < 0 else Orientation(True, False, True)
    if abs(theta) < 1.0 or abs(theta - 360) < 1.0:
        return Orientation(False, False, matrix[4] < 0)
    log.warning("%sdisplay rotation of %.1f degrees is not a multiple of 90; frames are used as decoded",
                f"{where}: " if where else "", theta)
    return UPRIGHT


def orientation_from_rotate_tag(value: str | None, where: str = "") -> Orientation:
    """The legacy ``rotate`` metadata tag (clockwise degrees, as old MP4 files and ffmpeg wrote it)."""
    if value is None:
        return UPRIGHT
    try:
        deg = int(round(float(value))) % 360
    except ValueError:
        return UPRIGHT
    return {0: UPRIGHT, 90: Orientation(True, True, False), 180: Orientation(False, True, True),
            270: Orientation(True, False, True)}.get(deg, UPRIGHT)
