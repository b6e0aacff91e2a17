"""Reading and validating the inputs of the recognition stage.

Features file (one ``.npz`` per video, written by ``vidstyle features``)::

    points       (n, 3) int     (frame, row, col) of each salient point
    descriptors  (n, d) float32 | uint8
    frame_index  (n,) int       == points[:, 0] (optional here; derived from points when absent)
    n_frames     int            frames of the video (frames without points are allowed)
    height, width, video, params (JSON str)   carried along, not needed for recognition

Labels files and the dataset manifest are owned by :mod:`vidstyle.formats.labels` and
:mod:`vidstyle.formats.dataset`. A features directory holds ``<video id>.npz``.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import InputError

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


def features_path(features_dir: str | Path, video_id: str) -> Path:
    return Path(features_dir) / f"{video_id}.npz"
