"""The features file (one ``.npz`` per video, written by ``vidstyle features``): its one owner.

Schema ``kind = "vidstyle.features"``, ``schema_version = 2``. Frames are *working* frames: the video
resampled to the working rate ``fps`` and size ``height`` x ``width`` that the features were computed at;
``source_index`` maps each one back to the video's decoded frame index.

================== ============== ==================================================================
key                dtype, shape   meaning
================== ============== ==================================================================
``kind``           str (0-d)      "vidstyle.features"
``schema_version`` int64 (0-d)    2
``points``         int32 (n, 3)   0-based (working frame, row, column) of each salient point, sorted by
                                  frame; row < height, column < width
``descriptors``    (n, d)         uint8 (scovanner2007, d = 640) or float32 (thesis d = 256, sift2d
                                  d = 128), finite; row i describes ``points[i]``
``frame_index``    int32 (n,)     ``points[:, 0]``
``n_frames``       int64 (0-d)    working frames (frames without points are allowed)
``height``         int64 (0-d)    working frame height in pixels
``width``          int64 (0-d)    working frame width in pixels
``fps``            float64 (0-d)  working frame rate (0: unknown)
``source_index``   int64 (F,)     decoded frame index of each working frame, increasing, < source_frames
``source_frames``  int64 (0-d)    frames the video decodes to
``source_fps``     float64 (0-d)  the video's average frame rate (0: unknown)
``source_width``,  int64 (0-d)    the video's frame size
``source_height``
``variant``        str (0-d)      descriptor variant ("scovanner2007", "thesis", "sift2d")
``params``         str (0-d)      JSON object: ``schema``, ``variant``, ``salient``, ``descriptor``,
                                  ``working`` (fps, height)
``video``          str (0-d)      path of the source video as given
================== ============== ==================================================================

Schema 1 (no ``kind``; frames were the video's own frames) still loads: ``source_index`` becomes
``arange(n_frames)`` and the working rate and size are the video's. Its minimum is ``descriptors``,
``n_frames`` and ``frame_index`` (or ``points``).

:func:`read_features` raises :class:`~vidstyle.formats.FormatError` naming the file and the field for
anything else, whatever the bytes (NaN descriptors included).
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ._base import FormatError, load_npz, npz_scalar, npz_version

KIND = "vidstyle.features"
SCHEMA_VERSION = 2
VERSIONS = (1, 2)

#: descriptor dtypes a schema-2 file may hold
DESCRIPTOR_DTYPES = (np.dtype(np.uint8), np.dtype(np.float32))


@dataclass
class Features:
    """Salient points and descriptors of one video at its working rate and size."""

    descriptors: np.ndarray
    """(n, d) uint8 or float32"""
    frame_index: np.ndarray
    """(n,) int64 working frame of each descriptor"""
    n_frames: int
    points: np.ndarray | None = None
    """(n, 3) int32 (frame, row, column); ``None`` only for minimal schema-1 files"""
    height: int = 0
    width: int = 0
    fps: float = 0.0
    variant: str = ""
    params: dict[str, Any] = field(default_factory=dict)
    video: str = ""
    source_index: np.ndarray | None = None
    """(n_frames,) int64 decoded frame index of each working frame (``None``: ``arange(n_frames)``)"""
    source_frames: int | None = None
    source_fps: float | None = None
    source_width: int | None = None
    source_height: int | None = None
    path: str = ""
    """the file it was read from ("" when built in memory)"""
    schema_version: int = SCHEMA_VERSION

    def __post_init__(self) -> None:
        self.validate()

    @property
    def dim(self) -> int:
        return int(self.descriptors.shape[1])

    def validate(self) -> None:
        """Check every field (and fill the defaults); raises :class:`FormatError` naming ``path``."""
        where = self.path or None

        def fail(f: str, problem: str) -> FormatError:
            return FormatError(where, f, problem)

        d = np.asarray(self.descriptors)
        if d.ndim != 2:
            raise fail("descriptors", f"must be 2-D (n, d), got shape {d.shape}")
        if d.dtype.kind not in "uif" or d.dtype == np.bool_:
            raise fail("descriptors", f"must be numeric, got dtype {d.dtype}")
        if self.schema_version >= 2 and d.dtype not in DESCRIPTOR_DTYPES:
            raise fail("descriptors", f"must be uint8 or float32, got {d.dtype}")
        if d.dtype.kind == "f" and not np.isfinite(d).all():
            bad = int(np.count_nonzero(~np.isfinite(d).all(axis=1)))
            raise fail("descriptors", f"{bad} row(s) hold NaN or infinite values")
        n = d.shape[0]
        for name in ("n_frames", "height", "width"):
            v = getattr(self, name)
            if isinstance(v, (bool, np.bool_)) or not isinstance(v, (int, np.integer)) or v < 0:
                raise fail(name, f"must be a non-negative integer, got {v!r}")
            setattr(self, name, int(v))
        if not (isinstance(self.fps, (int, float, np.floating, np.integer)) and np.isfinite(self.fps)
                and self.fps >= 0):
            raise fail("fps", f"must be a finite number >= 0, got {self.fps!r}")
        self.fps = float(self.fps)
        fi = np.asarray(self.frame_index)
        if fi.dtype.kind not in "iu" and not (fi.size == 0 and fi.dtype.kind == "f"):
            raise fail("frame_index", f"must be integers, got dtype {fi.dtype}")
        fi = fi.reshape(-1).astype(np.int64)
        if fi.shape[0] != n:
            raise fail("frame_index", f"{fi.shape[0]} frame indices for {n} descriptors")
        if fi.size and (fi.min() < 0 or fi.max() >= self.n_frames):
            raise fail("frame_index", f"frame indices outside [0, {self.n_frames}) (min {fi.min()}, max {fi.max()})")
        self.frame_index = fi
        self.descriptors = d
        if self.points is not None:
            p = np.asarray(self.points)
            if p.ndim != 2 or p.shape[1] != 3 or p.dtype.kind not in "iu":
                raise fail("points", f"must be an (n, 3) integer array, got {p.dtype} {p.shape}")
            if p.shape[0] != n:
                raise fail("points", f"{p.shape[0]} points for {n} descriptors")
            p = p.astype(np.int32)
            if n and not np.array_equal(p[:, 0], fi):
                raise fail("frame_index", "differs from points[:, 0]")
            if n and p[:, 1:].min() < 0:
                raise fail("points", "negative row or column")
            if n and self.height and p[:, 1].max() >= self.height:
                raise fail("points", f"row {p[:, 1].max()} outside the frame height {self.height}")
            if n and self.width and p[:, 2].max() >= self.width:
                raise fail("points", f"column {p[:, 2].max()} outside the frame width {self.width}")
            self.points = p
        elif self.schema_version >= 2:
            raise fail("points", "missing")
        if not isinstance(self.variant, str) or not isinstance(self.video, str):
            raise fail("variant", "variant and video must be strings")
        if not isinstance(self.params, dict):
            raise fail("params", f"must be a JSON object, got {type(self.params).__name__}")
        if self.source_index is None:
            self.source_index = np.arange(self.n_frames, dtype=np.int64)
        si = np.asarray(self.source_index)
        if si.ndim != 1 or si.dtype.kind not in "iu" and not (si.size == 0 and si.dtype.kind == "f"):
            raise fail("source_index", f"must be a 1-D integer array, got {si.dtype} {si.shape}")
        si = si.astype(np.int64)
        if si.shape[0] != self.n_frames:
            raise fail("source_index", f"{si.shape[0]} entries for {self.n_frames} frames")
        if si.size and (si[0] < 0 or np.any(np.diff(si) <= 0)):
            raise fail("source_index", "must be non-negative and increasing")
        self.source_index = si
        if self.source_frames is None:
            self.source_frames = self.n_frames
        if self.source_fps is None:
            self.source_fps = self.fps
        if self.source_width is None:
            self.source_width = self.width
        if self.source_height is None:
            self.source_height = self.height
        for name in ("source_frames", "source_width", "source_height"):
            v = getattr(self, name)
            if isinstance(v, (bool, np.bool_)) or not isinstance(v, (int, np.integer)) or v < 0:
                raise fail(name, f"must be a non-negative integer, got {v!r}")
            setattr(self, name, int(v))
        if si.size and si[-1] >= self.source_frames:
            raise fail("source_index", f"frame {si[-1]} outside the video's {self.source_frames} frames")
        sf = self.source_fps
        if not (isinstance(sf, (int, float, np.floating, np.integer)) and np.isfinite(sf) and sf >= 0):
            raise fail("source_fps", f"must be a finite number >= 0, got {sf!r}")
        self.source_fps = float(sf)

    def source_frame(self, working_frame: int | np.ndarray) -> np.ndarray:
        """Decoded frame index of working frame(s)."""
        return self.source_index[np.asarray(working_frame)]  # type: ignore[index]

    def to_arrays(self) -> dict[str, np.ndarray]:
        if self.points is None:
            raise FormatError(self.path or None, "points", "missing (cannot write a schema-2 file without points)")
        return {
            "kind": np.array(KIND),
            "schema_version": np.int64(SCHEMA_VERSION),
            "points": self.points.astype(np.int32),
            "descriptors": self.descriptors,
            "frame_index": self.frame_index.astype(np.int32),
            "n_frames": np.int64(self.n_frames),
            "height": np.int64(self.height),
            "width": np.int64(self.width),
            "fps": np.float64(self.fps),
            "source_index": np.asarray(self.source_index, np.int64),
            "source_frames": np.int64(self.source_frames),
            "source_fps": np.float64(self.source_fps),
            "source_width": np.int64(self.source_width),
            "source_height": np.int64(self.source_height),
            "variant": np.array(self.variant),
            "params": np.array(json.dumps(self.params, sort_keys=True, allow_nan=False)),
            "video": np.array(self.video),
        }


def write_features(path: str | os.PathLike, features: Features) -> Path:
    """Validate ``features`` and write it to ``path`` atomically (schema 2)."""
    from ..fileio import write_npz

    features.schema_version = SCHEMA_VERSION
    features.validate()
    # stored, not deflated: the uint8 descriptors deflate to about 65 % of their size at twice the time of
    # the rest of writing and reading them (0.4 s of a 60 s demo video's 2.2 s of features)
    write_npz(path, compressed=False, **features.to_arrays())
    return Path(path)


def read_features(path: str | os.PathLike) -> Features:
    """Read and validate a features ``.npz`` (schema 1 or 2); every problem is a :class:`FormatError`."""
    path = Path(path)
    z = load_npz(path, "features")
    version = npz_version(z, path, KIND, VERSIONS)
    if "descriptors" not in z:
        raise FormatError(path, "descriptors", "missing")
    n_frames = npz_scalar(z, path, "n_frames", "int")
    points = z.get("points")
    if "frame_index" in z:
        fi = z["frame_index"]
    elif points is not None:
        if points.ndim != 2 or points.shape[1] != 3:
            raise FormatError(path, "points", f"must have shape (n, 3), got {points.shape}")
        fi = points[:, 0]
    else:
        raise FormatError(path, "frame_index", "missing (and no points)")
    params: Any = {}
    if "params" in z:
        text = npz_scalar(z, path, "params", "str")
        try:
            params = json.loads(text, parse_constant=lambda c: (_ for _ in ()).throw(ValueError(c)))
        except (ValueError, RecursionError) as e:
            raise FormatError(path, "params", f"not JSON ({e})") from None
    elif version >= 2:
        raise FormatError(path, "params", "missing")
    req = version >= 2
    kw: dict[str, Any] = dict(
        height=npz_scalar(z, path, "height", "int", req),
        width=npz_scalar(z, path, "width", "int", req),
        fps=npz_scalar(z, path, "fps", "float", req),
        variant=npz_scalar(z, path, "variant", "str", req),
        video=npz_scalar(z, path, "video", "str", req),
    )
    kw = {k: v for k, v in kw.items() if v is not None}
    src: dict[str, Any] = {}
    if version >= 2:
        if "source_index" not in z:
            raise FormatError(path, "source_index", "missing")
        src = dict(
            source_index=z["source_index"],
            source_frames=npz_scalar(z, path, "source_frames", "int"),
            source_fps=npz_scalar(z, path, "source_fps", "float"),
            source_width=npz_scalar(z, path, "source_width", "int"),
            source_height=npz_scalar(z, path, "source_height", "int"),
        )
    return Features(
        descriptors=z["descriptors"], frame_index=fi, n_frames=n_frames, points=points, params=params,
        path=str(path), schema_version=version, **kw, **src,
    )


def directory_params(directory: str | os.PathLike) -> dict[str, Any]:
    """The extraction parameters (``params``: variant, salient points, descriptor, working rate and size)
    of a directory of features files, read and validated from its first ``.npz`` (a directory is one
    ``vidstyle features`` run, so every file records the same)."""
    directory = Path(directory)
    files = sorted(directory.glob("*.npz"))
    if not files:
        raise FormatError(directory, None, "no features files (.npz) in this directory")
    return read_features(files[0]).params
