"""Generalised distance transform (Felzenszwalb & Huttenlocher, "Distance Transforms of Sampled
Functions", 2012): ``D(q) = min_p f(p) + w (q - p)^2`` in linear time by the lower envelope of the
parabolas rooted at every sample, and its 2D separable form (along x, then along y) with arg-min
tracking for backtracking the max-product (min-sum) solution of pictorial structures.

The 1D transform's loops are compiled by numba (``cache=True``: compiled once per installation),
one call per batch of rows; without numba the same function runs as plain Python (slow, same result).
"""

from __future__ import annotations

import numpy as np

from ..compiled import compile_kernel

BIG = 1e12  # stands for +inf in cost maps (the envelope arithmetic needs finite numbers)


def _envelope_rows(F, W, D, arg):  # pragma: no cover - compiled by numba (tested through dt1d)
    """Felzenszwalb-Huttenlocher lower envelope, row by row: F (R, n) costs, W (R,) weights."""
    R, n = F.shape
    v = np.empty(n, dtype=np.int64)
    z = np.empty(n + 1)
    g = np.empty(n)
    for r in range(R):
        w = W[r]
        for q in range(n):
            g[q] = F[r, q] / w + q * q  # f/w + q^2: the envelope only needs these
        k = 0
        v[0] = 0
        z[0] = -np.inf
        z[1] = np.inf
        for q in range(1, n):
            s = (g[q] - g[v[k]]) / (2.0 * (q - v[k]))
            while s <= z[k]:
                k -= 1
                s = (g[q] - g[v[k]]) / (2.0 * (q - v[k]))
            k += 1
            v[k] = q
            z[k] = s
            z[k + 1] = np.inf
        k = 0
        for q in range(n):
            while z[k + 1] < q:
                k += 1
            p = v[k]
            arg[r, q] = p
            D[r, q] = w * (q - p) * (q - p) + F[r, p]


def _minplus_rows(D, pen, E, best):  # pragma: no cover - compiled by numba (tested through min_plus)
    K, M = D.shape
    for i in range(K):
        for m in range(M):
            b = 0
            e = D[0, m] + pen[i, 0]
            for j in range(1, K):
                c = D[j, m] + pen[i, j]
                if c < e:
                    e = c
                    b = j
            E[i, m] = e
            best[i, m] = b


# the inner loops compiled (vidstyle.compiled); the same Python functions run without numba
_envelope_rows = compile_kernel(_envelope_rows, _envelope_rows)
_minplus_rows = compile_kernel(_minplus_rows, _minplus_rows)


def dt1d(f: np.ndarray, w: float | np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Lower-envelope distance transform along the last axis of ``f`` (..., n), weight ``w > 0``
    (a scalar or one per row, broadcastable to ``f.shape[:-1]``). Linear time per row: each
    sample's parabola enters the envelope once and leaves it at most once.

    Returns ``(D, arg)``: ``D[..., q] = min_p f[..., p] + w (q - p)^2`` and ``arg[..., q]`` the
    minimising ``p`` (ties: the envelope's choice).
    """
    f = np.asarray(f, dtype=np.float64)
    shape = f.shape
    n = shape[-1]
    F = np.ascontiguousarray(np.minimum(f.reshape(-1, n), BIG))
    W = np.ascontiguousarray(np.broadcast_to(np.asarray(w, dtype=np.float64), shape[:-1]).reshape(-1))
    if np.any(W <= 0):
        raise ValueError("w must be positive")
    D = np.empty_like(F)
    arg = np.empty(F.shape, dtype=np.int64)
    if F.size:
        _envelope_rows(F, W, D, arg)
    return D.reshape(shape), arg.reshape(shape)


def min_plus(D: np.ndarray, pen: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Min-plus product over a small discrete axis (the part orientations): ``D`` (K, ...),
    ``pen`` (K', K) -> ``E[i, ...] = min_j D[j, ...] + pen[i, j]`` and the minimising ``j``."""
    D = np.asarray(D, dtype=np.float64)
    K = D.shape[0]
    pen = np.ascontiguousarray(pen, dtype=np.float64)
    flat = np.ascontiguousarray(D.reshape(K, -1))
    E = np.empty((pen.shape[0], flat.shape[1]))
    best = np.empty(E.shape, dtype=np.int64)
    _minplus_rows(flat, pen, E, best)
    return E.reshape((pen.shape[0],) + D.shape[1:]), best.reshape((pen.shape[0],) + D.shape[1:])


def dt2d(f: np.ndarray, wx, wy) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """2D transform of ``f`` (..., H, W): ``D[y, x] = min_{y', x'} f[y', x'] + wx (x - x')^2 +
    wy (y - y')^2``; ``wx``, ``wy`` scalars or one per map (broadcastable to ``f.shape[:-2]``).
    Returns ``(D, ay, ax)``: the arg-min row and column of every output cell."""
    f = np.asarray(f, dtype=np.float64)
    lead = f.shape[:-2]
    wx = np.broadcast_to(np.asarray(wx, dtype=np.float64), lead)[..., None]
    wy = np.broadcast_to(np.asarray(wy, dtype=np.float64), lead)[..., None]
    Dx, ax = dt1d(f, wx)  # along x (last axis)
    Dy, ay_t = dt1d(np.swapaxes(Dx, -1, -2), wy)  # along y
    D = np.swapaxes(Dy, -1, -2)
    ay = np.swapaxes(ay_t, -1, -2)
    ax_final = np.take_along_axis(ax, ay, axis=-2)
    return D, ay, ax_final


def brute_dt2d(f: np.ndarray, wx, wy) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Reference: the same minimisation by enumerating every (y', x') for every (y, x)."""
    f = np.asarray(f, dtype=np.float64)
    H, W = f.shape[-2:]
    ys, xs = np.mgrid[0:H, 0:W]
    wx = np.broadcast_to(np.asarray(wx, dtype=np.float64), f.shape[:-2])[..., None, None, None]
    wy = np.broadcast_to(np.asarray(wy, dtype=np.float64), f.shape[:-2])[..., None, None, None]
    cost = (f.reshape(f.shape[:-2] + (1, 1, H * W))
            + wx * (xs[..., None] - xs.reshape(-1)) ** 2 + wy * (ys[..., None] - ys.reshape(-1)) ** 2)
    best = cost.argmin(axis=-1)
    return cost.min(axis=-1), best // W, best % W
