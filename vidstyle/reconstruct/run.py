"""``vidstyle reconstruct`` as a library call: a video (and its poses) -> BVH, ``reconstruction.json``,
labels and a side-by-side preview."""

from __future__ import annotations

import logging
import os
from collections.abc import Sequence

import numpy as np

from ..errors import InputError
from .core import Observation, Reconstruction, Reconstructor

log = logging.getLogger(__name__)



def observation_for(video: str | os.PathLike | None, poses: str | os.PathLike | None, backend: str | None = None,
                    model: str | os.PathLike | None = None, frames: Sequence[int] | None = None, jobs: int = 1,
                    fps: float | None = None, size: tuple[int, int] | None = None,
                    view_step_cost: float | None = None, view_dwell_s: float | None = None) -> Observation:
    """The :class:`Observation` of ``video``: its ``poses`` file (``vidstyle pose`` output; the frames up to
    the last one it holds), or poses estimated here with ``backend`` / ``model`` on ``frames`` (default
    all). The frame rate and size come from the video (or ``fps`` / ``size`` when there is no video).
    ``view_step_cost``, ``view_dwell_s``: :meth:`Observation.from_poses`'s viewpoint tracking."""
    from ..formats.poses import read_poses

    n = None
    if video is not None:
        from ..video import VideoReader

        with VideoReader(video) as r:
            n, size = len(r), (r.width, r.height)
            ts = r.timestamps
            fps = float(1.0 / np.median(np.diff(ts))) if len(ts) > 1 else 30.0
    if fps is None or size is None:
        raise InputError("reconstruct: give the video (for its frame rate and size) or --fps and --size")
    if poses is not None:
        doc = read_poses(poses)
        last = max((f.frame for f in doc.frames), default=-1) + 1  # the frames the file covers
        n = last if n is None else min(n, last)
    else:
        if video is None:
            raise InputError("reconstruct: no video to estimate poses in (give VIDEO or --poses)")
        from ..pose.run import estimate_video

        doc = estimate_video(video, backend, model, list(frames) if frames is not None else None, jobs=jobs)
    if frames is not None and len(frames):
        n = max(frames) + 1 if n is None else min(n, max(frames) + 1)
    return Observation.from_poses(doc, fps, size, n, view_step_cost=view_step_cost, view_dwell_s=view_dwell_s)


def record_of(rec: Reconstruction, reconstructor: Reconstructor, video: str, poses: str, bvh: str, fps: float,
              size: tuple[int, int]):
    """The :class:`vidstyle.formats.reconstruction.ReconstructionRecord` of a reconstruction."""
    from ..formats.reconstruction import Neighbour, ReconstructedFrame, ReconstructionRecord

    lib = reconstructor.library_
    index = lib.index_
    frames = []
    for t in range(len(rec.observed)):
        nb = []
        if rec.observed[t]:
            for i, w in zip(rec.neighbours[t], rec.weights[t]):
                if i >= 0 and w > 0:
                    nb.append(Neighbour(int(index.clip_[i]), int(index.frame_[i]), float(min(max(w, 0.0), 1.0))))
        frames.append(ReconstructedFrame(t, bool(rec.observed[t]), float(rec.azimuth[t]), str(rec.labels[t]),
                                         (bool(rec.contacts[t, 0]), bool(rec.contacts[t, 1])), nb))
    params = {k: v for k, v in rec.params.items() if v is not None}
    return ReconstructionRecord(video, poses, bvh, fps, size, list(lib.paths_), params, rec.K, rec.elevation_deg,
                                rec.camera_height, frames)


def write_labels_of(rec: Reconstruction, path: str | os.PathLike, fps: float, video: str) -> bool:
    """Per-frame labels of the matched library frames as a labels file; False when the library has none."""
    from ..formats.labels import write_labels

    labels = [str(x) for x in rec.labels]
    known = sorted({x for x in labels if x})
    if not known:
        return False
    # frames without a label take the nearest labelled frame's (a labels file has one class per frame)
    arr = np.array(labels, dtype=object)
    idx = np.flatnonzero(arr != "")
    nearest = idx[np.clip(np.searchsorted(idx, np.arange(len(arr))), 0, len(idx) - 1)]
    arr = arr[nearest]
    write_labels(path, {"kind": "vidstyle.labels", "schema_version": 2, "video": video, "fps": float(fps),
                        "classes": known, "labels": list(arr)})
    return True


