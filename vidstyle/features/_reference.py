"""Naive per-point implementation of the thesis 3D SIFT variant, the baseline of the vectorised one.

One point at a time, the whole (unpadded) gradient volume computed once, samples visited by explicit
bounds checks, each of the 2^5 "quintilinear" corners of a sample accumulated with ``np.add.at``, and
the histogram peak refined by the same mean shift. It shares no code with the batched path except the
gradient and the bin geometry helpers, which are tested on their own against analytic volumes. Used by
the tests (agreement to float32 rounding) and by ``scripts/bench_features.py`` (the speed baseline).
"""

from __future__ import annotations

import itertools

import numpy as np

from .sift3d import Sift3DParams, ball_offsets, bin_centres, bin_solid_angles, gradients


def describe_thesis_loop(
    volume: np.ndarray, points: np.ndarray, params: Sift3DParams | None = None
) -> np.ndarray:
    p = params or Sift3DParams()
    vol = np.asarray(volume, dtype=np.float32)
    T, H, W = vol.shape
    st, ss = p.smooth_sigmas
    gx, gy, gt = (a.astype(np.float64) for a in gradients(vol, ss, st))
    offs = ball_offsets(p.sample_radius)
    nth, nph = p.n_theta, p.n_phi
    omega = bin_solid_angles(nth, nph)
    nt, ny, nx = p.n_subregions  # type: ignore[misc]
    sizes = p.sizes
    sig = p.gaussian_sigma
    out = np.zeros((len(points), p.dim), dtype=np.float32)
    for i, (t0, r0, c0) in enumerate(np.asarray(points, dtype=np.int64)):
        t, r, c = t0 + offs[:, 0], r0 + offs[:, 1], c0 + offs[:, 2]
        inside = (t >= 0) & (t < T) & (r >= 0) & (r < H) & (c >= 0) & (c < W)
        o = offs[inside]
        g = np.stack(
            [
                gx[t[inside], r[inside], c[inside]],
                gy[t[inside], r[inside], c[inside]],
                gt[t[inside], r[inside], c[inside]],
            ],
            axis=1,
        )
        pos = np.stack([o[:, 2], -o[:, 1], o[:, 0]], axis=1).astype(np.float64)  # x, y (up), t
        m = np.linalg.norm(g, axis=1)
        w = m * np.exp(-(o**2).sum(1) / (2 * sig * sig))
        if p.rotate:
            hist = np.zeros((nth, nph))
            for ti, pi, val in _orient_corners(g, omega):
                np.add.at(hist, (ti, pi), w * val)
            it, ip = np.unravel_index(int(np.argmax(hist)), hist.shape)
            tc, pc = bin_centres(nth, nph)
            d = np.array([np.cos(tc[it]) * np.cos(pc[ip]), np.sin(tc[it]) * np.cos(pc[ip]), np.sin(pc[ip])])
            u = np.divide(g, m[:, None], out=np.zeros_like(g), where=m[:, None] > 0)
            if p.mean_shift_start == "bin-mean":
                share = np.zeros(len(g))
                for ti, pi, val in _orient_corners(g, omega):
                    share += np.where((ti == it) & (pi == ip), val, 0.0)
                start = (share * w) @ u
                if np.linalg.norm(start) > 0:
                    d = start / np.linalg.norm(start)
            for _ in range(p.mean_shift_iterations):
                k = np.exp(p.kappa * (u @ d - 1)) * w
                new = k @ u
                if np.linalg.norm(new) > 0:
                    d = new / np.linalg.norm(new)
            th, ph = np.arctan2(d[1], d[0]), np.arctan2(d[2], np.hypot(d[0], d[1]))
            # M = Rz(th) Ry(-ph); samples and gradients are mapped by M^T
            Rz = np.array([[np.cos(th), -np.sin(th), 0], [np.sin(th), np.cos(th), 0], [0, 0, 1]])
            Ry = np.array([[np.cos(-ph), 0, np.sin(-ph)], [0, 1, 0], [-np.sin(-ph), 0, np.cos(-ph)]])
            M = Rz @ Ry
            g, pos = g @ M, pos @ M
        hist = np.zeros((nt, ny, nx, nth, nph))
        # spatial coordinates of sub-region centres are integers
        u_sp = [
            pos[:, 2] / sizes[0] + nt / 2 - 0.5,
            pos[:, 1] / sizes[1] + ny / 2 - 0.5,
            pos[:, 0] / sizes[2] + nx / 2 - 0.5,
        ]
        n_sp = (nt, ny, nx)
        for corner in itertools.product((0, 1), repeat=3):
            idx, wt = [], w.copy()
            for a in range(3):
                lo = np.floor(u_sp[a])
                frac = u_sp[a] - lo
                j = lo.astype(np.int64) + corner[a]
                wt = wt * (frac if corner[a] else 1 - frac)
                ok = (j >= 0) & (j < n_sp[a])
                wt = np.where(ok, wt, 0)
                idx.append(np.clip(j, 0, n_sp[a] - 1))
            for ti, pi, val in _orient_corners(g, omega):
                np.add.at(hist, (idx[0], idx[1], idx[2], ti, pi), wt * val)
        h = hist.reshape(-1)
        n = np.linalg.norm(h)
        if n > 0:
            h = np.minimum(h / n, p.clip)
            h = h / np.linalg.norm(h)
        out[i] = h
    return out


def _orient_corners(g: np.ndarray, omega: np.ndarray):
    """The 4 bilinear (theta wraps, phi clamped) bins of each gradient: (theta idx, phi idx, weight/omega)."""
    nth, nph = omega.shape
    theta = np.arctan2(g[:, 1], g[:, 0])
    phi = np.arctan2(g[:, 2], np.hypot(g[:, 0], g[:, 1]))
    ut = (theta + np.pi) / (2 * np.pi / nth) - 0.5
    up = np.clip((phi + np.pi / 2) / (np.pi / nph) - 0.5, 0, nph - 1)
    t0 = np.floor(ut)
    ft = ut - t0
    p0 = np.minimum(np.floor(up), nph - 2)
    fp = up - p0
    for a, b in itertools.product((0, 1), repeat=2):
        ti = (t0.astype(np.int64) + a) % nth
        pi = p0.astype(np.int64) + b
        yield ti, pi, (ft if a else 1 - ft) * (fp if b else 1 - fp) / omega[ti, pi]
