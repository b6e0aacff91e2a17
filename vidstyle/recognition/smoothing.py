"""Smoothing of per-frame labels over a window (thesis 6.1.3: window 6 at 20 fps, actions last 6-10 frames).

The window of frame n covers frames n - w//2 .. n - w//2 + w - 1 (w frames; for even w one more frame
before n than after it), clipped at the ends of the video.

- ``method="vote"`` (thesis): the label most frequent in the window; a draw goes to the label with the
  higher summed confidence in the window, and then to the lower class index.
- ``method="mean"``: the class with the highest mean class score over the window (needs the scores).

- ``method="viterbi"``: the most probable label sequence of a hidden Markov model whose states are
  the classes: emissions are the frame class scores raised to a power (``emission_weight``; the
  classifier's softmax scores are not calibrated probabilities, so their sharpness is a parameter), the
  transition matrix is learned from the training label sequences (:func:`transition_matrix`). A window
  vote can only remove runs shorter than half its window and blurs every boundary by up to half a window;
  Viterbi decodes the whole video at once, keeps a boundary where the scores change, and removes a short
  run when the chain says runs of that class are long. ``window`` is not used by it.

The smoothed confidence is the mean confidence of the window's frames that carry the winning label
(vote), the winning class' mean score (mean), or the frame's score of its decoded class (viterbi).
"""

from __future__ import annotations

import numpy as np

from ..errors import InputError, ParameterError

METHODS = ("vote", "mean", "viterbi")


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
    transitions: np.ndarray | None = None,
    emission_weight: float = 1.0,
) -> tuple[np.ndarray, np.ndarray]:
    """Smoothed class indices (n,) and confidence (n,). ``window <= 1`` returns the input unchanged
    for every method, so that "no smoothing" (window 1) means the same whatever the method."""
    labels = np.asarray(labels, np.int64)
    n = labels.shape[0]
    conf = np.ones(n) if confidence is None else np.asarray(confidence, np.float64)
    if method not in METHODS:
        raise ParameterError("method", f"must be one of {', '.join(METHODS)}, got {method!r}")
    if window <= 1 or n == 0:
        return labels.copy(), conf.copy()
    if method == "viterbi":
        if scores is None:
            raise InputError("smoothing 'viterbi' needs class scores")
        scores = np.asarray(scores, np.float64)
        T = transitions if transitions is not None else transition_matrix([], scores.shape[1])
        out = viterbi(emission_weight * np.log(np.maximum(scores, 1e-12)), np.log(np.maximum(T, 1e-300)))
        return out, scores[np.arange(n), out]
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


def transition_matrix(sequences, n_classes: int, prior: float = 1.0, self_prior: float = 0.0) -> np.ndarray:
    """Row-stochastic (n_classes, n_classes) matrix of frame-to-frame label transitions counted in
    ``sequences`` (each an int array of class indices), plus ``prior`` pseudo-counts on every entry
    (unseen transitions stay possible) and ``self_prior`` on the diagonal."""
    C = np.full((n_classes, n_classes), float(prior))
    C[np.diag_indices(n_classes)] += self_prior
    for seq in sequences:
        seq = np.asarray(seq, np.int64)
        if seq.size > 1:
            np.add.at(C, (seq[:-1], seq[1:]), 1.0)
    return C / C.sum(axis=1, keepdims=True)


def viterbi(log_emission: np.ndarray, log_transition: np.ndarray, log_start: np.ndarray | None = None) -> np.ndarray:
    """Most probable state path (n,) of an HMM given (n, K) log emissions and (K, K) log transitions
    (row = from). Ties go to the lower state index."""
    n, K = log_emission.shape
    if n == 0:
        return np.zeros(0, np.int64)
    delta = log_emission[0] + (np.zeros(K) if log_start is None else log_start)
    back = np.zeros((n, K), np.int64)
    for t in range(1, n):
        cand = delta[:, None] + log_transition  # (from, to)
        back[t] = np.argmax(cand, axis=0)
        delta = cand[back[t], np.arange(K)] + log_emission[t]
    path = np.empty(n, np.int64)
    path[-1] = int(np.argmax(delta))
    for t in range(n - 1, 0, -1):
        path[t - 1] = back[t, path[t]]
    return path
