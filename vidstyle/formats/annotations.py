"""The annotations file (``kind: "vidstyle.annotations"``, ``schema_version: 2``; version 1 files still load):
what a person marked on their videos in ``vidstyle annotate``, read by ``augment`` (transition marks and
enhancement-node decisions), ``train-recognizer --annotations`` (action segments) and ``pose --annotations``
(the marks' frames, and the performer to follow).

Conventions (the ones the exchange formats disagree about, fixed here once):

* a **frame** is a 0-based *decoded* index (the ``i``-th picture the decoder yields, as
  :class:`vidstyle.video.VideoReader` counts), never ``time x fps``;
* a **segment** ``{start, end, action}`` is half-open, ``start <= frame < end``; segments of one video do
  not overlap; a frame in no segment is unlabelled;
* every video is tied to its content (``sha256`` of the file bytes) and its decoded ``frames`` count, so an
  annotation never lands on another (or a re-encoded) video; ``fps`` is the average decoded rate, for
  display only (times come from the decoded timestamps);
* ``path`` is stored as written; a relative path is relative to the annotations file's directory;
* ``revision`` counts saves; the annotation server refuses a save whose revision is not the current one
  (a stale page), see :mod:`vidstyle.annotate.server`;
* ``performer`` (optional, one per video) is the person to follow when several are in view: the decoded
  ``frame`` where it was chosen and the pixel ``x`` (column), ``y`` (row) clicked there, in the input
  video's pixels of the upright frame as a player shows it (phone rotation applied; pixel centres at
  integers, as ``poses.json`` keypoints). The file does not know the video's size: ``x``, ``y`` are
  checked against it where the video is read (:func:`check_performer`).

Versions: 2 added ``performer``. A version-1 reader refuses any field it does not know, so a file holding
the new field had to change version (an older vidstyle then says the version is not supported, instead of
naming an unknown field); version 1 files are read as before (a ``performer`` in one is refused), and
every file is written as version 2.

Document layout::

    {"kind": "vidstyle.annotations", "schema_version": 2, "revision": 3,
     "classes": ["jab", "cross", ...],
     "videos": [{"path": "v.mp4", "sha256": "<64 hex>", "frames": 300, "fps": 30.0,
                 "transitions": [{"frame": 120, "from_action": "jab", "to_action": "cross",
                                  "status": "accepted",
                                  "candidates": [{"clip": "lib/01_01.bvh", "time": 1.25,
                                                  "status": "discarded"}]}],
                 "segments": [{"start": 0, "end": 118, "action": "jab"}],
                 "performer": {"frame": 12, "x": 241.0, "y": 160.0}}]}

:data:`JSON_SCHEMA` is the JSON Schema of this file (also at the repository's ``annotations/schema.json``);
:func:`write_annotations` checks an object against both the field rules here and that schema.
"""

from __future__ import annotations

import hashlib
import os
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ._base import Fields, FormatError, check_header, header, read_json_document, write_json_document

KIND = "vidstyle.annotations"
SCHEMA_VERSION = 2
#: versions the reader accepts (1: before ``performer``)
VERSIONS = (1, 2)
STATUSES = ("accepted", "discarded")
_SHA = re.compile(r"^[0-9a-f]{64}$")


@dataclass
class CandidateDecision:
    """A person's decision on one matched library pose (an enhancement-node candidate) of a transition:
    ``clip`` (BVH path as ``match-pose`` wrote it) at ``time`` seconds, ``accepted`` or ``discarded``."""

    clip: str
    time: float
    status: str = "accepted"


@dataclass
class Transition:
    """A marked transition frame (0-based decoded index) from one action to the next."""

    frame: int
    from_action: str
    to_action: str
    status: str = "accepted"
    candidates: list[CandidateDecision] = field(default_factory=list)

    def decision(self, clip: str, time: float, tol: float = 1e-6) -> str | None:
        """The person's decision on the library pose ``clip`` at ``time`` s (``accepted``, ``discarded``) or
        None when they left it undecided."""
        for c in self.candidates:
            if c.clip == clip and abs(c.time - time) <= tol:
                return c.status
        return None


@dataclass
class ActionSpan:
    """Frames ``start <= f < end`` (0-based decoded indices) perform ``action``."""

    start: int
    end: int
    action: str


@dataclass
class PerformerChoice:
    """The person to follow (``vidstyle pose --annotations``), as clicked in ``vidstyle annotate``: the one at
    pixel ``x`` (column), ``y`` (row) of decoded frame ``frame``, in the input video's pixels of the upright
    frame (pixel centres at integers)."""

    frame: int
    x: float
    y: float


