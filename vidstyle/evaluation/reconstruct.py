"""``vidstyle evaluate reconstruct``: 3D motion from video against the true 3D motion.

Data: the demo dataset's held-out renders, whose true 3D motion is the BVH each video was rendered from
(``truth.npz`` maps every video frame to a time of that take). By default one performance video of each
*test* performer of the ``unseen-performer`` split (:mod:`vidstyle.recognition.splits`), never the
performers the library (``vidstyle demo make-library``) was made from; ``max_frames`` keeps the first
frames of each.

Sources of the 2D keypoints: ``true2d`` (the truth projected through the render camera, with the true
azimuth) and, per ``poses_dirs`` entry, the pose stage's estimate (``<dir>/<video id>.poses.json``, named
by its backend). Methods: the reconstructor's ``method`` values (per-frame nearest neighbours ``nn``,
the lazy neighbourhood graph ``olng``). Skeletons: ``library`` (the output skeleton is the library's:
the performer's body is unknown, as for a user's video), ``height`` (the same reconstruction scaled to the
performer's standing height, as ``vidstyle reconstruct --height`` does when a user knows it: the
library's proportions at the performer's size; scored from the ``library`` run, which it only rescales)
and ``performer`` (the take's own skeleton given as ``--skeleton``: the error of the motion alone,
without the body-size difference). When the estimated
poses carry BlazePose's 3D world landmarks, they are scored too (method ``blazepose-world``: the offline
peer), turned into the reconstruction's world with the same assumed camera pitch; they are hip-centred, so
their MPJPE after one alignment per take and their foot skate are not scored (null).

Figures (:mod:`vidstyle.reconstruct.metrics`, mm): MPJPE after one yaw and floor translation per
sequence, root-relative MPJPE (pelvis subtracted per frame, one yaw per sequence), PA-MPJPE, acceleration
error (mm/frame^2) and foot skate (mm per frame of planted-foot slide, planted where the *true* foot is).
Frames without a pose are reconstructed (bridged) and scored like the others. Pooled rows weight every
video by its frames.
"""

from __future__ import annotations

import logging
import math
import os
import time
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from ..reconstruct.core import Observation

from ..errors import InputError

log = logging.getLogger(__name__)

SKELETONS = ("library", "height", "performer")


def _truth(dataset, video_id: str, n_frames: int | None):
    """(true 3D keypoints (T, 15, 3) mocap units, true 2D (T, 15, 2), true azimuth (T,), size, fps, bvh path)."""
    from ..augmg.projection import facing_of_keypoints, relative_azimuth
    from ..formats.truth import read_truth
    from ..mocap import read_bvh
    from ..mocap.keypoints import keypoint_positions
    from ..render.camera import Camera

    v = dataset.by_id()[video_id]
    truth = read_truth(dataset.root / v.raw["truth"])
    bvh = dataset.root / v.raw["bvh"]
    motion = read_bvh(bvh)
    T = len(truth.source_time) if n_frames is None else min(int(n_frames), len(truth.source_time))
    idx = np.clip(np.round(truth.source_time[:T] * motion.fps).astype(int), 0, motion.n_frames - 1)
    pts = keypoint_positions(motion)[idx]
    size = (int(truth.size[0]), int(truth.size[1]))
    cam = Camera(truth.K, truth.R, truth.t, size=size)
    uv, _ = cam.project(pts)
    centre = -np.asarray(truth.R).T @ np.asarray(truth.t)
    az = relative_azimuth(centre, pts[:, 2], facing_of_keypoints(pts))
    return pts, np.asarray(uv, dtype=np.float64), az, size, float(truth.fps), bvh


def default_videos(dataset, seed: int = 0) -> list[str]:
    """The first performance video of every test performer of the ``unseen-performer`` split."""
    from ..recognition.splits import make_split

    split = make_split(dataset, "unseen-performer", seed=seed)
    test = set(split.test)
    out = []
    for p in sorted(split.test_performers):
        perf = sorted(v.id for v in dataset.videos if v.performer == p and v.kind == "performance" and v.id in test)
        if perf:
            out.append(perf[0])
    if not out:
        raise InputError(f"{dataset.root}: no performance video of a test performer to reconstruct")
    return out


