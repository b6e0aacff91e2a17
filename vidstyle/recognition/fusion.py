"""Late fusion of frame recognizers (issue 28, item 4): the 3D SIFT recognizer sees the look of the
video, the pose-sequence recognizer the performer's skeleton; where one is unsure the other may not be.

Each recognizer's ``predict_video`` gives per-frame class ``scores`` (rows summing to 1: the softmax of
its one-vs-all decision values). :func:`fuse_scores` takes their weighted mean, class by class (the
recognizers may list their classes in different orders; a class one of them lacks scores 0 there), and
returns what a recognizer's ``smooth`` takes: the fused frame labels (arg max), the fused scores and the
winning score as confidence. The smoothing (label chain, durations) is then one recognizer's own.

Every frame counts both recognizers with their weights, also where one of them saw little (the
performer missing from the pose track, no salient point in the video frame): their scores there are
what each recognizer makes of its own missing input.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from ..errors import InputError, ParameterError
from . import defaults as D


def aligned_scores(scores: np.ndarray, classes: Sequence[str], target: Sequence[str]) -> np.ndarray:
    """``scores`` (F, len(classes)) with its columns reordered to ``target`` (0 for a class ``classes``
    lacks); a class of ``classes`` not in ``target`` is an error (the fused labels could not name it)."""
    classes = [str(c) for c in classes]
    target = [str(c) for c in target]
    extra = sorted(set(classes) - set(target))
    if extra:
        raise InputError(f"fusion: classes {extra} are not among {target}")
    scores = np.asarray(scores, dtype=np.float64)
    if scores.ndim != 2 or scores.shape[1] != len(classes):
        raise InputError(f"fusion: scores of shape {scores.shape} for {len(classes)} classes")
    out = np.zeros((scores.shape[0], len(target)))
    idx = {c: i for i, c in enumerate(target)}
    for j, c in enumerate(classes):
        out[:, idx[c]] = scores[:, j]
    return out


def fuse_scores(scores: Sequence[np.ndarray], classes: Sequence[Sequence[str]], weights: Sequence[float],
                target: Sequence[str]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(raw, fused, confidence)`` of the weighted mean of several recognizers' frame ``scores`` (each
    (F, its classes)), in the class order ``target`` (see the module docstring). ``weights`` are >= 0,
    not all 0, and are normalised to sum to 1."""
    if not (len(scores) == len(classes) == len(weights)) or not scores:
        raise InputError(f"fusion: {len(scores)} score arrays, {len(classes)} class lists, {len(weights)} weights")
    w = np.asarray(weights, dtype=np.float64)
    if not np.all(np.isfinite(w)) or np.any(w < 0) or w.sum() <= 0:
        raise ParameterError("weights", f"must be >= 0 and not all 0, got {list(weights)}")
    w = w / w.sum()
    n = {np.asarray(s).shape[0] for s in scores}
    if len(n) != 1:
        raise InputError(f"fusion: the recognizers scored different frame counts {sorted(n)}")
    fused = sum(wi * aligned_scores(s, c, target) for wi, s, c in zip(w, scores, classes))
    fused = np.nan_to_num(np.asarray(fused, dtype=np.float64), nan=0.0)
    raw = np.argmax(fused, axis=1).astype(np.int64) if fused.size else np.zeros(0, np.int64)
    conf = fused[np.arange(len(raw)), raw] if len(raw) else np.zeros(0)
    return raw, fused, conf


def fusion_power(power: float | None = None) -> float:
    """The power of the fused scores in the smoother: ``power``, or the validated default
    :data:`.defaults.FUSION_EMISSION_WEIGHT` when None; a power that is not finite and > 0 is a
    :class:`~vidstyle.errors.ParameterError` (every caller resolves the power here, before any work)."""
    p = float(D.FUSION_EMISSION_WEIGHT if power is None else power)
    if not (p > 0 and math.isfinite(p)):
        raise ParameterError("fusion_emission_weight", f"must be a finite number > 0, got {power}")
    return p


def smooth_fused(pose_model, pose_scores: np.ndarray, sift_model, sift_scores: np.ndarray, weight: float,
                 power: float | None = None) -> dict[str, np.ndarray]:
    """The fused recognizer's ``predict_video`` dict: :func:`fuse_scores` of the pose-sequence recognizer's and
    the 3D SIFT recognizer's frame scores (``weight`` on the pose recognizer's, the pose recognizer's classes),
    smoothed by the pose recognizer's smoother with the fused scores to the power :func:`fusion_power`
    (``power``)."""
    return pose_model.smooth(*fuse_scores([pose_scores, sift_scores], [pose_model.classes_, sift_model.classes_],
                                          [weight, 1.0 - weight], pose_model.classes_),
                             emission_weight=fusion_power(power))
