"""What one annotation server holds: its videos (one open, locked reader each, with an encoded-frame cache and
read-ahead) and the annotations store (atomic, schema-validated saves tied to each video's sha256 and
decoded frame count; a save from a stale revision is refused)."""

from __future__ import annotations

import copy
import logging
import os
import threading
from collections import OrderedDict
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import InputError
from ..formats import FormatError
from ..formats.annotations import (
    Annotations,
    VideoAnnotations,
    check_performer,
    file_sha256,
    from_document,
    read_annotations,
    resolve_video_path,
    stored_path,
    to_document,
    write_annotations,
)
from ..video import VideoReader

log = logging.getLogger(__name__)

#: encoded frames kept per video (a window, never the video)
IMAGE_CACHE = 48
#: frames decoded and encoded ahead of the last one asked for (so stepping forward hits the cache)
READ_AHEAD = 4
JPEG_QUALITY = 90


class Conflict(Exception):
    """A save from a page that did not see the current revision."""

    def __init__(self, current: int) -> None:
        self.current = current
        super().__init__(f"the annotations changed since this page loaded them (now at revision {current}); "
                         f"reload to see them")


@dataclass
class Video:
    """One video of the session, addressed by ``id`` (its position on the command line)."""

    id: str
    path: Path
    sha256: str
    reader: VideoReader
    lock: threading.Lock = field(default_factory=threading.Lock)
    _cache_lock: threading.Lock = field(default_factory=threading.Lock)
    _cache: OrderedDict = field(default_factory=OrderedDict)
    _wanted: int = -1
    _pool: ThreadPoolExecutor | None = None

    @property
    def frames(self) -> int:
        return len(self.reader)

    @property
    def timestamps(self) -> np.ndarray:
        return self.reader.timestamps

    @property
    def fps(self) -> float:
        return float(self.reader.info.fps)

    def describe(self) -> dict[str, Any]:
        return {"id": self.id, "name": self.path.name, "frames": self.frames, "fps": self.fps,
                "width": self.reader.width, "height": self.reader.height, "sha256": self.sha256,
                "duration": float(self.reader.info.duration),
                "constant_rate": bool(self.reader.info.constant_rate)}

    def image(self, index: int, fmt: str = "jpeg", read_ahead: bool = True) -> bytes:
        """The encoded image of decoded frame ``index`` (``IndexError`` outside the video).

        ``lock`` guards the reader (decoding); ``_cache_lock`` the encoded-frame cache, held only for a
        look-up or an insert, so a cached frame is served while the read-ahead decodes another."""
        if not 0 <= index < self.frames:
            raise IndexError(index)
        self._wanted = index
        data = self._cached(index, fmt)
        if data is None:
            with self.lock:
                data = self._cached(index, fmt)  # the read-ahead may have made it meanwhile
                img = self.reader.frame(index) if data is None else None
            if data is None:
                data = self._store(index, fmt, self._encode(img, fmt))
        if read_ahead and fmt == "jpeg" and READ_AHEAD:
            if self._pool is None:
                self._pool = ThreadPoolExecutor(1, thread_name_prefix=f"read-ahead-{self.id}")
            self._pool.submit(self._read_ahead, index)
        return data

    def _cached(self, index: int, fmt: str) -> bytes | None:
        with self._cache_lock:
            data = self._cache.get((index, fmt))
            if data is not None:
                self._cache.move_to_end((index, fmt))
            return data

    def _store(self, index: int, fmt: str, data: bytes) -> bytes:
        with self._cache_lock:
            self._cache[(index, fmt)] = data
            while len(self._cache) > IMAGE_CACHE:
                self._cache.popitem(last=False)
        return data

    def _encode(self, img: np.ndarray, fmt: str) -> bytes:
        import cv2

        if fmt == "png":
            ok, buf = cv2.imencode(".png", img, [cv2.IMWRITE_PNG_COMPRESSION, 1])
        else:
            ok, buf = cv2.imencode(".jpg", img, [cv2.IMWRITE_JPEG_QUALITY, JPEG_QUALITY])
        if not ok:  # pragma: no cover - OpenCV encodes any uint8 image
            raise InputError(f"{self.path}: a frame cannot be encoded")
        return buf.tobytes()

    def _read_ahead(self, index: int) -> None:
        for j in range(index + 1, min(self.frames, index + 1 + READ_AHEAD)):
            if self._wanted != index:  # the page moved on: stop, do not hold the reader
                return
            if self._cached(j, "jpeg") is not None:
                continue
            try:
                with self.lock:
                    img = self.reader.frame(j)
            except InputError:
                return
            self._store(j, "jpeg", self._encode(img, "jpeg"))

    def close(self) -> None:
        if self._pool is not None:
            self._pool.shutdown(wait=True, cancel_futures=True)
        with self.lock:
            self.reader.close()


def open_videos(paths: list[str | os.PathLike]) -> list[Video]:
    videos: list[Video] = []
    seen: dict[str, Path] = {}
    for k, p in enumerate(paths):
        p = Path(p)
        reader = VideoReader(p)
        sha = file_sha256(p)
        if sha in seen:
            reader.close()
            raise InputError(f"{p}: the same video as {seen[sha]} (identical content)")
        seen[sha] = p
        videos.append(Video(str(k), p.resolve(), sha, reader))
    return videos


