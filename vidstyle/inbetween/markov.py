"""Keyframe to keyframe by a Markov chain over pose clusters (Molina Tanco & Hilton 2000, seed 002).

Level 1 (:class:`MarkovInbetweener` ``fit``): every library frame's pose feature
(:func:`~.poses.pose_features`: angle-axis joint rotations with the heading removed, root height, and
optionally the feature's velocity) is reduced by PCA and vector-quantised by k-means; a first-order
Markov chain over the clusters is counted from consecutive frames of each clip (Laplace-smoothed), with
explicit durations: the transition counts exclude staying in a cluster, and each cluster's run lengths
(frames spent in it before leaving) are counted as its duration distribution.

Synthesis between a start and an end key pose ``T`` frames apart:

1. the keys are quantised to clusters ``c_0`` and ``c_T``; :func:`best_cluster_path` finds the most probable
   cluster sequence of exactly ``T + 1`` frames from ``c_0`` to ``c_T`` by dynamic programming (Viterbi with
   fixed ends over the explicit-duration chain: the paper's "only transitions between different states",
   with each stay scored by its duration, so the gap length shapes the path);
2. level 2 (:func:`segment_path`): the library frames that best realise that cluster sequence, by a second
   dynamic programme over (output frame x library frame): playing the next frame of a clip is free, a jump
   between clips costs ``jump_cost`` and is allowed only between poses of one cluster (the frontiers of the
   paper's "motion segments"), a frame outside the asked cluster costs ``mismatch_cost``, and the first and
   last frames pay their feature distance to the start and end keys (the paper's "segments closest to the
   keyframes");
3. the segments are placed end to end (each continues from where the previous one is, Placement of the
   root heading and floor position), blended over ``blend_frames`` at each jump with the motion graph's
   blend (:func:`vidstyle.motiongraph.blend.blend_frames`), and pinned to the two keys
   (:func:`~.poses.pin`), so the output passes exactly through both. The root follows the segments'
   own path (``root_path="library"``, the paper) or a cubic Hermite curve with the keys' root velocities
   (``"hermite"``: the body's motion comes from the library, where it goes from the keys' own momentum;
   a library without the performer's kind of motion otherwise drags the root along its own paths).

The library is any fitted :class:`~vidstyle.motiongraph.MotionGraph` (its frames ``rotations_``,
``root_positions_``, ``frame_clip_``, ``skeleton_`` and ``fps``).
"""

from __future__ import annotations

from itertools import pairwise

import numpy as np

from ..errors import ParameterError
from ..mocap.placement import Placement
from ..mocap.retarget import leg_length
from ..motiongraph.blend import blend_frames, slerp
from . import defaults as D
from .poses import ROOT_PATHS, Keypose, pin, placement_onto, pose_features, slerp_inbetween


def run_lengths(labels: np.ndarray, cont: np.ndarray) -> list[tuple[int, int]]:
    """``(cluster, frames)`` of every run of one cluster inside one clip (``cont[i]``: frame ``i`` follows
    frame ``i-1`` in its clip)."""
    N = len(labels)
    brk = np.ones(N, bool)
    brk[1:] = ~cont[1:] | (labels[1:] != labels[:-1])
    starts = np.flatnonzero(brk)
    ends = np.concatenate([starts[1:], [N]])
    return [(int(labels[a]), int(b - a)) for a, b in zip(starts, ends)]


def duration_tables(counts: np.ndarray, n: int, smoothing: float) -> tuple[np.ndarray, np.ndarray]:
    """``log P(d | c)`` and ``log P(D >= d | c)`` for ``d = 0 .. n`` (column 0 unused, -inf) from run-length
    ``counts`` (K, L+1) (column d: runs of d frames), each count plus ``smoothing`` over ``1 .. max(L, n)``."""
    K, L1 = counts.shape
    M = max(L1 - 1, n)
    c = np.zeros((K, M + 1))
    c[:, :L1] = counts
    c[:, 1:] += smoothing
    c[:, 0] = 0.0
    p = c / c.sum(axis=1, keepdims=True)
    surv = np.cumsum(p[:, ::-1], axis=1)[:, ::-1]
    with np.errstate(divide="ignore"):
        log_d, log_s = np.log(p[:, : n + 1]), np.log(surv[:, : n + 1])
    log_d[:, 0] = log_s[:, 0] = -np.inf
    return log_d, log_s


