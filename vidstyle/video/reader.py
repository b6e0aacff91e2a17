"""Frame-exact, streaming video reading: the one place vidstyle decodes video.

Frames are addressed by **decoded index**: frame ``i`` is the ``i``-th picture the decoder yields in
presentation order, never ``time x fps`` and never the container's declared frame count. Opening a file
demuxes its packets once (no decoding; about a second for ten minutes of 1080p) to learn every frame's
presentation timestamp and the key frames; after that

* ``iter_frames()`` streams frames in order, holding one decoded frame at a time;
* ``frame(i)`` seeks to the key frame at or before ``i`` and decodes forward to exactly ``i``
  (a short forward step from the last frame decoded reuses the open decoder, so stepping is cheap);
* a *working* rate and size (``fps=``, ``height=``) resamples in time by timestamp (nearest decoded frame
  to each tick of the working clock, so constant and variable frame rate both work) and in space with
  area averaging (libswscale). The method runs at 20 fps on a figure about 60-100 px tall.

Frames come *upright*, as a player shows them: the stream's display matrix (phones store portrait video
as rotated landscape pictures) is applied exactly (:mod:`vidstyle.video.orientation`), so ``width`` and
``height`` and every pixel coordinate refer to the displayed frame. ``autorotate=False`` gives the
decoded pictures as coded.

Unreadable, empty and truncated input raises :class:`vidstyle.errors.InputError` naming the file.
"""

from __future__ import annotations

import logging
import os
from collections import OrderedDict
from collections.abc import Iterator
from dataclasses import dataclass
from fractions import Fraction
from pathlib import Path

import numpy as np

from ..errors import InputError
from .orientation import (
    UPRIGHT,
    Orientation,
    orientation_from_matrix,
    orientation_from_rotate_tag,
    parse_display_matrix,
    rotation_of,
)

log = logging.getLogger(__name__)

#: decoded frames kept for random access (a window, never the video)
CACHE_FRAMES = 16
#: FFmpeg demuxers of still images (a PNG renamed .mp4 is one picture, not a video); any "*_pipe" too
IMAGE_FORMATS = frozenset({"image2", "image2pipe", "png_pipe", "jpeg_pipe", "webp_pipe", "bmp_pipe", "tiff_pipe"})


@dataclass(frozen=True)
class VideoInfo:
    """What the demuxer says of a video stream, with frames counted by decoding order."""

    path: str
    frames: int
    """number of frames (packets that carry a picture), in presentation order"""
    fps: float
    """average rate: (frames - 1) / (last timestamp - first timestamp); 0 for a one-frame video"""
    width: int
    """displayed width (after the display matrix); the decoded pictures' is ``coded_size[0]``"""
    height: int
    """displayed height"""
    timestamps: np.ndarray
    """float64 (frames,), seconds from the first frame, increasing"""
    orientation: Orientation = UPRIGHT
    """how the decoded pictures are turned for display (from the stream's display matrix)"""
    rotation: float = 0.0
    """the display matrix's counter-clockwise rotation in degrees (as ffprobe's ``rotation``; 0 if none)"""

    @property
    def coded_size(self) -> tuple[int, int]:
        """(width, height) of the decoded pictures, before the display matrix"""
        return self.orientation.coded_size(self.width, self.height)

    @property
    def duration(self) -> float:
        if self.frames < 2:
            return 0.0
        return float(self.timestamps[-1] + (self.timestamps[-1] - self.timestamps[0]) / (self.frames - 1))

    @property
    def constant_rate(self) -> bool:
        if self.frames < 3:
            return True
        d = np.diff(self.timestamps)
        return bool(np.ptp(d) <= 0.01 * float(np.median(d)) + 2e-3)


def _open(path: Path):
    import av

    if not path.exists():
        raise InputError(f"{path}: file not found")
    if path.is_dir():
        raise InputError(f"{path}: is a directory, not a video")
    try:
        container = av.open(str(path), mode="r", metadata_errors="ignore")
    except (av.error.FFmpegError, UnicodeDecodeError, ValueError) as e:
        raise InputError(f"{path}: cannot be read as video ({_reason(e)})") from None
    if not container.streams.video:
        container.close()
        raise InputError(f"{path}: cannot be read as video (no video stream)")
    formats = (container.format.name or "").split(",")
    if any(f in IMAGE_FORMATS or f.endswith("_pipe") for f in formats):
        codec = container.streams.video[0].codec_context.name
        container.close()
        raise InputError(f"{path}: is a still image ({codec}), not a video")
    return container


