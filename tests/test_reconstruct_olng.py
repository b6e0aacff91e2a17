"""The OLNG path costs (Tautges 2012, seed 001) against brute force: every path of every node enumerated
by the definition (node costs, skipping edges at the target's cost, twice the K-th neighbour's cost for
each window frame before the path starts), on random small sequences."""

from __future__ import annotations

import numpy as np
import pytest

from vidstyle.reconstruct.olng import BASIC_STEPS, STEPS, olng_costs


def _brute(index, clip, cost, M, steps):
    T, K = index.shape
    pen = 2.0 * cost.max(axis=1)
    best = np.full((T, K), np.inf)
    span = np.zeros((T, K), dtype=int)

    def paths(t, k):  # every path ending at (t, k): lists of (t, k), earliest first
        yield [(t, k)]
        for di, dt in steps:
            tp = t - dt
            if tp < 0:
                continue
            for kp in range(K):
                if clip[tp, kp] == clip[t, k] and index[t, k] - index[tp, kp] == di:
                    for p in paths(tp, kp):
                        yield p + [(t, k)]

    for t in range(T):
        first = max(0, t - M + 1)
        for k in range(K):
            for p in paths(t, k):
                start = p[0][0]
                if t - start > M - 1:
                    continue
                c = sum(cost[a, b] for a, b in p)
                c += sum(cost[b2] for (a1, _), b2 in zip(p, p[1:]) if b2[0] - a1 == 2)
                c += sum(pen[first:start])
                s = t - start + 1
                if c < best[t, k] - 1e-9 or (abs(c - best[t, k]) <= 1e-9 and s < span[t, k]):
                    best[t, k], span[t, k] = c, s
    return best, span


@pytest.mark.parametrize("seed", range(12))
def test_costs_equal_brute_force(seed):
    rng = np.random.default_rng(seed)
    T, K, M = int(rng.integers(1, 9)), int(rng.integers(1, 5)), int(rng.integers(1, 6))
    # a library of two clips; nodes near a walking diagonal so that many continuations exist
    base = np.arange(T)[:, None] * rng.integers(1, 3) + rng.integers(0, 4, size=(T, K))
    clip = rng.integers(0, 2, size=(T, K))
    index = base + 1000 * clip
    cost = rng.random((T, K)).round(3)
    steps = STEPS if seed % 2 == 0 else BASIC_STEPS
    got, got_span = olng_costs(index, clip, cost, M, steps=steps)
    want, want_span = _brute(index, clip, cost, M, steps)
    assert np.allclose(got, want, rtol=0, atol=1e-9)
    assert np.array_equal(got_span, want_span)


def test_a_coherent_path_beats_a_closer_scattered_neighbour():
    """Frame 3's neighbour 0 continues a four-frame walk through the clip; neighbour 1 is nearer but has
    no coherent past: after the window fills, the walk ranks first."""
    index = np.array([[10, 500], [11, 300], [12, 900], [13, 700]])
    clip = np.zeros_like(index)
    cost = np.array([[0.3, 0.9], [0.3, 0.9], [0.3, 0.9], [0.3, 0.1]])
    total, span = olng_costs(index, clip, cost, window=4)
    assert total[3, 0] < total[3, 1] and span[3, 0] == 4 and span[3, 1] == 1
    assert np.isclose(total[3, 0], 1.2)  # four node costs, no penalty
    assert np.isclose(total[3, 1], 0.1 + 2 * (0.9 + 0.9 + 0.9))  # alone: three frames before it unrepresented


def test_a_skipped_frame_costs_the_target_node_and_clip_boundaries_break_paths():
    index = np.array([[5], [50], [6]])
    cost = np.array([[0.2], [0.5], [0.3]])
    total, span = olng_costs(index, np.zeros((3, 1), int), cost, window=3)
    assert np.isclose(total[2, 0], 0.2 + 0.3 + 0.3) and span[2, 0] == 3  # (1, 2) step: 5 -> 6 skipping frame 1
    total, span = olng_costs(index, np.array([[0], [0], [1]]), cost, window=3)
    assert span[2, 0] == 1  # another clip: no continuation


@pytest.mark.parametrize("bad", [dict(window=0), dict(cost=np.full((2, 2), np.nan)), dict(cost=-np.ones((2, 2))),
                                 dict(index=np.zeros((2, 3), int))])
def test_bad_input_is_refused(bad):
    args = dict(index=np.zeros((2, 2), int), clip=np.zeros((2, 2), int), cost=np.ones((2, 2)), window=3)
    args.update(bad)
    with pytest.raises(ValueError):
        olng_costs(**args)