def path_score(path: np.ndarray, log_a: np.ndarray, log_d: np.ndarray, log_s: np.ndarray) -> float:
    """Log probability of a cluster sequence under the explicit-duration chain of
    :func:`best_cluster_path` (the reference its dynamic programme is tested against)."""
    runs = []
    for c in path:
        if runs and runs[-1][0] == c:
            runs[-1][1] += 1
        else:
            runs.append([int(c), 1])
    if len(runs) == 1:
        return float(log_s[runs[0][0], runs[0][1]])
    score = log_s[runs[0][0], runs[0][1]] + log_s[runs[-1][0], runs[-1][1]]
    score += sum(log_d[c, d] for c, d in runs[1:-1])
    score += sum(log_a[a[0], b[0]] for a, b in pairwise(runs))
    return float(score)


def best_cluster_path(log_a: np.ndarray, start: int, end: int, n_states: int, log_d: np.ndarray | None = None,
                      log_s: np.ndarray | None = None) -> tuple[np.ndarray, float]:
    """Most probable cluster sequence ``s_0 .. s_{n-1}`` from ``start`` to ``end`` (both fixed).

    The chain moves between *different* clusters (``log_a[i, j] = log P(j | i, leaving i)``, diagonal
    ignored) and stays in cluster ``c`` for ``d`` frames with ``log_d[c, d]`` (an explicit duration:
    what makes the gap's length shape the path; a first-order chain's own most probable path of a fixed
    length just sits in the stickiest cluster). The first and last runs are cut by the keys, so they
    score the survival ``log_s[c, d] = log P(D >= d | c)``. Without ``log_d``/``log_s`` every duration
    scores 0 (the fewest-hops most probable path). Dynamic programming over (frames covered, cluster of
    the run ending there): O(n^2 K + n K^2). Returns the path and its log probability (``-inf``: none)."""
    K = log_a.shape[0]
    n = int(n_states)
    if n < 1:
        raise ValueError("n_states must be at least 1")
    if log_d is None:
        log_d = np.zeros((K, n + 1))
    if log_s is None:
        log_s = np.zeros((K, n + 1))
    la = np.array(log_a, dtype=np.float64, copy=True)
    np.fill_diagonal(la, -np.inf)
    # G[t, c]: best score of the first t frames, the last run (cluster c) ending at frame t-1 and scored as a
    # middle run (or as the first run when it is the first)
    G = np.full((n + 1, K), -np.inf)
    back = np.full((n + 1, K, 2), -1, np.int64)  # (duration, previous cluster); previous -1: the first run
    M = np.full((n + 1, K), -np.inf)  # M[t, c]: best G[t, c'] + la[c', c] over c' (entering c after t frames)
    argM = np.zeros((n + 1, K), np.int64)
    for t in range(1, n):
        G[t, start] = log_s[start, t]
        if t > 1:
            cand = M[t - 1 : 0 : -1] + log_d[:, 1:t].T  # row d-1: entering after t-d frames, staying d
            d = np.argmax(cand, axis=0)
            val = cand[d, np.arange(K)]
            better = val > G[t]
            G[t] = np.where(better, val, G[t])
            dd = d[better] + 1
            back[t][better] = np.stack([dd, argM[t - dd, np.flatnonzero(better)]], axis=1)
        enter = G[t][:, None] + la
        argM[t] = np.argmax(enter, axis=0)
        M[t] = enter[argM[t], np.arange(K)]
    best, choice = (log_s[end, n], (n, -1)) if start == end else (-np.inf, None)
    for d in range(1, n):
        prev = G[n - d] + la[:, end]
        c = int(np.argmax(prev))
        if prev[c] + log_s[end, d] > best:
            best, choice = float(prev[c] + log_s[end, d]), (d, c)
    if choice is None or not np.isfinite(best):
        return np.full(n, start, np.int64), -np.inf
    path = np.empty(n, np.int64)
    t, c = n, end
    d, p = choice
    while True:
        path[t - d : t] = c
        t -= d
        if p < 0:
            break
        c = p
        d, p = (t, -1) if back[t, c, 1] < 0 and back[t, c, 0] < 0 else (int(back[t, c, 0]), int(back[t, c, 1]))
    return path, float(best)


