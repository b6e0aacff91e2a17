"""Slope-limited dynamic time warping (Du 2014, 3.2.2) and the time-warp functions it yields.

**Path rules** (a path through the cost matrix ``C`` (n, m) from ``(0, 0)`` to ``(n-1, m-1)``):
monotone and continuous (steps ``(1, 1)`` diagonal, ``(0, 1)`` horizontal, ``(1, 0)`` vertical),
boundary points fixed (the first and last frames of two segments of a primitive are the same keyframes),
and the **slope limit** ``L``: at most ``L`` consecutive horizontal steps and at most ``L`` consecutive
vertical steps (Du: ``L = 5``). Du allows an exception at the boundary so that two segments of very
different lengths still align: here, horizontal steps along the first or last row and vertical steps along
the first or last column are not counted (they neither extend nor end a run).

The dynamic programme keeps, per cell, the best cost of a path ending there in each *run state* (the last
step diagonal, or the ``k``-th horizontal, or the ``k``-th vertical step of a run, ``k <= L``): ``O(n m L)``
time, exact under the rules above (``tests/test_actionmodel_dtw.py`` checks it against enumerating every
admissible path). The path cost is the sum of ``C`` over its cells.

**Warp**: :func:`path_to_warp` turns a path into the function ``w(i)``, the (fractional) frame of the
instance shown at frame ``i`` of the reference: the mean of the instance frames the path matches to
reference frame ``i``, then made strictly increasing (steps at least ``min_step``) with its end points
kept, so it has a log-derivative (:mod:`.warp`).
"""

from __future__ import annotations

import numpy as np

from ..compiled import compile_kernel

INF = np.inf


def _dtw_loop(C, L):  # pragma: no cover - compiled by numba; the same code runs as Python without it
    n, m = C.shape
    S = 1 + 2 * L  # state 0: diagonal (or start); 1..L: horizontal run k; L+1..2L: vertical run k
    D = np.full((n, m, S), np.inf)
    D[0, 0, 0] = C[0, 0]
    for i in range(n):
        for j in range(m):
            if i == 0 and j == 0:
                continue
            c = C[i, j]
            if i > 0 and j > 0:
                best = np.inf
                for s in range(S):
                    if D[i - 1, j - 1, s] < best:
                        best = D[i - 1, j - 1, s]
                D[i, j, 0] = best + c
            if j > 0:  # horizontal step (i, j-1) -> (i, j)
                free = i == 0 or i == n - 1
                if free:
                    best = np.inf
                    for s in range(S):
                        if D[i, j - 1, s] < best:
                            best = D[i, j - 1, s]
                    # a free step keeps the state it came from: store it in the cheapest matching state
                    for s in range(S):
                        v = D[i, j - 1, s] + c
                        if v < D[i, j, s]:
                            D[i, j, s] = v
                else:
                    best = D[i, j - 1, 0]
                    for s in range(L + 1, S):
                        if D[i, j - 1, s] < best:
                            best = D[i, j - 1, s]
                    if best + c < D[i, j, 1]:
                        D[i, j, 1] = best + c
                    for k in range(2, L + 1):
                        v = D[i, j - 1, k - 1] + c
                        if v < D[i, j, k]:
                            D[i, j, k] = v
            if i > 0:  # vertical step (i-1, j) -> (i, j)
                free = j == 0 or j == m - 1
                if free:
                    for s in range(S):
                        v = D[i - 1, j, s] + c
                        if v < D[i, j, s]:
                            D[i, j, s] = v
                else:
                    best = D[i - 1, j, 0]
                    for s in range(1, L + 1):
                        if D[i - 1, j, s] < best:
                            best = D[i - 1, j, s]
                    if best + c < D[i, j, L + 1]:
                        D[i, j, L + 1] = best + c
                    for k in range(2, L + 1):
                        v = D[i - 1, j, L + k - 1] + c
                        if v < D[i, j, L + k]:
                            D[i, j, L + k] = v
    return D


_dtw_kernel = compile_kernel(_dtw_loop, _dtw_loop)


def _backtrack(D: np.ndarray, C: np.ndarray, L: int) -> list[tuple[int, int]]:
    n, m, S = D.shape
    i, j = n - 1, m - 1
    s = int(np.argmin(D[i, j]))
    path = [(i, j)]
    tol = 1e-9
    while (i, j) != (0, 0):
        cur = D[i, j, s] - C[i, j]
        found = False
        # candidates: (prev cell, prev state) that lead to (i, j, s) under the rules
        cands = []
        if s == 0 and i > 0 and j > 0:
            cands += [(i - 1, j - 1, t) for t in range(S)]
        if j > 0:
            if i == 0 or i == n - 1:
                cands.append((i, j - 1, s))
            elif s == 1:
                cands += [(i, j - 1, 0)] + [(i, j - 1, t) for t in range(L + 1, S)]
            elif 2 <= s <= L:
                cands.append((i, j - 1, s - 1))
        if i > 0:
            if j == 0 or j == m - 1:
                cands.append((i - 1, j, s))
            elif s == L + 1:
                cands += [(i - 1, j, 0)] + [(i - 1, j, t) for t in range(1, L + 1)]
            elif s > L + 1:
                cands.append((i - 1, j, s - 1))
        for pi, pj, ps in cands:
            v = D[pi, pj, ps]
            if np.isfinite(v) and abs(v - cur) <= tol * max(1.0, abs(cur)):
                i, j, s = pi, pj, ps
                found = True
                break
        if not found:  # pragma: no cover - rounding: take the cheapest candidate
            pi, pj, ps = min(cands, key=lambda c: D[c])
            i, j, s = pi, pj, ps
        path.append((i, j))
    return path[::-1]


