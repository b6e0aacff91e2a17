"""3D SIFT descriptors of points in a video volume (Scovanner, Ali, Shah 2007; thesis section 4.1).

Public entry point: :func:`describe` ``(volume, points, variant="thesis") -> (n, d)``.

``volume`` is a float array shaped (frames, height, width); ``points`` an (n, 3) integer array of 0-based
(frame, row, column). Two variants:

``"thesis"`` (default, float32, 256-D with the default parameters)
    The method as the paper and the thesis describe it, with their typos fixed:

    1. The volume is smoothed by a separable Gaussian (``smooth_sigma``, default 1 voxel, in space and
       time, edge values repeated beyond the border): in Lowe's notation, which the thesis copies, ``L``
       is the scale-space image G * I, not the raw frames. Gradients are raw
       central differences (not halved, as in thesis eq. 1), one-sided times 2 on the first/last plane
       of an axis so that the scale stays the same at the border.
    2. Coordinates are x = column (right), y = up (towards row 0), t = frame. Gradient direction:
       theta = atan2(Ly, Lx) in [-pi, pi), phi = atan2(Lt, sqrt(Lx^2 + Ly^2)) in [-pi/2, pi/2]
       (phi is the *elevation*, not the polar angle: thesis eq. 5 integrates sin(theta) over the wrong
       angle). The solid angle of the bin [theta1, theta2] x [phi1, phi2] is
       (theta2 - theta1) * (sin phi2 - sin phi1); the bins near the poles are the small ones, so dividing by
       it equalises a uniform distribution of directions.
    3. Samples: every voxel in the ball of radius ``radius`` around the point (a ball, not a cube, so that
       the sample set is itself invariant under rotation). Each adds m * exp(-|p|^2 / (2 sigma^2)) / omega;
       the thesis' eq. 6 has "- (t - t')^2" inside the exponent, a sign typo.
    4. Dominant orientation: the peak of the Gaussian-weighted, solid-angle-normalised 8x4 histogram,
       refined by spherical mean shift (von Mises-Fisher kernel, concentration ``kappa``,
       ``mean_shift_iterations`` steps) on the same weighted gradient directions, started from the
       weighted mean direction of the peak bin's samples. The histogram peak alone is quantised to
       45 degrees, which would give rotation invariance only for multiples of the bin width; the
       mean-shift mode is a continuous function of the data, so it turns with the video (its density
       needs no 1/omega: a kernel density on the sphere is already per unit solid angle). Only the choice
       of the peak bin is discrete, so points whose two strongest modes are nearly equal can still flip.
    5. Rotation: with M = Rz(theta) Ry(-phi) (thesis eq. 7, whose first column is the dominant direction),
       sample offsets and gradients are both mapped by M^T, sending the dominant direction to
       theta = phi = 0. A rotation of the video about the time axis by alpha turns every gradient and
       the dominant direction by alpha, so M^T g is unchanged: the descriptor is invariant.
    6. Sub-regions: ``n_subregions`` per axis (t, y, x) of ``subregion_size`` voxels (``subregion_size_t``
       frames in time); each sample is spread over the neighbouring sub-regions by trilinear weights on
       its rotated position and over the neighbouring (theta, phi) bins by bilinear weights (theta wraps,
       phi is clamped at the poles) -- the "quintilinear" interpolation of the thesis.
    7. Concatenate (layout ``[sub_t, sub_y, sub_x, theta, phi]``, phi fastest, sub_y counted upwards),
       L2-normalise, clip at ``clip`` (0.2), L2-normalise again (as 2D SIFT). An empty neighbourhood
       (no gradient anywhere) gives all zeros.

``"scovanner2007"`` (uint8, 640-D)
    The descriptor as the authors' released code computes it; see :mod:`vidstyle.features.scovanner2007`.

Speed: gradients are computed once per slab of frames (``chunk_frames``) and the neighbourhoods of a batch
of points are gathered at once; the sub-histograms are one batched matrix product
(sub-region weights)^T x (orientation weights) per batch, because the quintilinear weight of a sample is
the outer product of its spatial and its orientation weights.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, replace
from typing import Any

import numpy as np

from ..errors import InputError

#: Gaussian smoothing kernels are cut at this many standard deviations (scipy's default is 4; 3 keeps
#: slab margins small and changes the weights by < 1 %).
SMOOTH_TRUNCATE = 3.0


@dataclass(frozen=True)
class Sift3DParams:
    """Parameters of the thesis variant. All lengths are in voxels (pixels, frames)."""

    n_subregions: int | tuple[int, int, int] = 2
    """Sub-regions per axis, one int for all axes or (t, y, x). Thesis 2 (2x2x2); Scovanner also 4."""
    subregion_size: float = 4.0
    """Edge of a sub-region in pixels."""
    subregion_size_t: float | None = None
    """Edge of a sub-region in frames (default: ``subregion_size``)."""
    n_theta: int = 8
    n_phi: int = 4
    sigma: float | None = None
    """Gaussian weighting of samples; default half the descriptor's largest width (Lowe 2004)."""
    radius: float | None = None
    """Radius of the sample ball; default covers every sample with non-zero trilinear weight along an axis."""
    smooth_sigma: float = 1.0
    smooth_sigma_t: float | None = None
    rotate: bool = True
    """Rotate to the dominant orientation (False: plain, non-invariant descriptor)."""
    kappa: float = 8.0
    """Concentration of the mean-shift kernel (about 20 degrees, half an orientation bin)."""
    mean_shift_iterations: int = 8
    mean_shift_start: str = "bin-mean"
    """Mean-shift start: "bin-mean" (weighted mean direction of the peak bin) or "bin-centre"."""
    clip: float = 0.2
    chunk_frames: int = 64
    batch_points: int = 64

    def __post_init__(self) -> None:
        n = self.n_subregions
        n = (int(n),) * 3 if np.isscalar(n) else tuple(int(v) for v in n)  # type: ignore[arg-type]
        object.__setattr__(self, "n_subregions", n)
        problems = []
        if len(n) != 3 or min(n) < 1:
            problems.append(f"n_subregions must be >= 1 per axis, got {self.n_subregions}")
        for name in ("subregion_size", "kappa", "clip"):
            if not getattr(self, name) > 0:
                problems.append(f"{name} must be > 0")
        for name in ("subregion_size_t", "sigma", "radius"):
            v = getattr(self, name)
            if v is not None and not v > 0:
                problems.append(f"{name} must be > 0")
        for name in ("smooth_sigma", "smooth_sigma_t"):
            v = getattr(self, name)
            if v is not None and not v >= 0:
                problems.append(f"{name} must be >= 0")
        if self.n_theta < 2 or self.n_phi < 2:
            problems.append("n_theta and n_phi must be >= 2")
        if self.mean_shift_start not in ("bin-mean", "bin-centre"):
            problems.append(
                f"mean_shift_start must be 'bin-mean' or 'bin-centre', got {self.mean_shift_start!r}"
            )
        if self.chunk_frames < 1 or self.batch_points < 1 or self.mean_shift_iterations < 0:
            problems.append("chunk_frames, batch_points must be >= 1, mean_shift_iterations >= 0")
        if problems:
            raise InputError("sift3d parameters: " + "; ".join(problems))

    @property
    def sizes(self) -> tuple[float, float, float]:
        """Sub-region edge along (t, y, x)."""
        st = self.subregion_size if self.subregion_size_t is None else self.subregion_size_t
        return (float(st), float(self.subregion_size), float(self.subregion_size))

    @property
    def smooth_sigmas(self) -> tuple[float, float]:
        """(temporal, spatial) smoothing sigma."""
        st = self.smooth_sigma if self.smooth_sigma_t is None else self.smooth_sigma_t
        return float(st), float(self.smooth_sigma)

    @property
    def dim(self) -> int:
        nt, ny, nx = self.n_subregions  # type: ignore[misc]
        return nt * ny * nx * self.n_theta * self.n_phi

    @property
    def gaussian_sigma(self) -> float:
        if self.sigma is not None:
            return float(self.sigma)
        return max(n * s for n, s in zip(self.n_subregions, self.sizes)) / 2.0  # type: ignore[arg-type]

    @property
    def sample_radius(self) -> float:
        if self.radius is not None:
            return float(self.radius)
        # trilinear weight of sub-region k is non-zero up to half a sub-region beyond the grid
        return max((n / 2.0 + 0.5) * s for n, s in zip(self.n_subregions, self.sizes))  # type: ignore[arg-type]

    def to_dict(self) -> dict[str, Any]:
        d = asdict(self)
        d["n_subregions"] = list(self.n_subregions)  # type: ignore[arg-type]
        return d