def _decodable(container, stream) -> Iterator:
    """Decoded frames of ``stream`` in presentation order, leaving out corrupt packets (the last packet of
    a file cut short is truncated: the demuxer flags it, :func:`probe` does not count it, and feeding it to
    the decoder would lose the frames still held for reordering)."""
    for packet in container.demux(stream):
        if packet.size and packet.is_corrupt:
            continue
        yield from packet.decode()


def _display_matrix(stream, packet) -> tuple[bool, tuple[int, ...] | None]:
    """(a picture was decoded, its display matrix or None) for one demuxed packet."""
    import av

    try:
        frames = stream.decode(packet)
    except (av.error.FFmpegError, ValueError):
        return False, None
    for frame in frames:
        for side in frame.side_data:
            if getattr(side.type, "name", str(side.type)) == "DISPLAYMATRIX":
                return True, parse_display_matrix(bytes(side))
        return True, None
    return False, None


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def _reason(e: Exception) -> str:
    return " ".join(str(getattr(e, "strerror", None) or e).split()) or type(e).__name__


def probe(path: str | os.PathLike, autorotate: bool = True) -> VideoInfo:
    """Index ``path`` by demuxing its video stream (decoding only the first picture, for its display
    matrix). ``autorotate=False``: report the decoded pictures' size and no orientation."""
    import av

    path = Path(path)
    container = _open(path)
    try:
        stream = container.streams.video[0]
        tb = stream.time_base or Fraction(1, 1)
        pts: list[int] = []
        missing_pts = 0
        corrupt = 0
        matrix = None
        need_matrix = True
        try:
            for packet in container.demux(stream):
                if packet.size == 0:  # flush packet at the end
                    continue
                if packet.is_corrupt:  # a truncated packet (a file cut short): no frame decodes from it
                    corrupt += 1
                    continue
                if need_matrix:  # decode until the first picture: its side data carries the display matrix
                    found, matrix = _display_matrix(stream, packet)
                    need_matrix = not found and len(pts) < 64
                if packet.pts is None:
                    missing_pts += 1
                    pts.append(packet.dts if packet.dts is not None else len(pts))
                else:
                    pts.append(packet.pts)
        except av.error.FFmpegError as e:
            raise InputError(f"{path}: truncated or corrupt video ({_reason(e)})") from None
        width = int(stream.codec_context.width or 0)
        height = int(stream.codec_context.height or 0)
        rotate_tag = stream.metadata.get("rotate")
    finally:
        container.close()
    if matrix is not None:
        orientation = orientation_from_matrix(matrix, str(path))
        rotation = float(rotation_of(matrix))
    else:
        orientation = orientation_from_rotate_tag(rotate_tag, str(path))
        rotation = -float(rotate_tag) if rotate_tag not in (None, "") and _is_number(rotate_tag) else 0.0
    if not autorotate:
        orientation, rotation = UPRIGHT, 0.0
    if not orientation.identity:
        log.info("%s: display matrix: %s", path, orientation.describe())
    width, height = orientation.display_size(width, height)
    if not pts:
        raise InputError(f"{path}: cannot be read as video (no frame could be decoded)")
    if corrupt:
        log.warning("%s: %d corrupt packet(s) left out (truncated or damaged video)", path, corrupt)
    if missing_pts:
        log.debug("%s: %d packets without pts; using dts / order", path, missing_pts)
    order = np.unique(np.asarray(pts, dtype=np.int64))
    if len(order) != len(pts):
        raise InputError(f"{path}: corrupt video ({len(pts) - len(order)} frames share a timestamp)")
    t = (order - order[0]).astype(np.float64) * float(tb)
    # exact rational arithmetic, so that 39 frames over 39 * 1/20 s give 20.0, not 19.999999999999996
    span = int(order[-1] - order[0])
    fps = float(Fraction(len(t) - 1) / (span * Fraction(tb))) if len(t) > 1 and span > 0 else 0.0
    info = VideoInfo(str(path), len(order), float(fps), width, height, t, orientation, rotation)
    info.__dict__["_pts"] = order  # the raw timestamps, for exact seeking (not part of the public view)
    return info


