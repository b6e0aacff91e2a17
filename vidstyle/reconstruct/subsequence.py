"""Whole-sequence reconstruction by a subsequence graph (SSG; Tautges 2012, sections 4.3.2-4.3.5).

The alternative to the per-frame search (:mod:`.olng`): the query -- a video's per-frame 2D
bone-direction features (:func:`vidstyle.augmg.projection.angle_features`) -- is matched window by
window against whole library subsequences, and the best chain of overlapping subsequences is
cross-faded.

**Windows.** The T query frames are cut into windows of ``window`` frames (Tautges: N = 15 frames at
60 fps, a quarter of a second; the caller converts, e.g. ``round(0.25 * fps)``) starting every
``window - overlap`` frames (Tautges: o = 6), so consecutive windows share exactly ``overlap`` frames.
The last window ends at frame T and may be shorter (it still has more than ``overlap`` frames).
``overlap <= window // 2``, so no query frame lies in three windows.

**Subsequence DTW** (section 4.3.3). A window of L query frames n = 0..L-1 is compared with the N
library frames m (the rows of the index's features at *one* view: the most frequent of the window's
valid frames' ``views``, ties to the smaller; or, with ``all_views``, every view, keeping per library
frame the view of least end cost). Local cost ``C(n, m) = w_n ||q_n - f_m||`` (Euclidean feature
distance, computed for a whole window by one GEMM, ``|q|^2 + |f|^2 - 2 q.f`` in float64) with
``w_n`` the frame's confidence weight (default 1) and 0 for a missing frame (``valid`` False), so a
missing frame never steers the alignment. The accumulated cost is Tautges' eq. 4.2 (0-based here):

    D(0, m) = C(0, m)
    D(n, m) = inf                                       if m is the first frame of its clip and n > 0
    D(n, m) = min( D(n-1, m-1) + C(n, m),               step (1, 1)
                   D(n-1, m-2) + C(n, m),               step (1, 2): the library skips frame m-1
                   D(n-2, m-1) + 2 C(n, m) )            step (2, 1): the query skips frame n-1
                                                        otherwise, D = inf outside the matrix

so warping paths have slopes in [1/2, 2] and never cross a clip boundary (every clip's first frame is
a fresh m = 1: a predecessor in another clip counts as outside the matrix). Ties between the steps go
to the earlier one in that list. The factor 2 of the (2, 1) step stands in for the skipped frame's
cost; with weights it is ``(w_{n-1} + w_n) d(n, m)`` (the skipped frame's weight at the landing
frame's distance; 2 C(n, m) when the weights are equal, so eq. 4.2 exactly without weights), and the
step may not land on a weight-0 frame after skipping a weighted one (that would skip a real frame for
free next to a missing one; :func:`skip_factors`). The ``k`` best subsequences are retrieved by their
end cost ``D(L-1, m)`` as Müller (Information Retrieval for Music and Motion, 4.4) does: repeatedly the
least end, skipping ends within ``exclusion`` frames (default ``window // 2``) of an already retrieved
end of the same clip; each is backtracked through the steps that produced D (so through the weights)
to its warping path. The DP (with the local costs computed inside it from the GEMM's products) and
the backtracking run in numba (:func:`vidstyle.compiled.compile_kernel`); :func:`subsequence_dtw`,
:func:`accumulated_cost` and :func:`warping_positions` with ``compiled=False`` are the numpy / Python
references, equal to them bit for bit.

**Query frame -> library frame.** A path step gives each query frame its library frame; a query frame
skipped by a (2, 1) step sits at the midpoint of the two library frames around it and takes the
earlier one (the library frame is held; a library frame may repeat or be skipped). A missing query
frame takes the library position interpolated linearly between the nearest valid frames of the window
on either side, or, before the first / after the last valid frame of the window, continued at speed 1
from it (clamped to the clip). A window without any valid frame keeps its path as retrieved (all its
subsequences cost 0; only the transition costs choose among them).

**Graph** (section 4.3.4). Nodes are the retrieved subsequences of every window, with node cost their
DTW cost ``D(L-1, end)``; an edge joins every subsequence of window i to every one of window i+1, with
transition cost eq. 4.4, the sum over the ``overlap`` shared query frames and all joints of the squared
distance between the two subsequences' 3D poses (``points3d``) at those frames. Tautges first aligns
each subsequence to the control signal (a rotation about the vertical and a ground translation, eq.
4.3); our control signal is 2D and view-relative and ``points3d`` are facing-normalised and
root-relative, so both poses are already in the one frame the alignment would bring them to and are
compared as they are. A source node leads to every subsequence of the first window; the path cost is
the sum of its node costs plus ``transition_weight`` times the sum of its edge costs, minimised by
dynamic programming over the windows in order (the graph is a layered DAG).

**Synthesis** (section 4.3.5). Every query frame gets two library frames ``ids[t]`` and the weight
``alpha[t]`` of the first, the pose being ``alpha P[ids[t, 0]] + (1 - alpha) P[ids[t, 1]]`` (eq. 4.5).
Outside overlaps both are the chosen subsequence's frame and alpha is 1. In the overlap of windows i
and i+1 (positions r = 0..o-1) ``ids[t, 0]`` is window i's frame and ``ids[t, 1]`` window i+1's, and
``alpha = 1 - s(r / (o - 1))`` with the smoothstep ``s(a) = 3a^2 - 2a^3``: 1 at the first overlap frame,
0 at the last, with zero slope at both ends, so the blend's velocity is continuous (Tautges asks for a
C1 transition function; a linear ramp would kink the velocity). With ``overlap == 1`` the single
shared frame takes alpha 0.5; with 0 the subsequences are cut.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache

import numpy as np

#: step codes of :func:`accumulated_cost` (query step, library step)
STEP_DIAGONAL, STEP_LIBRARY_SKIP, STEP_QUERY_SKIP = 0, 1, 2


@dataclass
class SubsequencePath:
    """The reconstruction of a query of T frames through I windows (module docstring).

    ``ids`` (T, 2) int64 library frames (indices into the index's frames) of every query frame,
    ``alpha`` (T,) float64 weight of ``ids[:, 0]`` (the pose is ``alpha P[ids0] + (1 - alpha) P[ids1]``;
    outside overlaps ``ids[:, 0] == ids[:, 1]`` and alpha is 1), ``cost`` the chosen path's total cost
    (node costs + ``transition_weight`` x edge costs). Per window: ``windows`` (I, 2) query frames
    [start, stop), ``start`` / ``end`` (I,) the chosen subsequence's library frames at the window's first
    and last query frame, ``node_cost`` (I,) its DTW cost, ``transition_cost`` (I,) the cost of the edge
    into it (0 for the first window, unweighted), ``view`` (I,) the view it was matched at,
    ``window_ids`` (I, window) the library frame of each of the window's query frames (-1 beyond a short
    last window), ``n_candidates`` (I,) how many subsequences the window retrieved."""

    ids: np.ndarray
    alpha: np.ndarray
    cost: float
    windows: np.ndarray
    start: np.ndarray
    end: np.ndarray
    node_cost: np.ndarray
    transition_cost: np.ndarray
    view: np.ndarray
    window_ids: np.ndarray
    n_candidates: np.ndarray


# ------------------------------------------------------------------------------------------ windows
def window_bounds(n_frames: int, window: int, overlap: int) -> np.ndarray:
    """(I, 2) query frames [start, stop) of the windows of a sequence of ``n_frames`` (module docstring)."""
    if n_frames < 1:
        raise ValueError(f"need at least one query frame, got {n_frames}")
    if window < 1 or overlap < 0 or overlap > window // 2:
        raise ValueError(f"need window >= 1 and 0 <= overlap <= window // 2, got window {window}, "
                         f"overlap {overlap}")
    hop = window - overlap
    out = []
    s = 0
    while True:
        out.append((s, min(s + window, n_frames)))
        if s + window >= n_frames:
            break
        s += hop
    return np.array(out, dtype=np.int64)


def segment_bounds(clip: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(first, last) library frame of the clip run every library frame lies in, each (N,) int64: a run
    is a maximal block of consecutive frames with one ``clip`` value."""
    clip = np.asarray(clip)
    N = len(clip)
    if N == 0:
        return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64)
    starts = np.concatenate([[0], np.flatnonzero(clip[1:] != clip[:-1]) + 1])
    lengths = np.diff(np.concatenate([starts, [N]]))
    first = np.repeat(starts, lengths).astype(np.int64)
    last = np.repeat(starts + lengths - 1, lengths).astype(np.int64)
    return first, last


