"""The pose-sequence recognizer on the demo dataset's splits (issue 28, first measurement).

Training: the mocap takes (BVH + per-frame labels at the mocap rate) of the split's training performers,
sets A and B together (the pose recognizer has no vocabulary, so A's performers train it too; validation
and test performers never do), projected through ``n_views`` virtual cameras each
(:func:`~vidstyle.recognition.posetraining.virtual_views`) with keypoint noise and dropouts.

Test input, per test video of the split (the same videos as ``vidstyle evaluate recognition``):

- ``true``: the true 2D keypoints — the video's BVH keypoints at the frames it shows (its truth sidecar's
  ``source_time``) projected through its camera (the sidecar's ``K``, ``R``, ``t``): an upper bound;
- a directory of ``<video id>.poses.json`` (``vidstyle pose``): only the test videos that have one are
  scored, and the metrics say which.

Noise calibration (:func:`measure_pose_error`): a pose file against the true keypoints of its video, in
units of the true torso length.
"""

from __future__ import annotations

import logging
import time
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import InputError
from ..formats.dataset import Dataset
from ..formats.labels import read_labels
from ..recognition.posefeatures import NECK, PELVIS, PoseTrack, track_from_poses
from ..recognition.poserecognizer import PoseRecognizer
from ..recognition.posetraining import KeypointNoise, check_training_memory, dataset_motions, virtual_views
from ..recognition.splits import make_split
from .recognition import score_videos

log = logging.getLogger(__name__)


def true_keypoints(dataset: Dataset, video_id: str) -> np.ndarray:
    """(F, 15, 2) true 2D keypoints of a dataset video (see the module docstring)."""
    from ..mocap import read_bvh
    from ..mocap.keypoints import keypoint_positions
    from ..render.camera import Camera

    v = dataset.by_id()[video_id]
    truth = np.load(dataset.root / v.raw["truth"])
    motion = read_bvh(dataset.root / v.raw["bvh"])
    idx = np.clip(np.round(truth["source_time"] * motion.fps).astype(int), 0, motion.n_frames - 1)
    pts = keypoint_positions(motion)[idx]
    cam = Camera(truth["K"], truth["R"], truth["t"], size=tuple(int(s) for s in truth["size"]))
    uv, _ = cam.project(pts)
    return np.asarray(uv, dtype=np.float64)


def measure_pose_error(dataset: Dataset, poses_dir: Path, ids: list[str]) -> dict[str, Any]:
    """Error of the pose files ``<poses_dir>/<id>.poses.json`` against the true keypoints, in true torso
    lengths: median and RMS of the inliers (< 0.5), outlier share, missing-frame share."""
    from ..formats.poses import read_poses

    errs, n_missing, n = [], 0, 0
    for i in ids:
        true = true_keypoints(dataset, i)
        est = track_from_poses(read_poses(poses_dir / f"{i}.poses.json"), dataset.fps, len(true)).xy
        torso = np.linalg.norm(true[:, NECK] - true[:, PELVIS], axis=-1)
        found = np.all(np.isfinite(est), axis=(1, 2))
        n += len(true)
        n_missing += int((~found).sum())
        e = np.linalg.norm(est[found] - true[found], axis=-1) / torso[found, None]
        errs.append(e.ravel())
    e = np.concatenate(errs) if errs else np.zeros(0)
    inl = e[e < 0.5]
    return {"videos": ids, "n_frames": n, "missing_share": n_missing / max(n, 1),
            "median": float(np.median(e)) if e.size else None,
            "inlier_rms_per_coordinate": float(np.sqrt(np.mean(inl**2) / 2)) if inl.size else None,
            "outlier_share": float((e >= 0.5).mean()) if e.size else None}


def evaluate_pose_recognition(dataset: Dataset, split_kind: str = "unseen-performer", seed: int = 0,
                              test_dataset: Dataset | None = None, poses_dir: str | Path | None = None,
                              n_views: int = 8, noise: KeypointNoise | None = None,
                              recognizer_params: dict | None = None, score_set: str = "test",
                              phases=(0,)) -> dict[str, Any]:
    """Train a :class:`PoseRecognizer` on the split's training performers' mocap seen from ``n_views``
    virtual cameras and score the test set T (or ``score_set="val"``: V) from the true 2D keypoints or
    from the pose files in ``poses_dir`` (see the module docstring)."""
    split = make_split(dataset, split_kind, seed=seed, test_dataset=test_dataset)
    if score_set == "val":
        ids, score_ds = split.val, dataset
    else:
        ids, score_ds = split.test, (test_dataset if split.kind == "unseen-camera" else dataset)
    train_perf = sorted(set(split.vocab_performers) | set(split.train_performers))
    t0 = time.perf_counter()
    motions = dataset_motions(dataset, train_perf, dataset.fps, phases)
    params = {"random_state": seed, "fps": dataset.fps, **(recognizer_params or {})}
    rec = PoseRecognizer(**params)
    check_training_memory(rec, sum(len(m.points) for m in motions) * n_views)
    tracks, labels = virtual_views(motions, n_views, seed, noise)
    rec.fit(tracks, labels, classes=dataset.classes or None)
    t_train = time.perf_counter() - t0

    from ..formats.poses import read_poses

    t0 = time.perf_counter()
    by_id = score_ds.by_id()
    used, outputs, truths, skipped = [], [], [], []
    n_pred_frames = 0
    for i in ids:
        truth = read_labels(score_ds.labels_path(by_id[i]))
        if poses_dir is None:
            track = PoseTrack(true_keypoints(score_ds, i), score_ds.fps, source=i)
        else:
            p = Path(poses_dir) / f"{i}.poses.json"
            if not p.exists():
                skipped.append(i)
                continue
            track = track_from_poses(read_poses(p), score_ds.fps, len(truth.labels))
        t1 = time.perf_counter()
        outputs.append(rec.predict_video(track))
        n_pred_frames += track.n_frames
        used.append(i)
        truths.append(truth.labels)
        log.debug("%s: %.2fs", i, time.perf_counter() - t1)
    t_pred = time.perf_counter() - t0
    if not used:
        raise InputError(f"{poses_dir}: no pose file of any test video")
    actions = [by_id[i].action if by_id[i].kind == "single" else None for i in used]
    metrics = score_videos(rec.classes_, truths, outputs, used, actions)
    return {
        "kind": "vidstyle.metrics.recognition", "schema_version": 1, "recognizer": "pose",
        "seed": seed, "split": split.to_dict(), "scored_set": "V" if score_set == "val" else "T",
        "input": "true-2d" if poses_dir is None else f"poses:{poses_dir}",
        "scored_videos": used, "skipped_videos": skipped,
        "training": {"performers": train_perf, "n_motions": len(motions), "n_views": n_views,
                     "phases": list(phases), "noise": noise.to_dict() if noise else None},
        "params": rec.public_params(), "model": rec.summary(), **metrics,
        "timing_s": {"train": t_train, "predict": t_pred,
                     "predict_frames_per_s": n_pred_frames / t_pred if t_pred > 0 else None},
    }