def segment_path(labels: np.ndarray, cont: np.ndarray, path: np.ndarray, cost_first: np.ndarray,
                 cost_last: np.ndarray, mismatch_cost: float, jump_cost: float,
                 emission: np.ndarray | None = None, warp_cost: float | None = None,
                 emission_t: np.ndarray | None = None) -> tuple[np.ndarray, float]:
    """Level 2: the library frame shown at each output frame (``len(path)``), least total cost.

    ``labels`` (N,) cluster of each library frame; ``cont[i]``: frame ``i`` follows frame ``i-1`` in the same
    clip. Moves: play ``i-1 -> i`` (``cont[i]``, free) or jump ``j -> i`` with ``labels[j]`` equal to the
    cluster of ``i``'s predecessor in its clip (of ``i`` itself at a clip start), cost ``jump_cost``; with
    ``warp_cost``, also hold ``i -> i`` and skip ``i-2 -> i`` inside a clip at that cost (a time warp
    of the segment, so a segment whose pace differs from the gap's can still meet both keys).
    Frame costs: ``mismatch_cost`` when ``labels[i] != path[t]`` (or, given ``emission`` (N, K), ``mismatch_cost
    * emission[i, path[t]]``: a soft mismatch, e.g. the squared distance to the cluster's centre), plus
    ``cost_first`` at t = 0 and ``cost_last`` at the last t. ``emission_t``: ``emission.T`` as a C-contiguous
    float64 (K, N) array, when the caller keeps one (the compiled pass reads it so; otherwise each call
    makes that copy)."""
    N = len(labels)
    K = int(max(labels.max(), path.max())) + 1
    n = len(path)
    entry = np.where(cont, np.roll(labels, 1), labels)  # cluster a jump into i must come from
    cont2 = np.zeros(N, bool)
    cont2[2:] = cont[2:] & cont[1:-1]
    kernel = _segment_kernel()
    if kernel is not None:
        history = np.empty((n, N))
        move = np.zeros((n, N), np.int8)
        kernel(np.ascontiguousarray(labels, dtype=np.int64), np.ascontiguousarray(cont, dtype=np.bool_), cont2,
               np.ascontiguousarray(entry, dtype=np.int64), np.ascontiguousarray(path, dtype=np.int64),
               np.ascontiguousarray(cost_first, dtype=np.float64), np.ascontiguousarray(cost_last, dtype=np.float64),
               float(mismatch_cost), float(jump_cost),
               np.zeros((1, 1)) if emission is None else (
                   _emission_rows(emission) if emission_t is None else emission_t),
               emission is not None, 0.0 if warp_cost is None else float(warp_cost), warp_cost is not None, K,
               history, move)
        return _segment_backtrack(labels, entry, history, move)
    return _segment_path_numpy(labels, cont, path, cost_first, cost_last, mismatch_cost, jump_cost, emission,
                               warp_cost, K, entry, cont2)


def _emission_rows(emission: np.ndarray) -> np.ndarray:
    """``emission`` (N, K) as the compiled pass reads it: (K, N) C-contiguous float64."""
    return np.ascontiguousarray(np.asarray(emission, dtype=np.float64).T)


def _segment_backtrack(labels, entry, history, move) -> tuple[np.ndarray, float]:
    n = len(history)
    V = history[-1]
    frames = np.empty(n, np.int64)
    i = int(np.argmin(V))
    total = float(V[i])
    for t in range(n - 1, -1, -1):
        frames[t] = i
        if t == 0:
            break
        mv = move[t, i]
        if mv == 1:
            same = np.flatnonzero(labels == entry[i])
            i = int(same[np.argmin(history[t - 1][same])])
        else:
            i = i - (1, 0, 0, 2)[mv]
    return frames, total


