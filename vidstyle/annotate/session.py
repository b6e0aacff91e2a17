"""What one annotation server holds: its videos (one open, locked reader each, with an encoded-frame cache and
read-ahead) and the annotations store (atomic, schema-validated saves tied to each video's sha256 and
decoded frame count; a save from a stale revision is refused)."""

from __future__ import annotations

import contextlib
import copy
import fcntl
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
from ..fileio import parse_json_bytes
from ..formats import FormatError
from ..formats.annotations import (
    Annotations,
    VideoAnnotations,
    check_performer,
    file_sha256,
    from_document,
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


#: the largest annotations file read (bytes)
MAX_FILE = 64 << 20


class Conflict(Exception):
    """A save from a page that did not see the current revision (or a file changed on disk that cannot be
    used). ``current``: the revision the store is at; the page reloads (``GET /api/annotations``), puts
    its changes onto that state and saves again from ``current``."""

    def __init__(self, current: int, message: str | None = None) -> None:
        self.current = current
        super().__init__(message or f"the annotations changed since this page loaded them (now at revision "
                                    f"{current}); reload them and redo or merge your changes")


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
    frame count, is refused at start (an annotation never lands on another video).

    Several processes may serve one file (two ``annotate`` runs, a script): a save is a compare-and-swap
    on the file itself - under an exclusive ``flock`` of a lock file beside it (``.<name>.lock``, beside
    the symlink's target when the file is a link) the store re-reads the file if it changed on disk, refuses
    a save made from another revision (:class:`Conflict`), and writes. Every read of the state re-reads the
    file when its identity (inode, size, modification time) changed, so a reloaded page sees what another
    process or an editor wrote. An outside edit that kept the revision number counts as a new revision."""

    def __init__(self, path: str | os.PathLike, videos: list[Video], classes: list[str]) -> None:
        self.path = Path(path)
        self.videos = {v.id: v for v in videos}
        self.classes = list(classes)
        self.lock = threading.Lock()
        self._stamp: tuple | None = None
        ann, self._stamp = self._read_disk()
        self.ann = self._merge(ann, self.path)

    # ---------------------------------------------------------------------------------------- the file
    def _lock_path(self) -> Path:
        target = Path(os.path.realpath(self.path))
        return target.parent / f".{target.name}.lock"

    @contextlib.contextmanager
    def file_lock(self):
        """Hold the exclusive lock on the annotations file (blocks while another process saves)."""
        lp = self._lock_path()
        lp.parent.mkdir(parents=True, exist_ok=True)
        fd = os.open(lp, os.O_RDWR | os.O_CREAT | getattr(os, "O_CLOEXEC", 0), 0o666)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX)
            yield
        finally:
            os.close(fd)  # closing the descriptor releases the lock

    def _read_disk(self) -> tuple[Annotations | None, tuple | None]:
        """The file's annotations and its stamp (None, None when there is no file). The stamp and the
        bytes come from one open descriptor, so they belong together."""
        try:
            with open(self.path, "rb") as f:
                st = os.fstat(f.fileno())
                raw = f.read(MAX_FILE + 1)
        except FileNotFoundError:
            return None, None
        except OSError as e:
            raise FormatError(self.path, None, f"cannot be read ({e.strerror or e})") from None
        stamp = (st.st_dev, st.st_ino, st.st_size, st.st_mtime_ns, st.st_ctime_ns)
        if len(raw) > MAX_FILE:
            raise FormatError(self.path, None, f"larger than {MAX_FILE} bytes")
        return from_document(parse_json_bytes(raw, self.path), self.path), stamp

    def _disk_stamp(self) -> tuple | None:
        try:
            st = os.stat(self.path)
        except FileNotFoundError:
            return None
        return (st.st_dev, st.st_ino, st.st_size, st.st_mtime_ns, st.st_ctime_ns)

    def _merge(self, ann: Annotations | None, where) -> Annotations:
        """``ann`` (the file's content, or None) with this session's classes and videos put in, validated."""
        if ann is None:
            ann = Annotations(classes=list(self.classes), videos=[], revision=0)
        known = set(ann.classes)
        for c in self.classes:  # linear: a set of the names, not a list search per name
            if c not in known:
                known.add(c)
                ann.classes.append(c)
        by_sha = {v.sha256: v for v in ann.videos}
        by_path = None
        for v in self.videos.values():
            entry = by_sha.get(v.sha256)
            if entry is None:
                if by_path is None:
                    by_path = {resolve_video_path(self.path, other): other for other in ann.videos}
                other = by_path.get(v.path)
                if other is not None:
                    raise FormatError(where, "sha256", f"annotates {other.path} with another content "
                                      "(the video file changed since it was annotated); refusing to put "
                                      "its marks on this video")
                entry = VideoAnnotations(stored_path(self.path, v.path), v.sha256, v.frames, v.fps)
                ann.videos.append(entry)
            elif entry.frames != v.frames:
                raise FormatError(where, "frames", f"{entry.path}: the file says {entry.frames} frames, "
                                  f"{v.path} decodes to {v.frames}")
            check_performer(entry, v.reader.width, v.reader.height, where)
        to_document(ann)  # validate the merged state before serving it
        return ann

    def refresh(self) -> None:
        """Re-read the file if it changed on disk since this store last read or wrote it (call holding
        ``self.lock``). :class:`Conflict` when the changed file cannot be used (invalid, or it contradicts
        this session's videos): the in-memory state is kept, nothing is overwritten."""
        stamp = self._disk_stamp()
        if stamp == self._stamp:
            return
        if stamp is None:  # the file was removed: keep what we have; the next save writes it again
            self._stamp = None
            return
        try:
            ann, stamp = self._read_disk()
            merged = self._merge(ann, self.path)
        except FormatError as e:
            raise Conflict(self.ann.revision, f"the annotations file changed on disk and cannot be used "
                                              f"({e}); fix or restore it, then reload") from None
        if merged.revision <= self.ann.revision and to_document(merged) != to_document(self.ann):
            merged.revision = self.ann.revision + 1  # an outside edit is a change the page has not seen
        self.ann, self._stamp = merged, stamp
        log.info("annotate: %s changed on disk; now at revision %d", self.path, merged.revision)

    # ---------------------------------------------------------------------------------------- the API
    def entry(self, video_id: str) -> VideoAnnotations:
        return self.ann.video(self.videos[video_id].sha256)  # type: ignore[return-value]

    def state(self) -> dict[str, Any]:
        """The API view: revision, classes, and per served video its transitions, segments and performer
        choice (``{frame, x, y}`` as in the file, or null). The file is re-read when it changed on disk
        (a file that cannot be used is logged and the last good state served)."""
        with self.lock:
            try:
                self.refresh()
            except Conflict as e:
                log.warning("annotate: %s", e)
            doc = to_document(self.ann)
        by_sha = {v["sha256"]: v for v in doc["videos"]}
        return {"revision": doc["revision"], "classes": doc["classes"],
                "videos": [{"id": v.id, "transitions": by_sha[v.sha256]["transitions"],
                            "segments": by_sha[v.sha256]["segments"],
                            "performer": by_sha[v.sha256].get("performer")} for v in self.videos.values()]}

    def save(self, body: Any) -> int:
        """Apply an API-view ``body`` (see :meth:`state`) made at ``body["revision"]``; write; return the
        new revision. :class:`Conflict` on a stale revision, :class:`FormatError` on invalid content; in
        both cases nothing changes. The revision check and the write happen under the file lock, after
        re-reading a file another process changed: two saves from one revision never both succeed."""
        if not isinstance(body, dict):
            raise FormatError("request", None, "expected a JSON object")
        rev = body.get("revision")
        if isinstance(rev, bool) or not isinstance(rev, int):
            raise FormatError("request", "revision", "expected the integer revision the page loaded")
        with self.lock, self.file_lock():
            self.refresh()
            if rev != self.ann.revision:
                raise Conflict(self.ann.revision)
            new = self.apply(body)
            new.revision = self.ann.revision + 1
            write_annotations(self.path, new)
            self.ann, self._stamp = new, self._disk_stamp()
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
        by_sha = {d["sha256"]: d for d in doc["videos"]}
        for k, v in enumerate(vids):
            vid = v.get("id") if isinstance(v, dict) else None
            if not isinstance(vid, str) or vid not in self.videos or vid in seen:
                raise FormatError("request", f"videos[{k}].id", "not a video of this session (or repeated)")
            seen.add(vid)
            target = by_sha[self.videos[vid].sha256]
            extra = set(v) - {"id", "transitions", "segments", "performer"}
            if extra:
                raise FormatError("request", f"videos[{k}]", f"unknown field(s) {sorted(extra)}"[:300])
            for key in ("transitions", "segments"):
                if key in v:
                    target[key] = v[key]
            if "performer" in v:  # null clears the choice (the file then has none)
                target.pop("performer", None)
                if v["performer"] is not None:
                    target["performer"] = v["performer"]
        try:
            new = from_document(copy.deepcopy(doc), "request")
        except RecursionError:
            raise FormatError("request", None, "nested too deeply") from None
        for vid in self.videos.values():  # the file cannot know the frame size; the server does
            check_performer(new.video(vid.sha256), vid.reader.width, vid.reader.height, "request")
        return new
