"""Reading and validating the inputs of the recognition stage.

Features file (one ``.npz`` per video, written by ``vidstyle features``)::

    points       (n, 3) int     (frame, row, col) of each salient point
    descriptors  (n, d) float32 | uint8
    frame_index  (n,) int       == points[:, 0] (optional here; derived from points when absent)
    n_frames     int            frames of the video (frames without points are allowed)
    height, width, video, params (JSON str)   carried along, not needed for recognition

Labels file (JSON, one label per video frame)::

    {"video": "videos/p03_jab_front.mp4", "fps": 20, "classes": [...], "labels": [...], ...}

Dataset manifest ``DIR/dataset.json`` (written by ``vidstyle demo make-dataset``): ``fps``, ``actions``,
``classes``, ``performers`` and ``videos`` (``id``, ``performer``, ``kind`` single|performance, ``action``,
``view``, ``azimuth_deg``, ``video``, ``labels``). A features directory holds ``<video id>.npz``.
"""

from __future__ import annotations

import json
import logging
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from ..errors import InputError
from ..fileio import read_json

log = logging.getLogger(__name__)


@dataclass
class VideoFeatures:
    """The descriptors of one video and the frame each one belongs to."""

    descriptors: np.ndarray  # (n, d)
    frame_index: np.ndarray  # (n,) int64
    n_frames: int
    video: str = ""
    path: str = ""
    variant: str = ""  # descriptor variant recorded by `vidstyle features` ("" when unknown)

    @property
    def dim(self) -> int:
        return int(self.descriptors.shape[1])

    def __post_init__(self) -> None:
        where = self.path or self.video or "features"
        d = np.asarray(self.descriptors)
        if d.ndim != 2:
            raise InputError(f"{where}: 'descriptors' must be 2-D (n, d), got shape {d.shape}")
        fi = np.asarray(self.frame_index).astype(np.int64, copy=False).reshape(-1)
        if fi.shape[0] != d.shape[0]:
            raise InputError(f"{where}: {d.shape[0]} descriptors but {fi.shape[0]} frame indices")
        if self.n_frames < 0:
            raise InputError(f"{where}: 'n_frames' must be >= 0, got {self.n_frames}")
        if fi.size and (fi.min() < 0 or fi.max() >= self.n_frames):
            raise InputError(f"{where}: frame indices outside [0, {self.n_frames}) (min {fi.min()}, max {fi.max()})")
        self.descriptors = d
        self.frame_index = fi
        self.n_frames = int(self.n_frames)


def load_features(path: str | Path) -> VideoFeatures:
    """Load and validate one features ``.npz``; every problem becomes an :class:`InputError`."""
    path = Path(path)
    if not path.is_file():
        raise InputError(f"{path}: features file not found")
    try:
        with np.load(path, allow_pickle=False) as z:
            data = {k: z[k] for k in z.files}
    except Exception as e:  # zipfile/format errors of every kind
        raise InputError(f"{path}: not a readable .npz ({e})") from None
    for key in ("descriptors", "n_frames"):
        if key not in data:
            raise InputError(f"{path}: missing array '{key}'")
    desc = data["descriptors"]
    if desc.ndim != 2:
        raise InputError(f"{path}: 'descriptors' must be 2-D (n, d), got shape {desc.shape}")
    if "frame_index" in data:
        fi = data["frame_index"]
    elif "points" in data:
        pts = data["points"]
        if pts.ndim != 2 or pts.shape[1] != 3:
            raise InputError(f"{path}: 'points' must have shape (n, 3), got {pts.shape}")
        fi = pts[:, 0]
    else:
        raise InputError(f"{path}: missing 'frame_index' (and 'points')")
    if "points" in data and data["points"].shape[0] != desc.shape[0]:
        raise InputError(f"{path}: {data['points'].shape[0]} points but {desc.shape[0]} descriptors")
    if not np.issubdtype(desc.dtype, np.number):
        raise InputError(f"{path}: 'descriptors' must be numeric, got {desc.dtype}")
    try:
        n_frames = int(data["n_frames"])
    except (TypeError, ValueError):
        raise InputError(f"{path}: 'n_frames' must be an integer") from None
    video = str(data["video"]) if "video" in data else ""
    variant = str(data["variant"]) if "variant" in data else ""
    return VideoFeatures(desc, fi, n_frames, video=video, path=str(path), variant=variant)