def _segment_loop(labels, cont, cont2, entry, path, cost_first, cost_last, mismatch, jump, emission_t, soft, warp,
                  warped, K, history, move):
    # compiled by numba: the forward pass of _segment_path_numpy, frame by frame, the same float64 operations
    # (a candidate replaces the running best only when strictly lower, np.minimum's NaN kept)
    N = labels.shape[0]
    n = path.shape[0]
    inf = np.inf
    best = np.empty(K)
    for t in range(n):
        c = path[t]
        row = history[t]
        if t == 0:
            for i in range(N):
                row[i] = cost_first[i] + (mismatch * emission_t[c, i] if soft else mismatch * (1.0 if labels[i] != c else 0.0))
        else:
            V = history[t - 1]
            best[:] = inf
            for i in range(N):  # np.minimum.reduceat of V per cluster
                b = best[labels[i]]
                if not np.isnan(b) and (np.isnan(V[i]) or V[i] < b):
                    best[labels[i]] = V[i]
            for i in range(N):
                v = V[i - 1] if i >= 1 and cont[i] else inf
                m = 0
                cands = (best[entry[i]] + jump, V[i] + warp if warped else inf,
                         V[i - 2] + warp if warped and i >= 2 and cont2[i] else inf)
                for k in range(3 if warped else 1):
                    x = cands[k]
                    if x < v:
                        m = k + 1
                    if np.isnan(v) or np.isnan(x):
                        v = np.nan
                    elif x < v:
                        v = x
                move[t, i] = m
                row[i] = v + (mismatch * emission_t[c, i] if soft else mismatch * (1.0 if labels[i] != c else 0.0))
        if t == n - 1:
            for i in range(N):
                row[i] = row[i] + cost_last[i]


_SEGMENT_KERNEL: list = []


def _segment_kernel():
    """:func:`_segment_loop` compiled (:func:`vidstyle.compiled.compile_kernel`), or None without numba."""
    if not _SEGMENT_KERNEL:
        from ..compiled import compile_kernel

        _SEGMENT_KERNEL.append(compile_kernel(_segment_loop))
    return _SEGMENT_KERNEL[0]


def _segment_path_numpy(labels, cont, path, cost_first, cost_last, mismatch_cost, jump_cost, emission, warp_cost,
                        K, entry, cont2) -> tuple[np.ndarray, float]:
    """:func:`segment_path` in numpy (the reference of the compiled forward pass, and its fallback)."""
    N = len(labels)
    n = len(path)

    emission_t = None if emission is None else np.ascontiguousarray(emission.T)  # (K, N): one row per cluster
    order = np.argsort(labels, kind="stable")  # per-cluster minima by one reduceat over frames sorted by cluster
    present = np.unique(labels)
    starts = np.searchsorted(labels[order], present)

    def emit(c: int) -> np.ndarray:
        return mismatch_cost * (labels != c) if emission_t is None else mismatch_cost * emission_t[c]

    V = cost_first + emit(path[0])
    if n == 1:
        V = V + cost_last
    history = [V]
    move = np.zeros((n, N), np.int8)  # 0 play, 1 jump, 2 hold, 3 skip
    for t in range(1, n):
        cand = np.full((4, N), np.inf)
        cand[0, 1:][cont[1:]] = V[:-1][cont[1:]]
        best = np.full(K, np.inf)
        best[present] = np.minimum.reduceat(V[order], starts)
        cand[1] = best[entry] + jump_cost
        if warp_cost is not None:
            cand[2] = V + warp_cost
            cand[3, 2:][cont2[2:]] = V[:-2][cont2[2:]] + warp_cost
        V = cand[0].copy()
        mv = move[t]
        for k in range(1, 4 if warp_cost is not None else 2):
            better = cand[k] < V
            mv[better] = k
            np.minimum(V, cand[k], out=V)
        V += emit(path[t])
        if t == n - 1:
            V = V + cost_last
        history.append(V)
    return _segment_backtrack(labels, entry, np.array(history), move)


