"""Poses of chosen frames of one video, through the project's one parallel path (frame chunks, each
worker opening its own :class:`vidstyle.video.VideoReader`: memory stays bounded by a chunk)."""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import InputError, ParameterError
from ..formats.poses import PoseFrame, Poses
from .defaults import PS_SCALES
from .interfaces import MODEL_BACKENDS, PoseBackend, backend_factory, check_backend

log = logging.getLogger(__name__)


@dataclass
class _Chunk:
    video: str
    frames: list[int]
    backend: str
    model_path: str | None
    scales: tuple[float, ...] = (1.0,)
    track: bool = False
    person: tuple[float, float] | None = None
    person_frame: int | None = None

#: backends followed through the video by default (single-person estimators run on real footage, where
#: other people may be in view); the pictorial structures run on the whole frame unless asked
TRACKED_BACKENDS = ("blazepose",)


def working_height(backend: PoseBackend, native_height: int) -> int:
    """The height a backend reads a video at (:meth:`PoseBackend.working_height`)."""
    return int(backend.working_height(native_height))


def to_input_pixels(pts: np.ndarray, work_size: tuple[int, int], in_size: tuple[int, int]) -> np.ndarray:
    """Keypoints (n, 3) at the working size -> the input video's pixels (pixel centres at integers)."""
    out = np.array(pts, dtype=np.float64, copy=True)
    sx, sy = in_size[0] / work_size[0], in_size[1] / work_size[1]
    out[:, 0] = (out[:, 0] + 0.5) * sx - 0.5
    out[:, 1] = (out[:, 1] + 0.5) * sy - 0.5
    return out


def _make_estimator(backend: str, model_path: str | None) -> PoseBackend:
    return backend_factory(backend)(model_path)


def _run_chunk(chunk: _Chunk) -> list[PoseFrame]:
    est = _make_estimator(chunk.backend, chunk.model_path)
    if chunk.scales != (1.0,):
        est.set_inference(scales=chunk.scales)
    out = estimate_frames(chunk.video, est, chunk.frames, chunk.track, chunk.person, chunk.person_frame)
    est.close()
    return out


def estimate_frames(video, est, frames: list[int], track: bool, person: tuple[float, float] | None = None,
                    person_frame: int | None = None, tracker_params: dict | None = None) -> list[PoseFrame]:
    """Poses of ``frames`` of ``video`` by the backend instance ``est``, read at its working height, in the
    input video's pixels (scores clipped to 0..1): each frame alone, or (``track``) one performer followed
    by :class:`vidstyle.pose.people.PerformerTracker` (``tracker_params``: its settings; ``person``: a
    pixel of the input video, chosen at ``person_frame`` or the first frame with people). Frames without
    a pose are :meth:`PoseFrame.none` with the reason."""
    from ..video import VideoReader

    with VideoReader(video) as probe:
        in_size = (probe.info.width, probe.info.height)
    h = working_height(est, in_size[1])
    out = []
    tracker = None
    if track:
        from .people import PerformerTracker

        chosen = None
        if person is not None:  # the pixel is given in the input video's frame
            scale = h / in_size[1]
            chosen = ((person[0] + 0.5) * scale - 0.5, (person[1] + 0.5) * scale - 0.5)
        tracker = PerformerTracker(est, person=chosen, **(tracker_params or {}))
    with VideoReader(video, height=None if h == in_size[1] else h) as reader:
        if tracker is not None:
            tracked = tracker.follow(lambda i: np.asarray(reader.frame(i)), frames, person_frame)
            poses = (t.pose if t.pose is not None else PoseFrame.none(t.index, t.missing or "performer not found")
                     for t in tracked)
        else:
            bg = video_background(reader) if est.uses_background else None
            poses = (est.estimate(np.asarray(reader.frame(i)), i, background=bg) for i in frames)
        for pf in poses:
            if pf.found:
                pf.points = to_input_pixels(pf.points, reader.size, in_size)
                pf.points[:, 2] = np.clip(pf.points[:, 2], 0.0, 1.0)
            out.append(pf)
    return out


