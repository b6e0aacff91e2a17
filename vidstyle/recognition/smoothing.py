"""Smoothing of per-frame labels over a window (thesis 6.1.3: window 6 at 20 fps, actions last 6-10 frames).

The window of frame n covers frames n - w//2 .. n - w//2 + w - 1 (w frames; for even w one more frame
before n than after it), clipped at the ends of the video.

- ``method="vote"`` (thesis): the label most frequent in the window; a draw goes to the label with the
  higher summed confidence in the window, and then to the lower class index.
- ``method="mean"``: the class with the highest mean class score over the window (needs the scores).

The smoothed confidence is the mean confidence of the window's frames that carry the winning label
(vote) or the winning class' mean score (mean).
"""

from __future__ import annotations

import numpy as np

from ..errors import InputError


def _window_sum(x: np.ndarray, window: int) -> np.ndarray:
    """Sum of rows n - w//2 .. n - w//2 + w - 1 of ``x`` (n, k), clipped at the ends."""
    n = x.shape[0]
    c = np.concatenate([np.zeros((1,) + x.shape[1:], x.dtype), np.cumsum(x, axis=0)])
    lo = np.clip(np.arange(n) - window // 2, 0, n)
    hi = np.clip(np.arange(n) - window // 2 + window, 0, n)
    return c[hi] - c[lo]


def smooth_labels(
    labels: np.ndarray,
    n_classes: int,
    window: int = 6,
    confidence: np.ndarray | None = None,
    scores: np.ndarray | None = None,
    method: str = "vote",
) -> tuple[np.ndarray, np.ndarray]:
    """Smoothed class indices (n,) and confidence (n,). ``window <= 1`` returns the input unchanged."""
    labels = np.asarray(labels, np.int64)
    n = labels.shape[0]
    conf = np.ones(n) if confidence is None else np.asarray(confidence, np.float64)
    if method not in ("vote", "mean"):
        raise InputError(f"--smoothing: must be vote or mean, got {method!r}")
    if window <= 1 or n == 0:
        return labels.copy(), conf.copy()
    if method == "mean":
        if scores is None:
            raise InputError("smoothing 'mean' needs class scores")
        s = _window_sum(np.asarray(scores, np.float64), window)
        count = _window_sum(np.ones((n, 1)), window)
        mean = s / count
        out = np.argmax(mean, axis=1)
        return out, mean[np.arange(n), out]
    onehot = np.zeros((n, n_classes))
    onehot[np.arange(n), labels] = 1.0
    votes = _window_sum(onehot, window)
    cs = _window_sum(onehot * conf[:, None], window)
    # votes are integers and the confidence sum of a class is < window + 1, so this orders by votes first
    key = votes * (window + 1) + cs
    out = np.argmax(key, axis=1)
    winner_votes = votes[np.arange(n), out]
    return out, cs[np.arange(n), out] / np.maximum(winner_votes, 1)
