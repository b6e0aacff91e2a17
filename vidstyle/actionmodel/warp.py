"""Time warps as unconstrained vectors: the log-derivative representation.

A warp ``w`` (M,) maps frame ``i`` of the aligned (reference) time to the instance's (fractional) frame
``w[i]``; it is strictly increasing with ``w[0] = 0``. Its representation is the log of its steps,
``d = log(diff(w))`` (M-1,): any real vector ``d`` gives back a strictly increasing warp
``w = [0, cumsum(exp(d))]`` (so a Gaussian over ``d`` never draws time running backwards), the instance's
length is ``w[-1] + 1 = 1 + sum(exp(d))`` frames, and a uniformly faster instance is a constant shift of
``d``. This is the square-root-slope idea of functional data registration in its log form (e.g. Ramsay &
Silverman, *Functional Data Analysis*, ch. 7).
"""

from __future__ import annotations

import numpy as np


def warp_to_logderiv(w: np.ndarray) -> np.ndarray:
    """(M-1,) log steps of a strictly increasing warp ``w`` (M,); ValueError when a step is not > 0."""
    steps = np.diff(np.asarray(w, dtype=np.float64))
    if np.any(steps <= 0):
        raise ValueError("the warp must be strictly increasing")
    return np.log(steps)


def logderiv_to_warp(d: np.ndarray) -> np.ndarray:
    """The warp ``[0, cumsum(exp(d))]`` (M,) of log steps ``d`` (M-1,)."""
    d = np.asarray(d, dtype=np.float64)
    return np.concatenate([[0.0], np.cumsum(np.exp(d))])


def invert_warp(w: np.ndarray, n_frames: int | None = None) -> np.ndarray:
    """Aligned time (fractional reference frame) of every instance frame ``0 .. n_frames-1`` (default
    ``round(w[-1]) + 1``) under the strictly increasing warp ``w``: linear interpolation of ``w``'s
    inverse, clamped to ``[0, M-1]``."""
    w = np.asarray(w, dtype=np.float64)
    if n_frames is None:
        n_frames = int(round(float(w[-1]))) + 1
    t = np.arange(int(n_frames), dtype=np.float64)
    if len(w) < 2:
        return np.zeros(len(t))
    # scale so that the last instance frame maps to the last reference frame exactly
    t = t * (w[-1] / max(n_frames - 1, 1)) if n_frames > 1 else t
    return np.interp(t, w, np.arange(len(w), dtype=np.float64))
