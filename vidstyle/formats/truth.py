"""The renderer's ground-truth sidecar ``<video stem>.truth.npz``: the owner of its schema.

Arrays (F video frames, J joints, C body capsules); the meaning of each is documented in
:mod:`vidstyle.render`. Header: ``kind`` () str ``"vidstyle.render_truth"``, ``schema_version`` () int 2
(sidecars without them are schema 1 and still load)::

    joints2d (F, J, 2) f32, joints3d (F, J, 3) f32, visible (F, J) bool, depth (F, J) f32,
    joint_names (J,) str, parents (J,) int in [-1, J), K (3, 3), R (3, 3), t (3,),
    azimuth_deg, elevation_deg, facing_deg () finite, fps () > 0, size (2,) int > 0 (W, H),
    labels (F,) str, transition (F,) bool, source_time (F,) finite, part_owner (C,) int in [0, J),
    appearance () str (JSON), background () str, [seed () int, noise_sigma () >= 0]

Every float is finite.
"""

from __future__ import annotations

import json
import os
import zipfile
from dataclasses import dataclass, fields
from pathlib import Path

import numpy as np

from ..fileio import atomic_path
from ._base import NPZ_LOCK, FormatError, check_array

KIND = "vidstyle.render_truth"
SCHEMA_VERSION = 2
SUFFIX = ".truth.npz"


@dataclass
class RenderTruth:
    joints2d: np.ndarray
    joints3d: np.ndarray
    visible: np.ndarray
    depth: np.ndarray
    joint_names: np.ndarray
    parents: np.ndarray
    K: np.ndarray
    R: np.ndarray
    t: np.ndarray
    azimuth_deg: float
    elevation_deg: float
    facing_deg: float
    fps: float
    size: np.ndarray
    labels: np.ndarray
    transition: np.ndarray
    source_time: np.ndarray
    part_owner: np.ndarray
    appearance: str
    background: str
    seed: int | None = None
    noise_sigma: float | None = None
    path: str = ""

    @property
    def n_frames(self) -> int:
        return int(self.joints2d.shape[0])

    def to_arrays(self) -> dict[str, np.ndarray]:
        """The arrays as stored (without the header), e.g. ``truth["labels"]``."""
        out: dict[str, np.ndarray] = {}
        for f in fields(self):
            v = getattr(self, f.name)
            if f.name == "path" or v is None:
                continue
            out[f.name] = np.asarray(v)
        return out


def _scalar(z: dict, key: str, path, kind: str = "f", required: bool = True):
    if key not in z:
        if required:
            raise FormatError(path, key, "missing")
        return None
    a = z[key]
    if a.shape != ():
        raise FormatError(path, key, f"expected a scalar, got shape {a.shape}")
    if kind == "s":
        if a.dtype.kind not in "U":
            raise FormatError(path, key, f"expected a string, got {a.dtype}")
        return str(a)
    if a.dtype.kind not in ("iu" if kind == "i" else "iuf"):
        raise FormatError(path, key, f"expected a {'integer' if kind == 'i' else 'number'}, got {a.dtype}")
    v = int(a) if kind == "i" else float(a)
    if kind == "f" and not np.isfinite(v):
        raise FormatError(path, key, f"must be finite, got {v}")
    return v


def _arr(z: dict, key: str, path, shape, dtype_kinds: str, finite: bool = True) -> np.ndarray:
    if key not in z:
        raise FormatError(path, key, "missing")
    a = z[key]
    if a.dtype.kind not in dtype_kinds:
        raise FormatError(path, key, f"unexpected dtype {a.dtype}")
    if a.dtype.kind == "U":
        if a.ndim != len(shape) or any(s is not None and s != n for s, n in zip(shape, a.shape)):
            raise FormatError(path, key, f"expected shape {shape}, got {a.shape}")
        return a
    return check_array(a, path, key, shape, dtype=a.dtype, finite=finite)