@dataclass
class VideoAnnotations:
    path: str
    sha256: str
    frames: int
    fps: float
    transitions: list[Transition] = field(default_factory=list)
    segments: list[ActionSpan] = field(default_factory=list)
    performer: PerformerChoice | None = None


@dataclass
class Annotations:
    classes: list[str]
    videos: list[VideoAnnotations] = field(default_factory=list)
    revision: int = 0

    def video(self, sha256: str) -> VideoAnnotations | None:
        """The entry of the video with this content hash (see :func:`file_sha256`), or None."""
        return next((v for v in self.videos if v.sha256 == sha256), None)

    def video_for(self, path: str | os.PathLike, annotations_path: str | os.PathLike | None = None) -> VideoAnnotations:
        """The entry of the video file ``path``, matched by content; :class:`FormatError` when the file is
        not annotated here (``annotations_path`` names this file in the message)."""
        v = self.video(file_sha256(path))
        if v is None:
            raise FormatError(annotations_path, "videos", f"no annotations of {path} (no video with its sha256)")
        return v


# ------------------------------------------------------------------------------------------ JSON Schema
_NAME = {"type": "string", "minLength": 1}
_STATUS = {"enum": list(STATUSES)}
_INDEX = {"type": "integer", "minimum": 0}
JSON_SCHEMA: dict[str, Any] = {
    "$schema": "https://json-schema.org/draft/2020-12/schema",
    "$id": "https://vidstyle.invalid/annotations/schema.json",
    "title": "vidstyle annotations (transition frames, action segments, performer)",
    "description": "0-based decoded frame indices; segments half-open [start, end); videos tied to the "
                   "sha256 of the file and its decoded frame count; performer: a frame and a pixel of the "
                   "upright frame in the input video's pixels (schema_version 2; version 1 files have "
                   "none). Rules JSON Schema cannot say (frames, segments and the performer's frame inside "
                   "the video, no overlapping segments, actions among the classes, one mark per frame) are "
                   "checked by vidstyle.formats.annotations.",
    "type": "object",
    "required": ["kind", "schema_version", "revision", "classes", "videos"],
    "additionalProperties": False,
    "properties": {
        "kind": {"const": KIND},
        "schema_version": {"enum": list(VERSIONS)},
        "revision": _INDEX,
        "classes": {"type": "array", "items": _NAME, "uniqueItems": True},
        "videos": {
            "type": "array",
            "items": {
                "type": "object",
                "required": ["path", "sha256", "frames", "fps", "transitions", "segments"],
                "additionalProperties": False,
                "properties": {
                    "path": _NAME,
                    "sha256": {"type": "string", "pattern": "^[0-9a-f]{64}$"},
                    "frames": {"type": "integer", "minimum": 1},
                    "fps": {"type": "number", "minimum": 0},
                    "transitions": {
                        "type": "array",
                        "items": {
                            "type": "object",
                            "required": ["frame", "from_action", "to_action", "status"],
                            "additionalProperties": False,
                            "properties": {
                                "frame": _INDEX,
                                "from_action": _NAME,
                                "to_action": _NAME,
                                "status": _STATUS,
                                "candidates": {
                                    "type": "array",
                                    "items": {
                                        "type": "object",
                                        "required": ["clip", "time", "status"],
                                        "additionalProperties": False,
                                        "properties": {"clip": _NAME, "time": {"type": "number", "minimum": 0},
                                                       "status": _STATUS},
                                    },
                                },
                            },
                        },
                    },
                    "segments": {
                        "type": "array",
                        "items": {
                            "type": "object",
                            "required": ["start", "end", "action"],
                            "additionalProperties": False,
                            "properties": {"start": _INDEX, "end": {"type": "integer", "minimum": 1},
                                           "action": _NAME},
                        },
                    },
                    "performer": {
                        "type": "object",
                        "required": ["frame", "x", "y"],
                        "additionalProperties": False,
                        "properties": {"frame": _INDEX, "x": {"type": "number", "minimum": 0},
                                       "y": {"type": "number", "minimum": 0}},
                    },
                },
            },
        },
    },
    # version 1 (before the performer choice) has no performer
    "if": {"properties": {"schema_version": {"const": 1}}},
    "then": {"properties": {"videos": {"items": {"not": {"required": ["performer"]}}}}},
}


# ------------------------------------------------------------------------------------------ read
def file_sha256(path: str | os.PathLike, chunk: int = 1 << 20) -> str:
    """sha256 of the file's bytes (hex), read in chunks."""
    h = hashlib.sha256()
    with open(path, "rb") as f:
        while True:
            b = f.read(chunk)
            if not b:
                break
            h.update(b)
    return h.hexdigest()