# --------------------------------------------------------------------------------------------------
# gradients and angles


def smooth_volume(volume: np.ndarray, sigma_t: float, sigma_s: float) -> np.ndarray:
    """Separable Gaussian smoothing, float32; beyond the border the edge value is repeated.

    Kernels are cut at ``SMOOTH_TRUNCATE`` sigma and normalised to sum 1 (so constant and linear
    intensity profiles are preserved away from the border).
    """
    import cv2

    vol = np.asarray(volume, dtype=np.float32)
    if sigma_s > 0:
        k = 2 * math.ceil(SMOOTH_TRUNCATE * sigma_s) + 1
        vol = np.stack(
            [
                cv2.GaussianBlur(f, (k, k), sigma_s, sigmaY=sigma_s, borderType=cv2.BORDER_REPLICATE)
                for f in vol
            ]
        )
    if sigma_t > 0 and vol.shape[0] > 1:
        rad = math.ceil(SMOOTH_TRUNCATE * sigma_t)
        x = np.arange(-rad, rad + 1)
        w = np.exp(-(x * x) / (2.0 * sigma_t * sigma_t))
        w = (w / w.sum()).astype(np.float32)
        T = vol.shape[0]
        idx = np.arange(T)
        out = np.zeros_like(vol)
        for k, wk in zip(x, w):
            out += wk * vol[np.clip(idx + k, 0, T - 1)]
        vol = out
    return vol