def crossfade_alpha(overlap: int) -> np.ndarray:
    """(overlap,) weight of the earlier subsequence at each overlap frame: ``1 - s(r / (o - 1))``,
    ``s(a) = 3a^2 - 2a^3`` (1 down to 0, zero slope at both ends); 0.5 for a single overlap frame."""
    if overlap < 0:
        raise ValueError(f"overlap must be >= 0, got {overlap}")
    if overlap == 1:
        return np.array([0.5])
    a = np.arange(overlap) / max(overlap - 1, 1)
    return 1.0 - (3 * a**2 - 2 * a**3)


# ---------------------------------------------------------------------------------------- local cost
def cost_matrix(query: np.ndarray, library: np.ndarray, weights: np.ndarray | None = None,
                library_sq: np.ndarray | None = None, chunk: int = 65536) -> np.ndarray:
    """(L, N) float64 ``C(n, m) = w_n ||query[n] - library[m]||``: ``query`` (L, D), ``library`` (N, D)
    (any float dtype; taken to float64 a chunk of ``chunk`` rows at a time for the GEMM), ``weights``
    (L,) (None: 1), ``library_sq`` (N,) the library's squared norms if already known. Computed as
    ``sqrt(max((|q|^2 + |f|^2) - 2 q.f, 0)) w``, the same operations :func:`subsequence_dtw`'s kernel
    does cell by cell."""
    q = np.asarray(query, dtype=np.float64)
    if q.ndim != 2 or library.ndim != 2 or library.shape[1] != q.shape[1]:
        raise ValueError(f"query (L, D) and library (N, D) must agree, got {q.shape} and {library.shape}")
    if library_sq is None:
        library_sq = squared_norms(library, chunk)
    w = np.ones(len(q)) if weights is None else np.asarray(weights, dtype=np.float64)
    return _cost_from_gram(_gram(q, library, chunk), (q * q).sum(axis=1), library_sq, w)


