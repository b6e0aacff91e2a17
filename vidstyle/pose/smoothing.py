"""Temporal smoothing of keypoint tracks: the One-Euro filter (Casiez, Roussel & Vogel, CHI 2012).

A first-order low-pass filter whose cut-off frequency rises with the signal's speed: still keypoints are
smoothed hard (jitter removed), fast ones lightly (little lag). Per coordinate:
``cutoff = min_cutoff + beta * |dx/dt|`` (the derivative itself low-passed at ``d_cutoff``),
``alpha = 1 / (1 + 1 / (2 pi cutoff dt))``. Positions are in pixels, so ``beta`` is per pixel/s. A gap
(a frame without the keypoint) restarts the filter.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import ParameterError

MIN_CUTOFF = 1.0
BETA = 0.05
D_CUTOFF = 1.0


def _alpha(cutoff: np.ndarray | float, dt: float) -> np.ndarray:
    tau = 1.0 / (2.0 * math.pi * np.asarray(cutoff, dtype=np.float64))
    return 1.0 / (1.0 + tau / dt)


def one_euro(track: np.ndarray, times: np.ndarray, min_cutoff: float = MIN_CUTOFF, beta: float = BETA,
             d_cutoff: float = D_CUTOFF) -> np.ndarray:
    """Filter ``track`` (F, ...) sampled at ``times`` (F,) seconds, increasing; NaN entries are gaps that
    restart the filter for that coordinate. Returns a new array."""
    for name, v in (("min_cutoff", min_cutoff), ("beta", beta), ("d_cutoff", d_cutoff)):
        if not (math.isfinite(v) and v >= 0) or (name != "beta" and v == 0):
            raise ParameterError(name, f"must be a finite number {'>= 0' if name == 'beta' else '> 0'}, got {v!r}")
    x = np.asarray(track, dtype=np.float64)
    t = np.asarray(times, dtype=np.float64)
    if len(t) != len(x):
        raise ValueError(f"{len(x)} samples but {len(t)} times")
    out = x.copy()
    if len(x) == 0:
        return out
    prev = x[0].copy()
    dprev = np.zeros_like(prev)
    for i in range(1, len(x)):
        dt = t[i] - t[i - 1]
        if not dt > 0:
            raise ValueError("times must increase")
        cur = x[i]
        gap = ~np.isfinite(prev) | ~np.isfinite(cur)
        dx = (cur - prev) / dt
        a_d = _alpha(d_cutoff, dt)
        dhat = a_d * dx + (1 - a_d) * dprev
        a = _alpha(min_cutoff + beta * np.abs(dhat), dt)
        filt = a * cur + (1 - a) * prev
        filt = np.where(gap, cur, filt)
        dhat = np.where(gap, 0.0, dhat)
        out[i] = filt
        prev, dprev = filt, dhat
    return out