def central_difference(v: np.ndarray, axis: int) -> np.ndarray:
    """v[i+1] - v[i-1] (not halved); on the first/last plane the one-sided difference times 2."""
    v = np.moveaxis(v, axis, 0)
    out = np.zeros_like(v)
    if v.shape[0] >= 2:
        out[1:-1] = v[2:] - v[:-2]
        out[0] = 2 * (v[1] - v[0])
        out[-1] = 2 * (v[-1] - v[-2])
    return np.moveaxis(out, 0, axis)


def gradients(
    volume: np.ndarray, smooth_sigma: float = 0.0, smooth_sigma_t: float | None = None
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(Lx, Ly, Lt) of a (frames, height, width) volume: x = column, y = up (towards row 0), t = frame."""
    vol = np.asarray(volume)
    if vol.ndim != 3:
        raise InputError(f"volume: expected (frames, height, width), got shape {vol.shape}")
    st = smooth_sigma if smooth_sigma_t is None else smooth_sigma_t
    vol = smooth_volume(vol, st, smooth_sigma)
    return central_difference(vol, 2), -central_difference(vol, 1), central_difference(vol, 0)


def gradient_angles(gx: np.ndarray, gy: np.ndarray, gt: np.ndarray) -> tuple[np.ndarray, ...]:
    """Magnitude m, azimuth theta = atan2(Ly, Lx) and elevation phi = atan2(Lt, sqrt(Lx^2 + Ly^2))."""
    r = np.sqrt(gx * gx + gy * gy)
    return np.sqrt(r * r + gt * gt), np.arctan2(gy, gx), np.arctan2(gt, r)


def bin_solid_angles(n_theta: int = 8, n_phi: int = 4) -> np.ndarray:
    """Solid angle of each (theta, phi) bin, shape (n_theta, n_phi); they sum to 4 pi.

    theta bins split [-pi, pi) evenly, phi (elevation) bins split [-pi/2, pi/2] evenly; the band between
    elevations phi1 < phi2 spans dtheta * (sin phi2 - sin phi1) steradians.
    """
    edges = np.linspace(-np.pi / 2, np.pi / 2, n_phi + 1)
    band = (2 * np.pi / n_theta) * np.diff(np.sin(edges))
    return np.broadcast_to(band, (n_theta, n_phi)).copy()


def bin_centres(n_theta: int = 8, n_phi: int = 4) -> tuple[np.ndarray, np.ndarray]:
    """Centre angles (theta, phi) of the orientation bins."""
    dth, dph = 2 * np.pi / n_theta, np.pi / n_phi
    return -np.pi + (np.arange(n_theta) + 0.5) * dth, -np.pi / 2 + (np.arange(n_phi) + 0.5) * dph


def direction(theta: np.ndarray, phi: np.ndarray) -> np.ndarray:
    """Unit vector (x, y, t) of azimuth theta and elevation phi."""
    theta, phi = np.asarray(theta), np.asarray(phi)
    return np.stack([np.cos(theta) * np.cos(phi), np.sin(theta) * np.cos(phi), np.sin(phi)], axis=-1)


def rotation_matrix(theta: np.ndarray | float, phi: np.ndarray | float) -> np.ndarray:
    """Thesis eq. 7, M = Rz(theta) Ry(-phi): M e_x is the direction (theta, phi); M^T undoes it."""
    theta, phi = np.asarray(theta, dtype=np.float64), np.asarray(phi, dtype=np.float64)
    ct, st, cp, sp = np.cos(theta), np.sin(theta), np.cos(phi), np.sin(phi)
    z = np.zeros_like(ct)
    return np.stack(
        [
            np.stack([ct * cp, -st, -ct * sp], -1),
            np.stack([st * cp, ct, -st * sp], -1),
            np.stack([sp, z, cp], -1),
        ],
        -2,
    )


def orientation_bins(
    theta: np.ndarray, phi: np.ndarray, n_theta: int = 8, n_phi: int = 4
) -> tuple[np.ndarray, np.ndarray]:
    """Soft (bilinear) orientation binning: the 4 bins of each direction and their weights / solid angle.

    theta is linear between neighbouring bin centres and wraps at +-pi; phi is linear between centres
    and clamped beyond the outermost centres (everything nearer a pole than the polar bin's centre goes
    to that bin). Bin index = i_theta * n_phi + i_phi. Returns (index, weight), each shaped (4, ...);
    the four indices of a direction are distinct, so they can be scattered with plain assignment.
    """
    theta, phi = np.asarray(theta), np.asarray(phi)
    dt = theta.dtype if np.issubdtype(theta.dtype, np.floating) else np.dtype(np.float64)
    f = dt.type
    # (theta + pi) / dtheta - 1/2: coordinate in units of bins, bin centres at integers
    ut = theta * f(n_theta / (2 * np.pi)) + f(n_theta / 2 - 0.5)
    fl = np.floor(ut)
    ft = ut - fl
    # ut >= -1/2, so floor >= -1: wrap with a select, cheaper than masked updates or an integer modulo
    i0 = np.where(fl < 0, fl + n_theta, fl).astype(np.int32)
    i1 = np.where(i0 == n_theta - 1, 0, i0 + 1).astype(np.int32)
    up = phi * f(n_phi / np.pi) + f(n_phi / 2 - 0.5)
    np.clip(up, 0, n_phi - 1, out=up)
    j0f = np.minimum(np.floor(up), f(n_phi - 2))
    fp = up - j0f  # stays in the input precision (float32 - int32 would promote to float64)
    j0 = j0f.astype(np.int32)
    inv_omega = (1.0 / bin_solid_angles(n_theta, n_phi)[0]).astype(dt)
    b0 = (1 - fp) * inv_omega[j0]
    b1 = fp * inv_omega[j0 + 1]
    a0 = 1 - ft
    idx = np.empty((4, *theta.shape), dtype=np.int32)
    wt = np.empty((4, *theta.shape), dtype=dt)
    np.multiply(i0, n_phi, out=idx[0])
    np.add(idx[0], j0, out=idx[0])
    np.add(idx[0], 1, out=idx[1])
    np.multiply(i1, n_phi, out=idx[2])
    np.add(idx[2], j0, out=idx[2])
    np.add(idx[2], 1, out=idx[3])
    np.multiply(a0, b0, out=wt[0])
    np.multiply(a0, b1, out=wt[1])
    np.multiply(ft, b0, out=wt[2])
    np.multiply(ft, b1, out=wt[3])
    return idx, wt


def orientation_weights(theta: np.ndarray, phi: np.ndarray, n_theta: int = 8, n_phi: int = 4) -> np.ndarray:
    """Dense form of :func:`orientation_bins`: shape (..., n_theta * n_phi)."""
    idx, wt = orientation_bins(theta, phi, n_theta, n_phi)
    K = n_theta * n_phi
    out = np.zeros((wt[0].size, K), dtype=wt.dtype)
    rows = np.arange(wt[0].size)
    for k in range(4):
        out[rows, idx[k].reshape(-1)] = wt[k].reshape(-1)
    return out.reshape(*np.shape(theta), K)


# --------------------------------------------------------------------------------------------------
# the descriptor


def ball_offsets(radius: float) -> np.ndarray:
    """Integer (dt, dr, dc) with dt^2 + dr^2 + dc^2 <= radius^2, in C order of (dt, dr, dc)."""
    r = math.floor(radius)
    g = np.arange(-r, r + 1)
    dt, dr, dc = np.meshgrid(g, g, g, indexing="ij")
    keep = dt**2 + dr**2 + dc**2 <= radius * radius + 1e-9
    return np.stack([dt[keep], dr[keep], dc[keep]], axis=1)


def check_points(volume: np.ndarray, points: Any) -> np.ndarray:
    """``points`` as an (n, 3) int64 array of (frame, row, column) inside ``volume``; raises
    :class:`InputError` for another shape, non-integer or out-of-volume coordinates."""
    pts = np.asarray(points)
    if pts.size == 0:
        return np.zeros((0, 3), dtype=np.int64)
    if pts.ndim != 2 or pts.shape[1] != 3:
        raise InputError(f"points: expected an (n, 3) array of (frame, row, column), got shape {pts.shape}")
    if not np.issubdtype(pts.dtype, np.integer) and (
        not np.all(np.isfinite(pts)) or not np.array_equal(pts, np.round(pts))
    ):
        raise InputError("points: expected integer (frame, row, column) coordinates")
    pts = pts.astype(np.int64)
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    if np.any(lo < 0) or np.any(hi >= np.asarray(volume.shape)):
        raise InputError(f"points: coordinates outside the volume of shape {volume.shape}")
    return pts


def check_volume(volume: Any) -> np.ndarray:
    """``volume`` as a non-empty real (frames, height, width) array; raises :class:`InputError` otherwise."""
    vol = np.asarray(volume)
    if vol.ndim != 3 or min(vol.shape) < 1:
        raise InputError(f"volume: expected a non-empty (frames, height, width) array, got shape {vol.shape}")
    if not np.issubdtype(vol.dtype, np.number) or np.issubdtype(vol.dtype, np.complexfloating):
        raise InputError(f"volume: expected real numbers, got dtype {vol.dtype}")
    return vol


def describe(
    volume: np.ndarray,
    points: np.ndarray,
    variant: str = "thesis",
    params: Any = None,
    **overrides: Any,
) -> np.ndarray:
    """3D SIFT descriptors of ``points`` (n, 3 ints: frame, row, column) in ``volume`` (frames, h, w).

    A shortcut to :func:`vidstyle.features.descriptors.get_descriptor` ``(variant, params).describe``.
    Returns (n, d): float32 with d = ``params.dim`` (256 by default) for ``variant="thesis"``; uint8 with
    d = 640 for ``variant="scovanner2007"`` (which takes no parameters). Keyword ``overrides`` replace
    fields of ``params`` (e.g. ``n_subregions=4``).
    """
    from .descriptors import get_descriptor

    if overrides:
        if variant == "scovanner2007":
            raise InputError("variant scovanner2007: takes no parameters (it is fixed by the released code)")
        if params is None:
            params = get_descriptor(variant).params  # type: ignore[attr-defined]
        params = replace(params, **overrides)
    return get_descriptor(variant, params).describe(volume, points)


def dominant_orientation(
    volume: np.ndarray, points: np.ndarray, params: Sift3DParams | None = None, **overrides: Any
) -> tuple[np.ndarray, np.ndarray]:
    """Dominant gradient direction (theta, phi) around each point, as used by the thesis variant."""
    vol = check_volume(volume)
    pts = check_points(vol, points)
    p = replace(params if params is not None else Sift3DParams(), rotate=True, **overrides)
    theta = np.zeros(len(pts))
    phi = np.zeros(len(pts))
    for idx, arrays in neighbourhood_batches(vol, pts, p):
        _, c = describe_batch(*arrays, p)
        theta[idx] = np.arctan2(c[:, 1], c[:, 0])
        phi[idx] = np.arctan2(c[:, 2], np.hypot(c[:, 0], c[:, 1]))
    return theta, phi


def neighbourhood_batches(vol: np.ndarray, pts: np.ndarray, p: Sift3DParams):
    """Yield (indices into pts, (gradients (P, 3, N) in x, y, t, offsets (3, N) in x, y, t, gauss (N,)))."""
    T, H, W = vol.shape
    offs = ball_offsets(p.sample_radius)
    R = int(np.abs(offs).max()) if len(offs) else 0
    # offsets in (x, y, t): y counts upwards, i.e. against the row index
    xyt = np.ascontiguousarray(np.stack([offs[:, 2], -offs[:, 1], offs[:, 0]]).astype(np.float32))
    sig = p.gaussian_sigma
    gauss = np.exp(-(offs.astype(np.float64) ** 2).sum(1) / (2 * sig * sig)).astype(np.float32)
    sig_t, sig_s = p.smooth_sigmas
    kt = math.ceil(SMOOTH_TRUNCATE * sig_t) if sig_t > 0 else 0
    Hp, Wp = H + 2 * R, W + 2 * R
    flat_off = (offs[:, 0] * Hp + offs[:, 1]) * Wp + offs[:, 2]

    order = np.argsort(pts[:, 0], kind="stable")
    frames = pts[order, 0]
    start = 0
    while start < len(order):
        f0 = int(frames[start])
        stop = int(np.searchsorted(frames, f0 + p.chunk_frames, side="left"))
        f1 = int(frames[stop - 1]) + 1
        # margins: R for the samples, 1 for the central difference, kt for the temporal smoothing, so
        # that the slab's gradients equal those of the whole volume wherever they are sampled
        a, b = max(f0 - R - 1 - kt, 0), min(f1 + R + 1 + kt, T)
        gx, gy, gt = gradients(vol[a:b], sig_s, sig_t)
        # zero padding: samples outside the volume have no gradient, i.e. they are skipped
        g = np.zeros((b - a + 2 * R, Hp, Wp, 3), dtype=np.float32)
        g[R : R + b - a, R : R + H, R : R + W] = np.stack([gx, gy, gt], axis=-1)
        g = g.reshape(-1, 3)
        for s in range(start, stop, p.batch_points):
            sel = order[s : min(s + p.batch_points, stop)]
            q = pts[sel]
            base = ((q[:, 0] - a + R) * Hp + (q[:, 1] + R)) * Wp + (q[:, 2] + R)
            samples = np.take(g, base[:, None] + flat_off[None, :], axis=0)
            yield sel, (np.ascontiguousarray(samples.transpose(0, 2, 1)), xyt, gauss)
        start = stop


def describe_batch(
    g: np.ndarray, xyt: np.ndarray, gauss: np.ndarray, p: Sift3DParams
) -> tuple[np.ndarray, np.ndarray]:
    """Descriptors (P, d) and dominant directions (P, 3) of gathered neighbourhoods g (P, 3, N)."""
    P, _, N = g.shape
    nth, nph = p.n_theta, p.n_phi
    K = nth * nph
    gx, gy, gt = g[:, 0], g[:, 1], g[:, 2]
    r = np.sqrt(gx * gx + gy * gy)
    m = np.sqrt(r * r + gt * gt)
    w = m * gauss
    c = np.tile(np.array([1.0, 0.0, 0.0], dtype=np.float32), (P, 1))
    if p.rotate:
        idx, wt = orientation_bins(np.arctan2(gy, gx), np.arctan2(gt, r), nth, nph)
        idx += (np.arange(P, dtype=np.int32) * K)[:, None]
        hist = np.bincount(idx.reshape(-1), (wt * w).reshape(-1), minlength=P * K).reshape(P, K)
        peak = np.argmax(hist, axis=1)
        tc, pc = bin_centres(nth, nph)
        c = direction(tc[peak // nph], pc[peak % nph]).astype(np.float32)
        with np.errstate(invalid="ignore", divide="ignore"):
            u = np.where(m[:, None, :] > 0, g / m[:, None, :], np.float32(0))
        if p.mean_shift_start == "bin-mean":
            # start from the mean direction of the samples in the peak bin, each weighted by its soft
            # share of that bin: a continuous function of the data (unlike the bin centre), already
            # near the mode, so that the mean shift needs a few iterations instead of dozens
            share = (wt * (idx == (peak + np.arange(P) * K)[:, None])).sum(0) * w
            new = np.matmul(u, share[:, :, None])[:, :, 0]
            norm = np.sqrt((new * new).sum(1, keepdims=True))
            c = np.where(norm > 0, new / np.where(norm > 0, norm, 1), c)
        kappa = np.float32(p.kappa)
        for _ in range(p.mean_shift_iterations):
            cos = np.matmul(c[:, None, :], u)[:, 0, :]
            k = np.exp(kappa * (cos - 1)) * w
            new = np.matmul(u, k[:, :, None])[:, :, 0]
            norm = np.sqrt((new * new).sum(1, keepdims=True))
            c = np.where(norm > 0, new / np.where(norm > 0, norm, 1), c)
        th0 = np.arctan2(c[:, 1], c[:, 0])
        ph0 = np.arctan2(c[:, 2], np.hypot(c[:, 0], c[:, 1]))
        Mt = rotation_matrix(th0, ph0).astype(np.float32).transpose(0, 2, 1)
        g = np.matmul(Mt, g)
        pos = np.matmul(Mt, xyt)
        gx, gy, gt = g[:, 0], g[:, 1], g[:, 2]
        r = np.sqrt(gx * gx + gy * gy)
    else:
        pos = np.broadcast_to(xyt, (P, *xyt.shape))
    idx, wt = orientation_bins(np.arctan2(gy, gx), np.arctan2(gt, r), nth, nph)
    O = np.zeros((P * N, K), dtype=np.float32)
    idx += np.arange(0, P * N * K, K, dtype=np.int32).reshape(P, N)
    O.reshape(-1)[idx.reshape(-1)] = wt.reshape(-1)

    nt, ny, nx = p.n_subregions  # type: ignore[misc]
    st, sy, sx = p.sizes

    def tri(coord: np.ndarray, n: int, size: float) -> np.ndarray:
        u = coord * np.float32(1.0 / size) + np.float32(n / 2.0 - 0.5)
        return np.maximum(1 - np.abs(u[:, None, :] - np.arange(n, dtype=np.float32)[:, None]), 0)

    ax, ay, at = tri(pos[:, 0], nx, sx), tri(pos[:, 1], ny, sy), tri(pos[:, 2], nt, st)
    S = (at[:, :, None, None, :] * ay[:, None, :, None, :]) * (ax * w[:, None, :])[:, None, None, :, :]
    hist = np.matmul(S.reshape(P, nt * ny * nx, N), O.reshape(P, N, K)).reshape(P, -1)
    return normalise_sift(hist, p.clip), c


def normalise_sift(hist: np.ndarray, clip: float = 0.2) -> np.ndarray:
    """L2-normalise rows, clip at ``clip``, L2-normalise again (Lowe 2004); zero rows stay zero."""
    h = np.asarray(hist, dtype=np.float32)
    for i in range(2):
        n = np.sqrt((h.astype(np.float64) ** 2).sum(axis=1, keepdims=True)).astype(np.float32)
        h = np.divide(h, n, out=np.zeros_like(h), where=n > 0)
        if i == 0:
            h = np.minimum(h, np.float32(clip))
    return h