def _gram(q: np.ndarray, library: np.ndarray, chunk: int = 65536) -> np.ndarray:
    """(N, L) float64 ``library @ q.T`` by float64 GEMMs over chunks of ``chunk`` library rows."""
    N = len(library)
    G = np.empty((N, len(q)))
    qt = np.ascontiguousarray(q.T)
    for s in range(0, N, chunk):
        e = min(N, s + chunk)
        np.matmul(np.asarray(library[s:e], dtype=np.float64), qt, out=G[s:e])
    return G


def _cost_from_gram(G: np.ndarray, q2: np.ndarray, f2: np.ndarray, w: np.ndarray) -> np.ndarray:
    out = (q2[:, None] + f2[None, :]) - 2.0 * G.T
    np.maximum(out, 0.0, out=out)
    np.sqrt(out, out=out)
    out *= w[:, None]
    return out


def squared_norms(library: np.ndarray, chunk: int = 65536) -> np.ndarray:
    """(N,) float64 squared norm of every row of ``library`` (N, D)."""
    out = np.empty(len(library))
    for s in range(0, len(library), chunk):
        f = np.asarray(library[s:s + chunk], dtype=np.float64)
        out[s:s + len(f)] = (f * f).sum(axis=1)
    return out


# --------------------------------------------------------------------------------- subsequence DTW
def _accumulate_numpy(C: np.ndarray, first: np.ndarray, skip: np.ndarray, D: np.ndarray,
                      S: np.ndarray) -> None:
    L, N = C.shape
    inf = np.inf
    m = np.arange(N)
    ok1 = m - 1 >= first  # the predecessor column m-1 lies in m's clip
    ok2 = m - 2 >= first
    D[0] = C[0]
    S[0] = 0
    for n in range(1, L):
        c = C[n]
        b0 = np.full(N, inf)
        b0[1:] = D[n - 1, :-1] + c[1:]
        b0 = np.where(ok1, b0, inf)
        b1 = np.full(N, inf)
        b1[2:] = D[n - 1, :-2] + c[2:]
        b1 = np.where(ok2, b1, inf)
        b2 = np.full(N, inf)
        if n >= 2 and skip[n] >= 0:
            b2[1:] = D[n - 2, :-1] + skip[n] * c[1:]
            b2 = np.where(ok1, b2, inf)
        best = b0
        step = np.zeros(N, dtype=np.int8)
        take = b1 < best
        best = np.where(take, b1, best)
        step[take] = 1
        take = b2 < best
        best = np.where(take, b2, best)
        step[take] = 2
        D[n] = best
        S[n] = step