def render_frames(rotations: np.ndarray, roots: np.ndarray, clip: np.ndarray, frames: np.ndarray,
                  start: Placement, blend: int) -> tuple[np.ndarray, np.ndarray]:
    """Library ``frames`` (one per output frame) as placed motion: the first at ``start``, each later
    segment continuing from where the previous one is (its predecessor frame put onto the frame shown
    before the jump), jumps blended over ``blend`` frames (departing clip's continuation into the
    arriving segment, :func:`~vidstyle.motiongraph.blend.blend_frames`). A hold or a skip of one frame
    inside a clip (a time warp) stays in its segment."""
    n = len(frames)
    rot, root = np.empty((n, rotations.shape[1], 4)), np.empty((n, 3))
    here = start
    seams = []
    t = 0
    while t < n:
        t1 = t + 1
        while t1 < n and 0 <= frames[t1] - frames[t1 - 1] <= 2 and clip[frames[t1]] == clip[frames[t1 - 1]]:
            t1 += 1
        f = frames[t:t1]
        if t > 0:
            j, i = frames[t - 1], frames[t]
            pred = i - 1 if i > 0 and clip[i - 1] == clip[i] else i
            pj_rot, pj_root = rot[t - 1, 0], root[t - 1]
            onto = placement_onto(rotations[pred, 0], roots[pred], pj_rot, pj_root)
            seams.append((t, j, here))
            here = onto
        rot[t:t1], root[t:t1] = here.apply_frames(rotations[f], roots[f])
        t = t1
    bounds = [s[0] for s in seams] + [n]
    for s, (t, j, was) in enumerate(seams):
        r = min(blend, bounds[s + 1] - t)
        if r < 1:
            continue
        cont = j + 1 + np.arange(r)
        same = clip[np.minimum(cont, len(clip) - 1)] == clip[j]
        cont = np.where(same & (cont < len(clip)), cont, j)  # hold the clip's last frame past its end
        ra, pa = was.apply_frames(rotations[cont], roots[cont])
        rot[t : t + r], root[t : t + r] = blend_frames(ra, pa, rot[t : t + r], root[t : t + r], r)
    return rot, root


def coverage_weight(key_distance: float, scale: float | None) -> float:
    """The weight of the library's body motion against the keys' SLERP: ``exp(-(d / scale)^2)`` for the
    keys' ``key_distance`` ``d`` (:meth:`MarkovInbetweener.plan`); 1 without a ``scale``.

    Keys near library poses (``d`` below a cluster spread or so) keep the library's motion; keys that no
    library frame resembles (a kind of motion the library lacks) fall back toward plain interpolation,
    where the Markov path's segments, found among unrelated motion, would only add a wrong action. On
    held-out CMU subjects whose motion the library lacks, the ungated library motion scored worse than
    SLERP at every gap (``scripts/validate_inbetween.py``)."""
    if scale is None:
        return 1.0
    return float(np.exp(-((float(key_distance) / float(scale)) ** 2)))


