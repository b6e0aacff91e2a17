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
units of the true torso length; or (:func:`residual_noise`) the estimator's errors themselves, frame by
frame, handed to training frames of similar poses.
"""

from __future__ import annotations

import functools
import logging
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import InputError
from ..formats.dataset import Dataset
from ..formats.labels import read_labels
from ..recognition.posefeatures import NECK, PELVIS, PoseTrack, track_from_poses
from ..recognition.poserecognizer import PoseRecognizer
from ..recognition.posetraining import (
    KeypointNoise,
    ResidualNoise,
    check_training_memory,
    dataset_motions,
    virtual_views,
)
from ..recognition.splits import make_split
from .recognition import score_videos

log = logging.getLogger(__name__)


@functools.lru_cache(maxsize=32)
def _take_keypoints(path: str, mtime_ns: int, size: int) -> tuple[np.ndarray, float]:
    """(every frame's 3D keypoints, read-only; fps) of a take's BVH. The views of one take share it, so
    it is read once per take (the cache key changes when the file does)."""
    from ..mocap import read_bvh
    from ..mocap.keypoints import keypoint_positions

    motion = read_bvh(path)
    pts = keypoint_positions(motion)
    pts.setflags(write=False)
    return pts, float(motion.fps)


def true_keypoints(dataset: Dataset, video_id: str) -> np.ndarray:
    """(F, 15, 2) true 2D keypoints of a dataset video (see the module docstring)."""
    from ..render.camera import Camera

    v = dataset.by_id()[video_id]
    truth = np.load(dataset.root / v.raw["truth"])
    bvh = dataset.root / v.raw["bvh"]
    try:
        st = bvh.stat()
    except OSError:  # read_bvh names the file and the problem
        take, fps = _take_keypoints.__wrapped__(str(bvh), 0, 0)
    else:
        take, fps = _take_keypoints(str(bvh), st.st_mtime_ns, st.st_size)
    idx = np.clip(np.round(truth["source_time"] * fps).astype(int), 0, len(take) - 1)
    pts = take[idx]
    cam = Camera(truth["K"], truth["R"], truth["t"], size=tuple(int(s) for s in truth["size"]))
    uv, _ = cam.project(pts)
    return np.asarray(uv, dtype=np.float64)


def measure_pose_error(dataset: Dataset, poses_dir: Path, ids: list[str], pairs=None) -> dict[str, Any]:
    """:func:`pose_error` of the pose files ``<poses_dir>/<id>.poses.json`` against the true keypoints of
    the dataset videos ``ids`` (``pairs``: their :func:`pose_pairs`, when already read)."""
    trues, ests = pairs if pairs is not None else pose_pairs(dataset, poses_dir, ids)
    return {"videos": list(ids), **pose_error(trues, ests)}


def pose_pairs(dataset: Dataset, poses_dir: Path, ids: list[str]) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """The true keypoints (:func:`true_keypoints`) and the pose file ``<poses_dir>/<id>.poses.json``'s
    keypoints (F, 15, 2; NaN where it has none) of each dataset video of ``ids``, on the same frames."""
    from ..formats.poses import read_poses

    trues, ests = [], []
    for i in ids:
        true = true_keypoints(dataset, i)
        trues.append(true)
        ests.append(track_from_poses(read_poses(Path(poses_dir) / f"{i}.poses.json"), dataset.fps, len(true)).xy)
    return trues, ests


def residual_noise(dataset: Dataset, poses_dir: Path, ids: list[str], k: int = 3, pairs=None) -> ResidualNoise:
    """The :class:`~vidstyle.recognition.posetraining.ResidualNoise` of the pose files
    ``<poses_dir>/<id>.poses.json`` against the true keypoints of the dataset videos ``ids`` (calibration
    videos: never the ones the recognizer is scored on; ``pairs``: their :func:`pose_pairs`, when already
    read)."""
    trues, ests = pairs if pairs is not None else pose_pairs(dataset, poses_dir, ids)
    return ResidualNoise.from_tracks(trues, ests, k=k, videos=list(ids))


def gated_residual_noise(bank: ResidualNoise, dataset: Dataset, reach_ids: list[str], quantile: float,
                         fallback: KeypointNoise) -> ResidualNoise:
    """``bank`` gated by its reach: a training pose further from every calibration pose than the
    ``quantile`` of the distances of the true poses of the dataset videos ``reach_ids`` (poses the
    estimator is used on: not the calibration videos) takes ``fallback`` instead."""
    d = np.concatenate([bank.distances(true_keypoints(dataset, i)) for i in reach_ids])
    gate = float(np.nanquantile(d, quantile))
    return ResidualNoise(bank.keys, bank.residuals, k=bank.k, max_distance=gate, fallback=fallback,
                         extra={**bank.extra, "gate_quantile": quantile})


def pose_error(trues: list[np.ndarray], ests: list[np.ndarray]) -> dict[str, Any]:
    """Error of estimated 2D keypoint tracks (F, 15, 2; a frame with any NaN is missing) against true ones,
    in true torso lengths: median, the RMS per coordinate of the inliers (< 0.5) and of the outliers, outlier
    share, missing-frame share and the mean length of the runs of missing frames."""
    errs, n_missing, n, runs = [], 0, 0, []
    for true, est in zip(trues, ests):
        torso = np.linalg.norm(true[:, NECK] - true[:, PELVIS], axis=-1)
        found = np.all(np.isfinite(est), axis=(1, 2))
        n += len(true)
        n_missing += int((~found).sum())
        edges = np.diff(np.concatenate([[0], (~found).astype(np.int8), [0]]))
        runs += list(np.flatnonzero(edges == -1) - np.flatnonzero(edges == 1))
        e = np.linalg.norm(est[found] - true[found], axis=-1) / torso[found, None]
        errs.append(e.ravel())
    e = np.concatenate(errs) if errs else np.zeros(0)
    inl, outl = e[e < 0.5], e[e >= 0.5]
    return {"n_frames": n, "missing_share": n_missing / max(n, 1),
            "missing_run_mean": float(np.mean(runs)) if runs else None,
            "median": float(np.median(e)) if e.size else None,
            "inlier_rms_per_coordinate": float(np.sqrt(np.mean(inl**2) / 2)) if inl.size else None,
            "outlier_rms_per_coordinate": float(np.sqrt(np.mean(outl**2) / 2)) if outl.size else None,
            "outlier_share": float((e >= 0.5).mean()) if e.size else None}


def noise_from_error(error: dict[str, Any]) -> KeypointNoise:
    """The :class:`KeypointNoise` whose corruption matches a measured pose error
    (:func:`measure_pose_error`): Gaussian noise of the inliers' RMS, outliers at the measured share and
    RMS, dropouts at the measured missing share and run length (defaults where a figure is missing)."""
    d = KeypointNoise()
    return KeypointNoise(
        sigma=error.get("inlier_rms_per_coordinate") or d.sigma,
        outlier_rate=error["outlier_share"] if error.get("outlier_share") is not None else d.outlier_rate,
        outlier_sigma=error.get("outlier_rms_per_coordinate") or d.outlier_sigma,
        dropout_rate=float(error.get("missing_share", d.dropout_rate)),
        dropout_length=max(1.0, error.get("missing_run_mean") or d.dropout_length),
        extra={"calibrated_on_videos": len(error.get("videos", []))})


def train_for_split(dataset: Dataset, split, seed: int, n_views: int, noise: KeypointNoise | None,
                    recognizer_params: dict | None = None, phases=(0,), extra_motions=()) -> tuple[PoseRecognizer, dict]:
    """A :class:`PoseRecognizer` trained on the mocap takes of ``split``'s training performers (sets A and
    B) and on ``extra_motions`` (labelled clips, :func:`~vidstyle.recognition.posetraining.clip_motions`),
    seen from ``n_views`` virtual cameras with ``noise``; and what the metrics record of the training."""
    train_perf = sorted(set(split.vocab_performers) | set(split.train_performers))
    t0 = time.perf_counter()
    motions = dataset_motions(dataset, train_perf, dataset.fps, phases) + list(extra_motions)
    params = {"random_state": seed, "fps": dataset.fps, **(recognizer_params or {})}
    rec = PoseRecognizer(**params)
    check_training_memory(rec, sum(len(m.points) for m in motions) * n_views)
    tracks, labels = virtual_views(motions, n_views, seed, noise)
    rec.fit(tracks, labels, classes=dataset.classes or None)
    return rec, {"performers": train_perf, "n_motions": len(motions), "n_views": n_views,
                 "extra_clips": sorted({m.name.split("[")[0] for m in extra_motions}),
                 "phases": list(phases), "noise": noise.to_dict() if noise else None,
                 "train_s": time.perf_counter() - t0}


def pose_track_of(score_ds: Dataset, video_id: str, poses_dir: str | Path | None, n_frames: int) -> PoseTrack | None:
    """The pose track a test video is scored from: its true 2D keypoints (``poses_dir`` None), or its
    ``<poses_dir>/<id>.poses.json`` (None when there is none)."""
    from ..formats.poses import read_poses

    if poses_dir is None:
        return PoseTrack(true_keypoints(score_ds, video_id), score_ds.fps, source=video_id)
    p = Path(poses_dir) / f"{video_id}.poses.json"
    if not p.exists():
        return None
    return track_from_poses(read_poses(p), score_ds.fps, n_frames)


def sift_outputs(model, features_dir: str | Path, ids: list[str], cache: dict | None = None) -> list[dict]:
    """The 3D SIFT recognizer ``model``'s ``predict_video`` of each video's ``<features_dir>/<id>.npz``;
    ``cache`` (video id -> output, filled here) keeps them for the next call with the same model."""
    from ..recognition.io import load_features

    cache = {} if cache is None else cache
    for i in ids:
        if i in cache:
            continue
        p = Path(features_dir) / f"{i}.npz"
        if not p.exists():
            raise InputError(f"{p}: no features of the video {i}")
        cache[i] = model.predict_video(load_features(p))
    return [cache[i] for i in ids]


def fused_outputs(pose_rec: PoseRecognizer, pose_outs: list[dict], sift_model, sift_outs: list[dict],
                  weight: float, emission_weight: float | None = None) -> list[dict]:
    """Late fusion (:func:`~vidstyle.recognition.fusion.fuse_scores`) of the two recognizers' frame
    scores, ``weight`` on the pose recognizer's, smoothed by the pose recognizer's smoother with the fused
    scores to the power ``emission_weight`` (None: :data:`vidstyle.recognition.defaults.FUSION_EMISSION_WEIGHT`)."""
    from ..recognition.fusion import smooth_fused

    out = []
    for po, so in zip(pose_outs, sift_outs):
        n = min(len(po["raw"]), len(so["raw"]))
        if abs(len(po["raw"]) - len(so["raw"])) > 1:
            raise InputError(f"fusion: {len(po['raw'])} pose frames against {len(so['raw'])} video frames")
        out.append(smooth_fused(pose_rec, po["scores"][:n], sift_model, so["scores"][:n], weight, emission_weight))
    return out


def evaluate_pose_recognition(dataset: Dataset, split_kind: str = "unseen-performer", seed: int = 0,
                              test_dataset: Dataset | None = None, poses_dir: str | Path | None = None,
                              n_views: int = 8, noise: KeypointNoise | None = None,
                              recognizer_params: dict | None = None, score_set: str = "test",
                              phases=(0,)) -> dict[str, Any]:
    """Train a :class:`PoseRecognizer` on the split's training performers' mocap seen from ``n_views``
    virtual cameras and score the test set T (or ``score_set="val"``: V) from the true 2D keypoints or
    from the pose files in ``poses_dir`` (see the module docstring)."""
    split = make_split(dataset, split_kind, seed=seed, test_dataset=test_dataset)
    rec, training = train_for_split(dataset, split, seed, n_views, noise, recognizer_params, phases)
    return score_pose_recognizer(rec, training, dataset, split, test_dataset, poses_dir, score_set)


@dataclass
class PredictedSet:
    """A pose recognizer's ``predict_video`` of the videos of a scored set (:func:`predict_pose_set`): the
    videos that had a pose track (``used``) with their outputs and true labels, those without
    (``skipped``), the frames predicted and the seconds it took."""

    score_ds: Dataset
    used: list[str]
    outputs: list[dict]
    truths: list[list[str]]
    skipped: list[str]
    n_frames: int
    seconds: float


def predict_pose_set(rec: PoseRecognizer, dataset: Dataset, split, test_dataset: Dataset | None = None,
                     poses_dir: str | Path | None = None, score_set: str = "test") -> PredictedSet:
    """Run ``rec`` on ``split``'s test set (or ``score_set="val"``) from true 2D or the pose files in
    ``poses_dir`` (:func:`pose_track_of`)."""
    if score_set == "val":
        ids, score_ds = split.val, dataset
    else:
        ids, score_ds = split.test, (test_dataset if split.kind == "unseen-camera" else dataset)
    t0 = time.perf_counter()
    by_id = score_ds.by_id()
    used, outputs, truths, skipped = [], [], [], []
    n_pred_frames = 0
    for i in ids:
        truth = read_labels(score_ds.labels_path(by_id[i]))
        track = pose_track_of(score_ds, i, poses_dir, len(truth.labels))
        if track is None:
            skipped.append(i)
            continue
        outputs.append(rec.predict_video(track))
        n_pred_frames += track.n_frames
        used.append(i)
        truths.append(truth.labels)
    if not used:
        raise InputError(f"{poses_dir}: no pose file of any test video")
    return PredictedSet(score_ds, used, outputs, truths, skipped, n_pred_frames, time.perf_counter() - t0)


def score_pose_recognizer(rec: PoseRecognizer, training: dict, dataset: Dataset, split,
                          test_dataset: Dataset | None = None, poses_dir: str | Path | None = None,
                          score_set: str = "test", sift: tuple | None = None,
                          input_name: str | None = None, predicted: PredictedSet | None = None,
                          sift_cache: dict | None = None) -> dict[str, Any]:
    """Metrics of a trained pose recognizer on ``split``'s test set (or ``score_set="val"``) from true 2D
    or the pose files in ``poses_dir``; with ``sift = (model, features_dir, weight[, emission_weight])``,
    of its late fusion with that 3D SIFT recognizer (``weight`` on the pose scores; 0 = the 3D SIFT
    recognizer alone, smoothed by the pose recognizer's smoother; :func:`fused_outputs`). ``input_name``:
    what the metrics call the pose files' source (default ``poses:<poses_dir>``). ``predicted``:
    :func:`predict_pose_set` of the same arguments, already run (several fusion weights score one
    prediction); ``sift_cache``: of :func:`sift_outputs`."""
    from ..recognition.fusion import fusion_power

    if predicted is None:
        predicted = predict_pose_set(rec, dataset, split, test_dataset, poses_dir, score_set)
    used, outputs, truths = predicted.used, predicted.outputs, predicted.truths
    by_id = predicted.score_ds.by_id()
    fusion = None
    if sift is not None:
        model, features_dir, weight = sift[:3]
        power = sift[3] if len(sift) > 3 else None
        outputs = fused_outputs(rec, outputs, model, sift_outputs(model, features_dir, used, sift_cache), weight,
                                power)
        truths = [t[: len(o["raw"])] for t, o in zip(truths, outputs)]
        fusion = {"weight_pose": weight, "weight_sift": 1.0 - weight, "features": str(features_dir),
                  "emission_weight": fusion_power(power)}
    actions = [by_id[i].action if by_id[i].kind == "single" else None for i in used]
    metrics = score_videos(rec.classes_, truths, outputs, used, actions)
    t_pred = predicted.seconds
    return {
        "kind": "vidstyle.metrics.recognition", "schema_version": 1,
        "recognizer": "pose" if fusion is None else ("sift" if fusion["weight_pose"] == 0 else "pose+sift"),
        "seed": training.get("seed", rec.random_state), "split": split.to_dict(),
        "scored_set": "V" if score_set == "val" else "T",
        "input": "true-2d" if poses_dir is None else (input_name or f"poses:{poses_dir}"), "fusion": fusion,
        "scored_videos": used, "skipped_videos": predicted.skipped, "training": training,
        "params": rec.public_params(), "model": rec.summary(), **metrics,
        "timing_s": {"train": training.get("train_s"), "predict": t_pred,
                     "predict_frames_per_s": predicted.n_frames / t_pred if t_pred > 0 else None},
    }
