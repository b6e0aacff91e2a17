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

- ``method="duration"``: Viterbi over an *explicit-duration* HMM (a hidden semi-Markov model by state
  expansion). Each class k becomes a chain of sub-states 0 .. D_k - 1 ("the current frame is the
  (i+1)-th of its run"); from sub-state i the run ends with the hazard p_k(i+1) / S_k(i+1) and otherwise
  moves on to i + 1, and the last sub-state loops on itself (a geometric tail for runs of D_k frames or
  more). So the run lengths follow p_k, the per-class duration distribution learned from the training
  label sequences (:func:`duration_model`: a log-normal kernel estimate over the complete runs, which
  tolerates performers faster or slower than the training ones, mixed with a small uniform floor),
  instead of the geometric distribution every plain HMM implies. When a run ends the next class
  follows the class-change matrix of the training runs. The first run may start anywhere in its run
  (sub-state i with probability proportional to S_k(i + 1), the residual life of a renewal process)
  and the last run is cut off by the end of the video (no exit term). A short spurious run now costs
  its improbably short duration, and a real short action (a jab of 8 frames) is not swallowed by the
  long runs around it. It needs ``durations`` (a :class:`DurationModel`); ``window`` is not used.

The smoothed confidence is the mean confidence of the window's frames that carry the winning label
(vote), the winning class' mean score (mean), or the frame's score of its decoded class (viterbi).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InputError, ParameterError

METHODS = ("vote", "mean", "viterbi", "duration")


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
    durations: "DurationModel | None" = None,
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
    if method == "duration":
        if scores is None:
            raise InputError("smoothing 'duration' needs class scores")
        if durations is None:
            raise InputError("smoothing 'duration' needs a duration model (the recognizer's durations_)")
        scores = np.asarray(scores, np.float64)
        out = duration_viterbi(emission_weight * np.log(np.maximum(scores, 1e-12)), durations)
        return out, scores[np.arange(n), out]
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


# ------------------------------------------------------------------ explicit-duration HMM
@dataclass
class DurationModel:
    """Per-class run lengths and class changes (see ``method="duration"`` in the module docstring).

    ``pmf`` (K, D): P(run length = d) for d = 1 .. D_k - 1 in columns 0 .. D_k - 2 and the total mass of
    lengths >= D_k in column D_k - 1 (zero beyond); ``n_substates`` (K,) = D_k; ``tail`` (K,) self-loop
    probability of the last sub-state; ``change`` (K, K) class-change probabilities (zero diagonal, rows
    sum to 1); ``n_runs`` (K,) complete runs each class was learned from.
    """

    pmf: np.ndarray
    n_substates: np.ndarray
    tail: np.ndarray
    change: np.ndarray
    n_runs: np.ndarray

    @property
    def n_classes(self) -> int:
        return int(self.pmf.shape[0])

    def length_pmf(self, k: int, d: int) -> float:
        """P(a run of class ``k`` lasts exactly ``d`` frames), tail included."""
        D = int(self.n_substates[k])
        if d < D:
            return float(self.pmf[k, d - 1])
        q = float(self.tail[k])
        return float(self.pmf[k, D - 1]) * q ** (d - D) * (1.0 - q)

    def survival(self, k: int, d: int) -> float:
        """P(a run of class ``k`` lasts at least ``d`` frames)."""
        D = int(self.n_substates[k])
        if d <= D:
            return float(self.pmf[k, d - 1 : D].sum())
        return float(self.pmf[k, D - 1]) * float(self.tail[k]) ** (d - D)

    def to_dict(self) -> dict:
        return {"pmf": self.pmf.tolist(), "n_substates": self.n_substates.tolist(), "tail": self.tail.tolist(),
                "change": self.change.tolist(), "n_runs": self.n_runs.tolist()}

    @classmethod
    def from_dict(cls, d: dict) -> "DurationModel":
        return cls(np.asarray(d["pmf"], float), np.asarray(d["n_substates"], np.int64), np.asarray(d["tail"], float),
                   np.asarray(d["change"], float), np.asarray(d["n_runs"], np.int64))


def label_runs(seq) -> list[tuple[int, int, bool]]:
    """(class, length, complete) of every run of ``seq``; a run touching either end is not complete."""
    seq = np.asarray(seq, np.int64)
    if seq.size == 0:
        return []
    cut = np.flatnonzero(np.diff(seq)) + 1
    starts = np.concatenate([[0], cut])
    ends = np.concatenate([cut, [seq.size]])
    return [(int(seq[a]), int(b - a), bool(a > 0 and b < seq.size)) for a, b in zip(starts, ends)]


def duration_model(sequences, n_classes: int, bandwidth: float = 0.2, floor: float = 0.02,
                   max_substates: int = 80, prior: float = 1.0) -> DurationModel:
    """Learn a :class:`DurationModel` from label sequences (int arrays of class indices).

    A class' run lengths are its complete runs (runs cut by a video's ends are left out; a class with no
    complete run uses its cut runs, one with no run at all gets a flat distribution). Their density is a
    log-normal kernel estimate with ``bandwidth`` (in log frames) on lengths 1 .. 4 x the longest run, mixed
    with ``floor`` of a uniform distribution over the same lengths; lengths from D_k = min(max_substates,
    ceil(1.25 x the longest run)) on are one tail sub-state whose self-loop gives the estimate's mean excess
    length. Class changes are counted between consecutive runs, plus ``prior`` on every off-diagonal entry.
    """
    K = int(n_classes)
    runs = [r for seq in sequences for r in label_runs(seq)]
    change = np.full((K, K), float(prior))
    for seq in sequences:
        rs = label_runs(seq)
        for (a, _, _), (b, _, _) in zip(rs[:-1], rs[1:]):
            change[a, b] += 1.0
    np.fill_diagonal(change, 0.0)
    rs = change.sum(axis=1, keepdims=True)
    change = np.divide(change, rs, out=np.full((K, K), 1.0 / max(K - 1, 1)), where=rs > 0)
    np.fill_diagonal(change, 0.0)
    Ds, pmfs, tails, counts = [], [], [], []
    for k in range(K):
        lengths = np.array([n for c, n, ok in runs if c == k and ok], float)
        counts.append(lengths.size)
        if lengths.size == 0:
            lengths = np.array([n for c, n, _ in runs if c == k], float)
        longest = int(lengths.max()) if lengths.size else 20
        D = int(max(2, min(max_substates, np.ceil(1.25 * longest))))
        grid = np.arange(1, 4 * max(longest, D) + 1, dtype=float)
        if lengths.size:
            z = (np.log(grid)[:, None] - np.log(lengths)[None, :]) / bandwidth
            dens = (np.exp(-0.5 * z * z) / grid[:, None]).sum(axis=1)
            dens /= dens.sum()
        else:
            dens = np.full(grid.size, 1.0 / grid.size)
        dens = (1.0 - floor) * dens + floor / grid.size
        pmf = np.zeros(D)
        pmf[: D - 1] = dens[: D - 1]
        pmf[D - 1] = dens[D - 1 :].sum()
        excess = float((dens[D - 1 :] * (grid[D - 1 :] - D + 1)).sum() / max(pmf[D - 1], 1e-300))
        tails.append(float(np.clip(1.0 - 1.0 / max(excess, 1.0), 0.0, 0.999)))
        Ds.append(D)
        pmfs.append(pmf)
    Dmax = max(Ds)
    P = np.zeros((K, Dmax))
    for k, pmf in enumerate(pmfs):
        P[k, : pmf.size] = pmf
    return DurationModel(P, np.array(Ds, np.int64), np.array(tails), change, np.array(counts, np.int64))


def _duration_arrays(m: DurationModel):
    """Log advance / exit / tail-stay probabilities and log start probabilities over the (K, D) sub-states."""
    K, D = m.pmf.shape
    with np.errstate(divide="ignore", invalid="ignore"):
        surv = np.cumsum(m.pmf[:, ::-1], axis=1)[:, ::-1]  # surv[k, i] = S_k(i + 1)
        hazard = np.where(surv > 0, m.pmf / surv, 1.0)
        log_adv = np.log(np.clip(1.0 - hazard, 0.0, 1.0))
        log_exit = np.log(np.clip(hazard, 0.0, 1.0))
        valid = np.arange(D)[None, :] < m.n_substates[:, None]
        last = m.n_substates - 1
        log_exit[np.arange(K), last] = np.log(1.0 - m.tail)
        log_adv[np.arange(K), last] = -np.inf  # the last sub-state does not advance, it loops
        log_stay = np.log(m.tail)
        # residual life: start in sub-state i with probability S(i + 1) (the tail: S(D) / (1 - q))
        w = np.where(valid, surv, 0.0)
        w[np.arange(K), last] = surv[np.arange(K), last] / np.maximum(1.0 - m.tail, 1e-12)
        w /= w.sum(axis=1, keepdims=True)
        log_start = np.log(w) - np.log(K)
        log_exit[~valid] = -np.inf
        log_adv[~valid] = -np.inf
        log_change = np.log(m.change)
    return log_adv, log_exit, log_stay, log_start, log_change, last


def duration_viterbi(log_emission: np.ndarray, model: DurationModel, start: str = "any") -> np.ndarray:
    """Most probable class path (n,) of the explicit-duration HMM of ``model`` given (n, K) log emissions.

    ``start="any"``: the first run may begin at any point of its run (residual life); ``"onset"``: the
    video starts at the beginning of a run (sub-state 0, classes equally likely)."""
    n, K = log_emission.shape
    if K != model.n_classes:
        raise InputError(f"duration model: {model.n_classes} classes, emissions have {K}")
    if n == 0:
        return np.zeros(0, np.int64)
    D = model.pmf.shape[1]
    log_adv, log_exit, log_stay, log_start, log_change, last = _duration_arrays(model)
    if start == "onset":
        log_start = np.full((K, D), -np.inf)
        log_start[:, 0] = -np.log(K)
    elif start != "any":
        raise ParameterError("start", f"must be 'any' or 'onset', got {start!r}")
    rows = np.arange(K)
    delta = log_start + log_emission[0][:, None]
    back = np.zeros((n, K, D), np.int32)  # flat index k * D + i of the predecessor sub-state
    idx = np.arange(K * D, dtype=np.int32).reshape(K, D)
    for t in range(1, n):
        ex = delta + log_exit  # (K, D): leave class j from sub-state i
        ex_arg = np.argmax(ex, axis=1)
        ex_best = ex[rows, ex_arg]  # (K,)
        cand = ex_best[:, None] + log_change  # (from, to)
        frm = np.argmax(cand, axis=0)
        new = np.full((K, D), -np.inf)
        b = np.zeros((K, D), np.int32)
        new[:, 0] = cand[frm, rows]
        b[:, 0] = idx[frm, ex_arg[frm]]
        new[:, 1:] = delta[:, :-1] + log_adv[:, :-1]
        b[:, 1:] = idx[:, :-1]
        stay = delta[rows, last] + log_stay
        better = stay > new[rows, last]
        new[rows[better], last[better]] = stay[better]
        b[rows[better], last[better]] = idx[rows[better], last[better]]
        delta = new + log_emission[t][:, None]
        back[t] = b
    s = int(np.argmax(delta))
    path = np.empty(n, np.int64)
    for t in range(n - 1, -1, -1):
        path[t] = s // D
        if t:
            s = int(back[t].ravel()[s])
    return path
