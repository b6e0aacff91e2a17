"""Windowed point-cloud frame distance (Kovar, Gleicher, Pighin 2002) and its all-pairs evaluation.

A *window* is ``k`` consecutive frames of one clip; its point cloud holds every joint of every frame,
joint ``j`` weighted ``w_j``. The distance between windows ``p`` and ``p'`` is

    D = min over theta, x0, z0 of  sum_n w_n | p_n - (R_y(theta) p'_n + (x0, 0, z0)) |^2

with ``R_y(theta)`` the rotation about +Y that turns +Z towards +X (``x -> x cos + z sin``,
``z -> -x sin + z cos``). With coordinates centred on each window's weighted mean (``~``) and
``W = sum w``, the optimal translation cancels the horizontal means and

    A = sum w (x~ x~' + z~ z~'),  B = sum w (x~ z~' - z~ x~'),  theta = atan2(B, A),
    D = S + S' + W (ybar - ybar')^2 - 2 sum w y~ y~' - 2 sqrt(A^2 + B^2),

where ``S = sum w |p~|^2``. ``x0 = xbar - (cos xbar' + sin zbar')``, ``z0 = zbar - (-sin xbar' + cos zbar')``.
(The formula in ``docs/design.md``, written with un-normalised sums, is the same after expanding the centring.)

``A``, ``B`` and ``sum w y~ y~'`` are inner products of per-window feature vectors of length ``k*J``
(``sqrt(w) x~`` etc.), so all pairs of windows reduce to three matrix products (GEMMs). The distance
matrix is symmetric, so only blocks on and above the diagonal are computed; each block is computed with
a one-window halo so local minima can be found without its neighbours, and only candidates (local
minima below the threshold) leave the block: memory is O(tile^2), never O(N^2).

Distances are reported as RMS over the cloud, ``sqrt(D / W)``, in the motion's length unit.
"""

from __future__ import annotations

import logging
import os
import threading
from dataclasses import dataclass
from functools import cache
from typing import Iterator, Sequence

import numpy as np

log = logging.getLogger(__name__)


# ---------------------------------------------------------------------------------------------- weights
def joint_weights(parents: np.ndarray) -> np.ndarray:
    """(J,) weights ``1 + log(subtree size)``: the root and spine, which carry the whole pose, weigh
    about 4x an end effector; a wrist with fingers about 2x."""
    parents = np.asarray(parents)
    size = np.ones(len(parents))
    for j in range(len(parents) - 1, -1, -1):  # file order: children come after parents
        if parents[j] >= 0:
            size[parents[j]] += size[j]
    return 1.0 + np.log(size)


# ---------------------------------------------------------------------------------------------- pairs
def align_windows(p: np.ndarray, q: np.ndarray, w: np.ndarray) -> tuple[np.ndarray, ...]:
    """Closed-form alignment of windows ``q`` onto ``p``.

    ``p``, ``q``: (..., k, J, 3) point clouds; ``w``: (J,) joint weights.
    Returns ``(D, theta, x0, z0)`` each of shape ``(...)``: the minimal weighted squared distance and
    the transform ``T(q) = R_y(theta) q + (x0, 0, z0)`` that attains it. Float64 throughout.
    """
    p = np.asarray(p, dtype=np.float64)
    q = np.asarray(q, dtype=np.float64)
    ww = np.broadcast_to(np.asarray(w, dtype=np.float64), p.shape[-2:-1])[None, :]  # (1, J) per frame
    W = ww.sum() * p.shape[-3]
    mp = np.einsum("...kjc,kj->...c", p, np.broadcast_to(ww, p.shape[-3:-1])) / W
    mq = np.einsum("...kjc,kj->...c", q, np.broadcast_to(ww, q.shape[-3:-1])) / W
    pc = p - mp[..., None, None, :]
    qc = q - mq[..., None, None, :]
    wk = np.broadcast_to(ww, p.shape[-3:-1])
    A = np.einsum("...kj,kj,...kj->...", pc[..., 0], wk, qc[..., 0]) + np.einsum(
        "...kj,kj,...kj->...", pc[..., 2], wk, qc[..., 2]
    )
    B = np.einsum("...kj,kj,...kj->...", pc[..., 0], wk, qc[..., 2]) - np.einsum(
        "...kj,kj,...kj->...", pc[..., 2], wk, qc[..., 0]
    )
    Y = np.einsum("...kj,kj,...kj->...", pc[..., 1], wk, qc[..., 1])
    S = np.einsum("...kjc,kj->...", pc * pc, wk)
    Sq = np.einsum("...kjc,kj->...", qc * qc, wk)
    theta = np.arctan2(B, A)
    D = S + Sq + W * (mp[..., 1] - mq[..., 1]) ** 2 - 2.0 * Y - 2.0 * np.hypot(A, B)
    c, s = np.cos(theta), np.sin(theta)
    x0 = mp[..., 0] - (c * mq[..., 0] + s * mq[..., 2])
    z0 = mp[..., 2] - (-s * mq[..., 0] + c * mq[..., 2])
    return np.maximum(D, 0.0), theta, x0, z0