def parse_person(text: str | None) -> tuple[float, float] | None:
    """``"X,Y"`` (pixels of the input video) -> (x, y); :class:`ParameterError` naming ``person``."""
    if text is None:
        return None
    try:
        x, y = (float(v) for v in str(text).split(","))
    except ValueError:
        raise ParameterError("person", f"{text!r} is not X,Y in pixels") from None
    if not (math.isfinite(x) and math.isfinite(y) and x >= 0 and y >= 0):
        raise ParameterError("person", f"{text!r} is not a pixel of the video")
    return x, y


def smooth_poses(poses: Poses, fps: float, min_cutoff: float | None = None, beta: float | None = None) -> Poses:
    """The poses with every keypoint track One-Euro filtered (:mod:`vidstyle.pose.smoothing`) over the
    frames that have a pose; frames are timed by their index at ``fps``."""
    from . import smoothing

    found = [pf for pf in poses.frames if pf.found]
    if len(found) < 2:
        return poses
    xy = np.stack([pf.points[:, :2] for pf in found])
    times = np.array([pf.frame for pf in found], dtype=np.float64) / fps
    # a frame whose keypoint is unsure is a gap for that keypoint
    sure = np.stack([pf.points[:, 2] for pf in found]) > 0
    xy = np.where(sure[..., None], xy, np.nan)
    filt = smoothing.one_euro(xy, times, smoothing.MIN_CUTOFF if min_cutoff is None else min_cutoff,
                              smoothing.BETA if beta is None else beta)
    for pf, f in zip(found, filt):
        ok = np.all(np.isfinite(f), axis=1)
        pf.points[ok, :2] = f[ok]
    return poses


BACKGROUND_FRAMES = 25


def video_background(reader) -> np.ndarray | None:
    """Static-camera background of a whole video: the per-pixel median of ``BACKGROUND_FRAMES``
    frames spread evenly over it (memory: those frames only). None for videos under 3 frames."""
    from .foreground import background_model

    n = len(reader)
    if n < 3:
        return None
    idx = sorted(set(np.linspace(0, n - 1, min(n, BACKGROUND_FRAMES)).round().astype(int).tolist()))
    return background_model(np.asarray(reader.frame(i)) for i in idx)


def parse_frames(text: str | None, n_frames: int) -> list[int]:
    """``"12,40,100"`` -> sorted unique indices (all frames when ``None``); errors name the frame."""
    if text is None or not str(text).strip():
        return list(range(n_frames))
    out = set()
    for tok in str(text).split(","):
        tok = tok.strip()
        if not tok:
            continue
        try:
            i = int(tok)
        except ValueError:
            raise ParameterError("frames", f"{tok!r} is not a frame index") from None
        if not 0 <= i < n_frames:
            raise ParameterError("frames", f"{i} is outside the video's 0..{n_frames - 1}")
        out.add(i)
    if not out:
        raise ParameterError("frames", "no frame index given")
    return sorted(out)


def resolve_model(backend: str, model_path):
    """The pose model file of ``backend``: ``model_path`` when given, else, for a backend that needs one
    (:data:`~vidstyle.pose.interfaces.MODEL_BACKENDS`), the model shipped with the package
    (:func:`vidstyle.pose.defaults.shipped_model_path`); None for backends without a model file."""
    if model_path is not None or backend not in MODEL_BACKENDS:
        return model_path
    from .defaults import shipped_model_path

    path = shipped_model_path()
    if not path.is_file():
        raise ParameterError("model", f"the {backend} backend needs a pose model (vidstyle train-pose): none "
                             f"given, and this installation has no shipped model ({path})")
    return str(path)