class Store:
    """The annotations file of a session: the current :class:`Annotations` and its revision.

    Videos of the file not opened in this session are kept as they are. A video is matched by content
    (sha256); a file entry with the same path but another content, or the same content but another decoded
    frame count, is refused at start (an annotation never lands on another video)."""

    def __init__(self, path: str | os.PathLike, videos: list[Video], classes: list[str]) -> None:
        self.path = Path(path)
        self.videos = {v.id: v for v in videos}
        self.lock = threading.Lock()
        if self.path.exists():
            ann = read_annotations(self.path)
        else:
            ann = Annotations(classes=list(classes), videos=[], revision=0)
        for c in classes:
            if c not in ann.classes:
                ann.classes.append(c)
        by_sha = {v.sha256: v for v in ann.videos}
        for v in videos:
            entry = by_sha.get(v.sha256)
            if entry is None:
                for other in ann.videos:
                    if resolve_video_path(self.path, other) == v.path:
                        raise FormatError(self.path, "sha256", f"annotates {other.path} with another content "
                                          "(the video file changed since it was annotated); refusing to put "
                                          "its marks on this video")
                entry = VideoAnnotations(stored_path(self.path, v.path), v.sha256, v.frames, v.fps)
                ann.videos.append(entry)
            elif entry.frames != v.frames:
                raise FormatError(self.path, "frames", f"{entry.path}: the file says {entry.frames} frames, "
                                  f"{v.path} decodes to {v.frames}")
            check_performer(entry, v.reader.width, v.reader.height, self.path)
        to_document(ann)  # validate the merged state before serving it
        self.ann = ann

    def entry(self, video_id: str) -> VideoAnnotations:
        return self.ann.video(self.videos[video_id].sha256)  # type: ignore[return-value]

    def state(self) -> dict[str, Any]:
        """The API view: revision, classes, and per served video its transitions, segments and performer
        choice (``{frame, x, y}`` as in the file, or null)."""
        with self.lock:
            doc = to_document(self.ann)
        by_sha = {v["sha256"]: v for v in doc["videos"]}
        return {"revision": doc["revision"], "classes": doc["classes"],
                "videos": [{"id": v.id, "transitions": by_sha[v.sha256]["transitions"],
                            "segments": by_sha[v.sha256]["segments"],
                            "performer": by_sha[v.sha256].get("performer")} for v in self.videos.values()]}

    def save(self, body: Any) -> int:
        """Apply an API-view ``body`` (see :meth:`state`) made at ``body["revision"]``; write; return the
        new revision. :class:`Conflict` on a stale revision, :class:`FormatError` on invalid content; in
        both cases nothing changes."""
        if not isinstance(body, dict):
            raise FormatError("request", None, "expected a JSON object")
        rev = body.get("revision")
        if isinstance(rev, bool) or not isinstance(rev, int):
            raise FormatError("request", "revision", "expected the integer revision the page loaded")
        with self.lock:
            on_disk = self._disk_revision()
            if rev != self.ann.revision or (on_disk is not None and on_disk != self.ann.revision):
                raise Conflict(max(self.ann.revision, on_disk or 0))
            new = self.apply(body)
            new.revision = self.ann.revision + 1
            write_annotations(self.path, new)
            self.ann = new
            return new.revision

    def apply(self, body: dict) -> Annotations:
        """The annotations with ``body``'s classes and per-video marks put in (validated, not saved)."""
        doc = to_document(self.ann)
        if "classes" in body:
            doc["classes"] = body["classes"]
        vids = body.get("videos", [])
        if not isinstance(vids, list):
            raise FormatError("request", "videos", "expected a list")
        seen = set()
        for k, v in enumerate(vids):
            if not isinstance(v, dict) or v.get("id") not in self.videos or v.get("id") in seen:
                raise FormatError("request", f"videos[{k}].id", "not a video of this session (or repeated)")
            seen.add(v["id"])
            sha = self.videos[v["id"]].sha256
            target = next(d for d in doc["videos"] if d["sha256"] == sha)
            extra = set(v) - {"id", "transitions", "segments", "performer"}
            if extra:
                raise FormatError("request", f"videos[{k}]", f"unknown field(s) {sorted(extra)}")
            for key in ("transitions", "segments"):
                if key in v:
                    target[key] = v[key]
            if "performer" in v:  # null clears the choice (the file then has none)
                target.pop("performer", None)
                if v["performer"] is not None:
                    target["performer"] = v["performer"]
        new = from_document(copy.deepcopy(doc), "request")
        for vid in self.videos.values():  # the file cannot know the frame size; the server does
            check_performer(new.video(vid.sha256), vid.reader.width, vid.reader.height, "request")
        return new

    def _disk_revision(self) -> int | None:
        if not self.path.exists():
            return None
        try:
            return read_annotations(self.path).revision
        except FormatError:
            return None