# ---------------------------------------------------------------------------------------------- data
@dataclass
class WindowSet:
    """Every valid window of a frame database.

    ``positions`` (N, J, 3) global joint positions of all clips one after another; ``clip_of_frame`` (N,);
    windows start at ``starts`` (Nw,) and never cross a clip boundary; ``clip`` (Nw,) is each window's clip.
    """

    positions: np.ndarray
    starts: np.ndarray
    clip: np.ndarray
    weights: np.ndarray
    k: int

    @classmethod
    def from_clips(cls, positions: np.ndarray, clip_of_frame: np.ndarray, weights: np.ndarray, k: int) -> "WindowSet":
        clip_of_frame = np.asarray(clip_of_frame)
        N = len(clip_of_frame)
        if N < k:
            return cls(positions, np.zeros(0, np.int64), np.zeros(0, np.int64), np.asarray(weights, float), k)
        # window starting at s is valid when frame s+k-1 lies in the same clip as s
        s = np.arange(N - k + 1)
        ok = clip_of_frame[s] == clip_of_frame[s + k - 1]
        starts = s[ok]
        return cls(positions, starts, clip_of_frame[starts], np.asarray(weights, dtype=np.float64), k)

    @property
    def clip_end(self) -> np.ndarray:
        """(Nw,) one past the last window index of each window's clip."""
        if getattr(self, "_clip_end", None) is None:
            last = np.r_[np.flatnonzero(np.diff(self.clip)) + 1, len(self.clip)]
            self._clip_end = np.repeat(last, np.diff(np.r_[0, last]))
        return self._clip_end

    @property
    def n_windows(self) -> int:
        return len(self.starts)

    @property
    def total_weight(self) -> float:
        return float(self.weights.sum() * self.k)

    def clouds(self, idx: np.ndarray) -> np.ndarray:
        """(len(idx), k, J, 3) point clouds of windows ``idx``."""
        frames = self.starts[idx][:, None] + np.arange(self.k)
        return self.positions[frames]

    def features(self, lo: int, hi: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Centred, weighted features of windows lo..hi-1 (float64).

        Returns ``U`` (n, 3, k*J) holding ``sqrt(w) x~, sqrt(w) z~, sqrt(w) y~``, the weighted squared norm
        ``S`` (n,), the mean height ``ybar`` (n,), and the horizontal means (n, 2) (x, z).
        """
        P = self.clouds(np.arange(lo, hi))  # (n, k, J, 3)
        w = self.weights
        W = self.total_weight
        mean = np.einsum("nkjc,j->nc", P, w) / W
        P = P - mean[:, None, None, :]
        S = np.einsum("nkjc,j->n", P * P, w)
        sw = np.sqrt(w)
        n = hi - lo
        U = np.empty((n, 3, self.k * len(w)))
        U[:, 0] = (P[..., 0] * sw).reshape(n, -1)
        U[:, 1] = (P[..., 2] * sw).reshape(n, -1)
        U[:, 2] = (P[..., 1] * sw).reshape(n, -1)
        return U, S, mean[:, 1].copy(), mean[:, [0, 2]].copy()


@dataclass
class TileResult:
    """Candidates of one block: window pairs ``(a, b)`` with ``a < b`` that are local minima of the
    distance below the threshold, their exact (float64) squared distance ``D`` and alignment of ``b``
    onto ``a`` (theta, x0, z0); ``n_below``: how many pairs (a < b, outside the excluded band) were
    below the threshold; ``n_pairs``: how many such pairs the block covered."""

    a: np.ndarray
    b: np.ndarray
    D: np.ndarray
    theta: np.ndarray
    x0: np.ndarray
    z0: np.ndarray
    n_below: int
    n_pairs: int


def _tile_dist(ws: WindowSet, r0: int, r1: int, c0: int, c1: int, dtype) -> np.ndarray:
    """Squared distance of windows r0..r1-1 (rows) against c0..c1-1 (columns), from three GEMMs, in a new
    array. See :func:`_tile_dist_into`."""
    rows = _block_features(ws, r0, r1, dtype)
    cols = rows if (r0, r1) == (c0, c1) else _block_features(ws, c0, c1, dtype)
    return _tile_dist_into(rows, cols, ws.total_weight, _Workspace(), fresh=True)


@dataclass
class _BlockFeatures:
    """The GEMM operands of a block of windows, in the GEMMs' dtype (from :meth:`WindowSet.features`):
    ``xz`` (n, 2L) = (sqrt(w) x~, sqrt(w) z~) the left operand of A and B and the right one of A,
    ``zx`` (n, 2L) = (sqrt(w) z~, -sqrt(w) x~) the right operand of B, ``y`` (n, L) = sqrt(w) y~,
    ``S`` (n,) the weighted squared norms, ``ybar`` (n,) the mean heights."""

    xz: np.ndarray
    zx: np.ndarray
    y: np.ndarray
    S: np.ndarray
    ybar: np.ndarray


def _block_features(ws: WindowSet, lo: int, hi: int, dtype) -> _BlockFeatures:
    U, S, ybar, _ = ws.features(lo, hi)
    n, L = len(S), U.shape[2]
    xz = U[:, :2].reshape(n, 2 * L).astype(dtype)
    zx = np.empty_like(xz)  # B = sum x~ z~' - z~ x~' : the same left operand against (z~', -x~')
    zx[:, :L] = xz[:, L:]
    np.negative(xz[:, :L], out=zx[:, L:])
    return _BlockFeatures(xz, zx, U[:, 2].astype(dtype), S.astype(dtype), ybar.astype(dtype))


class _FeatureCache:
    """Block features shared by the threads of one pass, the ``capacity`` most recently used kept (the
    tiles are visited so that a few blocks serve many tiles, see :func:`_tile_order`). Each block is
    computed once while it stays in the cache; a thread asking for a block another is computing waits."""

    def __init__(self, ws: WindowSet, dtype, capacity: int):
        import threading
        from collections import OrderedDict

        self.ws, self.dtype, self.capacity = ws, dtype, capacity
        self._lock = threading.Lock()
        self._items: OrderedDict = OrderedDict()
        self._event = threading.Event

    def __call__(self, lo: int, hi: int) -> _BlockFeatures:
        key = (lo, hi)
        with self._lock:
            entry = self._items.get(key)
            owner = entry is None
            if owner:
                entry = self._items[key] = [self._event(), None]
                while len(self._items) > self.capacity:
                    self._items.popitem(last=False)
            else:
                self._items.move_to_end(key)
        if owner:
            try:
                entry[1] = _block_features(self.ws, lo, hi, self.dtype)
            finally:
                entry[0].set()
        else:
            entry[0].wait()
        return entry[1] if entry[1] is not None else _block_features(self.ws, lo, hi, self.dtype)


class _Workspace:
    """The two tile buffers of one thread, reused from tile to tile (grown when a tile needs more)."""

    def __init__(self):
        self._bufs: dict = {}

    def get(self, name: str, shape: tuple, dtype) -> np.ndarray:
        size = int(np.prod(shape))
        buf = self._bufs.get(name)
        if buf is None or buf.dtype != np.dtype(dtype) or buf.size < size:
            buf = self._bufs[name] = np.empty(size, dtype)
        return buf[:size].reshape(shape)


def _tile_dist_into(rows: _BlockFeatures, cols: _BlockFeatures, total_weight: float, work: _Workspace,
                    fresh: bool = False) -> np.ndarray:
    """Squared distance of the ``rows`` windows against the ``cols`` ones: three GEMMs (in BLAS) and the
    element-wise rest in two compiled passes over the tile (:func:`_tail_numpy` is their reference).
    The result is one of ``work``'s buffers (a new array when ``fresh``).

    Every O(tile^2) step runs in the features' dtype (float32 halves the memory traffic; the few
    candidates are re-evaluated in float64 afterwards)."""
    dtype = rows.xz.dtype.type
    n, m = len(rows.S), len(cols.S)
    A = np.empty((n, m), dtype) if fresh else work.get("A", (n, m), dtype)
    B = work.get("B", (n, m), dtype)
    right = cols.xz
    if right is rows.xz:  # one buffer on both sides would make numpy call syrk, which rounds differently
        right = right.copy()
    np.matmul(rows.xz, right.T, out=A)
    np.matmul(rows.xz, cols.zx.T, out=B)
    _tail1()(A, B)  # A = sqrt(A^2 + B^2) without libm's slow hypot
    ry, cy = rows.y, cols.y
    if cy is ry:
        cy = cy.copy()
    np.matmul(ry, cy.T, out=B)
    # A = -2 (A + Y) + W (ybar - ybar')^2 + S + S' (the vertical means are not aligned)
    _tail2()(A, B, rows.ybar, cols.ybar, rows.S, cols.S, dtype(-2.0), dtype(total_weight))
    return A


def _tail1_loop(A, B):
    # compiled by numba: A = sqrt(A * A + B * B) element by element in A's dtype, what _tail_numpy's
    # A *= A; B *= B; A += B; sqrt(A) does (B is left unchanged, it is overwritten next)
    n, m = A.shape
    for i in range(n):
        for j in range(m):
            a = A[i, j]
            b = B[i, j]
            A[i, j] = np.sqrt(a * a + b * b)


def _tail2_loop(A, Y, yr, yc, Sr, Sc, minus2, W):
    # compiled by numba: the rest of _tail_numpy in its order, every operation in the tile's dtype
    # (minus2 and W are scalars of that dtype): ((((A + Y) * -2) + ((yr - yc)^2 * W)) + Sr) + Sc
    n, m = A.shape
    for i in range(n):
        yi = yr[i]
        si = Sr[i]
        for j in range(m):
            t = (A[i, j] + Y[i, j]) * minus2
            d = yi - yc[j]
            t = t + (d * d) * W
            A[i, j] = (t + si) + Sc[j]


def _tail1_numpy(A, B):
    A *= A
    B *= B
    A += B
    np.sqrt(A, out=A)


def _tail2_numpy(A, Y, yr, yc, Sr, Sc, minus2, W):
    A += Y
    A *= minus2
    np.subtract.outer(yr, yc, out=Y)
    Y *= Y
    Y *= W
    A += Y
    A += Sr[:, None]
    A += Sc[None, :]


def _candidates_loop(D, r0, r1, c0, c1, er0, ec0, clip, min_gap, thr, out_a, out_b):
    # compiled by numba: the pairs (ga, gb) of the inner block, row by row, that are below ``thr`` (a
    # float64 holding the threshold as the comparison's dtype rounds it), not excluded (gb <= ga, or
    # one clip and gb - ga < min_gap), and not beaten by a valid neighbour (same clips, inside the
    # database): a neighbour beats when it is smaller, or equal and earlier in row-major order.
    # Writes the first len(out_a) into out_a/out_b; returns (below, candidates) -- what
    # _candidates_numpy does with nonzero and fancy indexing.
    Nw = len(clip)
    n_below = 0
    n_cand = 0
    cap = len(out_a)
    for ga in range(r0, r1):
        la = ga - er0
        ca = clip[ga]
        for gb in range(c0, c1):
            lb = gb - ec0
            val = D[la, lb]
            if not val < thr:
                continue
            cb = clip[gb]
            if gb <= ga or (ca == cb and gb - ga < min_gap):
                continue
            n_below += 1
            keep = True
            for da in range(-1, 2):
                na = ga + da
                if na < 0 or na >= Nw or clip[na] != ca:
                    continue
                for db in range(-1, 2):
                    if da == 0 and db == 0:
                        continue
                    nb = gb + db
                    if nb < 0 or nb >= Nw or clip[nb] != cb:
                        continue
                    nv = D[la + da, lb + db]
                    if nv < val or (nv == val and (da < 0 or (da == 0 and db < 0))):
                        keep = False
                        break
                if not keep:
                    break
            if keep:
                if n_cand < cap:
                    out_a[n_cand] = ga
                    out_b[n_cand] = gb
                n_cand += 1
    return n_below, n_cand


def _candidates_numpy(D, r0, r1, c0, c1, er0, ec0, clip, min_gap, threshold_sq):
    """Sub-threshold local minima of the inner block of ``D`` (the reference of the compiled
    :func:`_candidates_loop`): ``(ga, gb, n_below)``."""
    Nw = len(clip)
    inner = D[r0 - er0 : r1 - er0, c0 - ec0 : c1 - ec0]
    ia, ib = np.nonzero(inner < threshold_sq)
    ga, gb = ia + r0, ib + c0
    excluded = (gb <= ga) | ((clip[ga] == clip[gb]) & (gb - ga < min_gap))
    ga, gb = ga[~excluded], gb[~excluded]
    n_below = len(ga)
    if len(ga):
        # neighbour test on the few sub-threshold pairs only
        la, lb = ga - er0, gb - ec0
        val = D[la, lb]
        keep = np.ones(len(ga), bool)
        for da in (-1, 0, 1):
            for db in (-1, 0, 1):
                if da == 0 and db == 0:
                    continue
                na, nb = ga + da, gb + db
                ok = (na >= 0) & (na < Nw) & (nb >= 0) & (nb < Nw)
                na_c, nb_c = np.clip(na, 0, Nw - 1), np.clip(nb, 0, Nw - 1)
                ok &= (clip[na_c] == clip[ga]) & (clip[nb_c] == clip[gb])
                nv = D[np.clip(la + da, 0, D.shape[0] - 1), np.clip(lb + db, 0, D.shape[1] - 1)]
                earlier = (da, db) < (0, 0)
                worse = (nv < val) | ((nv == val) & earlier)
                keep &= ~(ok & worse)
        ga, gb = ga[keep], gb[keep]
    return ga, gb, n_below


def _candidates(D, r0, r1, c0, c1, er0, ec0, clip, min_gap, threshold_sq, work: _Workspace):
    """:func:`_candidates_loop` compiled, or :func:`_candidates_numpy` without numba."""
    kernel = _candidates_kernel()
    if kernel is None:
        return _candidates_numpy(D, r0, r1, c0, c1, er0, ec0, clip, min_gap, threshold_sq)
    # the comparison ``D < threshold_sq`` is made in numpy's result dtype (a Python float is weak: the
    # threshold is rounded to a float32 tile's dtype); float32 -> float64 is exact, so comparing in float64
    # against that rounded value gives the same answers
    thr = float(np.asarray(threshold_sq, dtype=np.result_type(D.dtype, threshold_sq)))
    cap = max(1024, (r1 - r0) * (c1 - c0) // 64)
    while True:
        out_a, out_b = work.get("ca", (cap,), np.int64), work.get("cb", (cap,), np.int64)
        n_below, n = kernel(D, r0, r1, c0, c1, er0, ec0, clip, min_gap, thr, out_a, out_b)
        if n <= cap:
            return out_a[:n].copy(), out_b[:n].copy(), int(n_below)
        cap = n


def compute_tile(
    ws: WindowSet,
    r0: int,
    r1: int,
    c0: int,
    c1: int,
    threshold_sq: float,
    min_gap: int,
    dtype=np.float32,
    return_matrix: bool = False,
    features=None,
    work: _Workspace | None = None,
):
    """Candidates of the block rows r0..r1-1 x columns c0..c1-1 (requires c0 >= r0). See :class:`TileResult`.

    The block is computed with a one-window halo; a pair is a candidate when its distance is below
    ``threshold_sq`` and <= every valid neighbour (same clips, one window earlier or later on either
    side), strictly < the neighbours that come earlier in row-major order (so a flat pair of equal
    minima yields one candidate). Pairs within one clip closer than ``min_gap`` windows are excluded
    as candidates (they are ordinary playback) but still count as neighbours.

    ``features(lo, hi)``: where the block features come from (a cache shared by the tiles of a pass;
    default: computed here); ``work``: the buffers to reuse (default: this thread's).
    """
    Nw = ws.n_windows
    er0, er1 = max(r0 - 1, 0), min(r1 + 1, Nw)
    ec0, ec1 = max(c0 - 1, 0), min(c1 + 1, Nw)
    if features is None:
        features = lambda lo, hi: _block_features(ws, lo, hi, dtype)
    if work is None:
        work = _thread_workspace()
    rows = features(er0, er1)
    cols = rows if (er0, er1) == (ec0, ec1) else features(ec0, ec1)
    D = _tile_dist_into(rows, cols, ws.total_weight, work, fresh=return_matrix)
    ga, gb, n_below = _candidates(D, r0, r1, c0, c1, er0, ec0, ws.clip, min_gap, threshold_sq, work)
    # pairs a < b outside the band, counted per row without an O(tile^2) mask
    a = np.arange(r0, r1)
    lo = np.maximum(c0, a + 1)
    n_upper = np.maximum(c1 - lo, 0)
    band_hi = np.minimum(np.minimum(a + min_gap, ws.clip_end[a]), c1)  # exclusive
    n_band = np.maximum(band_hi - lo, 0)
    n_pairs = int((n_upper - n_band).sum())
    if len(ga):
        Dx, th, x0, z0 = align_windows(ws.clouds(ga), ws.clouds(gb), ws.weights)
    else:
        Dx = th = x0 = z0 = np.zeros(0)
    res = TileResult(ga.astype(np.int64), gb.astype(np.int64), Dx, th, x0, z0, n_below, n_pairs)
    if return_matrix:
        return res, D
    return res


_local = threading.local()


def _thread_workspace() -> _Workspace:
    """This thread's buffers (the joblib and Dask workers' tiles, and calls outside a pass)."""
    work = getattr(_local, "work", None)
    if work is None:
        work = _local.work = _Workspace()
    return work


def _compiled(loop):
    """``loop`` compiled (:func:`vidstyle.compiled.compile_kernel`), or None without numba."""
    from ..compiled import compile_kernel

    return compile_kernel(loop)


@cache
def _tail1():
    return _compiled(_tail1_loop) or _tail1_numpy


@cache
def _tail2():
    return _compiled(_tail2_loop) or _tail2_numpy


@cache
def _candidates_kernel():
    return _compiled(_candidates_loop)


def distance_matrix(ws: WindowSet, dtype=np.float64) -> np.ndarray:
    """The full (Nw, Nw) squared-distance matrix by GEMMs. Small N only (tests, threshold samples)."""
    return _tile_dist(ws, 0, ws.n_windows, 0, ws.n_windows, dtype)


def sample_distances(ws: WindowSet, n_pairs: int, min_gap: int, seed: int) -> np.ndarray:
    """Exact squared distances of ``n_pairs`` random window pairs (a != b, outside the same-clip band)."""
    rng = np.random.default_rng(seed)
    Nw = ws.n_windows
    if Nw < 2:
        return np.zeros(0)
    a = rng.integers(0, Nw, size=2 * n_pairs)
    b = rng.integers(0, Nw, size=2 * n_pairs)
    ok = (a != b) & ~((ws.clip[a] == ws.clip[b]) & (np.abs(a - b) < min_gap))
    a, b = a[ok][:n_pairs], b[ok][:n_pairs]
    # chunks of 4096 pairs on a pool of threads, one per core (numpy releases the GIL in the element-wise
    # work; every chunk is computed as on its own, so the distances do not depend on the thread count)
    from concurrent.futures import ThreadPoolExecutor

    starts = range(0, len(a), 4096)

    def chunk(s: int) -> np.ndarray:
        return align_windows(ws.clouds(a[s : s + 4096]), ws.clouds(b[s : s + 4096]), ws.weights)[0]

    with ThreadPoolExecutor(max_workers=max(1, min(len(starts), os.cpu_count() or 1))) as pool:
        out = list(pool.map(chunk, starts))
    return np.concatenate(out) if out else np.zeros(0)


# ---------------------------------------------------------------------------------------------- tiling
def tile_ranges(n: int, tile: int) -> list[tuple[int, int, int, int]]:
    """Blocks (r0, r1, c0, c1) on and above the diagonal of an n x n matrix."""
    edges = list(range(0, n, tile)) + [n]
    blocks = []
    for i in range(len(edges) - 1):
        for j in range(i, len(edges) - 1):
            blocks.append((edges[i], edges[i + 1], edges[j], edges[j + 1]))
    return blocks


TILE_GROUP = 4  # row blocks whose features stay cached while the column blocks go by (see _tile_order)


def _tile_order(blocks: list[tuple[int, int, int, int]], tile: int) -> list[tuple[int, int, int, int]]:
    """``blocks`` (from :func:`tile_ranges`) in the order the in-process pass visits them: groups of
    ``TILE_GROUP`` block rows, in each the block columns one after another and each column's tiles of
    the group's rows, so a group's row features and one column's features serve every tile of the
    group (block features are computed about ``n_blocks^2 / (2 TILE_GROUP)`` times instead of twice a tile).
    The candidates are merged by pair index, so the order does not change the result."""
    key = lambda b: (b[0] // tile // TILE_GROUP, b[2], b[0])
    return sorted(blocks, key=key)


def _run_block(args) -> TileResult:
    ws, block, threshold_sq, min_gap, dtype = args
    from threadpoolctl import threadpool_limits

    with threadpool_limits(1, user_api="blas"):
        return compute_tile(ws, *block, threshold_sq=threshold_sq, min_gap=min_gap, dtype=dtype)


def _run_block_dask(ws, block, threshold_sq, min_gap, dtype) -> TileResult:
    from ..parallel import dask_task

    return dask_task(_run_block, (ws, block, threshold_sq, min_gap, dtype))


def all_pair_candidates(
    ws: WindowSet,
    threshold_sq: float,
    min_gap: int,
    tile: int = 2048,
    dtype=np.float32,
    n_jobs: int = 1,
    scheduler: str | None = None,
    progress: bool = True,
) -> TileResult:
    """Local-minimum candidates over all window pairs, tile by tile.

    ``n_jobs == 1``: in this process, the tiles on a pool of threads (one per core; numpy releases
    the GIL in its products) with one BLAS thread each; ``n_jobs > 1`` or -1: joblib (loky) workers with
    one BLAS thread each; ``scheduler``: the address of a Dask scheduler (``tcp://host:port``), the
    windows are scattered to the workers once. Every tile's products run on one BLAS thread whichever
    way it is run, so the result does not depend on it: a multi-threaded BLAS blocks a float32 product
    differently, which moves the last bits and, through near-ties, the local-minimum candidates.
    """
    blocks = tile_ranges(ws.n_windows, tile)
    results: list[TileResult] = []
    if scheduler:
        results = _dask_blocks(ws, blocks, threshold_sq, min_gap, dtype, scheduler)
    elif n_jobs == 1 or len(blocks) <= 1:
        from concurrent.futures import ThreadPoolExecutor

        from threadpoolctl import threadpool_limits

        threads = min(len(blocks), os.cpu_count() or 1)
        features = _FeatureCache(ws, dtype, capacity=TILE_GROUP + threads + 1)
        local = threading.local()  # each thread's buffers, freed with the pool

        def run(block):
            work = getattr(local, "work", None)
            if work is None:
                work = local.work = _Workspace()
            return compute_tile(ws, *block, threshold_sq=threshold_sq, min_gap=min_gap, dtype=dtype,
                                features=features, work=work)

        blocks = _tile_order(blocks, tile)
        with threadpool_limits(1, user_api="blas"), ThreadPoolExecutor(max_workers=threads) as pool:
            it: Iterator = pool.map(run, blocks)  # in the order of the blocks
            if progress:
                from ..logutil import progress as _progress

                it = _progress(it, f"distance tiles ({ws.n_windows} windows)", total=len(blocks))
            results = list(it)
    else:
        from joblib import Parallel, delayed

        from ..parallel import loky_backend

        workers = (os.cpu_count() or 1) if n_jobs < 0 else n_jobs
        log.info("%d distance tiles on %d joblib workers", len(blocks), workers)
        par = Parallel(n_jobs=workers, backend=loky_backend(), return_as="generator", max_nbytes="1M")
        results = list(par(delayed(_run_block)((ws, b, threshold_sq, min_gap, dtype)) for b in blocks))
    return merge_results(results)


def _dask_blocks(ws, blocks, threshold_sq, min_gap, dtype, scheduler) -> list[TileResult]:
    from ..parallel import dask_client

    with dask_client(scheduler) as client:
        log.info("%d distance tiles on Dask cluster %s", len(blocks), scheduler)
        [ws_future] = client.scatter([ws], broadcast=True)
        futures = [client.submit(_run_block_dask, ws_future, b, threshold_sq, min_gap, dtype, pure=False) for b in blocks]
        return client.gather(futures)


def merge_results(results: Sequence[TileResult]) -> TileResult:
    if not results:
        z = np.zeros(0)
        return TileResult(z.astype(np.int64), z.astype(np.int64), z, z, z, z, 0, 0)
    cat = lambda name: np.concatenate([getattr(r, name) for r in results])  # noqa: E731
    a, b = cat("a"), cat("b")
    order = np.lexsort((b, a))
    return TileResult(
        a[order],
        b[order],
        cat("D")[order],
        cat("theta")[order],
        cat("x0")[order],
        cat("z0")[order],
        int(sum(r.n_below for r in results)),
        int(sum(r.n_pairs for r in results)),
    )