def check_estimate_params(backend: str, model_path, scales) -> tuple[float, ...]:
    """The checks of :func:`estimate_video`'s settings (:class:`ParameterError` naming the parameter:
    ``backend``, ``model``, ``scales``); returns the zoom factors."""
    check_backend(backend)
    resolve_model(backend, model_path)
    if scales is None:
        return PS_SCALES if backend == "ps" else (1.0,)
    if backend != "ps":
        raise ParameterError("scales", "multi-scale inference is a ps backend setting")
    from .estimator import check_scales  # the ps model's module (scikit-learn, numba): not for BlazePose

    try:
        return check_scales(scales)
    except ValueError as exc:
        raise ParameterError("scales", str(exc)) from None


def default_backend(model_path) -> str:
    """``vidstyle pose``'s backend when none is named: the pictorial structures when a pose model is
    given, else BlazePose (it needs no training and works on real people: multi-view PCK@0.2 on the
    calibrated real views, see docs/results.md)."""
    return "ps" if model_path is not None else "blazepose"


def estimate_video(video: str | Path, backend: str | None = None, model_path: str | Path | None = None,
                   frames: list[int] | None = None, jobs: int = -1, scheduler: str | None = None,
                   chunk_frames: int = 16, scales=None, track: bool | None = None,
                   person: tuple[float, float] | None = None, smooth: bool = False,
                   person_frame: int | None = None) -> Poses:
    """Poses of ``frames`` (default: all) of ``video`` (``vidstyle pose``); ``backend``: a name of
    :data:`vidstyle.pose.interfaces.BACKENDS` (default :func:`default_backend`; ``model_path``: the ``ps``
    backend's pose model file, default the shipped one, :func:`resolve_model`); ``scales``: zoom factors of the ps backend's multi-scale inference
    (:meth:`vidstyle.pose.estimator.PoseModel.estimate`; default :data:`vidstyle.pose.defaults.PS_SCALES`). ``track`` (default: on for
    :data:`TRACKED_BACKENDS`): follow one performer through the frames
    (:class:`vidstyle.pose.people.PerformerTracker`; ``person``: the one at that pixel of the input video
    in the first frame with people, or in frame ``person_frame`` when given (chosen there, then followed
    forward and backward from it: :meth:`~vidstyle.pose.people.PerformerTracker.follow`; the frame need
    not be one of ``frames``), else the most prominent), in one worker since each frame continues from
    the last; frames without the performer have no pose (a reason instead). ``smooth``: One-Euro filter
    the keypoint tracks (:func:`smooth_poses`)."""
    from ..parallel import parallel_map
    from ..video import VideoReader

    backend = default_backend(model_path) if backend is None else backend
    scales = check_estimate_params(backend, model_path, scales)
    model_path = resolve_model(backend, model_path)
    track = backend in TRACKED_BACKENDS if track is None else bool(track)
    if person is not None and not track:
        raise ParameterError("person", "choosing a person needs tracking (track=True)")
    if person_frame is not None and person is None:
        raise ParameterError("person_frame", "is the frame of a chosen person: give person as well")
    with VideoReader(video) as r:
        n = len(r)
        fps = r.fps
    if person_frame is not None and not (isinstance(person_frame, (int, np.integer)) and 0 <= person_frame < n):
        raise ParameterError("person_frame", f"{person_frame!r} is not a frame of the video (0..{n - 1})")
    frames = list(range(n)) if frames is None else frames
    if backend in MODEL_BACKENDS:  # fail early on a bad model file, before any worker starts
        _make_estimator(backend, str(model_path))
    size = len(frames) if track else max(1, min(chunk_frames, math.ceil(len(frames) / 2)))
    chunks = [_Chunk(str(video), frames[i:i + size], backend, None if model_path is None else str(model_path),
                     scales, track, person, None if person_frame is None else int(person_frame))
              for i in range(0, len(frames), max(size, 1))]
    res = parallel_map(_run_chunk, chunks, jobs=1 if track else jobs, scheduler=None if track else scheduler,
                       description=f"pose ({backend})")
    params: dict = {"scales": list(scales)} if scales != (1.0,) else {}
    if track:
        params["tracked"] = True
        if person is not None:
            params["person"] = [float(person[0]), float(person[1])]
        if person_frame is not None:
            params["person_frame"] = int(person_frame)
    poses = Poses(str(video), backend, [pf for part in res for pf in part], params=params)
    if smooth:
        poses = smooth_poses(poses, fps if fps > 0 else 1.0)
        poses.params["smoothed"] = "one-euro"
    return poses


