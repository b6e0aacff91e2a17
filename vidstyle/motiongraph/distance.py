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
from dataclasses import dataclass
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
    """Squared distance of windows r0..r1-1 (rows) against c0..c1-1 (columns), from three GEMMs.

    Every O(tile^2) step runs in place in ``dtype`` (float32 halves the memory traffic; the few
    candidates are re-evaluated in float64 afterwards)."""
    Ur, Sr, yr, _ = ws.features(r0, r1)
    if (r0, r1) == (c0, c1):
        Uc, Sc, yc = Ur, Sr, yr
    else:
        Uc, Sc, yc, _ = ws.features(c0, c1)
    n, m, L = len(Sr), len(Sc), Ur.shape[2]
    left = Ur[:, :2].reshape(n, 2 * L).astype(dtype)
    right = Uc[:, :2].reshape(m, 2 * L).astype(dtype)
    A = left @ right.T
    # B = sum x~ z~' - z~ x~' : the same left operand against (z~', -x~')
    swapped = np.empty_like(right)
    swapped[:, :L] = right[:, L:]
    np.negative(right[:, :L], out=swapped[:, L:])
    B = left @ swapped.T
    del swapped, right, left
    A *= A  # sqrt(A^2 + B^2) without libm's slow hypot
    B *= B
    A += B
    np.sqrt(A, out=A)
    B = np.matmul(Ur[:, 2].astype(dtype), Uc[:, 2].astype(dtype).T, out=B)
    A += B
    A *= -2.0
    np.subtract.outer(yr.astype(dtype), yc.astype(dtype), out=B)  # the vertical means are not aligned
    B *= B
    B *= dtype(ws.total_weight)
    A += B
    del B
    A += Sr.astype(dtype)[:, None]
    A += Sc.astype(dtype)[None, :]
    return A


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
):
    """Candidates of the block rows r0..r1-1 x columns c0..c1-1 (requires c0 >= r0). See :class:`TileResult`.

    The block is computed with a one-window halo; a pair is a candidate when its distance is below
    ``threshold_sq`` and <= every valid neighbour (same clips, one window earlier or later on either
    side), strictly < the neighbours that come earlier in row-major order (so a flat pair of equal
    minima yields one candidate). Pairs within one clip closer than ``min_gap`` windows are excluded
    as candidates (they are ordinary playback) but still count as neighbours.
    """
    Nw = ws.n_windows
    er0, er1 = max(r0 - 1, 0), min(r1 + 1, Nw)
    ec0, ec1 = max(c0 - 1, 0), min(c1 + 1, Nw)
    D = _tile_dist(ws, er0, er1, ec0, ec1, dtype)
    inner = D[r0 - er0 : r1 - er0, c0 - ec0 : c1 - ec0]
    ia, ib = np.nonzero(inner < threshold_sq)
    ga, gb = ia + r0, ib + c0
    excluded = (gb <= ga) | ((ws.clip[ga] == ws.clip[gb]) & (gb - ga < min_gap))
    ga, gb = ga[~excluded], gb[~excluded]
    n_below = len(ga)
    # pairs a < b outside the band, counted per row without an O(tile^2) mask
    a = np.arange(r0, r1)
    lo = np.maximum(c0, a + 1)
    n_upper = np.maximum(c1 - lo, 0)
    band_hi = np.minimum(np.minimum(a + min_gap, ws.clip_end[a]), c1)  # exclusive
    n_band = np.maximum(band_hi - lo, 0)
    n_pairs = int((n_upper - n_band).sum())
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
                ok &= (ws.clip[na_c] == ws.clip[ga]) & (ws.clip[nb_c] == ws.clip[gb])
                nv = D[np.clip(la + da, 0, D.shape[0] - 1), np.clip(lb + db, 0, D.shape[1] - 1)]
                earlier = (da, db) < (0, 0)
                worse = (nv < val) | ((nv == val) & earlier)
                keep &= ~(ok & worse)
        ga, gb = ga[keep], gb[keep]
    if len(ga):
        Dx, th, x0, z0 = align_windows(ws.clouds(ga), ws.clouds(gb), ws.weights)
    else:
        Dx = th = x0 = z0 = np.zeros(0)
    res = TileResult(ga.astype(np.int64), gb.astype(np.int64), Dx, th, x0, z0, n_below, n_pairs)
    if return_matrix:
        return res, D
    return res


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
    out = []
    for s in range(0, len(a), 4096):
        out.append(align_windows(ws.clouds(a[s : s + 4096]), ws.clouds(b[s : s + 4096]), ws.weights)[0])
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

        def run(block):
            return compute_tile(ws, *block, threshold_sq=threshold_sq, min_gap=min_gap, dtype=dtype)

        threads = min(len(blocks), os.cpu_count() or 1)
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