def crop_features(f: VideoFeatures, start: int, end: int) -> VideoFeatures:
    """The features of frames ``start <= i < end`` only, renumbered from 0 (a labelled stretch of a
    partly annotated video)."""
    if not 0 <= start < end <= f.n_frames:
        raise InputError(f"{f.path or f.video}: frames {start}..{end} outside 0..{f.n_frames}")
    keep = (f.frame_index >= start) & (f.frame_index < end)
    return VideoFeatures(f.descriptors[keep], f.frame_index[keep] - start, end - start,
                         video=f"{f.video}[{start}:{end}]", path=f"{f.path}[{start}:{end}]", variant=f.variant)


@dataclass
class LabelTrack:
    """Per-frame ground truth of one video."""

    labels: list[str]
    classes: list[str]
    video: str
    fps: float
    path: str = ""


def load_labels(path: str | Path) -> LabelTrack:
    doc = read_json(path)
    if not isinstance(doc, dict):
        raise InputError(f"{path}: labels file must be a JSON object")
    labels = doc.get("labels")
    if not isinstance(labels, list) or not all(isinstance(x, str) for x in labels):
        raise InputError(f"{path}: 'labels' must be a list of class names")
    classes = doc.get("classes")
    if classes is None:
        classes = sorted(set(labels))
    if not isinstance(classes, list) or not all(isinstance(x, str) for x in classes):
        raise InputError(f"{path}: 'classes' must be a list of class names")
    unknown = sorted(set(labels) - set(classes))
    if unknown:
        raise InputError(f"{path}: labels not in 'classes': {', '.join(unknown[:5])}")
    return LabelTrack(labels, classes, str(doc.get("video", "")), float(doc.get("fps", 20)), str(path))


def check_labels_match(features: VideoFeatures, track: LabelTrack) -> None:
    if len(track.labels) != features.n_frames:
        raise InputError(
            f"{track.path or track.video}: {len(track.labels)} labels but the features file "
            f"{features.path or features.video} has n_frames={features.n_frames}"
        )


@dataclass
class DatasetVideo:
    id: str
    performer: str
    kind: str
    action: str | None
    view: str | None
    azimuth_deg: float | None
    video: str
    labels: str
    raw: dict


@dataclass
class Dataset:
    root: Path
    classes: list[str]
    actions: list[str]
    fps: float
    seed: Any
    videos: list[DatasetVideo]

    def labels_path(self, v: DatasetVideo) -> Path:
        return self.root / v.labels

    def by_id(self) -> dict[str, DatasetVideo]:
        return {v.id: v for v in self.videos}


def load_dataset(path: str | Path) -> Dataset:
    """Load ``dataset.json`` (``path`` may be the file or its directory)."""
    path = Path(path)
    if path.is_dir():
        path = path / "dataset.json"
    doc = read_json(path)
    if not isinstance(doc, dict) or not isinstance(doc.get("videos"), list):
        raise InputError(f"{path}: a dataset manifest needs a 'videos' list")
    videos = []
    for i, v in enumerate(doc["videos"]):
        if not isinstance(v, dict):
            raise InputError(f"{path}: videos[{i}] must be an object")
        for key in ("id", "performer", "labels"):
            if key not in v:
                raise InputError(f"{path}: videos[{i}] lacks '{key}'")
        videos.append(
            DatasetVideo(
                id=str(v["id"]),
                performer=str(v["performer"]),
                kind=str(v.get("kind", "single")),
                action=v.get("action"),
                view=None if v.get("view") is None else str(v.get("view")),
                azimuth_deg=v.get("azimuth_deg"),
                video=str(v.get("video", "")),
                labels=str(v["labels"]),
                raw=v,
            )
        )
    ids = [v.id for v in videos]
    if len(set(ids)) != len(ids):
        raise InputError(f"{path}: duplicate video ids")
    classes = doc.get("classes") or sorted({c for v in videos for c in ([v.action] if v.action else [])})
    return Dataset(
        root=path.parent,
        classes=list(classes),
        actions=list(doc.get("actions") or []),
        fps=float(doc.get("fps", 20)),
        seed=doc.get("seed"),
        videos=videos,
    )


def features_path(features_dir: str | Path, video_id: str) -> Path:
    return Path(features_dir) / f"{video_id}.npz"


def params_json(obj: Any) -> str:
    return json.dumps(obj, sort_keys=True, default=str)


def as_paths(items: Sequence[str | Path]) -> list[Path]:
    return [Path(p) for p in items]
