"""Online lazy neighbourhood graph (OLNG; Tautges 2012, section 3.4.3 / 3.7-3.9).

Each control frame ``t`` (here: the performer's 2D pose in a video frame) has ``K`` nearest library
frames, its *nodes*, each with a library index ``i`` (consecutive within a clip), a clip and a cost (its
feature distance). A node ``(t2, i2)`` *continues* ``(t1, i1)`` of the same clip when the step
``(i2 - i1, t2 - t1)`` is one of Tautges' step sizes: ``(1, 1)``, ``(2, 1)``, ``(1, 2)`` (the basic
steps, strictly monotone in both indices) and, to bridge a single scattered neighbourhood,
``(2, 2)``, ``(3, 2)``, ``(4, 2)``. A path is a chain of continuations inside the window of the last
``M`` control frames. Its cost is the sum of

- the costs of its nodes,
- the cost of each edge that skips a control frame (``t2 - t1 = 2``): the cost of the node it points
  at (so a shortcut is not cheaper than a step through the skipped frame); other edges cost 0,
- for every control frame of the window *before* the path starts, twice the cost of that frame's
  ``K``-th (most distant) neighbour: shortness is penalised, so a long coherent path beats a short one
  of slightly smaller node costs, while a frame where no path reaches far back still gets a ranking.

:func:`olng_costs` returns, for every node, the cost of the best path ending there (what the OLNG's
incremental update maintains, computed here for a whole sequence at once by dynamic programming over
(frame, node, path span)), and the span of that path. A node with a small cost is a reliable local
neighbour; the reconstruction blends the best of them.
"""

from __future__ import annotations

import numpy as np

#: Tautges' step sizes (library step, control step): the basic ones and the three that bridge a gap
BASIC_STEPS = ((1, 1), (2, 1), (1, 2))
BRIDGE_STEPS = ((2, 2), (3, 2), (4, 2))
STEPS = BASIC_STEPS + BRIDGE_STEPS


def olng_costs(index: np.ndarray, clip: np.ndarray, cost: np.ndarray, window: int,
               steps=STEPS, penalty_factor: float = 2.0) -> tuple[np.ndarray, np.ndarray]:
    """Best-path costs of every node of a sequence.

    ``index`` (T, K) int library frame of each node (consecutive frames of a clip are consecutive
    integers), ``clip`` (T, K) its clip, ``cost`` (T, K) its cost (non-negative, finite; the columns
    need not be sorted), ``window`` the OLNG's ``M`` (a path spans at most ``M`` control frames).
    Returns ``(total, span)``, each (T, K): the minimal path cost over paths ending at the node (see the
    module text) and the number of control frames that best path spans (1: the node alone).
    """
    index = np.asarray(index, dtype=np.int64)
    clip = np.asarray(clip, dtype=np.int64)
    cost = np.asarray(cost, dtype=np.float64)
    if index.ndim != 2 or clip.shape != index.shape or cost.shape != index.shape:
        raise ValueError(f"index, clip and cost must be (T, K) arrays of one shape, got {index.shape}, "
                         f"{clip.shape}, {cost.shape}")
    if window < 1:
        raise ValueError(f"window must be >= 1, got {window}")
    if not np.all(np.isfinite(cost)) or np.any(cost < 0):
        raise ValueError("cost must be finite and non-negative")
    T, K = index.shape
    M = int(window)
    if T == 0 or K == 0:
        return np.zeros((T, K)), np.zeros((T, K), dtype=np.int64)
    for di, dt in steps:
        if di < 1 or dt not in (1, 2):
            raise ValueError(f"step ({di}, {dt}): library steps must be >= 1 and control steps 1 or 2")
    pen = penalty_factor * cost.max(axis=1)  # (T,) the K-th neighbour's cost, doubled
    prefix = np.concatenate([[0.0], np.cumsum(pen)])  # prefix[t] = pen[0] + ... + pen[t-1]
    # D[t, k, s]: the least node + edge cost of a path ending at (t, k) that started s frames earlier
    D = np.full((T, K, M), np.inf)
    D[:, :, 0] = cost
    by_dt: dict[int, tuple[int, ...]] = {}
    for di, dt in steps:
        by_dt.setdefault(dt, ())
        by_dt[dt] += (di,)
    for t in range(T):
        for dt, dis in by_dt.items():
            if t - dt < 0 or dt > M - 1:
                continue
            step = index[t][None, :] - index[t - dt][:, None]  # (K prev, K)
            ok = (clip[t][None, :] == clip[t - dt][:, None]) & np.isin(step, dis)
            if not ok.any():
                continue
            edge = cost[t] if dt == 2 else np.zeros(K)  # a skipping edge costs its target node's cost
            prev = D[t - dt][:, None, : M - dt]  # (K prev, 1, spans)
            cand = np.where(ok[:, :, None], prev, np.inf).min(axis=0)  # (K, spans)
            D[t, :, dt:] = np.minimum(D[t, :, dt:], cand + (cost[t] + edge)[:, None])
    # the shortness penalty: the window of frame t is max(0, t-M+1)..t; a path of span s starts at t-s
    t_idx = np.arange(T)[:, None]
    s_idx = np.arange(M)[None, :]
    first = np.maximum(t_idx - M + 1, 0)
    start = t_idx - s_idx
    shortness = np.where(start >= first, prefix[np.clip(start, 0, None)] - prefix[first], np.inf)  # (T, M)
    total_s = D + shortness[:, None, :]
    best = np.argmin(total_s, axis=2)
    total = np.take_along_axis(total_s, best[:, :, None], axis=2)[:, :, 0]
    return total, best + 1
