"""2D SIFT-like descriptor of the frame patch at a salient point: the "2D SIFT instead of 3D" ablation.

It sees one frame only (no temporal gradient), so comparing it with the 3D variants on the same salient
points measures what the time axis of 3D SIFT buys for recognition (issue 4, item 6).

For a point (frame t, row r, column c) of a (frames, height, width) volume:

1. Frame t is smoothed by a Gaussian (``smooth_sigma``, edge values repeated) and differentiated by
   central differences (not halved; one-sided times 2 at the border, as the 3D variant): x = column
   (right), y = up (towards row 0). Magnitude m = sqrt(Lx^2 + Ly^2), orientation theta = atan2(Ly, Lx).
2. Samples: every pixel in the disc of radius ``radius`` around the point (a disc, so that the sample set
   is itself invariant under rotation); samples outside the frame have no gradient (skipped).
3. Dominant orientation (Lowe 2004, 5): a 36-bin histogram of theta, each sample adding
   m * exp(-|p|^2 / (2 sigma_o^2)) (sigma_o = ``orientation_sigma``), spread linearly over its two nearest
   bins, circularly smoothed twice with [1, 1, 1] / 3; the peak bin's angle refined by a parabola through
   it and its neighbours.
4. Rotation by the dominant orientation: sample positions and gradient orientations are both turned by
   minus that angle, so a rotated image gives the same descriptor.
5. ``n_cells`` x ``n_cells`` cells of ``cell_size`` pixels (default 4 x 4 of 4 px) and ``n_bins``
   orientation bins (default 8): each sample adds m * exp(-|p|^2 / (2 sigma^2)) (sigma = half the
   descriptor width, Lowe) spread by trilinear weights over the neighbouring cells (rotated position)
   and orientation bins (circular). Layout ``[cell_y (upwards), cell_x, bin]``: 4 * 4 * 8 = 128 values.
6. SIFT normalisation: L2, clip at ``clip`` (0.2), L2 again; no gradient at all gives all zeros.

float32 out; deterministic.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from ..errors import InputError

N_ORIENTATION_BINS = 36  # Lowe's orientation histogram for the dominant orientation


@dataclass(frozen=True)
class Sift2DParams:
    n_cells: int = 4
    """Cells per side (4 -> 4 x 4)."""
    cell_size: float = 4.0
    """Cell edge in pixels."""
    n_bins: int = 8
    """Orientation bins per cell."""
    smooth_sigma: float = 1.0
    """Gaussian smoothing of the frame before gradients (Lowe's L = G * I)."""
    sigma: float | None = None
    """Gaussian weighting of samples; default half the descriptor width."""
    orientation_sigma: float | None = None
    """Gaussian weighting of the dominant-orientation histogram; default 1.5 cell sizes."""
    radius: float | None = None
    """Radius of the sample disc; default covers every sample with non-zero weight at any rotation."""
    rotate: bool = True
    clip: float = 0.2
    batch_points: int = 256

    def __post_init__(self) -> None:
        problems = []
        if self.n_cells < 1 or self.n_bins < 2:
            problems.append("n_cells must be >= 1 and n_bins >= 2")
        for name in ("cell_size", "clip"):
            if not getattr(self, name) > 0:
                problems.append(f"{name} must be > 0")
        for name in ("sigma", "orientation_sigma", "radius"):
            v = getattr(self, name)
            if v is not None and not v > 0:
                problems.append(f"{name} must be > 0")
        if not self.smooth_sigma >= 0:
            problems.append("smooth_sigma must be >= 0")
        if self.batch_points < 1:
            problems.append("batch_points must be >= 1")
        if problems:
            raise InputError("sift2d parameters: " + "; ".join(problems))

    @property
    def dim(self) -> int:
        return self.n_cells * self.n_cells * self.n_bins

    @property
    def gaussian_sigma(self) -> float:
        return float(self.sigma) if self.sigma is not None else self.n_cells * self.cell_size / 2.0

    @property
    def orientation_gaussian_sigma(self) -> float:
        return float(self.orientation_sigma) if self.orientation_sigma is not None else 1.5 * self.cell_size

    @property
    def sample_radius(self) -> float:
        if self.radius is not None:
            return float(self.radius)
        # the bilinear cell weight reaches half a cell beyond the grid; the corner of that square is the
        # farthest a sample can lie at any rotation
        return math.sqrt(2.0) * (self.n_cells / 2.0 + 0.5) * self.cell_size

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


def disc_offsets(radius: float) -> np.ndarray:
    """(N, 2) integer (row, column) offsets with row^2 + column^2 <= radius^2."""
    r = math.floor(radius)
    g = np.arange(-r, r + 1)
    dr, dc = np.meshgrid(g, g, indexing="ij")
    keep = dr**2 + dc**2 <= radius * radius + 1e-9
    return np.stack([dr[keep], dc[keep]], axis=1)


def frame_gradients(frame: np.ndarray, smooth_sigma: float) -> tuple[np.ndarray, np.ndarray]:
    """(Lx, Ly) of one frame: x = column, y = up; raw central differences, one-sided x2 at the border."""
    from .sift3d import central_difference, smooth_volume

    f = smooth_volume(np.asarray(frame, np.float32)[None], 0.0, smooth_sigma)[0]
    return central_difference(f, 1), -central_difference(f, 0)


def _dominant(theta: np.ndarray, w: np.ndarray) -> np.ndarray:
    """Dominant orientation (P,) from sample orientations and weights (P, N)."""
    P = theta.shape[0]
    nb = N_ORIENTATION_BINS
    u = np.mod(theta, 2 * np.pi) * (nb / (2 * np.pi))
    lo = np.floor(u).astype(np.int64)
    f = (u - lo).astype(np.float64)
    lo %= nb
    hi = (lo + 1) % nb
    base = (np.arange(P) * nb)[:, None]
    hist = np.bincount((lo + base).ravel(), (w * (1 - f)).ravel(), minlength=P * nb)
    hist += np.bincount((hi + base).ravel(), (w * f).ravel(), minlength=P * nb)
    hist = hist.reshape(P, nb)
    for _ in range(2):
        hist = (np.roll(hist, 1, axis=1) + hist + np.roll(hist, -1, axis=1)) / 3.0
    k = np.argmax(hist, axis=1)
    rows = np.arange(P)
    left, mid, right = hist[rows, (k - 1) % nb], hist[rows, k], hist[rows, (k + 1) % nb]
    den = left - 2 * mid + right
    shift = np.where(den < 0, 0.5 * (left - right) / np.where(den < 0, den, -1), 0.0)
    # samples are spread linearly between the two nearest bins, so bin k is centred on angle k * 2 pi / nb
    return (k + shift) * (2 * np.pi / nb)


def describe(volume: np.ndarray, points: np.ndarray, params: Sift2DParams | None = None) -> np.ndarray:
    """(n, ``params.dim``) float32 descriptors of ``points`` (frame, row, column) in ``volume``.

    ``volume`` and ``points`` are validated by :func:`vidstyle.features.sift3d.describe`, the public
    entry point (``variant="sift2d"``)."""
    from .sift3d import normalise_sift

    p = params or Sift2DParams()
    vol = np.asarray(volume)
    pts = np.asarray(points, np.int64).reshape(-1, 3)
    out = np.zeros((len(pts), p.dim), np.float32)
    if len(pts) == 0:
        return out
    _, H, W = vol.shape
    offs = disc_offsets(p.sample_radius)
    R = int(np.abs(offs).max()) if len(offs) else 0
    Hp, Wp = H + 2 * R, W + 2 * R
    flat_off = offs[:, 0] * Wp + offs[:, 1]
    x = offs[:, 1].astype(np.float64)
    y = -offs[:, 0].astype(np.float64)  # y counts upwards
    d2 = x * x + y * y
    gauss = np.exp(-d2 / (2 * p.gaussian_sigma**2))
    gauss_o = np.exp(-d2 / (2 * p.orientation_gaussian_sigma**2))
    nc, nb = p.n_cells, p.n_bins
    cells = np.arange(nc, dtype=np.float64)[:, None]

    order = np.argsort(pts[:, 0], kind="stable")
    frames = pts[order, 0]
    starts = np.flatnonzero(np.r_[True, frames[1:] != frames[:-1]])
    ends = np.r_[starts[1:], len(order)]
    # group points by frame: one gradient image per frame with points, zero-padded so that samples
    # outside the frame contribute nothing
    g = np.zeros((len(starts), Hp, Wp, 2), np.float32)
    for k, s in enumerate(starts):
        gx, gy = frame_gradients(vol[int(frames[s])], p.smooth_sigma)
        g[k, R : R + H, R : R + W, 0] = gx
        g[k, R : R + H, R : R + W, 1] = gy
    g = g.reshape(-1, 2)
    slot = np.repeat(np.arange(len(starts)), ends - starts)  # gradient image of each sorted point
    for s in range(0, len(order), p.batch_points):
        sel = order[s : s + p.batch_points]
        q = pts[sel]
        base = (slot[s : s + len(sel)] * Hp + q[:, 1] + R) * Wp + (q[:, 2] + R)
        smp = np.take(g, base[:, None] + flat_off[None, :], axis=0).astype(np.float64)  # (P, N, 2)
        gx, gy = smp[..., 0], smp[..., 1]
        m = np.sqrt(gx * gx + gy * gy)
        theta = np.arctan2(gy, gx)
        P = len(sel)
        if p.rotate:
            d = _dominant(theta, m * gauss_o)
        else:
            d = np.zeros(P)
        cd, sd = np.cos(d)[:, None], np.sin(d)[:, None]
        # rotate positions by -d
        xr = cd * x[None] + sd * y[None]
        yr = -sd * x[None] + cd * y[None]
        ux = xr / p.cell_size + (nc / 2.0 - 0.5)
        uy = yr / p.cell_size + (nc / 2.0 - 0.5)
        ax = np.maximum(1 - np.abs(ux[:, None, :] - cells), 0)  # (P, nc, N)
        ay = np.maximum(1 - np.abs(uy[:, None, :] - cells), 0)
        # orientation relative to the dominant one, bins centred on multiples of 2 pi / nb
        ub = np.mod(theta - d[:, None], 2 * np.pi) * (nb / (2 * np.pi))
        lo = np.floor(ub).astype(np.int64)
        f = ub - lo
        lo %= nb
        N = ub.shape[1]
        O = np.zeros((P * N, nb))
        # a sample's two bins are distinct (nb >= 2), so plain fancy assignment suffices (no add.at)
        row = np.arange(P * N) * nb
        O.reshape(-1)[row + lo.ravel()] = (1 - f).ravel()
        O.reshape(-1)[row + ((lo + 1) % nb).ravel()] = f.ravel()
        O = O.reshape(P, N, nb)
        w = m * gauss[None]
        S = (ay[:, :, None, :] * ax[:, None, :, :]) * w[:, None, None, :]  # (P, nc, nc, N)
        hist = np.matmul(S.reshape(P, nc * nc, -1), O).reshape(P, -1)
        out[sel] = normalise_sift(hist, p.clip)
    return out