def blazepose_world_points(poses, n_frames: int, elevation_deg: float) -> np.ndarray | None:
    """(T, 15, 3) BlazePose world landmarks (mm) in the reconstruction's world (+Y up, camera pitched by
    ``elevation_deg``), NaN where a frame has none; None when the file has no world landmarks."""
    from ..reconstruct.core import camera_rotation

    out = np.full((n_frames, 15, 3), np.nan)
    found = False
    for f in poses.frames:
        world = getattr(f, "world", None)
        if world is None or not f.found or f.frame >= n_frames:
            continue
        out[f.frame] = np.asarray(world, dtype=np.float64) * 1000.0  # metres, camera axes
        found = True
    if not found:
        return None
    return out @ camera_rotation(elevation_deg)  # camera -> world (rows of Rc are the camera axes)


def write_comparison(path: str | os.PathLike, pred_mm: np.ndarray, true_mm: np.ndarray, fps: float,
                     title: str = "") -> None:
    """A video of the reconstruction (orange) against the truth (grey), aligned by one yaw and floor
    translation (:func:`vidstyle.reconstruct.metrics.align_sequence`), seen from the front (left) and
    the side (right), orthographic, the floor as a line."""
    import cv2

    from ..augmg.keypoints import BONE_INDEX as _BONES
    from ..reconstruct import metrics as M
    from ..video.writer import VideoWriter

    aligned, _, _ = M.align_sequence(pred_mm, true_mm)
    both = np.concatenate([aligned, true_mm])
    ok = np.all(np.isfinite(both), axis=(1, 2))
    centre = np.nanmedian(true_mm[:, 2], axis=0)
    span = float(np.nanmax(both[ok][..., 1]) - min(0.0, float(np.nanmin(both[ok][..., 1])))) * 1.15 or 1.0
    size = 320
    px = size / span

    def view(p, axis):  # (15, 3) -> (15, 2) pixels: horizontal axis 0 (front) or 2 (side)
        h = p[:, axis] - centre[axis]
        return np.column_stack([size / 2 + h * px, size - 12 - p[:, 1] * px])

    with VideoWriter(path, fps) as out:
        for t in range(len(true_mm)):
            img = np.full((size, 2 * size, 3), 255, np.uint8)
            for off, axis in ((0, 0), (size, 2)):
                cv2.line(img, (off, size - 12), (off + size - 1, size - 12), (190, 190, 190), 1)
                for pts, colour in ((true_mm[t], (150, 150, 150)), (aligned[t], (0, 120, 255))):
                    if not np.all(np.isfinite(pts)):
                        continue
                    q = view(pts, axis)
                    for a, b in _BONES:
                        cv2.line(img, (int(off + q[a, 0]), int(q[a, 1])), (int(off + q[b, 0]), int(q[b, 1])), colour, 2,
                                 cv2.LINE_AA)
            cv2.putText(img, f"{title} {t}", (6, 16), cv2.FONT_HERSHEY_SIMPLEX, 0.45, (0, 0, 0), 1, cv2.LINE_AA)
            out.write(img)


def _figures(pred_mm: np.ndarray, true_mm: np.ndarray, fps: float) -> dict[str, Any]:
    from ..reconstruct import metrics as M

    ok = M.valid_frames(pred_mm, true_mm)
    contacts = M.foot_contacts(true_mm, fps)
    out = {"frames": int(ok.sum()),
           "mpjpe_mm": M.mpjpe(pred_mm, true_mm),
           "mpjpe_root_relative_mm": M.mpjpe_root_relative(pred_mm, true_mm),
           "pa_mpjpe_mm": M.pa_mpjpe(pred_mm, true_mm),
           "acceleration_error_mm_per_frame2": M.acceleration_error(pred_mm, true_mm),
           "foot_skate_mm_per_frame": M.foot_skate(pred_mm, contacts=contacts)}
    return {k: (None if isinstance(v, float) and not math.isfinite(v) else v) for k, v in out.items()}


def _hip_centred(figures: dict) -> dict:
    """BlazePose's world landmarks are hip-centred (no path through the room): the figures that need one,
    MPJPE after a single alignment per take and foot skate, do not apply to them."""
    return {**figures, "mpjpe_mm": None, "foot_skate_mm_per_frame": None}