def _accumulate_loop(C, first, skip, D, S):  # compiled by numba: _accumulate_numpy cell by cell
    L, N = C.shape
    inf = np.inf
    for m in range(N):
        D[0, m] = C[0, m]
        S[0, m] = 0
    for n in range(1, L):
        for m in range(N):
            c = C[n, m]
            ok1 = m - 1 >= first[m]
            b0 = D[n - 1, m - 1] + c if ok1 else inf
            b1 = D[n - 1, m - 2] + c if m - 2 >= first[m] else inf
            b2 = D[n - 2, m - 1] + skip[n] * c if (ok1 and n >= 2 and skip[n] >= 0) else inf
            best = b0
            step = 0
            if b1 < best:
                best = b1
                step = 1
            if b2 < best:
                best = b2
                step = 2
            D[n, m] = best
            S[n, m] = step


def _accumulate_gram_numpy(G, q2, f2, w, first, skip, D, S):
    _accumulate_numpy(_cost_from_gram(G, q2, f2, w), first, skip, D, S)


def _accumulate_gram_loop(G, q2, f2, w, first, skip, D, S):  # compiled by numba: _accumulate_gram_numpy
    # the local cost computed cell by cell from the Gram matrix G (N, L) (library-major, so a column of
    # C is one contiguous row of G), column by column: column m needs columns m-1 and m-2 only (D and
    # S are best column-major)
    N, L = G.shape
    inf = np.inf
    for m in range(N):
        ok1 = m - 1 >= first[m]
        ok2 = m - 2 >= first[m]
        for n in range(L):
            v = (q2[n] + f2[m]) - 2.0 * G[m, n]
            v = max(v, 0.0)
            c = np.sqrt(v) * w[n]
            if n == 0:
                D[0, m] = c
                S[0, m] = 0
                continue
            b0 = D[n - 1, m - 1] + c if ok1 else inf
            b1 = D[n - 1, m - 2] + c if ok2 else inf
            b2 = D[n - 2, m - 1] + skip[n] * c if (ok1 and n >= 2 and skip[n] >= 0) else inf
            best = b0
            step = 0
            if b1 < best:
                best = b1
                step = 1
            if b2 < best:
                best = b2
                step = 2
            D[n, m] = best
            S[n, m] = step


def _backtrack_loop(S, end, pos):  # compiled by numba; uncompiled it is the Python reference
    n = S.shape[0] - 1
    m = end
    pos[n] = m
    while n > 0:
        s = S[n, m]
        if s == 0:
            n -= 1
            m -= 1
        elif s == 1:
            n -= 1
            m -= 2
        else:
            pos[n - 1] = m - 0.5
            n -= 2
            m -= 1
        pos[n] = m


def _compiled(loop):
    """``loop`` compiled (:func:`vidstyle.compiled.compile_kernel`), or None without numba."""
    from ..compiled import compile_kernel

    return compile_kernel(loop)


@cache
def _accumulate_kernel():
    return _compiled(_accumulate_loop) or _accumulate_numpy


@cache
def _accumulate_gram_kernel():
    return _compiled(_accumulate_gram_loop) or _accumulate_gram_numpy


@cache
def _backtrack_kernel():
    return _compiled(_backtrack_loop) or _backtrack_loop


