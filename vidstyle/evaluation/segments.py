"""Frame labels scored as segments: how much of a recognizer's frame error is the placement of its
boundaries, and whether it finds the actions at all.

- :func:`tolerant_correct` / the *boundary-tolerant accuracy* at ``k`` frames: a frame counts as right when
  its predicted label is the true label of some frame at most ``k`` frames from it, i.e. when the
  prediction would be right had the true boundaries near it moved by up to ``k`` frames. ``k = 0`` is the
  frame accuracy; ``k = 1`` forgives the one frame either side of each true boundary, and only with one of
  the two labels that meet there (a third label is still wrong).
- :func:`segment_counts` / :func:`segmental_f1`, the segmental F1 score at an overlap threshold ``tau``
  (Lea et al. 2017, "Temporal convolutional networks for action segmentation and detection", the metric of
  the action-segmentation literature): the runs of equal labels are segments; a predicted segment is a
  true positive when its intersection over union with a true segment of the same label is at least ``tau``
  and that true segment is not matched yet (each predicted segment is tried against the true segment of
  the same label it overlaps most); every other predicted segment is a false positive and every unmatched
  true segment a false negative. Counts are summed over videos before precision and recall. Unlike frame
  accuracy, it penalises over-segmentation (a run broken by one stray frame is three segments) and hardly
  notices a boundary a frame or two off.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

from ..actionmodel.instances import label_runs as segments  # (label, start, end exclusive) of each run

TOLERANCES = (1, 2, 3)  # frames (at the method's working rate, 20 fps: 50-150 ms)
OVERLAPS = (0.1, 0.25, 0.5)  # the F1@{10, 25, 50} of the literature


def _as_array(labels) -> np.ndarray:
    return np.asarray(list(labels) if not isinstance(labels, np.ndarray) else labels)


def tolerant_correct(truth, pred, k: int) -> np.ndarray:
    """(n,) bool: ``pred[t]`` is the true label of some frame in ``[t - k, t + k]`` (module text)."""
    truth, pred = _as_array(truth), _as_array(pred)
    if truth.shape != pred.shape or truth.ndim != 1:
        raise ValueError(f"truth and prediction must be 1-D of one length, got {truth.shape} and {pred.shape}")
    if int(k) != k or k < 0:
        raise ValueError(f"the tolerance must be a whole number of frames >= 0, got {k}")
    n, k = len(truth), int(k)
    ok = pred == truth
    for d in range(1, min(k, n - 1) + 1):  # the true label d frames earlier and later
        ok[d:] |= pred[d:] == truth[: n - d]
        ok[: n - d] |= pred[: n - d] == truth[d:]
    return ok


def segment_counts(truth, pred, tau: float) -> tuple[int, int, int]:
    """``(true positives, false positives, false negatives)`` of one video at overlap ``tau`` (module text)."""
    if not 0.0 < tau <= 1.0:
        raise ValueError(f"the overlap threshold must be in (0, 1], got {tau}")
    true_segs, pred_segs = segments(truth), segments(pred)
    matched = np.zeros(len(true_segs), bool)
    tp = fp = 0
    for label, s, e in pred_segs:
        best, best_iou = -1, 0.0
        for j, (tl, ts, te) in enumerate(true_segs):
            if tl != label or te <= s or ts >= e:
                continue
            iou = (min(e, te) - max(s, ts)) / (max(e, te) - min(s, ts))
            if iou > best_iou:
                best, best_iou = j, iou
        if best >= 0 and best_iou >= tau and not matched[best]:
            matched[best] = True
            tp += 1
        else:
            fp += 1
    return tp, fp, int((~matched).sum())


def segmental_f1(truths: Sequence, preds: Sequence, tau: float) -> float | None:
    """F1 over videos (``truths[i]``, ``preds[i]`` label sequences) at overlap ``tau``; None without segments."""
    tp = fp = fn = 0
    for t, p in zip(truths, preds, strict=True):
        a, b, c = segment_counts(t, p, tau)
        tp, fp, fn = tp + a, fp + b, fn + c
    if tp == 0:
        return 0.0 if fp + fn else None
    precision, recall = tp / (tp + fp), tp / (tp + fn)
    return 2 * precision * recall / (precision + recall)


def boundary_scores(truths: Sequence, preds: Sequence, tolerances=TOLERANCES, overlaps=OVERLAPS) -> dict:
    """The metrics-file block: ``boundary_tolerant_accuracy`` (tolerance in frames -> accuracy over all
    frames) and ``segmental_f1`` (``tau`` in percent -> F1) of label sequences pooled over videos."""
    truths, preds = [_as_array(t) for t in truths], [_as_array(p) for p in preds]
    n = sum(len(t) for t in truths)
    tol = {str(int(k)): (float(sum(tolerant_correct(t, p, k).sum() for t, p in zip(truths, preds)) / n) if n else None)
           for k in tolerances}
    f1 = {str(int(round(100 * tau))): segmental_f1(truths, preds, tau) for tau in overlaps}
    return {"boundary_tolerant_accuracy": tol, "segmental_f1": f1}
