"""Generalised distance transform (Felzenszwalb & Huttenlocher, "Distance Transforms of Sampled
Functions", 2012): ``D(q) = min_p f(p) + w (q - p)^2`` in linear time by the lower envelope of the
parabolas rooted at every sample, and its 2D separable form (along x, then along y) with arg-min
tracking for backtracking the max-product (min-sum) solution of pictorial structures.

The 1D transform runs in lockstep over many rows at once (numpy over rows, a Python loop over the
samples of a row), which is what makes it fast on the small grids of the pose model (a few dozen
samples per row, hundreds of rows: one call per part and parent orientation set).
"""

from __future__ import annotations

import numpy as np

BIG = 1e12  # stands for +inf in cost maps (the envelope arithmetic needs finite numbers)


def dt1d(f: np.ndarray, w: float | np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Lower-envelope distance transform along the last axis of ``f`` (..., n), weight ``w > 0``
    (a scalar or one per row, broadcastable to ``f.shape[:-1]``).

    Returns ``(D, arg)``: ``D[..., q] = min_p f[..., p] + w (q - p)^2`` and ``arg[..., q]`` the
    minimising ``p`` (ties: the envelope's choice).
    """
    f = np.asarray(f, dtype=np.float64)
    shape = f.shape
    n = shape[-1]
    F = np.minimum(f.reshape(-1, n), BIG)
    R = F.shape[0]
    W = np.broadcast_to(np.asarray(w, dtype=np.float64), shape[:-1]).reshape(-1)
    if np.any(W <= 0):
        raise ValueError("w must be positive")
    rows = np.arange(R)
    v = np.zeros((R, n), dtype=np.int64)  # parabola roots of the envelope
    z = np.empty((R, n + 1))  # boundaries between envelope parabolas
    z[:, 0] = -np.inf
    z[:, 1] = np.inf
    k = np.zeros(R, dtype=np.int64)
    qq = np.arange(n, dtype=np.float64)
    g = F / W[:, None] + qq[None, :] ** 2  # f/w + q^2: the envelope only needs these
    for q in range(1, n):
        gq = g[:, q]
        vk = v[rows, k]
        s = (gq - g[rows, vk]) / (2.0 * (q - vk))
        pop = s <= z[rows, k]
        while pop.any():
            idx = np.flatnonzero(pop)
            k[idx] -= 1
            vk = v[idx, k[idx]]
            s[idx] = (gq[idx] - g[idx, vk]) / (2.0 * (q - vk))
            pop[idx] = s[idx] <= z[idx, k[idx]]
        k += 1
        v[rows, k] = q
        z[rows, k] = s
        z[rows, k + 1] = np.inf
    D = np.empty((R, n))
    arg = np.empty((R, n), dtype=np.int64)
    k[:] = 0
    for q in range(n):
        adv = z[rows, k + 1] < q
        while adv.any():
            k[adv] += 1
            adv = z[rows, k + 1] < q
        vk = v[rows, k]
        arg[:, q] = vk
        D[:, q] = W * (q - vk) ** 2 + F[rows, vk]
    return D.reshape(shape), arg.reshape(shape)


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
