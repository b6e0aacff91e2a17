"""The one video writer: frames (and, for variable frame rate, their times) to a file, atomically.

Codec by suffix: ``.mp4`` / ``.m4v`` / ``.mov`` H.264 (libx264, yuv420p, ``crf`` 17 by default: visually
lossless, so features computed on a written video are close to the rendered frames), ``.mkv`` FFV1
(lossless, for tests), ``.avi`` Motion-JPEG. Encoding is single-threaded, so the same frames give the
same bytes on every machine; ``background=True`` runs that one encoder on a thread of its own, beside the
caller that makes the frames (the same frames in the same order: the same bytes). The file appears under its name only when :meth:`close`
succeeds; an exception inside ``with VideoWriter(...)`` leaves no file.
"""

from __future__ import annotations

import contextlib
import os
import tempfile
from collections.abc import Iterable
from fractions import Fraction
from pathlib import Path

import numpy as np

from ..errors import InputError

CODECS = {".mp4": "libx264", ".m4v": "libx264", ".mov": "libx264", ".mkv": "ffv1", ".avi": "mjpeg"}

#: time base of written streams: fine enough for any frame time given in seconds (1/90 kHz, as MPEG-TS)
TIME_BASE = Fraction(1, 90000)


class VideoWriter:
    """Frame-by-frame writer; size fixed by the first frame. ``write(frame, time=None)``: ``frame`` is
    (H, W, 3) uint8 BGR or (H, W) uint8 gray; ``time`` (seconds) gives a variable frame rate, otherwise
    frame ``k`` is shown at ``k / fps``."""

    def __init__(self, path: str | os.PathLike, fps: float, crf: int = 17, background: bool = False) -> None:
        self.path = Path(path)
        #: encode on a thread of its own (:meth:`_encode_loop`; the encoder releases the GIL), so that
        #: making the next frame and encoding this one overlap
        self.background = bool(background)
        self._queue = None
        self._thread = None
        self._error: BaseException | None = None
        self._stopping = False
        suffix = self.path.suffix.lower()
        if suffix not in CODECS:
            raise InputError(f"{path}: video must end in {', '.join(CODECS)} (got {suffix or 'no suffix'!r})")
        if not (isinstance(fps, (int, float, np.number)) and np.isfinite(fps) and fps > 0):
            raise InputError(f"fps: must be a positive number, got {fps!r}")
        self.fps = float(fps)
        self.codec = CODECS[suffix]
        self.crf = int(crf)
        self.count = 0
        self.size: tuple[int, int] | None = None
        self._last_pts = -1
        self.path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=f".{self.path.stem}.", suffix=f".tmp{suffix}", dir=self.path.parent)
        os.close(fd)
        self._tmp = Path(tmp)
        self._container = None
        self._stream = None

    def __enter__(self) -> "VideoWriter":
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        if exc_type is None:
            self.close()
        else:
            self.abort()

    def _open(self, width: int, height: int) -> None:
        import av

        self._container = av.open(str(self._tmp), mode="w")
        rate = Fraction(self.fps).limit_denominator(1001 * 1000)
        stream = self._container.add_stream(self.codec, rate=rate)
        stream.width, stream.height = width, height
        if self.codec == "libx264":
            # yuv420p needs even sizes; odd ones keep full chroma instead of being padded or cropped
            even = width % 2 == 0 and height % 2 == 0
            stream.pix_fmt = "yuv420p" if even else "yuv444p"
            # one encoder thread: x264's output depends on its thread count (the machine's cores by
            # default), so a dataset made on another machine, or under load, would not be byte-identical
            stream.options = {"crf": str(self.crf), "preset": "veryfast", "threads": "1",
                              "x264-params": "threads=1:lookahead-threads=1:sliced-threads=0:mbtree=0:rc-lookahead=0"}
            stream.codec_context.thread_count = 1
        elif self.codec == "ffv1":
            stream.pix_fmt = "bgr0"
        else:
            stream.pix_fmt = "yuvj444p"
            stream.options = {"q:v": "2"}
        stream.time_base = TIME_BASE
        stream.codec_context.time_base = TIME_BASE
        self._stream = stream

    def write(self, frame: np.ndarray, time: float | None = None) -> None:
        import av

        frame = np.asarray(frame)
        if frame.dtype != np.uint8 or not (frame.ndim == 2 or (frame.ndim == 3 and frame.shape[2] == 3)):
            raise ValueError(f"frames must be (H, W, 3) BGR or (H, W) gray uint8, got {frame.shape} {frame.dtype}")
        if frame.ndim == 2:
            frame = np.repeat(frame[:, :, None], 3, axis=2)
        H, W = frame.shape[:2]
        if self._container is None:
            self.size = (W, H)
            self._open(W, H)
        elif (W, H) != self.size:
            raise ValueError(f"frame size {W}x{H} differs from the first frame's {self.size[0]}x{self.size[1]}")
        t = self.count / self.fps if time is None else float(time)
        pts = int(round(t / TIME_BASE))
        if pts <= self._last_pts:
            raise ValueError(f"frame {self.count}: time {t:.6f} s is not after the previous frame's")
        self._last_pts = pts
        if self._stream.pix_fmt == "yuv420p":  # type: ignore[union-attr]
            # BGR -> YUV 4:2:0 (BT.601, limited range, what decoders assume) by OpenCV: the same frames
            # then always give the same file (libswscale's conversion inside PyAV's encode did not)
            import cv2

            yuv = cv2.cvtColor(np.ascontiguousarray(frame), cv2.COLOR_BGR2YUV_I420)
            vf = av.VideoFrame.from_ndarray(yuv, format="yuv420p")
        else:
            vf = av.VideoFrame.from_ndarray(np.ascontiguousarray(frame), format="bgr24")
        vf.pts = pts
        vf.time_base = TIME_BASE
        if self.background:
            self._put(vf)
        else:
            self._encode(vf)
        self.count += 1

    def _encode(self, vf) -> None:
        for packet in self._stream.encode(vf):  # type: ignore[union-attr]
            self._container.mux(packet)  # type: ignore[union-attr]

    def _put(self, vf) -> None:
        """Hand a frame to the encoder thread (started with the first), at most a few frames ahead of it;
        an error of the encoder is raised here, at the next frame."""
        if self._thread is None:
            import queue
            import threading

            self._queue = queue.Queue(maxsize=4)
            self._thread = threading.Thread(target=self._encode_loop, name="vidstyle-video-encoder", daemon=True)
            self._thread.start()
        if self._error is not None:
            raise self._error
        self._queue.put(vf)  # type: ignore[union-attr]

    def _encode_loop(self) -> None:
        # every frame taken off the queue (so a put never waits forever), encoded until an error or a stop
        while True:
            vf = self._queue.get()  # type: ignore[union-attr]
            if vf is None:
                return
            if self._error is not None or self._stopping:
                continue
            try:
                self._encode(vf)
            except BaseException as e:  # raised in the caller's thread (write, close)
                self._error = e

    def _join(self) -> None:
        """Stop taking frames and wait until the encoder thread has encoded (or dropped) the queued ones."""
        if self._thread is not None:
            self._queue.put(None)  # type: ignore[union-attr]
            self._thread.join()
            self._thread = None

    def close(self) -> Path:
        """Finish the file and move it to its name; no frames written is an :class:`InputError`."""
        if self._tmp is None:
            return self.path
        if self.count == 0:
            self.abort()
            raise InputError(f"{self.path}: no frames to write")
        try:
            self._join()
            if self._error is not None:
                raise self._error
            for packet in self._stream.encode(None):  # type: ignore[union-attr]
                self._container.mux(packet)  # type: ignore[union-attr]
            self._container.close()  # type: ignore[union-attr]
            os.chmod(self._tmp, 0o644)
            os.replace(self._tmp, self.path)
        except BaseException:
            self.abort()
            raise
        self._tmp = None
        return self.path

    def abort(self) -> None:
        """Drop everything written so far (no file appears)."""
        self._stopping = True
        self._join()
        if self._container is not None:
            with contextlib.suppress(Exception):
                self._container.close()
            self._container = None
        if self._tmp is not None:
            with contextlib.suppress(FileNotFoundError):
                self._tmp.unlink()
            self._tmp = None


def write_video(
    frames: Iterable[np.ndarray] | np.ndarray,
    path: str | os.PathLike,
    fps: float,
    times: Iterable[float] | None = None,
    crf: int = 17,
) -> Path:
    """Write frames (BGR or gray uint8) to ``path`` atomically; ``times`` (seconds) for variable rate."""
    with VideoWriter(path, fps, crf=crf) as w:
        if times is None:
            for f in frames:
                w.write(f)
        else:
            for f, t in zip(frames, times, strict=True):
                w.write(f, t)
    return Path(path)
