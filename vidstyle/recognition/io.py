"""Reading and validating the inputs of the recognition stage.

Features file (one ``.npz`` per video, written by ``vidstyle features``): schema and reader in
:mod:`vidstyle.formats.features`; recognition uses its descriptors, frame indices and frame count.

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
    fps: float = 0.0  # working frame rate of the frames (0 when unknown)
    params: dict | None = None  # the features file's parameters (None when unknown)

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
    """The descriptors and frame indices of one features ``.npz`` (read and validated by
    :func:`vidstyle.formats.features.read_features`; every problem is a FormatError naming the file)."""
    from ..formats.features import read_features

    f = read_features(path)
    return VideoFeatures(f.descriptors, f.frame_index, f.n_frames, video=f.video, path=str(path),
                         variant=f.variant, fps=f.fps, params=f.params)


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