class VideoReader:
    """Frames of one video by decoded index, optionally at a working rate and size.

    ``fps``: working frame rate (``None``: every decoded frame). Only ever lowers the rate; a video slower
    than ``fps`` keeps its own frames. ``height``: working height in pixels, width scaled to keep the
    aspect ratio (``None``: native size); with ``enlarge=False`` a video not taller than ``height`` keeps
    its size. ``gray``: single-channel frames. Frames are uint8, BGR (OpenCV's
    order) unless ``gray``, upright as a player shows them (the display matrix applied; ``autorotate=False``
    keeps the decoded pictures as coded). Use as a context manager, or call :meth:`close`.
    """

    def __init__(
        self,
        path: str | os.PathLike,
        fps: float | None = None,
        height: int | None = None,
        gray: bool = False,
        enlarge: bool = True,
        autorotate: bool = True,
    ) -> None:
        if fps is not None and not fps > 0:
            raise InputError(f"fps: must be positive, got {fps}")
        if height is not None and not (isinstance(height, (int, np.integer)) and height >= 8):
            raise InputError(f"height: must be an integer of at least 8 pixels, got {height!r}")
        self.path = Path(path)
        self.info = probe(self.path, autorotate=autorotate)
        self.orientation = self.info.orientation
        if self.info.width <= 0 or self.info.height <= 0:
            raise InputError(f"{self.path}: cannot be read as video (no frame size)")
        self.gray = gray
        self._pts: np.ndarray = self.info.__dict__["_pts"]
        self.source_index = working_indices(self.info.timestamps, fps)
        """int64 (len(self),): decoded index of each working frame"""
        if height is None or height == self.info.height or (not enlarge and self.info.height < height):
            self.size = (self.info.width, self.info.height)
        else:
            self.size = (max(1, int(round(self.info.width * height / self.info.height))), int(height))
        self.fps = self.info.fps if fps is None or fps >= self.info.fps or self.info.fps == 0 else float(fps)
        self._container = None
        self._decoder: Iterator | None = None
        self._next_src = 0  # decoded index the open decoder yields next
        self._cache: OrderedDict[int, np.ndarray] = OrderedDict()
        self._reformatter = None  # one libswscale context for every frame (made on first use)

    # ---------------------------------------------------------------- public
    def __len__(self) -> int:
        return len(self.source_index)

    @property
    def width(self) -> int:
        return self.size[0]

    @property
    def height(self) -> int:
        return self.size[1]

    @property
    def timestamps(self) -> np.ndarray:
        """seconds of each working frame (from the first decoded frame)"""
        return self.info.timestamps[self.source_index]

    def __enter__(self) -> "VideoReader":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def close(self) -> None:
        if self._container is not None:
            self._container.close()
        self._container = None
        self._decoder = None
        self._reformatter = None
        self._cache.clear()

    def clear_cache(self) -> None:
        """Drop the decoded frames kept for random access (the next ``frame(i)`` decodes again)."""
        self._cache.clear()

    def __iter__(self) -> Iterator[np.ndarray]:
        for _, frame in self.iter_frames():
            yield frame

    def iter_frames(self, start: int = 0, stop: int | None = None) -> Iterator[tuple[int, np.ndarray]]:
        """(working index, frame) for ``start <= index < stop``, streamed in order."""
        stop = len(self) if stop is None else min(stop, len(self))
        for i in range(max(0, start), stop):
            yield i, self.frame(i)

    def frame(self, index: int) -> np.ndarray:
        """The working frame ``index`` (0-based); ``IndexError`` outside ``0 <= index < len(self)``."""
        n = len(self)
        if not isinstance(index, (int, np.integer)):
            raise TypeError(f"frame index must be an integer, got {type(index).__name__}")
        if not 0 <= index < n:
            raise IndexError(f"{self.path}: frame {index} out of range (0..{n - 1})")
        src = int(self.source_index[index])
        cached = self._cache.get(src)
        if cached is not None:
            self._cache.move_to_end(src)
            return cached
        img = self._convert(self._decode(src))
        self._cache[src] = img
        while len(self._cache) > CACHE_FRAMES:
            self._cache.popitem(last=False)
        return img

    __getitem__ = frame

    def read_all(self, dtype=np.uint8) -> np.ndarray:
        """Every working frame stacked (F, H, W[, 3]): for tests and short clips only."""
        return np.stack([np.asarray(f, dtype=dtype) for f in self])

    # --------------------------------------------------------------- private
    def _convert(self, frame) -> np.ndarray:
        """A decoded ``av.VideoFrame`` to the working size in BGR in one libswscale pass (area averaging
        when shrinking, bilinear when enlarging): converting the full-size picture first and resizing
        after would cost several times the decoding of a 1080p stream. Gray is OpenCV's BGR -> gray of
        that, so that gray frames equal what OpenCV's own decoding gives (its BGR is bit-identical).
        The conversion goes through one reader-wide ``VideoReformatter``, which keeps its swscale context
        from frame to frame: ``frame.to_ndarray(format=...)`` builds a new one per call, which costs
        about 4 ms even at 160x120 (17 times the conversion itself), for identical pixels."""
        import cv2

        if self._reformatter is None:
            from av.video.reformatter import VideoReformatter

            self._reformatter = VideoReformatter()
        cw, ch = self.orientation.coded_size(*self.size)  # working size before the display matrix
        if (frame.width, frame.height) == (cw, ch):
            img = self._reformatter.reformat(frame, format="bgr24").to_ndarray()
        else:
            interp = "AREA" if ch < frame.height else "BILINEAR"
            img = self._reformatter.reformat(frame, width=cw, height=ch, format="bgr24",
                                             interpolation=interp).to_ndarray()
        img = cv2.cvtColor(img, cv2.COLOR_BGR2GRAY) if self.gray else np.ascontiguousarray(img)
        img = self.orientation.apply(img)
        img.setflags(write=False)
        return img

    def _start(self, src: int) -> None:
        """Open (or reposition) the decoder so that it yields decoded frame ``src`` next or soon."""
        import av

        if self._container is None:
            self._container = _open(self.path)
            self._container.streams.video[0].thread_type = "AUTO"
        stream = self._container.streams.video[0]
        if src > 0:
            try:
                self._container.seek(int(self._pts[src]), backward=True, any_frame=False, stream=stream)
            except av.error.FFmpegError:
                self._container.seek(0, stream=stream)
        else:
            self._container.seek(int(self._pts[0]), backward=True, any_frame=False, stream=stream)
        self._decoder = _decodable(self._container, stream)
        self._next_src = -1  # unknown until the first frame's pts is seen

    def _decode(self, src: int):
        import av

        # continue the running decoder for a short step forward; otherwise seek to a key frame
        if self._decoder is None or not (0 <= self._next_src <= src <= self._next_src + 48):
            self._start(src)
        want = int(self._pts[src])
        try:
            for frame in self._decoder:  # type: ignore[union-attr]
                pts = frame.pts if frame.pts is not None else frame.dts
                if pts is None:
                    continue
                k = int(np.searchsorted(self._pts, pts))
                self._next_src = k + 1
                if pts < want:
                    continue
                if pts > want:
                    break
                return frame
        except av.error.FFmpegError as e:
            self._decoder = None
            raise InputError(f"{self.path}: frame {src} cannot be decoded; truncated or corrupt video "
                             f"({_reason(e)})") from None
        self._decoder = None
        raise InputError(f"{self.path}: frame {src} cannot be decoded (truncated or corrupt video)")


def working_indices(timestamps: np.ndarray, fps: float | None) -> np.ndarray:
    """Decoded index of each frame of a working clock at ``fps``: the decoded frame nearest to each tick
    ``k / fps`` (ties to the earlier frame). ``None``, or a rate at or above the video's, keeps every
    frame."""
    t = np.asarray(timestamps, dtype=np.float64)
    n = len(t)
    if fps is None or n < 2:
        return np.arange(n, dtype=np.int64)
    native = (n - 1) / t[-1] if t[-1] > 0 else 0.0
    if native == 0 or fps >= native * (1 - 1e-6):
        return np.arange(n, dtype=np.int64)
    step = 1.0 / fps
    ticks = np.arange(0.0, t[-1] + 0.5 / native, step)
    right = np.clip(np.searchsorted(t, ticks, side="left"), 1, n - 1)
    left = right - 1
    pick = np.where(np.abs(t[right] - ticks) < np.abs(ticks - t[left]) - 1e-9, right, left)
    pick = np.unique(pick)  # a tick past the end repeats the last frame
    return pick.astype(np.int64)
