"""The plain per-pair reference of the windowed frame distance, checked against a brute-force search
over the rotation angle. Other motion-graph tests (and scripts/bench_motiongraph.py) import it."""

from __future__ import annotations

import math

import numpy as np

from vidstyle.motiongraph.distance import align_windows


def _rot_y(q: np.ndarray, theta: float) -> np.ndarray:
    c, s = math.cos(theta), math.sin(theta)
    out = q.copy()
    out[:, 0] = c * q[:, 0] + s * q[:, 2]
    out[:, 2] = -s * q[:, 0] + c * q[:, 2]
    return out


def reference_pair(p: np.ndarray, q: np.ndarray, w: np.ndarray) -> tuple[float, float, float, float]:
    """Distance of two windows ((k, J, 3) each) by the textbook recipe, one pair at a time: theta from
    the un-normalised sums (docs/design.md), translation from the weighted means, then the weighted sum of
    squared distances evaluated directly on the transformed points."""
    k, J, _ = p.shape
    wn = np.tile(np.asarray(w, float), k)
    P, Q = p.reshape(-1, 3), q.reshape(-1, 3)
    sw = wn.sum()
    x, z, x2, z2 = P[:, 0], P[:, 2], Q[:, 0], Q[:, 2]
    xb, zb, x2b, z2b = (wn * x).sum(), (wn * z).sum(), (wn * x2).sum(), (wn * z2).sum()
    theta = math.atan2((wn * (x * z2 - x2 * z)).sum() - (xb * z2b - x2b * zb) / sw,
                       (wn * (x * x2 + z * z2)).sum() - (xb * x2b + zb * z2b) / sw)
    c, s = math.cos(theta), math.sin(theta)
    x0 = (xb - x2b * c - z2b * s) / sw
    z0 = (zb + x2b * s - z2b * c) / sw
    T = _rot_y(Q, theta) + np.array([x0, 0.0, z0])
    d = float((wn * ((P - T) ** 2).sum(1)).sum())
    return d, theta, x0, z0


def reference_distance_matrix(positions, starts, weights, k, upper_only=False) -> np.ndarray:
    """(Nw, Nw) squared distances, pair by pair (slow; small N only)."""
    n = len(starts)
    out = np.zeros((n, n))
    for a in range(n):
        pa = positions[starts[a] : starts[a] + k]
        for b in range(a + 1 if upper_only else 0, n):
            out[a, b] = reference_pair(pa, positions[starts[b] : starts[b] + k], weights)[0]
    return out


def _cost_at(p, q, w, theta):
    """Weighted squared distance after turning q by theta and the best floor shift for that angle."""
    k = p.shape[0]
    wn = np.tile(np.asarray(w, float), k)
    P, T = p.reshape(-1, 3), _rot_y(q.reshape(-1, 3), theta)
    shift = (wn[:, None] * (P - T)).sum(0) / wn.sum()
    shift[1] = 0.0
    return float((wn * ((P - T - shift) ** 2).sum(1)).sum())


def brute_force_pair(p, q, w, n_theta=3600):
    """Minimum over a grid of angles (translation optimal for each angle): independent of any sign."""
    k = p.shape[0]
    wn = np.tile(np.asarray(w, float), k)
    P, Q = p.reshape(-1, 3), q.reshape(-1, 3)
    best = (np.inf, 0.0)
    for theta in np.linspace(-np.pi, np.pi, n_theta, endpoint=False):
        T = _rot_y(Q, theta)
        shift = (wn[:, None] * (P - T)).sum(0) / wn.sum()
        shift[1] = 0.0
        d = float((wn * ((P - T - shift) ** 2).sum(1)).sum())
        if d < best[0]:
            best = (d, theta)
    return best


def _random_windows(rng, k=4, J=5):
    p = rng.normal(size=(k, J, 3)) * [1.0, 0.5, 1.0] + [3.0, 1.0, -2.0]
    # q is p turned and moved, plus noise: the true minimum is near a known angle
    theta = rng.uniform(-np.pi, np.pi)
    q = _rot_y(p.reshape(-1, 3), theta).reshape(p.shape) + [rng.normal() * 5, 0.0, rng.normal() * 5]
    q += rng.normal(size=q.shape) * 0.3
    return p, q, rng.uniform(0.5, 3.0, size=J), -theta


def test_closed_form_matches_brute_force_over_theta(rng):
    for _ in range(8):
        p, q, w, _ = _random_windows(rng)
        d, theta, x0, z0 = reference_pair(p, q, w)
        bd, btheta = brute_force_pair(p, q, w)
        assert d <= bd + 1e-9  # the closed form is at least as good as every grid angle
        assert bd - d < 1e-3 * max(bd, 1.0)
        # the closed form's angle is a minimum of the angle-only objective: nearby angles are no better
        for dt in (-2e-3, 2e-3):
            assert _cost_at(p, q, w, theta) <= _cost_at(p, q, w, theta + dt) + 1e-9
        assert np.isclose(_cost_at(p, q, w, theta), d, rtol=1e-9, atol=1e-9)
        assert abs(math.remainder(theta - btheta, 2 * math.pi)) < 2 * math.pi / 3600 * 1.5


def test_recovers_a_known_rigid_motion(rng):
    p, q, w, true_theta = _random_windows(rng)
    q = _rot_y(p.reshape(-1, 3), -true_theta).reshape(p.shape) + [4.0, 0.0, -7.0]  # exact copy, no noise
    d, theta, x0, z0 = reference_pair(p, q, w)
    assert d < 1e-18 * 1e6
    back = _rot_y(q.reshape(-1, 3), theta) + [x0, 0, z0]
    assert np.allclose(back, p.reshape(-1, 3), atol=1e-9)


def test_library_closed_form_equals_reference(rng):
    for _ in range(10):
        p, q, w, _ = _random_windows(rng)
        ref = reference_pair(p, q, w)
        got = align_windows(p, q, w)
        assert np.allclose([float(x) for x in got], ref, rtol=1e-9, atol=1e-9)


def test_vertical_offset_is_not_aligned(rng):
    """Only floor translation is free: a copy raised by h costs W h^2."""
    p, _, w, _ = _random_windows(rng)
    d = reference_pair(p, p + [0.0, 0.5, 0.0], w)[0]
    assert np.isclose(d, 0.25 * w.sum() * p.shape[0])
