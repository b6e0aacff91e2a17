"""One video -> one features ``.npz`` (schema: :mod:`vidstyle.formats.features`), streamed.

The video is read through :class:`vidstyle.video.VideoReader` at a working rate and size (the method's
20 fps and a figure about 60-100 px tall: ``height=120`` keeps the demo's 160x120 and turns a 1080x1920
phone clip into 68x120), in grayscale. Frames are processed in windows of ``window`` frames; each window
is described on a slab that adds ``margin`` frames on each side, the frames that the salient points
(t-1, t+1, flow) and the descriptor's neighbourhoods read (:attr:`Descriptor.temporal_margin`). The result
is identical to processing the whole volume at once (:func:`extract_features`), and peak memory is set by
``window + 2 * margin`` working frames, never by the video's length.

Everything is deterministic (no random numbers are used). Files are written atomically.
"""

from __future__ import annotations

import logging
import os
from collections.abc import Callable, Iterable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ..budget import require
from ..errors import InputError, ParameterError, ResourceError
from ..fileio import output_dir, outputs_by_stem
from ..parallel import limit_threads
from . import defaults as D
from .descriptors import DEFAULT_VARIANT, REGISTRY, Descriptor, get_descriptor
from .salient import SalientParams, salient_points

log = logging.getLogger(__name__)

#: schema of the ``params`` JSON inside a features file
FEATURES_SCHEMA = 2
#: working rate and height of the method (``vidstyle features --fps/--height`` defaults)
WORKING_FPS = D.WORKING_FPS
WORKING_HEIGHT = D.WORKING_HEIGHT
#: working frames described per window
WINDOW = 128


def _params(descriptor: Descriptor, salient: SalientParams, fps: float | None, height: int | None) -> dict:
    return {
        "schema": FEATURES_SCHEMA,
        "variant": descriptor.name,
        "salient": salient.to_dict(),
        "descriptor": descriptor.parameters(),
        "working": {"fps": fps, "height": height},
    }


def extract_features(
    frames: np.ndarray,
    variant: str | Descriptor = DEFAULT_VARIANT,
    salient: SalientParams | None = None,
    params: Any = None,
) -> dict[str, Any]:
    """Salient points and descriptors of a whole (frames, h, w) volume in [0, 1] at once (the reference
    that :func:`extract_stream` equals; for short clips and tests): ``points`` (n, 3) int32,
    ``descriptors`` (n, d), ``params`` (dict)."""
    descriptor = get_descriptor(variant, params)
    salient = salient or SalientParams()
    frames = np.asarray(frames)
    pts = salient_points(frames, salient)
    return {
        "points": pts.astype(np.int32),
        "descriptors": descriptor.describe(frames, pts).astype(descriptor.dtype, copy=False),
        "params": _params(descriptor, salient, None, None),
    }


