"""Generalised distance transform and pictorial-structures inference against brute force."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from vidstyle.mocap.keypoints import PART_PARENT_INDEX
from vidstyle.pose.dt import BIG, brute_dt2d, dt1d, dt2d
from vidstyle.pose.model import N_PARTS, PictorialStructures


def test_dt1d_matches_enumeration(rng):
    f = rng.normal(size=(50, 13)) * 4
    f[3, :5] = np.inf  # unreachable samples
    w = rng.uniform(0.1, 3.0, size=50)
    D, arg = dt1d(f, w)
    q = np.arange(13)
    brute = np.minimum(f, BIG)[:, None, :] + w[:, None, None] * (q[:, None] - q[None, :]) ** 2
    np.testing.assert_allclose(D, brute.min(axis=2))
    np.testing.assert_allclose(np.take_along_axis(brute, arg[..., None], 2)[..., 0], D)


def test_dt1d_analytic_single_minimum():
    """One finite sample: D is a parabola rooted there."""
    f = np.full(9, np.inf)
    f[6] = -2.0
    D, arg = dt1d(f, 0.5)
    np.testing.assert_allclose(D, -2.0 + 0.5 * (np.arange(9) - 6) ** 2)
    assert np.all(arg == 6)


@pytest.mark.parametrize("shape", [(1, 1), (5, 7), (8, 3), (2, 6, 9)])
def test_dt2d_matches_brute_force(rng, shape):
    f = rng.normal(size=shape) * 5
    wx, wy = 0.7, 1.9
    D, ay, ax = dt2d(f, wx, wy)
    B, _, _ = brute_dt2d(f, wx, wy)
    np.testing.assert_allclose(D, B, atol=1e-9)
    H, W = shape[-2:]
    yy, xx = np.mgrid[0:H, 0:W]
    flat = f.reshape(-1, H * W)
    got = np.take_along_axis(flat, (ay * W + ax).reshape(flat.shape[0], -1), 1).reshape(f.shape)
    np.testing.assert_allclose(got + wx * (xx - ax) ** 2 + wy * (yy - ay) ** 2, B, atol=1e-9)


def _toy_model(rng, K: int) -> PictorialStructures:
    m = PictorialStructures(n_orient=K)
    m.offsets_ = rng.integers(-1, 2, size=(N_PARTS, 2)).astype(float)
    m.child_offsets_ = rng.integers(-1, 2, size=(N_PARTS, 2)).astype(float)
    m.proximal_ = np.zeros((N_PARTS, 2))
    m.distal_ = np.zeros((N_PARTS, 2))
    m.wxy_ = rng.uniform(0.2, 2.0, N_PARTS)
    m.wt_ = rng.uniform(0.1, 1.0, N_PARTS)
    m.mu_ = rng.uniform(-1, 1, N_PARTS)
    m.root_prior_ = rng.uniform(0, 1, K)
    return m


def test_inference_is_the_exact_minimum(rng):
    """Min-sum by distance transforms equals brute-force minimisation of the same energy. The tree
    has 10 parts: brute force over all joint states is impossible, so it is done by exhaustive
    dynamic programming over each child's full state space (no distance transform), and on a
    3-part chain (torso, upper arm, forearm) by enumerating every configuration outright."""
    K, H, W = 3, 3, 4
    m = _toy_model(rng, K)
    scores = rng.normal(size=(N_PARTS, K, H, W)) * 2
    res = m.infer(scores)
    e = m.energy(scores, res["states"])
    assert e == pytest.approx(res["energy"])
    # exhaustive DP: message(parent state) = min over every child state of energy terms
    states = list(itertools.product(range(K), range(H), range(W)))
    cost = {j: {s: -scores[j][s] for s in states} for j in range(N_PARTS)}
    order = sorted(range(1, N_PARTS), key=lambda j: -int(j in (4, 5, 8, 9)))  # leaves first
    for j in order:
        i = int(PART_PARENT_INDEX[j])
        for si in states:
            b = m.rounded_offsets(m.offsets_[j])[si[0]]
            qi = np.array([si[2] + b[0], si[1] + b[1]])
            vals = []
            for sj in states:
                a = m.rounded_offsets(m.child_offsets_[j])[sj[0]]
                qj = np.array([sj[2] + a[0], sj[1] + a[1]])
                if not (0 <= qj[0] < W and 0 <= qj[1] < H and 0 <= qi[0] < W and 0 <= qi[1] < H):
                    continue
                dev = (sj[0] - si[0] - m.mu_[j] + K / 2) % K - K / 2
                vals.append(cost[j][sj] + m.wxy_[j] * float(np.sum((qi - qj) ** 2)) + m.wt_[j] * dev ** 2)
            cost[i][si] += min(vals) if vals else np.inf
    root = min(cost[0][s] + m.root_prior_[s[0]] for s in states)
    assert res["energy"] == pytest.approx(root)


def test_chain_enumeration(rng):
    """Every configuration of a 3-part chain enumerated: the DT solution has the minimum energy."""
    K, H, W = 2, 2, 3
    m = _toy_model(rng, K)
    scores = np.full((N_PARTS, K, H, W), -50.0)  # parts other than the chain: one forced cheap state
    for j in range(N_PARTS):
        if j not in (0, 2, 4):
            scores[j] = 0.0
            m.wxy_[j] = 1e-6
            m.wt_[j] = 1e-6
    scores[[0, 2, 4]] = rng.normal(size=(3, K, H, W)) * 3
    res = m.infer(scores)
    states = list(itertools.product(range(K), range(H), range(W)))
    best = np.inf
    base = res["states"].copy()
    for s0 in states:
        for s2 in states:
            for s4 in states:
                st = base.copy()
                st[0], st[2], st[4] = s0, s2, s4
                best = min(best, m.energy(scores, st))
    assert m.energy(scores, res["states"]) == pytest.approx(best, abs=1e-3)