def _pool(rows: list[dict]) -> dict[str, Any]:
    from ..formats.metrics import RECONSTRUCT_FIGURES

    out: dict[str, Any] = {"frames": int(sum(r["frames"] for r in rows))}
    for key in RECONSTRUCT_FIGURES:
        pairs = [(r[key], r["frames"]) for r in rows if r.get(key) is not None and r["frames"] > 0]
        n = sum(w for _, w in pairs)
        out[key] = float(sum(v * w for v, w in pairs) / n) if n else None
    return out


def library_bound_row(data: str, library_points: np.ndarray, true_mm: np.ndarray) -> dict[str, Any]:
    """A run row (method ``library-bound``, source ``truth``): per frame the library frame nearest the
    truth after a similarity alignment (:func:`vidstyle.reconstruct.metrics.library_bound`), so only its
    PA-MPJPE is a figure; the floor, set by the library's coverage, of what one library pose per frame
    reaches. ``library_points``: a fitted library's ``points_``."""
    from ..reconstruct import metrics as M

    b = M.library_bound(library_points, true_mm)
    ok = np.isfinite(b)
    return {"data": data, "source": "truth", "method": "library-bound", "skeleton": "library", "frames": int(ok.sum()),
            **{k: None for k in ("mpjpe_mm", "mpjpe_root_relative_mm", "acceleration_error_mm_per_frame2",
                                 "foot_skate_mm_per_frame")},
            "pa_mpjpe_mm": float(b[ok].mean()) if ok.any() else None}


def evaluate(dataset_dir: str | os.PathLike, library: Sequence[str | os.PathLike], videos: Sequence[str] | None = None,
             poses_dirs: Sequence[str | os.PathLike] = (), methods: Sequence[str] = ("nn", "olng"),
             skeletons: Sequence[str] = SKELETONS, max_frames: int | None = None, seed: int = 0,
             unit_mm: float | None = None, jobs: int = 1, animation: str | os.PathLike | None = None,
             **params) -> dict[str, Any]:
    """The reconstruct metrics document (module docstring). ``params``: :class:`Reconstructor` parameters.
    ``animation``: also write :func:`write_comparison` of the first video's reconstruction from the first
    estimated source (true 2D without one), the library skeleton and ``olng`` (else the last of ``methods``)."""
    from ..evaluation.augmg import mocap_unit_mm
    from ..formats.dataset import read_dataset
    from ..reconstruct.core import METHODS, Reconstructor
    from ..reconstruct.library import ReconstructionLibrary

    for m in methods:
        if m not in METHODS:
            raise InputError(f"--method: {m!r} is not one of {', '.join(METHODS)}")
    for s in skeletons:
        if s not in SKELETONS:
            raise InputError(f"--skeleton-kind: {s!r} is not one of {', '.join(SKELETONS)}")
    Reconstructor(**params).check_params()
    dataset = read_dataset(dataset_dir)
    mm = mocap_unit_mm(dict(dataset.extra), dataset_dir) if unit_mm is None else float(unit_mm)
    videos = list(videos) if videos else default_videos(dataset, seed)
    known = dataset.by_id()
    for v in videos:
        if v not in known:
            raise InputError(f"{dataset_dir}: no video {v!r}")
        for d in poses_dirs:
            if not (Path(d) / f"{v}.poses.json").is_file():
                raise InputError(f"{Path(d) / f'{v}.poses.json'}: no poses for video {v} (run vidstyle pose on it)")
    base = Reconstructor(jobs=jobs, **params)
    base.check_params()
    fps0 = float(dataset.fps)
    lib = ReconstructionLibrary(base.n_views, base.library_elevation_deg, fps0, jobs).fit(library)
    # every (video, skeleton) in parallel, one worker each (the library's index built once, here): their
    # rows depend on nothing but their own inputs, so the document is the same for any number of workers,
    # in the same order (frames_per_second is each run's own time, measured with the other workers busy)
    from ..parallel import parallel_map

    if "height" in skeletons and "library" not in skeletons:
        raise InputError("skeletons: 'height' needs 'library' too (it rescales the library skeleton's run)")
    runs_of = [s for s in skeletons if s != "height"]
    items = [(dataset, vid, max_frames, mm, tuple(str(d) for d in poses_dirs), tuple(methods), skel,
              lib if skel == "library" else None, library, params, fps0,
              str(animation) if animation is not None and vid == videos[0] and skel == runs_of[0] else None,
              skel == runs_of[-1], skel == "library" and "height" in skeletons)
             for vid in videos for skel in runs_of]
    runs: list[dict] = [row for rows in parallel_map(_evaluate_video, items, jobs=jobs, description="videos")
                        for row in rows]
    pooled = []
    keys = sorted({(r["source"], r["method"], r["skeleton"]) for r in runs})
    for src, method, skel in keys:
        rows = [r for r in runs if (r["source"], r["method"], r["skeleton"]) == (src, method, skel)]
        pooled.append({"data": "demo test performers", "source": src, "method": method, "skeleton": skel,
                       **_pool(rows)})
    estimated = [s for s in ("ps", "blazepose") if any(r["source"] == s for r in pooled)]
    headline: dict[str, Any] = {}

    def pick(src, method, skel, key="mpjpe_root_relative_mm"):
        for r in pooled:
            if (r["source"], r["method"], r["skeleton"]) == (src, method, skel):
                return r[key]
        return None

    best = "olng" if "olng" in methods else methods[0]
    if estimated:
        headline["reconstruct.mpjpe_mm"] = pick(estimated[0], best, "library")
        headline["reconstruct.pa_mpjpe_mm"] = pick(estimated[0], best, "library", "pa_mpjpe_mm")
        headline["reconstruct.mpjpe_performer_skeleton_mm"] = pick(estimated[0], best, "performer")
        headline["reconstruct.mpjpe_height_given_mm"] = pick(estimated[0], best, "height")
        headline["reconstruct.foot_skate_mm_per_frame"] = pick(estimated[0], best, "library", "foot_skate_mm_per_frame")
        headline["reconstruct.source"] = estimated[0]
    headline["reconstruct.mpjpe_true2d_mm"] = pick("true2d", best, "library")
    headline["reconstruct.method"] = best
    return {"runs": pooled + runs, "videos": videos,
            "params": {**base.get_params(), "methods": list(methods), "skeletons": list(skeletons),
                       "max_frames": max_frames, "library": [str(p) for p in library], "library_frames": lib.n_frames,
                       "unit_mm": mm},
            "headline": headline, "seed": seed}