def parse_truth(z: dict[str, np.ndarray], path: str | os.PathLike | None = None) -> RenderTruth:
    """Validate the arrays of a sidecar (see the module docstring)."""
    if "kind" in z or "schema_version" in z:
        kind = _scalar(z, "kind", path, "s")
        if kind != KIND:
            raise FormatError(path, "kind", f"expected {KIND!r}, got {kind!r}")
        v = _scalar(z, "schema_version", path, "i")
        if v not in (1, SCHEMA_VERSION):
            raise FormatError(path, "schema_version", f"{v} is not supported (expected 1, {SCHEMA_VERSION})")
    names = _arr(z, "joint_names", path, (None,), "U")
    J = len(names)
    j2 = _arr(z, "joints2d", path, (None, J, 2), "f")
    F = j2.shape[0]
    parents = _arr(z, "parents", path, (J,), "iu")
    if parents.size and (parents.min() < -1 or parents.max() >= J):
        raise FormatError(path, "parents", f"indices must lie in [-1, {J})")
    owner = _arr(z, "part_owner", path, (None,), "iu")
    if owner.size and (owner.min() < 0 or owner.max() >= J):
        raise FormatError(path, "part_owner", f"indices must lie in [0, {J})")
    size = _arr(z, "size", path, (2,), "iu")
    if (size <= 0).any():
        raise FormatError(path, "size", "width and height must be positive")
    fps = _scalar(z, "fps", path)
    if not fps > 0:
        raise FormatError(path, "fps", f"must be positive, got {fps}")
    appearance = _scalar(z, "appearance", path, "s")
    try:
        json.loads(appearance)
    except ValueError:
        raise FormatError(path, "appearance", "not valid JSON") from None
    noise = _scalar(z, "noise_sigma", path, required=False)
    if noise is not None and noise < 0:
        raise FormatError(path, "noise_sigma", f"must be >= 0, got {noise}")
    return RenderTruth(
        joints2d=j2, joints3d=_arr(z, "joints3d", path, (F, J, 3), "f"), visible=_arr(z, "visible", path, (F, J), "b"),
        depth=_arr(z, "depth", path, (F, J), "f"), joint_names=names, parents=parents,
        K=_arr(z, "K", path, (3, 3), "f"), R=_arr(z, "R", path, (3, 3), "f"), t=_arr(z, "t", path, (3,), "f"),
        azimuth_deg=_scalar(z, "azimuth_deg", path), elevation_deg=_scalar(z, "elevation_deg", path),
        facing_deg=_scalar(z, "facing_deg", path), fps=fps, size=size,
        labels=_arr(z, "labels", path, (F,), "U"), transition=_arr(z, "transition", path, (F,), "b"),
        source_time=_arr(z, "source_time", path, (F,), "f"), part_owner=owner, appearance=appearance,
        background=_scalar(z, "background", path, "s"), seed=_scalar(z, "seed", path, "i", required=False),
        noise_sigma=noise, path="" if path is None else str(path),
    )


def truth_path(path: str | os.PathLike) -> Path:
    """``clip.mp4`` -> ``clip.truth.npz``; a ``.truth.npz`` path is returned as is."""
    path = Path(path)
    return path if path.name.endswith(SUFFIX) else path.with_name(path.stem + SUFFIX)


def read_npz(path: str | os.PathLike) -> dict[str, np.ndarray]:
    """Every array of an ``.npz`` (no pickles); any damage (truncation, bad zip, bad member) is a FormatError."""
    path = Path(path)
    if path.is_dir():
        raise FormatError(path, None, "is a directory, not a file")
    try:
        with NPZ_LOCK, np.load(path, allow_pickle=False) as z:
            return {k: z[k] for k in z.files}
    except FileNotFoundError:
        raise FormatError(path, None, "file not found") from None
    except (zipfile.BadZipFile, zipfile.LargeZipFile):
        raise FormatError(path, None, "not a readable .npz (damaged or truncated zip)") from None
    except Exception as e:  # noqa: BLE001 - zlib.error, ValueError (pickled object arrays, bad header), EOFError, OSError...
        raise FormatError(path, None, f"not a readable .npz ({type(e).__name__}: {e})"[:300]) from None


def read_truth(path: str | os.PathLike) -> RenderTruth:
    """Read and validate a sidecar (``.truth.npz``, or the video beside which it lies)."""
    path = truth_path(path)
    if not path.exists():
        raise FormatError(path, None, "ground-truth sidecar not found")
    return parse_truth(read_npz(path), path)


def truth_arrays(truth: RenderTruth | dict[str, np.ndarray], path=None) -> dict[str, np.ndarray]:
    """The validated arrays of a sidecar, with its header, ready for ``np.savez_compressed``."""
    arrays = truth.to_arrays() if isinstance(truth, RenderTruth) else {k: np.asarray(v) for k, v in truth.items()}
    arrays = {k: v for k, v in arrays.items() if k not in ("kind", "schema_version")}
    arrays["kind"] = np.array(KIND)
    arrays["schema_version"] = np.int64(SCHEMA_VERSION)
    parse_truth(arrays, path)
    return arrays


def write_truth(path: str | os.PathLike, truth: RenderTruth | dict[str, np.ndarray]) -> None:
    """Validate and write a sidecar atomically (compressed), with its header."""
    arrays = truth_arrays(truth, path)
    with atomic_path(path, suffix=".npz") as tmp:
        np.savez_compressed(tmp, **arrays)
