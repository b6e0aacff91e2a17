"""The dataset manifest ``DIR/dataset.json``: the owner of its schema.

Written by ``vidstyle demo make-dataset`` and ``demo make-cmu-dataset``; read by recognition (splits,
training, scoring), style (learning per performer, evaluation) and the report. Schema (``kind``
``"vidstyle.dataset"``, ``schema_version`` 2; files without ``kind`` are schema 1 and still load)::

    {"kind": "vidstyle.dataset", "schema_version": 2,
     "seed": 0, "fps": 20,                      # video frame rate (> 0)
     "actions": ["Jab", ...],                   # the actions of the chains (unique; may be empty)
     "classes": ["Jab", ..., "Guard", "Step"],  # every label class (unique; default: the actions)
     "performers": [{"id": "p00",               # unique, at least one
                     "chain": {"actions": [...], "start": [A], "transition": [A][A],   # optional: the
                               "duration_frames": {action: [mean, sd]}}, ...}],       # true chain
     "videos": [{"id": "p00_jab_front",         # unique, at least one
                 "performer": "p00",            # one of performers[].id
                 "kind": "single" | "performance",
                 "action": "Jab" | null,        # single-action videos: one of classes
                 "view": "front", "azimuth_deg": 0.0,
                 "video": "videos/<id>.mp4", "labels": "labels/<id>.json",   # relative to DIR
                 "truth", "bvh", "bvh_labels": paths (optional), "frames": int (optional)}, ...],
     ...other keys (params, size, stats, source) carried along}

A chain's ``start`` and ``transition`` rows are finite, non-negative and sum to 1, over the same action
set as ``actions`` (in any order).
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ._base import Fields, FormatError, check_header, header, read_json_document, write_json_document

KIND = "vidstyle.dataset"
SCHEMA_VERSION = 2
VERSIONS = (1, 2)
VIDEO_KINDS = ("single", "performance")
FILE_NAME = "dataset.json"


@dataclass
class Chain:
    """A performer's true action chain (demo data): start and transition over ``actions``."""

    actions: list[str]
    start: np.ndarray  # (A,)
    transition: np.ndarray  # (A, A)
    duration_frames: dict[str, tuple[float, float]] = field(default_factory=dict)  # action -> (mean, sd)

    def reordered(self, actions: list[str]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(start, transition, mean duration) in the order of ``actions`` (NaN: duration unknown)."""
        idx = [self.actions.index(a) for a in actions]
        dur = np.array([float(self.duration_frames[a][0]) if a in self.duration_frames else np.nan for a in actions])
        return self.start[idx], self.transition[np.ix_(idx, idx)], dur

    def to_dict(self) -> dict:
        return {"actions": list(self.actions), "start": self.start.tolist(), "transition": self.transition.tolist(),
                "duration_frames": {a: [float(m), float(s)] for a, (m, s) in self.duration_frames.items()}}


@dataclass
class PerformerEntry:
    id: str
    chain: Chain | None = None
    extra: dict[str, Any] = field(default_factory=dict)

    def to_dict(self) -> dict:
        d: dict[str, Any] = {"id": self.id}
        if self.chain is not None:
            d["chain"] = self.chain.to_dict()
        return {**d, **{k: v for k, v in self.extra.items() if k not in d}}


@dataclass
class VideoEntry:
    id: str
    performer: str
    labels: str  # relative to the dataset directory
    kind: str = "single"
    action: str | None = None
    view: str | None = None
    azimuth_deg: float | None = None
    video: str = ""
    truth: str | None = None
    bvh: str | None = None
    bvh_labels: str | None = None
    frames: int | None = None
    extra: dict[str, Any] = field(default_factory=dict)

    _OPTIONAL = ("action", "view", "azimuth_deg", "truth", "bvh", "bvh_labels", "frames")

    @property
    def raw(self) -> dict:
        """The manifest entry as a document (every field, known or not)."""
        return self.to_dict()

    def to_dict(self) -> dict:
        d: dict[str, Any] = {"id": self.id, "performer": self.performer, "kind": self.kind}
        for key in self._OPTIONAL:
            if getattr(self, key) is not None:
                d[key] = getattr(self, key)
        d["video"] = self.video
        d["labels"] = self.labels
        return {**d, **{k: v for k, v in self.extra.items() if k not in d}}

    @property
    def take(self) -> str:
        """The performance take the video shows (its views share it): the BVH, else the video id."""
        return str(self.bvh or self.id)


@dataclass
class Dataset:
    """A parsed ``dataset.json``; ``root`` is its directory (the manifest's paths are relative to it)."""

    root: Path
    fps: float
    actions: list[str]
    classes: list[str]
    performers: list[PerformerEntry]
    videos: list[VideoEntry]
    seed: Any = None
    extra: dict[str, Any] = field(default_factory=dict)
    path: str = ""

    kind = KIND

    # -- queries -------------------------------------------------------------------------------------
    def by_id(self) -> dict[str, VideoEntry]:
        return {v.id: v for v in self.videos}

    def performer_ids(self) -> list[str]:
        return [p.id for p in self.performers]

    def labels_path(self, v: VideoEntry, labels_dir: str | os.PathLike | None = None) -> Path:
        """The label file of video ``v``: the manifest's ground truth, or with ``labels_dir`` the recognised
        labels ``<labels_dir>/<video id>.json`` (as ``vidstyle recognize --out-dir`` names them)."""
        if labels_dir is None:
            return self.root / v.labels
        return Path(labels_dir) / f"{v.id}.json"

    def performance_videos(self, performer: str, views=None) -> list[VideoEntry]:
        """Performance videos of ``performer`` (only ``views`` when given), sorted by id."""
        wanted = None if views is None else set(views)
        return sorted((v for v in self.videos if v.performer == performer and v.kind == "performance"
                       and (wanted is None or v.view in wanted)), key=lambda v: v.id)

    def performer_label_files(self, performer: str, labels_dir=None, views=None, require: bool = True
                              ) -> list[tuple[VideoEntry, Path]]:
        """(video, label file) of every performance video of ``performer``. The ONE way a performer's label
        files are found (learning a style, evaluating styles). ``require``: a missing file is an error."""
        out = []
        for v in self.performance_videos(performer, views):
            p = self.labels_path(v, labels_dir)
            if require and not p.is_file():
                what = "recognised labels" if labels_dir is not None else "label file"
                raise FormatError(p, None, f"{what} of video {v.id} (performer {performer}) not found")
            out.append((v, p))
        return out

    def to_dict(self) -> dict[str, Any]:
        doc = {**header(KIND, SCHEMA_VERSION), "seed": self.seed, "fps": self.fps, "actions": list(self.actions),
               "classes": list(self.classes), "performers": [p.to_dict() for p in self.performers],
               "videos": [v.to_dict() for v in self.videos]}
        return {**doc, **{k: v for k, v in self.extra.items() if k not in doc}}


def _chain(obj: Any, path, name: str) -> Chain:
    c = Fields(obj, path, name)
    actions = c.str_list("actions", unique=True, min_len=1)
    A = len(actions)
    start = c.array("start", shape=(A,)) if c.has("start") else np.full(A, 1.0 / A)
    trans = c.array("transition", shape=(A, A))
    for key, m in (("start", start), ("transition", trans)):
        if (m < 0).any() or not np.allclose(m.sum(axis=-1), 1.0, atol=1e-4):
            raise FormatError(path, c.name(key), "must be non-negative with rows summing to 1")
    dur: dict[str, tuple[float, float]] = {}
    if obj.get("duration_frames") is not None:
        d = c.sub("duration_frames")
        for a in d.obj:
            if a not in actions:
                raise FormatError(path, d.name(a), "not one of the chain's actions")
            arr = d.array(a, shape=(2,))
            dur[a] = (float(arr[0]), float(arr[1]))
    return Chain(actions, start, trans, dur)


def parse_dataset(doc: Any, path: str | os.PathLike | None = None, root: str | os.PathLike | None = None) -> Dataset:
    """Validate a manifest document (see the module docstring); ``root``: its directory."""
    version = check_header(doc, path, KIND, VERSIONS, legacy=True)
    f = Fields(doc, path)
    fps = f.number("fps", required=version >= 2, default=20.0, positive=True)
    actions = f.str_list("actions", required=False, unique=True) or []
    classes = f.str_list("classes", required=False, unique=True) or list(actions)
    missing = [a for a in actions if a not in classes]
    if missing:
        raise FormatError(path, "classes", f"lacks the actions {', '.join(missing)}")
    performers = []
    seen: set[str] = set()
    for i, p in enumerate(f.list("performers", min_len=1)):
        pf = Fields(p, path, f"performers[{i}]")
        pid = pf.str("id", nonempty=True)
        if pid in seen:
            raise FormatError(path, pf.name("id"), f"{pid!r} appears more than once")
        seen.add(pid)
        chain = None
        if p.get("chain") is not None:
            chain = _chain(p["chain"], path, pf.name("chain"))
            if actions and set(chain.actions) != set(actions):
                raise FormatError(path, pf.name("chain") + ".actions", "differ from the manifest's 'actions'")
        performers.append(PerformerEntry(pid, chain, {k: v for k, v in p.items() if k not in ("id", "chain")}))
    videos = []
    ids: set[str] = set()
    known = {p.id for p in performers}
    for i, v in enumerate(f.list("videos", min_len=1)):
        vf = Fields(v, path, f"videos[{i}]")
        vid = vf.str("id", nonempty=True)
        if vid in ids:
            raise FormatError(path, vf.name("id"), f"{vid!r} appears more than once")
        ids.add(vid)
        performer = vf.str("performer", nonempty=True)
        if performer not in known:
            raise FormatError(path, vf.name("performer"), f"{performer!r} is not one of performers[].id")
        kind = vf.str("kind", required=version >= 2, default="single", choices=VIDEO_KINDS)
        action = None if v.get("action") is None else vf.str("action")
        if action is not None and action not in classes:
            raise FormatError(path, vf.name("action"), f"{action!r} is not one of the classes")
        entry = VideoEntry(
            id=vid, performer=performer, labels=vf.str("labels", nonempty=True), kind=kind, action=action,
            view=None if v.get("view") is None else vf.str("view"),
            azimuth_deg=None if v.get("azimuth_deg") is None else vf.number("azimuth_deg"),
            video=vf.str("video", required=False, default="") or "",
            truth=None if v.get("truth") is None else vf.str("truth"),
            bvh=None if v.get("bvh") is None else vf.str("bvh"),
            bvh_labels=None if v.get("bvh_labels") is None else vf.str("bvh_labels"),
            frames=None if v.get("frames") is None else vf.int("frames", min=0),
        )
        entry.extra = {k: x for k, x in v.items() if k not in ("id", "performer", "kind", "video", "labels",
                                                              *VideoEntry._OPTIONAL)}
        videos.append(entry)
    extra = {k: v for k, v in doc.items()
             if k not in ("kind", "schema_version", "seed", "fps", "actions", "classes", "performers", "videos")}
    if root is None:
        root = Path(path).parent if path is not None else Path(".")
    return Dataset(Path(root), fps, list(actions), list(classes), performers, videos, doc.get("seed"), extra,
                   "" if path is None else str(path))


def manifest_path(path: str | os.PathLike) -> Path:
    """``path`` itself, or ``path/dataset.json`` when it is a directory."""
    path = Path(path)
    return path / FILE_NAME if path.is_dir() else path


def read_dataset(path: str | os.PathLike) -> Dataset:
    """Read and validate ``dataset.json`` (``path`` may be the file or its directory)."""
    path = manifest_path(path)
    return parse_dataset(read_json_document(path), path)


def write_dataset(path: str | os.PathLike, dataset: Dataset | dict) -> None:
    """Validate and write a manifest atomically (a dict is taken as the document, given a header)."""
    doc = dataset.to_dict() if isinstance(dataset, Dataset) else {**header(KIND, SCHEMA_VERSION), **dataset}
    doc["kind"], doc["schema_version"] = KIND, SCHEMA_VERSION
    parse_dataset(doc, path)
    write_json_document(path, doc)