def accumulated_cost(C: np.ndarray, first: np.ndarray, skip: np.ndarray | None = None,
                     compiled: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """Tautges' eq. 4.2 (module docstring) over a local cost matrix ``C`` (L, N) (finite, >= 0) and
    ``first`` (N,) the first library frame of each frame's clip (:func:`segment_bounds`). ``skip`` (L,)
    the factor of ``C(n, m)`` in the (2, 1) step landing on row n (None: 2, eq. 4.2; negative: that step
    is not allowed; :func:`skip_factors` gives the weighted ones). Returns
    ``(D, steps)``: D (L, N) float64 the accumulated cost, steps (L, N) int8 the step that reached each
    cell (:data:`STEP_DIAGONAL` (1, 1), :data:`STEP_LIBRARY_SKIP` (1, 2), :data:`STEP_QUERY_SKIP` (2, 1);
    0 in row 0 and wherever D is inf). ``compiled=False``: the numpy reference (identical results)."""
    C = np.ascontiguousarray(C, dtype=np.float64)
    first = np.ascontiguousarray(first, dtype=np.int64)
    if C.ndim != 2 or first.shape != (C.shape[1],):
        raise ValueError(f"C (L, N) and first (N,) must agree, got {C.shape} and {first.shape}")
    if C.shape[0] < 1:
        raise ValueError("C has no rows")
    skip = np.full(C.shape[0], 2.0) if skip is None else np.ascontiguousarray(skip, dtype=np.float64)
    if skip.shape != (C.shape[0],):
        raise ValueError(f"skip must be (L,) = ({C.shape[0]},), got {skip.shape}")
    D = np.empty(C.shape)
    S = np.empty(C.shape, dtype=np.int8)
    (_accumulate_kernel() if compiled else _accumulate_numpy)(C, first, skip, D, S)
    return D, S


def subsequence_dtw(query: np.ndarray, library: np.ndarray, first: np.ndarray,
                    weights: np.ndarray | None = None, library_sq: np.ndarray | None = None,
                    compiled: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """:func:`accumulated_cost` of :func:`cost_matrix` ``(query, library, weights)`` with the
    :func:`skip_factors` of the weights: ``query`` (L, D), ``library`` (N, D), ``first`` (N,), ``weights``
    (L,) (None: 1), ``library_sq`` (N,) the library's squared norms if known. Returns ``(D, steps)``, each
    (L, N), column-major. Compiled, the local costs are computed inside the DP from the GEMM's (N, L)
    products (no (L, N) cost matrix, no transposition); ``compiled=False`` builds the cost matrix and runs the numpy
    reference DP (identical results)."""
    q = np.asarray(query, dtype=np.float64)
    if q.ndim != 2 or library.ndim != 2 or library.shape[1] != q.shape[1] or len(q) < 1:
        raise ValueError(f"query (L >= 1, D) and library (N, D) must agree, got {q.shape} and "
                         f"{library.shape}")
    L, N = len(q), len(library)
    first = np.ascontiguousarray(first, dtype=np.int64)
    if first.shape != (N,):
        raise ValueError(f"first must be (N,) = ({N},), got {first.shape}")
    w = np.ones(L) if weights is None else np.ascontiguousarray(weights, dtype=np.float64)
    if w.shape != (L,):
        raise ValueError(f"weights must be (L,) = ({L},), got {w.shape}")
    f2 = squared_norms(library) if library_sq is None else np.ascontiguousarray(library_sq, dtype=np.float64)
    # column-major, the order the compiled kernel fills them in (column by column)
    D = np.empty((L, N), order="F")
    S = np.empty((L, N), dtype=np.int8, order="F")
    kernel = _accumulate_gram_kernel() if compiled else _accumulate_gram_numpy
    kernel(_gram(q, library), (q * q).sum(axis=1), f2, w, first, skip_factors(w), D, S)
    return D, S


def skip_factors(weights: np.ndarray) -> np.ndarray:
    """(L,) factor of ``C(n, m) = w_n d(n, m)`` in the (2, 1) step landing on row n, for per-frame weights
    ``w`` (L,): ``1 + w_{n-1} / w_n``, so the step costs ``(w_{n-1} + w_n) d(n, m)`` -- the landing
    frame's cost plus the skipped frame's, estimated at the landing frame's distance (Tautges' 2 C for
    equal weights). A step landing on a frame of weight 0 (missing) may only skip a frame of weight 0
    too (-1: not allowed), else it would drop the skipped frame's cost for free."""
    w = np.asarray(weights, dtype=np.float64)
    prev = np.concatenate([[0.0], w[:-1]])
    with np.errstate(divide="ignore", invalid="ignore"):
        f = np.where(w > 0, 1.0 + prev / np.where(w > 0, w, 1.0), np.where(prev > 0, -1.0, 2.0))
    return f


def warping_positions(steps: np.ndarray, end: int, compiled: bool = True) -> np.ndarray:
    """(L,) float64 library position of every query row on the warping path ending at ``(L-1, end)``,
    backtracked through ``steps`` (from :func:`accumulated_cost`; the cell must have a finite D). A row
    skipped by a (2, 1) step gets the midpoint ``m - 0.5`` of the library frames around it."""
    S = np.asarray(steps)
    if S.dtype != np.int8:
        S = S.astype(np.int8)
    if S.ndim != 2 or not 0 <= end < S.shape[1]:
        raise ValueError(f"steps must be (L, N) and 0 <= end < N, got {S.shape} and {end}")
    pos = np.empty(S.shape[0])
    (_backtrack_kernel() if compiled else _backtrack_loop)(S, int(end), pos)
    return pos


def best_ends(end_cost: np.ndarray, first: np.ndarray, k: int, exclusion: int) -> np.ndarray:
    """Müller's retrieval: up to ``k`` library frames, by increasing ``end_cost`` (N,) (ties: smaller
    frame first), each the least finite end cost outside the ``exclusion``-frame neighbourhood (in its
    own clip run, ``first`` (N,)) of the ends already taken."""
    end_cost = np.asarray(end_cost, dtype=np.float64)
    finite = np.isfinite(end_cost)
    n_finite = int(finite.sum())
    if n_finite == 0 or k < 1:
        return np.zeros(0, dtype=np.int64)
    # every rejected end lies in the neighbourhood of a taken one, so the k ends are among the
    # k (2 exclusion + 1) least
    M = min(n_finite, k * (2 * exclusion + 1))
    thr = np.partition(end_cost[finite], M - 1)[M - 1]
    cand = np.flatnonzero(end_cost <= thr)
    cand = cand[np.lexsort((cand, end_cost[cand]))]
    taken: list[int] = []
    for m in cand.tolist():
        if any(first[t] == first[m] and abs(t - m) <= exclusion for t in taken):
            continue
        taken.append(m)
        if len(taken) == k:
            break
    return np.array(taken, dtype=np.int64)


# ----------------------------------------------------------------------------------- the graph
def ssg_shortest_path(node_cost: list[np.ndarray], edge_cost: list[np.ndarray],
                      transition_weight: float = 1.0) -> tuple[np.ndarray, float]:
    """Least-cost source-to-last-window path of a subsequence graph: ``node_cost`` I arrays (k_i,),
    ``edge_cost`` I-1 arrays (k_i, k_{i+1}) (from window i's node a to window i+1's node b). Path cost:
    the sum of its node costs plus ``transition_weight`` x the sum of its edge costs. Returns
    ``(choice (I,) int64 node of each window, total cost)``; ties go to the smaller node index."""
    I = len(node_cost)
    if I == 0 or len(edge_cost) != I - 1:
        raise ValueError(f"need I >= 1 node arrays and I - 1 edge arrays, got {I} and {len(edge_cost)}")
    nodes = [np.asarray(c, dtype=np.float64) for c in node_cost]
    edges = [np.asarray(e, dtype=np.float64) for e in edge_cost]
    for i, e in enumerate(edges):
        if e.shape != (len(nodes[i]), len(nodes[i + 1])):
            raise ValueError(f"edge_cost[{i}] must be {(len(nodes[i]), len(nodes[i + 1]))}, got {e.shape}")
    if any(len(c) == 0 for c in nodes):
        raise ValueError("a window has no nodes")
    acc = nodes[0].copy()
    back = []
    for i in range(1, I):
        total = acc[:, None] + transition_weight * edges[i - 1]  # (k_{i-1}, k_i)
        arg = np.argmin(total, axis=0)
        back.append(arg)
        acc = total[arg, np.arange(total.shape[1])] + nodes[i]
    choice = np.empty(I, dtype=np.int64)
    choice[-1] = int(np.argmin(acc))
    for i in range(I - 1, 0, -1):
        choice[i - 1] = back[i - 1][choice[i]]
    return choice, float(acc[choice[-1]])


def transition_costs(points3d: np.ndarray, ids_a: np.ndarray, ids_b: np.ndarray) -> np.ndarray:
    """(Ka, Kb) eq. 4.4 cost between the subsequences of two consecutive windows over their shared query
    frames: ``ids_a`` (Ka, o) and ``ids_b`` (Kb, o) library frames at those frames, ``points3d`` (N, J, 3)."""
    A = points3d[ids_a].reshape(ids_a.shape[0], -1).astype(np.float64)  # (Ka, o J 3)
    B = points3d[ids_b].reshape(ids_b.shape[0], -1).astype(np.float64)
    diff = A[:, None, :] - B[None, :, :]
    return np.einsum("abx,abx->ab", diff, diff)


# ----------------------------------------------------------------------------------- retrieval
def _window_mapping(pos: np.ndarray, valid: np.ndarray, first: int, last: int) -> np.ndarray:
    """(L,) int64 library frame of each query frame of a window: path positions ``pos`` (L,) at valid
    frames, interpolated / continued at speed 1 at missing ones, rounded (half down) and clamped to
    the clip run [first, last]."""
    pos = pos.copy()
    if valid.any() and not valid.all():
        t = np.arange(len(pos))
        tv = np.flatnonzero(valid)
        p = np.interp(t, tv, pos[tv])
        p = np.where(t < tv[0], pos[tv[0]] - (tv[0] - t), p)
        p = np.where(t > tv[-1], pos[tv[-1]] + (t - tv[-1]), p)
        pos = np.where(valid, pos, p)
    return np.clip(np.ceil(pos - 0.5), first, last).astype(np.int64)


def _retrieve_window(q, w, valid_w, view_list, lib_features, lib_sq, first, last, k, exclusion, compiled):
    """The window's k subsequences: (ids (K, L) int64, cost (K,), view (K,))."""
    end_rows, step_mats = [], []
    for v in view_list:
        D, S = subsequence_dtw(q, lib_features[v], first, w, library_sq=lib_sq(v), compiled=compiled)
        end_rows.append(D[-1].copy())
        step_mats.append(S)
        del D
    if len(end_rows) == 1:
        end_cost = end_rows[0]
        which = np.zeros(len(end_cost), dtype=np.int64)
    else:
        ends_all = np.stack(end_rows)  # (V', N)
        which = np.argmin(ends_all, axis=0)  # ties: the earlier view
        end_cost = ends_all[which, np.arange(ends_all.shape[1])]
    ends = best_ends(end_cost, first, k, exclusion)
    ids = np.empty((len(ends), len(q)), dtype=np.int64)
    for j, m in enumerate(ends):
        pos = warping_positions(step_mats[which[m]], int(m), compiled=compiled)
        ids[j] = _window_mapping(pos, valid_w, int(first[m]), int(last[m]))
    return ids, end_cost[ends], np.asarray(view_list)[which[ends]].astype(np.int64)


def subsequence_reconstruct(features_q: np.ndarray, valid: np.ndarray, views: np.ndarray | None,
                            index_features: np.ndarray, clip: np.ndarray, points3d: np.ndarray,
                            window: int = 15, overlap: int = 6, k: int = 16, transition_weight: float = 1.0,
                            weights: np.ndarray | None = None, all_views: bool = False,
                            exclusion: int | None = None, compiled: bool = True) -> SubsequencePath:
    """Reconstruct a query through the subsequence graph (module docstring).

    ``features_q`` (T, D) the query frames' features, ``valid`` (T,) bool (False: a missing frame,
    features ignored), ``views`` (T,) int view index per frame into ``index_features`` (unused and may
    be None with ``all_views``), ``index_features`` (V, N, D) (a :class:`~vidstyle.augmg.index.PoseIndex`'s
    ``features_``; (N, D) for one view), ``clip`` (N,) clip of every library frame (a clip's frames
    consecutive and in order), ``points3d`` (N, J, 3) facing-normalised root-relative library poses.
    ``window`` / ``overlap`` query frames, ``k`` subsequences per window, ``transition_weight`` the weight
    of edge costs against node costs, ``weights`` (T,) non-negative per-frame confidence (None: 1),
    ``all_views`` match every window at every view, ``exclusion`` library frames around a retrieved end
    that no other end may take (None: ``window // 2``), ``compiled=False`` the numpy reference kernels.
    The query should run at the library's indexed frame rate (fps / stride) within the factor 2 the
    slopes allow. Returns a :class:`SubsequencePath`.
    """
    q = np.asarray(features_q, dtype=np.float64)
    if q.ndim != 2:
        raise ValueError(f"features_q must be (T, D), got {q.shape}")
    T, Dim = q.shape
    lib = np.asarray(index_features)
    if lib.ndim == 2:
        lib = lib[None]
    if lib.ndim != 3 or lib.shape[2] != Dim:
        raise ValueError(f"index_features must be (V, N, {Dim}) (or (N, {Dim})), "
                         f"got {np.shape(index_features)}")
    V, N, _ = lib.shape
    valid = np.asarray(valid)
    if valid.shape != (T,) or valid.dtype != bool:
        raise ValueError(f"valid must be a (T,) = ({T},) bool array, got {valid.shape} {valid.dtype}")
    clip = np.asarray(clip)
    if clip.shape != (N,) or N == 0:
        raise ValueError(f"clip must be (N,) = ({N},) with N >= 1, got {clip.shape}")
    points3d = np.asarray(points3d)
    if points3d.ndim != 3 or points3d.shape[0] != N or points3d.shape[2] != 3:
        raise ValueError(f"points3d must be (N, J, 3) with N = {N}, got {points3d.shape}")
    if not all_views:
        if views is None:
            raise ValueError("views is needed unless all_views")
        views = np.asarray(views)
        if views.shape != (T,) or not np.issubdtype(views.dtype, np.integer):
            raise ValueError(f"views must be a (T,) int array, got {views.shape} {views.dtype}")
        if T and (views.min() < 0 or views.max() >= V):
            raise ValueError(f"views must lie in [0, {V}), got [{views.min()}, {views.max()}]")
    if k < 1:
        raise ValueError(f"k must be >= 1, got {k}")
    if not np.isfinite(transition_weight) or transition_weight < 0:
        raise ValueError(f"transition_weight must be finite and >= 0, got {transition_weight}")
    w = np.ones(T) if weights is None else np.asarray(weights, dtype=np.float64)
    if w.shape != (T,) or not np.all(np.isfinite(w)) or np.any(w < 0):
        raise ValueError(f"weights must be a (T,) finite non-negative array, got shape {w.shape}")
    if not np.all(np.isfinite(q[valid])):
        raise ValueError("features_q must be finite at valid frames")
    bounds = window_bounds(T, window, overlap)
    excl = window // 2 if exclusion is None else int(exclusion)
    if excl < 0:
        raise ValueError(f"exclusion must be >= 0, got {exclusion}")
    w = np.where(valid, w, 0.0)
    q = np.where(valid[:, None], q, 0.0)
    first, last = segment_bounds(clip)

    sq_cache: dict[int, np.ndarray] = {}
    f64_cache: dict[int, np.ndarray] = {}

    class _Views:  # each view's features as float64, converted once (the GEMMs run in float64)
        def __getitem__(self, v: int) -> np.ndarray:
            if v not in f64_cache:
                f64_cache[v] = np.ascontiguousarray(lib[v], dtype=np.float64)
            return f64_cache[v]

    lib64 = _Views()

    def lib_sq(v: int) -> np.ndarray:
        if v not in sq_cache:
            sq_cache[v] = squared_norms(lib[v])
        return sq_cache[v]

    cand_ids, cand_cost, cand_view = [], [], []
    for s, e in bounds:
        vw = valid[s:e]
        if all_views:
            view_list = list(range(V))
        else:
            vv = views[s:e][vw] if vw.any() else views[s:e]
            view_list = [int(np.argmax(np.bincount(vv, minlength=V)))]
        ids, cost, vsel = _retrieve_window(q[s:e], w[s:e], vw, view_list, lib64, lib_sq, first, last, k, excl,
                                           compiled)
        if len(ids) == 0:
            raise ValueError(f"no library subsequence fits the window of query frames [{s}, {e}): every clip "
                             f"is shorter than {(e - s + 1) // 2} frames")
        cand_ids.append(ids)
        cand_cost.append(cost)
        cand_view.append(vsel)

    I = len(bounds)
    edges = []
    for i in range(I - 1):
        s1 = bounds[i + 1, 0]
        o = bounds[i, 1] - s1
        a = cand_ids[i][:, s1 - bounds[i, 0]:]
        b = cand_ids[i + 1][:, :o]
        edges.append(transition_costs(points3d, a, b))
    choice, total = ssg_shortest_path(cand_cost, edges, transition_weight)

    ids = np.empty((T, 2), dtype=np.int64)
    alpha = np.ones(T)
    win_ids = np.full((I, window), -1, dtype=np.int64)
    trans = np.zeros(I)
    for i, (s, e) in enumerate(bounds):
        mine = cand_ids[i][choice[i]]
        win_ids[i, :e - s] = mine
        ids[s:e, 0] = mine
        ids[s:e, 1] = mine
        if i > 0:
            trans[i] = edges[i - 1][choice[i - 1], choice[i]]
    for i in range(I - 1):
        s1, e0 = bounds[i + 1, 0], bounds[i, 1]
        o = e0 - s1
        if o == 0:
            continue
        ids[s1:e0, 0] = cand_ids[i][choice[i]][s1 - bounds[i, 0]:]
        ids[s1:e0, 1] = cand_ids[i + 1][choice[i + 1]][:o]
        alpha[s1:e0] = crossfade_alpha(o)
    chosen = [cand_ids[i][choice[i]] for i in range(I)]
    return SubsequencePath(
        ids=ids, alpha=alpha, cost=total, windows=bounds,
        start=np.array([c[0] for c in chosen], dtype=np.int64),
        end=np.array([c[-1] for c in chosen], dtype=np.int64),
        node_cost=np.array([cand_cost[i][choice[i]] for i in range(I)]),
        transition_cost=trans,
        view=np.array([cand_view[i][choice[i]] for i in range(I)], dtype=np.int64),
        window_ids=win_ids,
        n_candidates=np.array([len(c) for c in cand_ids], dtype=np.int64))