def extract_stream(
    frames: Iterable[np.ndarray],
    n_frames: int,
    variant: str | Descriptor = DEFAULT_VARIANT,
    salient: SalientParams | None = None,
    params: Any = None,
    window: int = WINDOW,
    progress: Callable[[int], None] | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Salient points (n, 3) int32 and descriptors (n, d) of ``n_frames`` uint8 (or [0, 1] float) gray
    frames streamed from ``frames``, holding at most ``window + 2 * margin`` frames; equal to
    :func:`extract_features` on the stacked volume. ``progress(k)`` is told of ``k`` frames done."""
    descriptor = get_descriptor(variant, params)
    salient = salient or SalientParams()
    if window < 1:
        raise InputError(f"window: must be >= 1, got {window}")
    margin = max(1, descriptor.temporal_margin)
    it = iter(frames)
    buf: list[np.ndarray] = []  # frames [buf_start, buf_start + len(buf))
    buf_start = 0
    all_pts, all_desc = [], []
    for s in range(0, n_frames, window):
        e = min(s + window, n_frames)
        a, b = max(0, s - margin), min(n_frames, e + margin)
        del buf[: a - buf_start]
        buf_start = a
        while buf_start + len(buf) < b:
            try:
                f = next(it)
            except StopIteration:
                raise InputError(f"frames: expected {n_frames} frames, got {buf_start + len(buf)}") from None
            f = np.asarray(f)
            buf.append(f.astype(np.float32) * np.float32(1 / 255) if f.dtype == np.uint8 else
                       np.asarray(f, np.float32))
        slab = np.stack(buf)
        pts = salient_points(slab, salient, start=s - a, stop=e - a)
        desc = descriptor.describe(slab, pts).astype(descriptor.dtype, copy=False)
        pts[:, 0] += a
        all_pts.append(pts)
        all_desc.append(desc)
        if progress is not None:
            progress(e - s)
    if not all_pts:
        return np.zeros((0, 3), np.int32), np.zeros((0, descriptor.dimension), descriptor.dtype)
    return np.concatenate(all_pts).astype(np.int32), np.concatenate(all_desc)


#: memory per pixel of the working frame per frame of the window (the frames, their flow fields and the
#: gradient volumes 3D SIFT samples): peak RSS growth of one video measured at 5.8 KB per pixel at
#: 640x480 and 4.6 KB at 1280x960 with the 128-frame window, i.e. 36-46 bytes per pixel and frame
BYTES_PER_WINDOW_PIXEL = 46


def process_video(
    video: str | os.PathLike,
    out_path: str | os.PathLike,
    variant: str | Descriptor = DEFAULT_VARIANT,
    salient: SalientParams | None = None,
    params: Any = None,
    fps: float | None = WORKING_FPS,
    height: int | None = WORKING_HEIGHT,
    window: int = WINDOW,
) -> dict[str, Any]:
    """Stream ``video`` at the working ``fps`` / ``height`` (``None``: the video's own; both only ever
    lower the video's rate and size), extract its features, write ``out_path`` atomically; return a short
    summary."""
    from ..formats.features import Features, write_features
    from ..video import VideoReader

    descriptor = get_descriptor(variant, params)
    salient = salient or SalientParams()
    with limit_threads(1), VideoReader(video, fps=fps, height=height, gray=True, enlarge=False) as reader:
        require(reader.width * reader.height * (window * BYTES_PER_WINDOW_PIXEL + 64),
                f"{video}: features at {reader.width}x{reader.height} over a {window}-frame window", "height",
                "lower the working height")
        n = len(reader)
        frames = (f for _, f in reader.iter_frames())
        try:
            pts, desc = extract_stream(frames, n, descriptor, salient, window=window)
        except MemoryError:
            raise ResourceError(f"{video}: out of memory extracting features at {reader.width}x{reader.height} "
                                f"(lower the working height)") from None
        info = reader.info
        feats = Features(
            descriptors=desc, frame_index=pts[:, 0], n_frames=n, points=pts,
            height=reader.height, width=reader.width, fps=float(reader.fps), variant=descriptor.name,
            params=_params(descriptor, salient, fps, height), video=str(video),
            source_index=reader.source_index, source_frames=info.frames, source_fps=info.fps,
            source_width=info.width, source_height=info.height,
        )
    write_features(out_path, feats)
    log.info("%s: %d frames (%dx%d at %.3g fps), %d points -> %s", video, n, feats.width, feats.height,
             feats.fps, len(pts), out_path)
    return {"video": str(video), "out": str(out_path), "frames": n, "points": int(len(pts))}


def _process_item(item: tuple) -> dict[str, Any]:
    return process_video(*item)


def run_features(
    videos: Sequence[str | os.PathLike],
    out_dir: str | os.PathLike,
    jobs: int = -1,
    variant: str = DEFAULT_VARIANT,
    salient: SalientParams | None = None,
    params: Any = None,
    scheduler: str | None = None,
    fps: float | None = WORKING_FPS,
    height: int | None = WORKING_HEIGHT,
) -> list[dict[str, Any]]:
    """Extract features of every video into ``out_dir``, videos in parallel: joblib with ``jobs`` local
    workers (-1 = all cores), or the Dask cluster at ``scheduler`` (its workers must see the same
    paths). Each worker runs OpenCV and BLAS on one thread; every output is written atomically."""
    from ..parallel import parallel_map

    descriptor = get_descriptor(variant, params)
    for v in videos:
        if not Path(v).is_file():
            raise InputError(f"{v}: file not found")
    outs = outputs_by_stem(videos, out_dir, ".npz")
    # created here; a killed run's temporaries of these outputs swept; removed again if this run fails empty
    with output_dir(out_dir, outs):
        items = [(str(v), str(o), descriptor, salient, None, fps, height) for v, o in zip(videos, outs)]
        return parallel_map(_process_item, items, jobs=jobs, scheduler=scheduler, description="features")


def extract_videos(
    videos: Sequence[str | os.PathLike],
    out_dir: str | os.PathLike,
    *,
    variant: str = D.VARIANT,
    fps: float | None = D.WORKING_FPS,
    height: int | None = D.WORKING_HEIGHT,
    points: int = D.N_POINTS,
    threshold: float = D.THRESHOLD,
    min_distance: float = D.MIN_DISTANCE,
    flow: str = D.FLOW,
    subregions: int = D.SUBREGIONS,
    subregion_size: float = D.SUBREGION_SIZE,
    smooth: float = D.SMOOTH,
    jobs: int = -1,
    scheduler: str | None = None,
) -> list[dict[str, Any]]:
    """The features stage (``vidstyle features``) with its validated defaults
    (:mod:`vidstyle.features.defaults`): per-frame salient points and their descriptors of every video,
    ``<out_dir>/<video stem>.npz`` each, at the working ``fps`` / ``height`` (0 or None: the video's own).
    ``subregions``, ``subregion_size`` and ``smooth`` apply to the ``thesis`` variant only. Parameters are
    checked before any work (:class:`ParameterError` naming the parameter); returns one summary per video."""
    from .sift3d import Sift3DParams

    if variant not in REGISTRY:
        raise ParameterError("variant", f"expected one of {', '.join(REGISTRY)}, got {variant!r}")
    if jobs == 0:
        raise ParameterError("jobs", "must be a positive number of workers or -1 for all cores")
    if fps is not None and not fps >= 0:
        raise ParameterError("fps", f"must be >= 0, got {fps}")
    if height is not None and (height < 0 or 0 < height < D.MIN_HEIGHT):
        raise ParameterError("height", f"must be 0 or at least {D.MIN_HEIGHT}, got {height}")
    if variant != "thesis" and (subregions != D.SUBREGIONS or subregion_size != D.SUBREGION_SIZE
                                or smooth != D.SMOOTH):
        raise ParameterError("variant", f"{variant}: subregions/subregion_size/smooth do not apply")
    salient = SalientParams(n_points=points, threshold=threshold, min_distance=min_distance, flow=flow)
    sift = (Sift3DParams(n_subregions=subregions, subregion_size=subregion_size, smooth_sigma=smooth)
            if variant == "thesis" else None)
    return run_features([str(v) for v in videos], out_dir, jobs=jobs, variant=variant, salient=salient,
                        params=sift, scheduler=scheduler, fps=fps or None, height=height or None)