def _check(cost, slope_limit):
    C = np.ascontiguousarray(cost, dtype=np.float64)
    if C.ndim != 2 or C.shape[0] < 1 or C.shape[1] < 1:
        raise ValueError(f"cost must be a non-empty (n, m) matrix, got shape {C.shape}")
    if not np.isfinite(C).all():
        raise ValueError("cost must be finite")
    L = int(slope_limit)
    if L < 1:
        raise ValueError(f"slope_limit must be >= 1, got {slope_limit}")
    return C, L


def dtw_cost(cost: np.ndarray, slope_limit: int = 5) -> float:
    """The total cost of :func:`dtw` without its path (no backtracking)."""
    C, L = _check(cost, slope_limit)
    return float(_dtw_kernel(C, L)[-1, -1].min())


def dtw(cost: np.ndarray, slope_limit: int = 5) -> tuple[float, np.ndarray]:
    """Slope-limited DTW of the cost matrix ``cost`` (n, m): ``(total cost, path (P, 2))`` (module text).
    Rows are the reference's frames, columns the instance's (any orientation works: the rules are
    symmetric)."""
    C, L = _check(cost, slope_limit)
    D = _dtw_kernel(C, L)
    total = float(D[-1, -1].min())
    if not np.isfinite(total):  # pragma: no cover - the free boundary rows/columns make every size feasible
        raise ValueError("no admissible path")
    return total, np.asarray(_backtrack(D, C, L), dtype=np.int64)


def path_runs_ok(path: np.ndarray, n: int, m: int, slope_limit: int) -> bool:
    """Whether ``path`` obeys the module's rules (used by the tests' brute force and by :func:`dtw`'s
    callers as a check): start, end, unit steps, and the slope limit away from the boundary."""
    p = np.asarray(path)
    if len(p) == 0 or tuple(p[0]) != (0, 0) or tuple(p[-1]) != (n - 1, m - 1):
        return False
    h = v = 0
    for (i0, j0), (i1, j1) in zip(p[:-1], p[1:]):
        di, dj = i1 - i0, j1 - j0
        if (di, dj) not in ((1, 1), (0, 1), (1, 0)):
            return False
        if (di, dj) == (1, 1):
            h = v = 0
        elif di == 0:  # horizontal
            if i1 in (0, n - 1):
                continue
            h, v = h + 1, 0
            if h > slope_limit:
                return False
        else:
            if j1 in (0, m - 1):
                continue
            v, h = v + 1, 0
            if v > slope_limit:
                return False
    return True


def path_to_warp(path: np.ndarray, n_ref: int, n_inst: int, min_step: float = 0.1,
                 smooth: float = 0.0) -> np.ndarray:
    """(n_ref,) strictly increasing warp ``w`` with ``w[0] = 0``, ``w[-1] = n_inst - 1`` (module text):
    ``w[i]`` the instance frame shown at reference frame ``i``. A one-frame reference gives ``[0]``.

    ``smooth`` > 0: the mean-matched warp's deviation from the straight line between its ends is smoothed
    with a Gaussian of that many reference frames (zero beyond the ends, then the ends put back) before
    the minimum step is enforced; a straight warp stays straight. A DTW path is a staircase; its steps (0, 1, 2 instance frames per reference frame)
    are quantisation, not timing, and their logarithms would dominate the temporal PCA."""
    p = np.asarray(path)
    sums = np.bincount(p[:, 0], weights=p[:, 1].astype(np.float64), minlength=n_ref)
    counts = np.bincount(p[:, 0], minlength=n_ref)
    w = sums / np.maximum(counts, 1)
    if smooth > 0 and n_ref > 2:
        from scipy.ndimage import gaussian_filter1d

        line = np.linspace(w[0], w[-1], n_ref)
        r = gaussian_filter1d(w - line, float(smooth), mode="constant")  # the deviation from the straight warp
        r -= np.linspace(r[0], r[-1], n_ref)  # ends held
        w = np.maximum.accumulate(line + r)
    return make_increasing(w, n_inst - 1, min_step)


def make_increasing(w: np.ndarray, end: float, min_step: float = 0.05) -> np.ndarray:
    """``w`` (non-decreasing, from 0 to ``end``) with every step at least ``min_step`` and the same
    end points: steps below it are raised to it and the others shrunk in proportion."""
    w = np.asarray(w, dtype=np.float64)
    if len(w) < 2:
        return np.zeros(len(w))
    steps = np.maximum(np.diff(w), 0.0)
    total = float(end)
    k = len(steps)
    eps = min(min_step, 0.5 * total / k) if total > 0 else 0.0
    if total <= 0:  # a one-frame instance: every reference frame shows frame 0 (the log-warp needs > 0)
        return np.linspace(0.0, 0.0, len(w))
    small = steps < eps
    rest = total - eps * small.sum()
    big = steps[~small].sum()
    if big <= 0:
        steps = np.full(k, total / k)
    else:
        steps = np.where(small, eps, steps * rest / big)
    return np.concatenate([[0.0], np.cumsum(steps)])