def _evaluate_video(item) -> list[dict]:
    """The rows of one video and skeleton of :func:`evaluate` (every source and method; BlazePose's world
    landmarks when ``world_rows``); writes the comparison animation when ``animation`` is given. ``lib``:
    the library's index for the skeleton ``library``; the performer's own is built here."""
    from ..formats.poses import read_poses
    from ..mocap import read_bvh
    from ..reconstruct.core import Observation, Reconstructor
    from ..reconstruct.library import ReconstructionLibrary

    (dataset, vid, max_frames, mm, poses_dirs, methods, skel, lib, library, params, fps0, animation,
     world_rows, height_rows) = item
    base = Reconstructor(jobs=1, **params)
    runs: list[dict] = []
    true_pts, uv, az, size, fps, bvh = _truth(dataset, vid, max_frames)
    T = len(true_pts)
    true_mm = true_pts * mm
    sources = {"true2d": Observation(uv, np.ones((T, 15)), az, fps, size, source=f"{vid} (true 2D)")}
    world = {}
    for d in poses_dirs:  # evaluate() checked that every file exists
        doc = read_poses(Path(d) / f"{vid}.poses.json")
        name = str(doc.backend)
        sources[name] = Observation.from_poses(doc, fps, size, T)
        w = blazepose_world_points(doc, T, base.elevation_deg if base.elevation_deg is not None
                                   else base.library_elevation_deg)
        if w is not None:
            world[name] = w
    shown = "olng" if "olng" in methods else methods[-1]
    performer = read_bvh(bvh).skeleton if lib is None or height_rows else None
    if lib is None:
        lib = ReconstructionLibrary(base.n_views, base.library_elevation_deg, fps0, 1).fit(library, skeleton=performer)
    rec = Reconstructor(jobs=1, **params).fit_library(lib)
    scale = None
    if height_rows:  # the performer's stature over the output skeleton's: what Reconstructor(height=) applies
        from ..mocap.retarget import stature

        scale = stature(performer) / stature(lib.skeleton_)
    for src, obs in sources.items():
        for method in methods:
            rec.set_params(method=method)
            t0 = time.perf_counter()
            out = rec.reconstruct(obs)
            seconds = time.perf_counter() - t0
            row = {"data": f"demo:{vid}", "source": src, "method": method, "skeleton": skel,
                   **_figures(out.points * mm, true_mm, fps),
                   "observed_frames": int(out.observed.sum()), "frames_per_second": T / max(seconds, 1e-9)}
            runs.append(row)
            if scale is not None:
                runs.append(_height_row(row, out, scale, mm, true_mm, fps))
            if (animation is not None and method == shown
                    and src == list(sources)[min(1, len(sources) - 1)]):
                write_comparison(animation, out.points * mm, true_mm, fps, f"{vid} {src} {method}")
            log.info("%s %s %s %s: root-relative MPJPE %.1f mm, PA %.1f mm", vid, src, method, skel,
                     row["mpjpe_root_relative_mm"] or float("nan"), row["pa_mpjpe_mm"] or float("nan"))
    for src, w in world.items() if world_rows else ():
        runs.append({"data": f"demo:{vid}", "source": src, "method": "blazepose-world", "skeleton": "blazepose",
                     **_hip_centred(_figures(w, true_mm, fps))})
    return runs


