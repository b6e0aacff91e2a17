"""Reading and validating the inputs of the recognition stage.

Features file (one ``.npz`` per video, written by ``vidstyle features``): schema and reader in
:mod:`vidstyle.formats.features`; recognition uses its descriptors, frame indices and frame count.

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
    fps: float = 0.0  # working frame rate of the frames (0 when unknown)
    params: dict | None = None  # the features file's parameters (None when unknown)
    source_index: np.ndarray | None = None  # (n_frames,) decoded video frame of each working frame
    source_frames: int | None = None  # frames the video decodes to

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
                         variant=f.variant, fps=f.fps, params=f.params, source_index=f.source_index,
                         source_frames=f.source_frames)


def crop_features(f: VideoFeatures, start: int, end: int) -> VideoFeatures:
    """The features of frames ``start <= i < end`` only, renumbered from 0 (a labelled stretch of a
    partly annotated video)."""
    if not 0 <= start < end <= f.n_frames:
        raise InputError(f"{f.path or f.video}: frames {start}..{end} outside 0..{f.n_frames}")
    keep = (f.frame_index >= start) & (f.frame_index < end)
    return VideoFeatures(f.descriptors[keep], f.frame_index[keep] - start, end - start,
                         video=f"{f.video}[{start}:{end}]", path=f"{f.path}[{start}:{end}]", variant=f.variant,
                         fps=f.fps)


def features_path(features_dir: str | Path, video_id: str) -> Path:
    return Path(features_dir) / f"{video_id}.npz"