def from_document(doc: Any, path: str | os.PathLike | None = None) -> Annotations:
    """Validate a parsed JSON document; :class:`FormatError` (naming ``path`` and the field) otherwise."""
    version = check_header(doc, path, KIND, VERSIONS)
    f = Fields(doc, path)
    _no_extra(f, {"kind", "schema_version", "revision", "classes", "videos"})
    revision = f.int("revision", min=0)
    classes = f.str_list("classes", unique=True)
    known = set(classes)
    videos = []
    seen_sha: set[str] = set()
    for i, v in enumerate(f.list("videos")):
        vf = Fields(v, path, f"videos[{i}]")
        _no_extra(vf, {"path", "sha256", "frames", "fps", "transitions", "segments"}
                  | ({"performer"} if version >= 2 else set()))
        vpath = vf.str("path", nonempty=True)
        sha = vf.str("sha256")
        if not _SHA.match(sha):
            raise vf.fail("sha256", "expected 64 lowercase hex digits (the sha256 of the video file)")
        if sha in seen_sha:
            raise vf.fail("sha256", "the same video appears twice")
        seen_sha.add(sha)
        frames = vf.int("frames", min=1)
        fps = vf.number("fps", min=0)
        transitions = []
        marked: set[int] = set()
        for j, t in enumerate(vf.list("transitions")):
            tf = Fields(t, path, f"videos[{i}].transitions[{j}]")
            _no_extra(tf, {"frame", "from_action", "to_action", "status", "candidates"})
            frame = tf.int("frame", min=0, max=frames - 1)
            if frame in marked:
                raise tf.fail("frame", f"frame {frame} is marked twice")
            marked.add(frame)
            a = _action(tf, "from_action", known)
            b = _action(tf, "to_action", known)
            status = tf.str("status", choices=STATUSES)
            cands = []
            for k, c in enumerate(tf.list("candidates") if tf.has("candidates") else []):
                cf = Fields(c, path, f"{tf.prefix}.candidates[{k}]")
                _no_extra(cf, {"clip", "time", "status"})
                cands.append(CandidateDecision(cf.str("clip", nonempty=True), cf.number("time", min=0),
                                       cf.str("status", choices=STATUSES)))
            transitions.append(Transition(frame, a, b, status, cands))
        segments = []
        for j, s in enumerate(vf.list("segments")):
            sf = Fields(s, path, f"videos[{i}].segments[{j}]")
            _no_extra(sf, {"start", "end", "action"})
            start = sf.int("start", min=0, max=frames - 1)
            end = sf.int("end", min=start + 1, max=frames)
            segments.append(ActionSpan(start, end, _action(sf, "action", known)))
        order = sorted(range(len(segments)), key=lambda j: segments[j].start)
        for a, b in zip(order, order[1:]):
            if segments[b].start < segments[a].end:
                raise FormatError(path, f"videos[{i}].segments[{b}]",
                                  f"overlaps segments[{a}] ({segments[a].start}..{segments[a].end})")
        performer = None
        if vf.has("performer"):
            pf = Fields(vf.get("performer"), path, vf.name("performer"))
            _no_extra(pf, {"frame", "x", "y"})
            performer = PerformerChoice(pf.int("frame", min=0, max=frames - 1), pf.number("x", min=0),
                                        pf.number("y", min=0))
        videos.append(VideoAnnotations(vpath, sha, frames, fps, transitions, segments, performer))
    return Annotations(classes, videos, revision)


def _action(f: Fields, key: str, known: set[str]) -> str:
    a = f.str(key, nonempty=True)
    if a not in known:
        raise f.fail(key, f"{a!r} is not in classes")
    return a


def _no_extra(f: Fields, allowed: set[str]) -> None:
    extra = sorted(set(f.obj) - allowed)
    if extra:
        raise f.fail(None, f"unknown field(s) {', '.join(map(repr, extra))}")


def read_annotations(path: str | os.PathLike, max_bytes: int = 64 << 20) -> Annotations:
    return from_document(read_json_document(path, max_bytes=max_bytes), path)