# ------------------------------------------------------------------------------------------ beyond the demo
def _runs_for(rec_base, obs: Observation, true_mm: np.ndarray, mm: float, fps: float, methods, data: str,
              source: str, skeleton: str, keypoints=None, height_scale: float | None = None) -> list[dict]:
    """One row per method; ``keypoints`` maps the reconstruction's keypoints (mm) to the truth's
    definitions first (e.g. :func:`vidstyle.augmg.index.girdle_midpoints`). With ``height_scale`` (the
    performer's stature over the output skeleton's) also a ``height`` row per method: the same
    reconstruction scaled so, as :func:`evaluate`'s ``height`` skeleton kind."""
    out = []
    for method in methods:
        rec_base.set_params(method=method)
        t0 = time.perf_counter()
        r = rec_base.reconstruct(obs)
        seconds = time.perf_counter() - t0
        pred = r.points * mm if keypoints is None else keypoints(r.points * mm)
        out.append({"data": data, "source": source, "method": method, "skeleton": skeleton,
                    **_figures(pred, true_mm, fps), "observed_frames": int(r.observed.sum()),
                    "frames_per_second": len(true_mm) / max(seconds, 1e-9)})
        if height_scale is not None:
            out.append(_height_row(out[-1], r, height_scale, mm, true_mm, fps, keypoints))
    return out


def _height_row(row: dict, rec, scale: float, mm: float, true_mm: np.ndarray, fps: float, keypoints=None) -> dict:
    """``row`` of the reconstruction ``rec`` scored again at the performer's height: ``rec.scaled(scale)``
    (what ``Reconstructor(height=)`` returns), skeleton ``height``."""
    pred = rec.scaled(scale).points * mm
    return {**row, "skeleton": "height", "scale": float(scale),
            **_figures(pred if keypoints is None else keypoints(pred), true_mm, fps)}


