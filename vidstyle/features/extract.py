"""One video -> one compressed ``.npz`` of salient points and their 3D SIFT descriptors.

Schema (``FEATURES_SCHEMA`` = 1), one file ``<out>/<video stem>.npz`` per video:

=============== ============== =====================================================================
key             dtype, shape   meaning
=============== ============== =====================================================================
``points``      int32 (n, 3)   0-based (frame, row, column) of each salient point, sorted by frame
``descriptors`` (n, d)         float32, d = 256 by default (variant "thesis"), or uint8, d = 640
                               (variant "scovanner2007"), or float32, d = 128 (variant "sift2d",
                               the 2D ablation); row i describes ``points[i]``
``frame_index`` int32 (n,)     frame of each point (``points[:, 0]``), for grouping by frame
``params``      str (0-d)      JSON: ``schema``, ``variant``, ``salient`` (N, thresholds, flow
                               method), ``descriptor`` (all descriptor parameters)
``variant``     str (0-d)      "thesis", "scovanner2007" or "sift2d"
``n_frames``    int64 (0-d)    frames decoded
``height``      int64 (0-d)    frame height in pixels
``width``       int64 (0-d)    frame width in pixels
``fps``         float64 (0-d)  frame rate the container declares (0 if unknown); frames are
                               addressed by index only
``video``       str (0-d)      path of the source video as given
=============== ============== =====================================================================

Everything is deterministic (no random numbers are used). Files are written atomically.
"""

from __future__ import annotations

import contextlib
import json
import logging
import os
import zipfile
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import InputError
from ..fileio import outputs_by_stem, write_npz
from .salient import SalientParams, salient_points
from .sift3d import VARIANTS, Sift3DParams, describe, params_json
from .videoio import read_gray

log = logging.getLogger(__name__)

FEATURES_SCHEMA = 1


@contextlib.contextmanager
def single_threaded() -> Iterator[None]:
    """OpenCV and BLAS on one thread: parallelism is across videos, and the per-point matrix products
    are too small to gain from threads (they lose)."""
    import cv2
    from threadpoolctl import threadpool_limits

    before = cv2.getNumThreads()
    cv2.setNumThreads(1)
    try:
        with threadpool_limits(limits=1):
            yield
    finally:
        cv2.setNumThreads(before)


def extract_features(
    frames: np.ndarray,
    variant: str = "thesis",
    salient: SalientParams | None = None,
    sift: Sift3DParams | None = None,
) -> dict[str, Any]:
    """Salient points and descriptors of a (frames, h, w) volume in [0, 1]; the .npz arrays (no metadata
    about a file)."""
    if variant not in VARIANTS:
        raise InputError(f"variant: expected one of {', '.join(VARIANTS)}, got {variant!r}")
    salient = salient or SalientParams()
    pts = salient_points(frames, salient)
    if variant == "thesis":
        desc = describe(frames, pts, "thesis", params=sift or Sift3DParams())
    elif variant == "sift2d":
        desc = describe(frames, pts, "sift2d")
        sift = None  # params_json records the 2D defaults
    else:
        desc = describe(frames, pts, "scovanner2007")
    params = {
        "schema": FEATURES_SCHEMA,
        "variant": variant,
        "salient": salient.to_dict(),
        "descriptor": json.loads(params_json(variant, sift)),
    }
    return {
        "points": pts.astype(np.int32),
        "descriptors": desc,
        "frame_index": pts[:, 0].astype(np.int32),
        "params": np.array(json.dumps(params, sort_keys=True)),
        "variant": np.array(variant),
        "n_frames": np.int64(frames.shape[0]),
        "height": np.int64(frames.shape[1]),
        "width": np.int64(frames.shape[2]),
    }


def process_video(
    video: str | os.PathLike,
    out_path: str | os.PathLike,
    variant: str = "thesis",
    salient: SalientParams | None = None,
    sift: Sift3DParams | None = None,
) -> dict[str, Any]:
    """Read ``video``, extract its features, write ``out_path`` atomically; return a short summary."""
    with single_threaded():
        v = read_gray(video)
        arrays = extract_features(v.frames, variant, salient, sift)
    arrays["fps"] = np.float64(v.fps)
    arrays["video"] = np.array(str(video))
    write_npz(out_path, **arrays)
    n = len(arrays["points"])
    log.info("%s: %d frames, %d points -> %s", video, v.frames.shape[0], n, out_path)
    return {"video": str(video), "out": str(out_path), "frames": int(v.frames.shape[0]), "points": n}


def _process_item(item: tuple) -> dict[str, Any]:
    return process_video(*item)


def run_features(
    videos: Sequence[str | os.PathLike],
    out_dir: str | os.PathLike,
    jobs: int = -1,
    variant: str = "thesis",
    salient: SalientParams | None = None,
    sift: Sift3DParams | None = None,
    scheduler: str | None = None,
) -> list[dict[str, Any]]:
    """Extract features of every video into ``out_dir``, videos in parallel: joblib with ``jobs`` local
    workers (-1 = all cores), or the Dask cluster at ``scheduler`` (its workers must see the same
    paths). Each worker runs OpenCV and BLAS on one thread; every output is written atomically."""
    from ..parallel import parallel_map

    if variant not in VARIANTS:
        raise InputError(f"--variant: expected one of {', '.join(VARIANTS)}, got {variant!r}")
    if jobs == 0:
        raise InputError("--jobs: must be a positive number of workers or -1 for all cores")
    for v in videos:
        if not Path(v).is_file():
            raise InputError(f"{v}: file not found")
    outs = outputs_by_stem(videos, out_dir, ".npz")
    Path(out_dir).mkdir(parents=True, exist_ok=True)
    items = [(str(v), str(o), variant, salient, sift) for v, o in zip(videos, outs)]
    return parallel_map(_process_item, items, jobs=jobs, scheduler=scheduler, description="features")


def load_features(path: str | os.PathLike) -> dict[str, Any]:
    """Read a features ``.npz``; ``params`` is decoded from JSON, scalars become Python values."""
    path = Path(path)
    try:
        with np.load(path, allow_pickle=False) as z:
            d = {k: z[k] for k in z.files}
    except FileNotFoundError:
        raise InputError(f"{path}: file not found") from None
    except (OSError, ValueError, zipfile.BadZipFile) as e:
        raise InputError(f"{path}: not a features .npz ({e})") from None
    missing = {"points", "descriptors", "frame_index", "params"} - set(d)
    if missing:
        raise InputError(f"{path}: not a features .npz (missing {', '.join(sorted(missing))})")
    for k in ("n_frames", "height", "width"):
        if k in d:
            d[k] = int(d[k])
    for k in ("variant", "video"):
        if k in d:
            d[k] = str(d[k])
    if "fps" in d:
        d["fps"] = float(d["fps"])
    d["params"] = json.loads(str(d["params"]))
    return d