def mark_frames(video: str | Path, annotations: str | Path, context: int = 0) -> list[int]:
    """The frames of ``video``'s transition marks in an annotations file (``vidstyle annotate``; the video
    must be the annotated one: same sha256), with ``context`` frames either side of each (inside the
    video); :class:`InputError` when there are none."""
    return _marks_of(video, annotations, context)[0]


def _marks_of(video, annotations, context: int):
    """(:func:`mark_frames`, the video's annotations entry, its upright ``(width, height)``)."""
    from ..formats.annotations import check_video, read_annotations
    from ..video import VideoReader

    from .defaults import MAX_CONTEXT

    if not 0 <= context <= MAX_CONTEXT:
        raise ParameterError("context", f"must be in 0..{MAX_CONTEXT}, got {context}")
    with VideoReader(video) as r:
        n = r.info.frames
        size = (r.info.width, r.info.height)
    if context >= n:
        raise ParameterError("context", f"must be less than the video's {n} frames, got {context}")
    ann = read_annotations(annotations)
    entry = ann.video_for(video, annotations)
    check_video(entry, video, n, annotations)
    idx = sorted({f for t in entry.transitions for f in range(max(0, t.frame - context), min(n, t.frame + context + 1))})
    if not idx:
        raise InputError(f"{annotations}: no transition marks for {video}")
    return idx, entry, size


def estimate_marks(video: str | Path, annotations: str | Path, backend: str | None = None,
                   model_path: str | Path | None = None, context: int = 0, jobs: int = -1,
                   scheduler: str | None = None, scales=None, track: bool | None = None,
                   person: tuple[float, float] | None = None) -> Poses:
    """Poses of the frames of ``video``'s transition marks (:func:`mark_frames`; ``vidstyle pose
    --annotations``), the frames AugMG matches; the other parameters as :func:`estimate_video`.

    The marks are scattered frames, not a continuous video, so without a performer choice they are not
    followed (AugMG's validated thresholds were chosen on whole-frame poses). A choice turns following
    on (``track`` None): ``person`` (a pixel of the input video, chosen in the first of these frames with
    people), else the performer stored for this video in the annotations file (``vidstyle annotate``'s
    "Choose performer": a frame and a pixel; chosen at that frame, then followed forward and backward
    from it). ``track=False`` ignores a stored choice; ``track=True`` without one follows the most
    prominent person. The choice used is logged."""
    from ..formats.annotations import check_performer

    backend = default_backend(model_path) if backend is None else backend
    check_estimate_params(backend, model_path, scales)
    idx, entry, size = _marks_of(video, annotations, context)
    stored = check_performer(entry, *size, annotations)
    person_frame = None
    if person is not None:
        track = True if track is None else track
        if stored is not None:
            log.info("performer: the person at pixel (%g, %g) given, not the one chosen in %s", *person, annotations)
        else:
            log.info("performer: the person at pixel (%g, %g) of the first marked frame with people", *person)
    elif stored is not None and track is not False:
        track, person, person_frame = True, (stored.x, stored.y), stored.frame
        log.info("performer: the person at pixel (%g, %g) of frame %d, as chosen in %s", stored.x, stored.y,
                 stored.frame, annotations)
    elif stored is not None:
        log.info("performer: the choice in %s is not used (not following the performer)", annotations)
    elif track:
        log.info("performer: the most prominent person (no choice in %s)", annotations)
    return estimate_video(video, backend, model_path, idx, jobs=jobs, scheduler=scheduler, scales=scales,
                          track=bool(track), person=person, person_frame=person_frame)