def evaluate_cmu_heldout(cmu_dir: str | os.PathLike, library_subjects: Sequence[str], test_subjects: Sequence[str],
                         seconds: float = 20.0, fps: float = 30.0, noise: float = 0.05, seed: int = 0,
                         methods: Sequence[str] = ("nn", "olng", "subsequence"), unit_mm: float = 56.44,
                         size: tuple[int, int] = (640, 480), jobs: int = 1, **params) -> dict[str, Any]:
    """Reconstruction of CMU subjects the library never saw. The library: every clip of
    ``library_subjects`` (file names ``<subject>_<trial>.bvh``); the test: the first ``seconds`` of every
    clip of ``test_subjects`` (each subject in one role), resampled to ``fps``, filmed by the
    reconstruction's camera model at a seeded azimuth (uniform about the performer's first facing),
    elevation (0-20 degrees) and distance (4.5-6.5 m) with the default 60-degree lens; 2D sources: the true
    projection (``true2d``) and it plus Gaussian noise of ``noise`` torso lengths per keypoint (``noisy``),
    both with the true azimuth. The output skeleton is the library's (the test subject's own body is not
    given), and scaled to the subject's stature (skeleton ``height``: as ``vidstyle reconstruct --height``
    when a user knows it). ``unit_mm``: millimetres per CMU unit (1/0.45 inch)."""
    from ..augmg.projection import facing_of_keypoints, relative_azimuth
    from ..mocap import read_bvh
    from ..mocap.keypoints import keypoint_positions
    from ..mocap.retarget import stature
    from ..motiongraph.graph import has_tpose_first_frame
    from ..reconstruct.camera import default_intrinsics, project
    from ..reconstruct.core import Observation, Reconstructor, camera_rotation

    cmu = Path(cmu_dir)
    lib_files = sorted(f for s in library_subjects for f in cmu.glob(f"{s}_*.bvh"))
    test_files = sorted(f for s in test_subjects for f in cmu.glob(f"{s}_*.bvh"))
    if set(library_subjects) & set(test_subjects):
        raise InputError("a CMU subject is either in the library or in the test, not both")
    if not lib_files or not test_files:
        raise InputError(f"{cmu}: no clips of subjects {list(library_subjects)} / {list(test_subjects)}")
    rng = np.random.default_rng(seed)
    base = Reconstructor(jobs=jobs, target_fps=fps, **params).fit([str(f) for f in lib_files])
    K = default_intrinsics(*size)
    lib_stature = stature(base.library_.skeleton_)
    runs: list[dict] = []
    truths: list[np.ndarray] = []
    for f in test_files:
        m = read_bvh(f)
        first = 1 if has_tpose_first_frame(m) else 0
        step = max(1, int(round(m.fps / fps)))
        pts = keypoint_positions(m)[first::step][: int(seconds * fps)]
        if len(pts) < 10:
            continue
        az0 = float(rng.uniform(0, 360))
        el = float(rng.uniform(0, 20))
        dist = float(rng.uniform(4500, 6500)) / unit_mm
        centre = pts[:, 2].mean(axis=0)
        face = facing_of_keypoints(pts[:1])[0]
        a = face + np.radians(az0)
        cam = centre + dist * np.array([np.sin(a) * np.cos(np.radians(el)), 0.0, np.cos(a) * np.cos(np.radians(el))])
        cam[1] = centre[1] + dist * np.sin(np.radians(el))
        # camera axes: looking at the performer's mean position, pitched by el
        fwd = centre - cam
        yaw = np.arctan2(fwd[0], fwd[2])
        Rc = camera_rotation(el)
        c, s = np.cos(yaw), np.sin(yaw)
        Ry = np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])  # world -> facing the camera's +Z
        R = Rc @ Ry.T
        uv = project((pts - cam) @ R.T, K)
        az = relative_azimuth(cam, pts[:, 2], facing_of_keypoints(pts))
        true_mm = pts * unit_mm
        truths.append(true_mm)
        torso = np.linalg.norm(uv[:, 1] - uv[:, 2], axis=-1)[:, None, None]
        sources = {"true2d": uv, "noisy": uv + rng.normal(0, 1, uv.shape) * noise * torso}
        for name, xy in sources.items():
            inside = np.all((xy >= 0) & (xy < np.array(size)), axis=-1)
            scores = inside.astype(float)
            obs = Observation(np.where(inside[..., None], xy, np.nan), scores, az, fps, size, source=f.name)
            runs += _runs_for(base, obs, true_mm, unit_mm, fps, methods, f"cmu:{f.stem}", name, "library",
                              height_scale=stature(m.skeleton) / lib_stature)
    pooled = []
    for key in sorted({(r["source"], r["method"], r["skeleton"]) for r in runs}):
        rows = [r for r in runs if (r["source"], r["method"], r["skeleton"]) == key]
        pooled.append({"data": "cmu held-out subjects", "source": key[0], "method": key[1], "skeleton": key[2],
                       **_pool(rows)})
    if truths:
        pooled.append(library_bound_row("cmu held-out subjects", base.library_.points_, np.concatenate(truths)))
    return {"runs": pooled + runs, "library_subjects": list(library_subjects), "test_subjects": list(test_subjects),
            "library_clips": len(lib_files), "library_frames": base.library_.n_frames,
            "params": {**base.get_params(), "seconds": seconds, "fps": fps, "noise": noise, "unit_mm": unit_mm,
                       "size": list(size)}, "seed": seed}


