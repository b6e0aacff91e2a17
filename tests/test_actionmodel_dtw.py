"""Slope-limited DTW against enumerating every path, and the log-derivative warp representation."""

from __future__ import annotations

import numpy as np
import pytest

from vidstyle.actionmodel.dtw import dtw, dtw_cost, make_increasing, path_to_warp
from vidstyle.actionmodel.warp import invert_warp, logderiv_to_warp, warp_to_logderiv


def _admissible(path, n, m, L) -> bool:
    """The rules of Du 3.2.2 written out independently: unit monotone steps from corner to corner; a run
    of more than L horizontal (vertical) steps is not allowed, except steps along the first/last row
    (column), which do not count."""
    if path[0] != (0, 0) or path[-1] != (n - 1, m - 1):
        return False
    run_h = run_v = 0
    for a, b in zip(path, path[1:]):
        step = (b[0] - a[0], b[1] - a[1])
        if step == (1, 1):
            run_h = run_v = 0
        elif step == (0, 1):
            if b[0] in (0, n - 1):
                continue
            run_h, run_v = run_h + 1, 0
            if run_h > L:
                return False
        elif step == (1, 0):
            if b[1] in (0, m - 1):
                continue
            run_v, run_h = run_v + 1, 0
            if run_v > L:
                return False
        else:
            return False
    return True


def _all_paths(n, m):
    out = []

    def rec(p):
        i, j = p[-1]
        if (i, j) == (n - 1, m - 1):
            out.append(list(p))
            return
        for di, dj in ((1, 1), (0, 1), (1, 0)):
            if i + di < n and j + dj < m:
                p.append((i + di, j + dj))
                rec(p)
                p.pop()

    rec([(0, 0)])
    return out


@pytest.mark.parametrize("n, m, L, seed", [(4, 4, 1, 0), (5, 3, 1, 1), (3, 6, 1, 2), (5, 5, 2, 3), (6, 4, 1, 4),
                                           (4, 6, 2, 5), (6, 6, 1, 6), (2, 5, 1, 7), (5, 1, 1, 8)])
def test_dtw_matches_brute_force(n, m, L, seed):
    C = np.random.default_rng(seed).random((n, m))
    best = min(sum(C[i, j] for i, j in p) for p in _all_paths(n, m) if _admissible(p, n, m, L))
    total, path = dtw(C, L)
    assert total == pytest.approx(best, abs=1e-12)
    assert dtw_cost(C, L) == pytest.approx(best, abs=1e-12)
    p = [tuple(map(int, x)) for x in path]
    assert _admissible(p, n, m, L)
    assert sum(C[i, j] for i, j in p) == pytest.approx(total, abs=1e-12)


def test_slope_limit_is_respected_on_larger_inputs():
    rng = np.random.default_rng(0)
    for L in (1, 2, 5):
        for _ in range(10):
            n, m = rng.integers(8, 40, 2)
            C = rng.random((n, m))
            # make long horizontal runs attractive: a cheap row in the middle
            C[n // 2] *= 0.01
            _, path = dtw(C, L)
            assert _admissible([tuple(map(int, x)) for x in path], n, m, L)


def test_unlimited_slope_equals_plain_dtw():
    """With L >= both sizes the limit never binds: the classic DTW recursion gives the same cost."""
    rng = np.random.default_rng(3)
    C = rng.random((7, 9))
    D = np.full((8, 10), np.inf)
    D[0, 0] = 0
    for i in range(1, 8):
        for j in range(1, 10):
            D[i, j] = C[i - 1, j - 1] + min(D[i - 1, j - 1], D[i - 1, j], D[i, j - 1])
    assert dtw(C, 20)[0] == pytest.approx(D[7, 9])


def test_bad_cost_is_refused():
    with pytest.raises(ValueError):
        dtw(np.zeros((0, 3)))
    with pytest.raises(ValueError):
        dtw(np.array([[np.nan]]))
    with pytest.raises(ValueError):
        dtw(np.ones((2, 2)), 0)


def test_warp_round_trips_and_stays_monotone():
    rng = np.random.default_rng(1)
    for _ in range(20):
        d = rng.normal(0, 1.5, rng.integers(1, 60))
        w = logderiv_to_warp(d)
        assert w[0] == 0 and np.all(np.diff(w) > 0)
        np.testing.assert_allclose(warp_to_logderiv(w), d, atol=1e-9)
        np.testing.assert_allclose(logderiv_to_warp(warp_to_logderiv(w)), w, atol=1e-9)
    with pytest.raises(ValueError):
        warp_to_logderiv(np.array([0.0, 1.0, 1.0]))


def test_path_to_warp_is_monotone_with_fixed_ends():
    rng = np.random.default_rng(2)
    for smooth in (0.0, 2.0):
        for _ in range(20):
            n, m = rng.integers(3, 30, 2)
            _, path = dtw(rng.random((n, m)), 5)
            w = path_to_warp(path, n, m, smooth=smooth)
            assert w[0] == 0 and w[-1] == pytest.approx(m - 1)
            assert np.all(np.diff(w) > 0)


def test_identity_path_gives_identity_warp():
    path = np.stack([np.arange(10), np.arange(10)], 1)
    np.testing.assert_allclose(path_to_warp(path, 10, 10, smooth=2.0), np.arange(10), atol=1e-12)


def test_invert_warp_inverts():
    w = logderiv_to_warp(np.log(np.linspace(0.5, 2.0, 30)))
    n = int(round(w[-1])) + 1
    u = invert_warp(w, n)
    assert u[0] == 0 and u[-1] == pytest.approx(len(w) - 1) and np.all(np.diff(u) > 0)
    # w(u(t)) = t (scaled so the last frame maps to the last reference frame)
    t = np.interp(u, np.arange(len(w)), w)
    np.testing.assert_allclose(t, np.arange(n) * w[-1] / (n - 1), atol=1e-9)


def test_make_increasing_keeps_ends():
    w = make_increasing(np.array([0, 0, 0, 3, 3, 4.0]), 4.0, 0.1)
    assert w[0] == 0 and w[-1] == pytest.approx(4.0) and np.all(np.diff(w) >= 0.1 - 1e-12)