def write_preview(rec: Reconstruction, video: str | os.PathLike | None, obs: Observation, path: str | os.PathLike) -> None:
    """A side-by-side video: left the input frame (grey when there is no video) with the reconstructed
    keypoints projected through the fitted camera (and the observed 2D keypoints as dots), right the
    reconstruction seen from the performer's side (orthographic, the floor as a line)."""
    import cv2

    from ..augmg.keypoints import BONE_INDEX as _BONES
    from ..video import VideoReader
    from ..video.writer import VideoWriter
    from .camera import project

    W, H = obs.size
    scale = max(1, int(round(360 / H)))
    w2, h2 = W * scale, H * scale
    uv = project(rec.camera_points(), rec.K)  # (T, 15, 2)
    # side view: look along -X (from the performer's right when they face +Z), orthographic
    pts = rec.points
    centre = np.nanmedian(pts[:, 2, [2, 1]], axis=0)
    extent = max(float(np.nanpercentile(np.abs(pts[..., 1] - centre[1]), 99)) * 2.4, 1e-6)
    side_px = 0.9 * h2 / extent

    def side(p):  # (15, 3) -> (15, 2) pixels in the right panel
        z, y = p[:, 2] - centre[0], p[:, 1] - centre[1]
        return np.column_stack([w2 / 2 + z * side_px, h2 / 2 - y * side_px])

    reader = VideoReader(video) if video is not None else None
    try:
        with VideoWriter(path, obs.fps) as out:
            for t in range(len(pts)):
                if reader is not None and t < len(reader):
                    img = reader.frame(t)
                    if img.ndim == 2:
                        img = cv2.cvtColor(img, cv2.COLOR_GRAY2BGR)
                else:
                    img = np.full((H, W, 3), 96, np.uint8)
                img = cv2.resize(img, (w2, h2), interpolation=cv2.INTER_NEAREST)
                panel = np.full((h2, w2, 3), 255, np.uint8)
                floor_y = int(round(h2 / 2 + centre[1] * side_px))
                cv2.line(panel, (0, floor_y), (w2 - 1, floor_y), (180, 180, 180), 1)
                for canvas, p, colour in ((img, uv[t] * scale, (0, 255, 255)), (panel, side(pts[t]), (40, 40, 40))):
                    if not np.all(np.isfinite(p)):
                        continue
                    for a, b in _BONES:
                        cv2.line(canvas, tuple(int(round(v)) for v in p[a]), tuple(int(round(v)) for v in p[b]),
                                 colour, 2, cv2.LINE_AA)
                ob = obs.xy[t] * scale
                for k in range(15):
                    if obs.scores[t, k] > 0.2 and np.all(np.isfinite(ob[k])):
                        cv2.circle(img, (int(round(ob[k, 0])), int(round(ob[k, 1]))), 3, (255, 0, 255), -1)
                text = f"{t}  {rec.labels[t]}" + ("" if rec.observed[t] else "  (bridged)")
                cv2.putText(panel, text, (8, 20), cv2.FONT_HERSHEY_SIMPLEX, 0.5, (0, 0, 0), 1, cv2.LINE_AA)
                out.write(np.concatenate([img, panel], axis=1))
    finally:
        if reader is not None:
            reader.close()


def reconstruct_video(video: str | os.PathLike | None, library: Sequence[str | os.PathLike], out: str | os.PathLike,
                      poses: str | os.PathLike | None = None, backend: str | None = None,
                      model: str | os.PathLike | None = None, frames: Sequence[int] | None = None,
                      skeleton: str | os.PathLike | None = None, record: str | os.PathLike | None = None,
                      labels: str | os.PathLike | None = None, preview: str | os.PathLike | None = None,
                      fps: float | None = None, size: tuple[int, int] | None = None, jobs: int = 1,
                      scheduler: str | None = None, cache_dir: str | os.PathLike | None = None,
                      view_step_cost: float | None = None, view_dwell_s: float | None = None,
                      **params) -> Reconstruction:
    """Reconstruct ``video`` against the ``library`` clips and write the BVH ``out`` (and the optional
    ``record`` / ``labels`` / ``preview`` files). ``params``: :class:`Reconstructor` parameters (checked
    before any work); ``cache_dir``: where the library index is cached between runs; ``view_step_cost``,
    ``view_dwell_s``: the viewpoint tracking of :meth:`Observation.from_poses` (default the validated one)."""
    from ..fileio import check_writable
    from ..mocap import read_bvh, write_bvh

    for p in (out, record, labels, preview):
        if p is not None:
            check_writable(p)
    reconstructor = Reconstructor(jobs=jobs, scheduler=scheduler, **params)
    reconstructor.check_params()
    obs = observation_for(video, poses, backend, model, frames, jobs=jobs, fps=fps, size=size,
                          view_step_cost=view_step_cost, view_dwell_s=view_dwell_s)
    target = read_bvh(skeleton).skeleton if skeleton is not None else None
    reconstructor.set_params(target_fps=obs.fps).fit(library, skeleton=target, cache_dir=cache_dir)
    rec = reconstructor.reconstruct(obs)
    write_bvh(rec.motion, out)
    log.info("wrote %s: %d frames (%d with a pose), %d library frames", out, len(rec.observed), int(rec.observed.sum()),
             reconstructor.library_.n_frames)
    if record is not None:
        from ..formats.reconstruction import write_reconstruction

        write_reconstruction(record, record_of(rec, reconstructor, str(video or ""), str(poses or ""), str(out), obs.fps,
                                               obs.size))
        log.info("wrote %s", record)
    if labels is not None:
        if write_labels_of(rec, labels, obs.fps, str(video or "")):
            log.info("wrote %s", labels)
        else:
            log.warning("--labels: the library clips have no labels (<clip>.labels.json); %s not written", labels)
    if preview is not None:
        write_preview(rec, video, obs, preview)
        log.info("wrote %s", preview)
    return rec


__all__ = ["observation_for", "reconstruct_video", "record_of", "write_labels_of", "write_preview"]