def evaluate_real(calibration: str | os.PathLike, poses_paths: Sequence[str | os.PathLike],
                  videos: Sequence[str | os.PathLike], library: Sequence[str | os.PathLike], unit_mm: float = 56.44,
                  methods: Sequence[str] = ("nn", "olng", "subsequence"), target_fps: float = 30.0, jobs: int = 1,
                  **params) -> dict[str, Any]:
    """Reconstruction of a real calibrated multi-view take from each view alone, against the 3D reference
    triangulated from all views (:func:`vidstyle.reconstruct.reference.triangulated_reference`; it shares
    the 2D estimator's biases). ``poses_paths``: BlazePose poses (with world landmarks) of every view,
    ``videos`` the views' videos (frame rate and size), in the same order. Also scores BlazePose's own 3D
    world landmarks of the view (``blazepose-world``) under the same assumed camera pitch and alignment.
    The reconstructions (and the library bound) are scored in the reference's keypoint definitions
    (:func:`vidstyle.augmg.index.girdle_midpoints`: pelvis and neck the midpoints of the hips and
    shoulders, as BlazePose's keypoints define them; root-relative MPJPE subtracts the pelvis)."""
    from ..augmg.index import girdle_midpoints
    from ..formats.poses import read_poses
    from ..reconstruct.core import Observation, Reconstructor
    from ..reconstruct.reference import reference_in_y_up, triangulated_reference
    from ..video import VideoReader

    ref = triangulated_reference(calibration, poses_paths)
    true_mm = reference_in_y_up(ref, floor_at_zero=True)
    base = Reconstructor(jobs=jobs, target_fps=target_fps, **params).fit(library)
    runs: list[dict] = []
    for name, p, v in zip(ref.names, poses_paths, videos):
        with VideoReader(v) as r:
            size = (r.width, r.height)
            ts = r.timestamps
        fps = float(1.0 / np.median(np.diff(ts)))
        doc = read_poses(p)
        frames = np.asarray(ref.frames)
        obs_all = Observation.from_poses(doc, fps, size, int(frames.max()) + 1)
        obs = Observation(obs_all.xy[frames], obs_all.scores[frames], obs_all.azimuth[frames], fps, size, str(p),
                          obs_all.backend)
        runs += _runs_for(base, obs, true_mm, unit_mm, fps, methods, f"real:{name}", "blazepose", "library",
                          keypoints=girdle_midpoints)
        world = blazepose_world_points(doc, int(frames.max()) + 1,
                                       base.elevation_deg if base.elevation_deg is not None else base.library_elevation_deg)
        if world is not None:
            runs.append({"data": f"real:{name}", "source": "blazepose", "method": "blazepose-world",
                         "skeleton": "blazepose", **_hip_centred(_figures(world[frames], true_mm, fps))})
    pooled = []
    for key in sorted({(r["source"], r["method"], r["skeleton"]) for r in runs}):
        rows = [r for r in runs if (r["source"], r["method"], r["skeleton"]) == key]
        pooled.append({"data": "real pose2sim take, every view", "source": key[0], "method": key[1],
                       "skeleton": key[2], **_pool(rows)})
    pooled.append(library_bound_row("real pose2sim take (the reference)",
                                    girdle_midpoints(base.library_.points_), true_mm))
    return {"runs": pooled + runs, "views": list(ref.names), "frames": len(ref.frames),
            "library_frames": base.library_.n_frames, "reference_up_axis": ref.up_axis,
            "params": {**base.get_params(), "unit_mm": unit_mm}}