class MarkovInbetweener:
    """Molina Tanco & Hilton's two-level model (scikit-learn conventions: parameters in ``__init__``,
    :meth:`fit` learns ``pca_``, ``kmeans_``, ``log_transitions_``, ``labels_``, ...; ``random_state`` seeds
    PCA and k-means and is stored with the model).

    Parameters: ``n_clusters`` (Markov states), ``n_components`` (PCA dimension), ``height_weight`` and
    ``velocity_weight`` (of the root height and feature-velocity parts of the pose feature),
    ``smoothing`` (pseudo-count of the transition counts), ``mismatch_cost``, ``jump_cost``, ``warp_cost``,
    ``key_weight`` (level 2, see :func:`segment_path`), ``blend_frames`` (jump blend length), ``root_path``
    (:data:`~.poses.ROOT_PATHS`), ``coverage_scale`` (:func:`coverage_weight`; ``None``: the paper, the
    library's motion as it is).
    """

    PARAMS = ("n_clusters", "n_components", "height_weight", "velocity_weight", "smoothing", "mismatch_cost",
              "jump_cost", "warp_cost", "key_weight", "blend_frames", "root_path", "coverage_scale", "random_state")

    def __init__(self, n_clusters: int = D.N_CLUSTERS, n_components: int = D.N_COMPONENTS,
                 height_weight: float = D.HEIGHT_WEIGHT, velocity_weight: float = D.VELOCITY_WEIGHT,
                 smoothing: float = D.SMOOTHING, mismatch_cost: float = D.MISMATCH_COST, jump_cost: float = D.JUMP_COST,
                 warp_cost: float | None = D.WARP_COST, key_weight: float = D.KEY_WEIGHT, blend_frames: int = D.BLEND_FRAMES,
                 root_path: str = D.ROOT_PATH, coverage_scale: float | None = D.COVERAGE_SCALE,
                 random_state: int = D.RANDOM_STATE) -> None:
        self.n_clusters = n_clusters
        self.n_components = n_components
        self.height_weight = height_weight
        self.velocity_weight = velocity_weight
        self.smoothing = smoothing
        self.mismatch_cost = mismatch_cost
        self.jump_cost = jump_cost
        self.warp_cost = warp_cost
        self.key_weight = key_weight
        self.blend_frames = blend_frames
        self.root_path = root_path
        self.coverage_scale = coverage_scale
        self.random_state = random_state

    def get_params(self, deep: bool = True) -> dict:
        return {k: getattr(self, k) for k in self.PARAMS}

    def set_params(self, **params) -> MarkovInbetweener:
        for k, v in params.items():
            if k not in self.PARAMS:
                raise ValueError(f"unknown parameter {k!r}")
            setattr(self, k, v)
        return self

    # ------------------------------------------------------------------------------------------ features
    def _features(self, rotations: np.ndarray, roots: np.ndarray, clip: np.ndarray | None = None,
                  previous: tuple[np.ndarray, np.ndarray] | None = None) -> np.ndarray:
        f = pose_features(rotations, roots, self.leg_, self.height_weight)
        if not self.velocity_weight:
            return f
        if previous is not None:
            v = f - pose_features(previous[0], previous[1], self.leg_, self.height_weight)
        elif clip is not None:
            v = np.zeros_like(f)
            v[1:] = f[1:] - f[:-1]
            first = np.ones(len(f), bool)
            first[1:] = clip[1:] != clip[:-1]
            nxt = np.flatnonzero(first & np.roll(~first, -1))
            v[nxt] = v[np.minimum(nxt + 1, len(f) - 1)]  # a clip's first frame: its successor's velocity
        else:
            v = np.zeros_like(f)
        return np.concatenate([f, v * self.velocity_weight], axis=1)

    def key_features(self, key: Keypose) -> np.ndarray:
        """The feature of one key pose (velocity from ``previous``, else from ``following``, else zero)."""
        if key.previous is None and key.following is not None and self.velocity_weight:
            nxt = key.following
            f = self._features(nxt.rotations[None], nxt.root[None], previous=(key.rotations[None], key.root[None]))[0]
            base = pose_features(key.rotations[None], key.root[None], self.leg_, self.height_weight)[0]
            return np.concatenate([base, f[len(base):]])
        prev = None if key.previous is None else (key.previous.rotations[None], key.previous.root[None])
        return self._features(key.rotations[None], key.root[None], previous=prev)[0]

    # ------------------------------------------------------------------------------------------ fit
    def fit(self, graph, y=None) -> MarkovInbetweener:
        from sklearn.cluster import KMeans
        from sklearn.decomposition import PCA

        for name in ("n_clusters", "n_components", "blend_frames"):
            if int(getattr(self, name)) < 1:
                raise ParameterError(name, f"must be at least 1, got {getattr(self, name)}")
        if self.root_path not in ROOT_PATHS:
            raise ParameterError("root_path", f"must be one of {', '.join(ROOT_PATHS)}, got {self.root_path!r}")
        if self.coverage_scale is not None and not float(self.coverage_scale) > 0:
            raise ParameterError("coverage_scale", f"must be positive or None, got {self.coverage_scale}")
        self.skeleton_ = graph.skeleton_
        self.fps_ = float(graph.fps)
        self.rotations_ = np.asarray(graph.rotations_)
        self.root_positions_ = np.asarray(graph.root_positions_)
        self.clip_ = np.asarray(graph.frame_clip_)
        N = len(self.clip_)
        if N < int(self.n_clusters):
            raise ParameterError("n_clusters", f"{self.n_clusters} clusters but the library has {N} frames")
        self.leg_ = float(leg_length(self.skeleton_))
        X = self._features(self.rotations_, self.root_positions_, self.clip_)
        n_comp = min(int(self.n_components), X.shape[1], N)
        self.pca_ = PCA(n_components=n_comp, random_state=self.random_state).fit(X)
        Z = self.pca_.transform(X)
        self.kmeans_ = KMeans(n_clusters=int(self.n_clusters), n_init=4, random_state=self.random_state).fit(Z)
        self.labels_ = self.kmeans_.labels_.astype(np.int64)
        self.features_ = Z
        self.spread_ = float(self.kmeans_.inertia_ / N) or 1.0  # mean squared distance to the centre
        # level 2's soft mismatch: squared distance of every frame to every centre, in mean spreads
        cen = self.kmeans_.cluster_centers_
        self.emission_ = np.maximum(
            np.sum(Z**2, 1)[:, None] - 2 * Z @ cen.T + np.sum(cen**2, 1)[None], 0.0) / self.spread_
        self.cont_ = np.zeros(N, bool)
        self.cont_[1:] = self.clip_[1:] == self.clip_[:-1]
        K = int(self.n_clusters)
        counts = np.zeros((K, K))
        a, b = self.labels_[:-1][self.cont_[1:]], self.labels_[1:][self.cont_[1:]]  # consecutive frames
        np.add.at(counts, (a, b), 1.0)
        np.fill_diagonal(counts, 0.0)  # the chain between different clusters; staying is the duration
        counts += float(self.smoothing)
        np.fill_diagonal(counts, 0.0)
        self.transitions_ = counts / counts.sum(axis=1, keepdims=True)
        with np.errstate(divide="ignore"):
            self.log_transitions_ = np.log(self.transitions_)
        runs = run_lengths(self.labels_, self.cont_)
        L = max(d for _, d in runs)
        self.duration_counts_ = np.zeros((K, L + 1))
        for c, d in runs:
            self.duration_counts_[c, d] += 1.0
        return self

    def quantise(self, key: Keypose) -> tuple[int, np.ndarray]:
        z = self.pca_.transform(self.key_features(key)[None])[0]
        return int(self.kmeans_.predict(z[None])[0]), z

    # ------------------------------------------------------------------------------------------ synthesis
    def _emission_t(self) -> np.ndarray | None:
        """``emission_`` transposed for the compiled segment pass, made once per fitted emission (a copy of
        the library's size per gap otherwise)."""
        if self.emission_ is None:
            return None
        cached = self.__dict__.get("_emission_rows_cache")
        if cached is None or cached[0] is not self.emission_:
            cached = self._emission_rows_cache = (self.emission_, _emission_rows(self.emission_))
        return cached[1]

    def plan(self, start: Keypose, end: Keypose, n_frames: int) -> dict:
        """The two levels for ``n_frames`` output frames (both keys included): cluster path, library frames;
        and ``key_distance``, the mean of the two keys' squared feature distances to their nearest library
        frame, in mean cluster spreads (how well the library knows the keys, :func:`coverage_weight`)."""
        c0, z0 = self.quantise(start)
        c1, z1 = self.quantise(end)
        log_d, log_s = duration_tables(self.duration_counts_, n_frames, float(self.smoothing))
        path, logp = best_cluster_path(self.log_transitions_, c0, c1, n_frames, log_d, log_s)
        d_first = np.sum((self.features_ - z0) ** 2, axis=1) / self.spread_
        d_last = np.sum((self.features_ - z1) ** 2, axis=1) / self.spread_
        w = float(self.key_weight)
        cost_first, cost_last = w * d_first, w * d_last
        frames, cost = segment_path(self.labels_, self.cont_, path, cost_first, cost_last,
                                    float(self.mismatch_cost), float(self.jump_cost), self.emission_,
                                    None if self.warp_cost is None else float(self.warp_cost),
                                    emission_t=self._emission_t())
        key_distance = 0.5 * float(d_first.min() + d_last.min())
        return {"clusters": path, "log_probability": logp, "frames": frames, "cost": cost, "key_distance": key_distance}

    def inbetween(self, start: Keypose, end: Keypose, n_frames: int, free_end: bool = False) -> tuple[np.ndarray, np.ndarray]:
        """(rotations (n, J, 4), roots (n, 3)) from ``start`` to ``end`` over ``n_frames`` output frames.
        ``free_end``: the end key keeps its pose and root height but takes the heading and floor position
        the synthesised motion arrives at (keys from different clips have unrelated world placements)."""
        plan = self.plan(start, end, n_frames)
        frames = plan["frames"]
        here = placement_onto(self.rotations_[frames[0], 0], self.root_positions_[frames[0]], start.rotations[0], start.root)
        rot, root = render_frames(self.rotations_, self.root_positions_, self.clip_, frames, here, int(self.blend_frames))
        if free_end:
            end = end.placed(placement_onto(end.rotations[0], end.root, rot[-1, 0], root[-1]))
        rot, root = pin(rot, root, start, end, self.root_path)
        weight = coverage_weight(plan["key_distance"], self.coverage_scale)
        if weight < 1.0:  # keys the library does not know: its body motion shrinks toward the keys' SLERP
            keyed, _ = slerp_inbetween(start, end, n_frames)
            rot = slerp(keyed, rot, np.full(rot.shape[:2], weight))
            rot[0], rot[-1] = start.rotations, end.rotations
        return rot, root