# ------------------------------------------------------------------------------------------ write
def to_document(ann: Annotations) -> dict[str, Any]:
    """The JSON document of ``ann`` (validated: an invalid object raises :class:`FormatError`)."""
    doc = {
        **header(KIND, SCHEMA_VERSION),
        "revision": int(ann.revision),
        "classes": list(ann.classes),
        "videos": [
            {
                "path": str(v.path),
                "sha256": v.sha256,
                "frames": int(v.frames),
                "fps": float(v.fps),
                "transitions": [
                    {"frame": int(t.frame), "from_action": t.from_action, "to_action": t.to_action,
                     "status": t.status,
                     **({"candidates": [{"clip": c.clip, "time": float(c.time), "status": c.status}
                                        for c in t.candidates]} if t.candidates else {})}
                    for t in sorted(v.transitions, key=lambda t: t.frame)
                ],
                "segments": [{"start": int(s.start), "end": int(s.end), "action": s.action}
                             for s in sorted(v.segments, key=lambda s: s.start)],
                **({"performer": {"frame": int(v.performer.frame), "x": float(v.performer.x),
                                  "y": float(v.performer.y)}} if v.performer is not None else {}),
            }
            for v in ann.videos
        ],
    }
    from_document(doc, "<annotations>")
    validate_schema(doc)
    return doc


def validate_schema(doc: Any, path: str | os.PathLike | None = "<annotations>") -> None:
    """Check ``doc`` against :data:`JSON_SCHEMA` (jsonschema); :class:`FormatError` naming the field."""
    import jsonschema

    validator = jsonschema.Draft202012Validator(JSON_SCHEMA)
    err = jsonschema.exceptions.best_match(validator.iter_errors(doc))
    if err is not None:
        where = "".join(f"[{p}]" if isinstance(p, int) else f".{p}" for p in err.absolute_path).lstrip(".")
        raise FormatError(path, where or None, f"schema: {err.message}"[:300])


def write_annotations(path: str | os.PathLike, ann: Annotations) -> None:
    """Validate ``ann`` and write it atomically (temporary file + rename)."""
    write_json_document(path, to_document(ann))


# ------------------------------------------------------------------------------------------ use
def resolve_video_path(annotations_path: str | os.PathLike, video: VideoAnnotations) -> Path:
    """The video file of ``video``: a relative ``path`` is relative to the annotations file's directory."""
    p = Path(video.path)
    return (p if p.is_absolute() else Path(annotations_path).resolve().parent / p).resolve()


def stored_path(annotations_path: str | os.PathLike, video_path: str | os.PathLike) -> str:
    """How to write ``video_path`` into an annotations file at ``annotations_path``: relative to its
    directory when that is possible, else absolute."""
    v = Path(video_path).resolve()
    try:
        return os.path.relpath(v, Path(annotations_path).resolve().parent)
    except ValueError:
        return str(v)


def frame_labels(video: VideoAnnotations, classes: list[str]) -> np.ndarray:
    """int64 (frames,): index into ``classes`` of each decoded frame's segment action, -1 if unlabelled."""
    index = {c: k for k, c in enumerate(classes)}
    y = np.full(video.frames, -1, dtype=np.int64)
    for s in video.segments:
        if s.action not in index:
            raise FormatError(None, "segments.action", f"{s.action!r} is not in classes")
        y[s.start:s.end] = index[s.action]
    return y


def labelled_runs(video: VideoAnnotations) -> list[tuple[int, int]]:
    """Maximal half-open runs ``[a, b)`` of frames inside segments (touching segments join one run): the
    pieces of a partly labelled video a frame-wise learner can train on."""
    runs: list[list[int]] = []
    for s in sorted(video.segments, key=lambda s: s.start):
        if runs and runs[-1][1] == s.start:
            runs[-1][1] = s.end
        else:
            runs.append([s.start, s.end])
    return [(a, b) for a, b in runs]


def check_video(video: VideoAnnotations, video_path: str | os.PathLike, frames: int,
                where: str | os.PathLike | None = None) -> None:
    """Refuse annotations of another video: the file's sha256 and decoded frame count must match."""
    sha = file_sha256(video_path)
    if sha != video.sha256:
        raise FormatError(where, "sha256", f"{video_path} is not the annotated video (its content hash "
                                           f"differs: the file changed or is another video)")
    if frames != video.frames:
        raise FormatError(where, "frames", f"{video_path} decodes to {frames} frames, the annotations "
                                           f"say {video.frames}")


def check_performer(video: VideoAnnotations, width: int, height: int,
                    where: str | os.PathLike | None = None) -> PerformerChoice | None:
    """``video``'s performer choice, refused when its pixel lies outside the (upright) ``width`` x ``height``
    frame of the video it is used on (the file itself does not know the size); None when there is none."""
    p = video.performer
    if p is not None and not (p.x <= width - 0.5 and p.y <= height - 0.5):
        raise FormatError(where, "performer", f"pixel ({p.x:g}, {p.y:g}) is outside {video.path}'s "
                                              f"{width}x{height} frame")
    return p
