"""3D SIFT as the authors' released code computes it (``describe(..., variant="scovanner2007")``).

This differs from the paper (Scovanner, Ali, Shah 2007) and from the thesis variant in
:mod:`vidstyle.features.sift3d`; the definition below was established by reading that code. With the
volume I indexed as I(r, c, t) (row, column, frame) and computed in float64:

- Gradient per voxel, no smoothing, raw differences (not halved):
  g1 = I(r, c+1, t) - I(r, c-1, t); g2 = I(r-1, c, t) - I(r+1, c, t) (positive towards row 0);
  g3 = I(r, c, t+1) - I(r, c, t-1). On the first/last plane of an axis the one-sided difference times 2,
  e.g. g1(c=0) = 2 * (I(c=1) - I(c=0)), g2(r=0) = 2 * (I(r=0) - I(r=1)). An axis of length 1 has zero
  gradient. Magnitude m = sqrt(g1*g1 + g2*g2 + g3*g3), direction u = g / m (each component divided by m);
  voxels with m = 0 are skipped.
- 80 orientation bins: the faces of the unit icosahedron, vertices the cyclic permutations of
  (+-a, +-b, 0) with a = phi / sqrt(1 + phi^2), b = 1 / sqrt(1 + phi^2), phi the golden ratio, evaluated in
  float64 exactly like that (rounded constants move samples across bin boundaries). Each face is split
  once into four at its edge midpoints, the midpoints pushed onto the unit sphere; a bin's direction is
  its face's centroid normalised, c = (v1 + v2 + v3) / sqrt(c . c).
- Each voxel goes to its 3 bins of largest cosine d_k = u1*c1 + u2*c2 + u3*c3 (evaluated in that order,
  no fused multiply-add), ties broken by the lower bin index, in decreasing order of d; weights
  w_k = d_k^20 / (d_(1)^20 + d_(2)^20 + d_(3)^20) (sum in that order, powers by the C library's ``pow``,
  as Python's ``float ** 20``). No solid-angle normalisation, no dominant orientation, no rotation.
- Neighbourhood: offsets -6..+6 on every axis (13^3 voxels) around the point, visited with the frame
  offset outermost, then row, then column; samples outside the volume are skipped. Each adds
  m * G * w_k (left to right) with G = exp(-(dr^2 + dc^2 + dt^2) / (2 * 5^2)) (C library ``exp``).
- Sub-regions 2x2x2 with hard assignment, per axis offsets -6..-1 -> 0 and 0..+6 -> 1. Descriptor
  layout: index ((s_t * 2 + s_r) * 2 + s_c) * 80 + bin, bins in the order of :func:`orientation_bins`.
- 640 values: L2-normalise (divide by the square root of the sum of squares accumulated in index
  order), entries above 0.2 set to 0.2, L2-normalise again, times 512, rounded half away from zero,
  capped at 255, uint8. An all-zero histogram gives all zeros.

Accumulation happens sample by sample in the visiting order above, in a compiled loop (numba, no
fast-math) that makes the same additions in the same order as ``np.bincount`` over the flattened
contributions (its numpy reference, :func:`_accumulate_numpy`), so the float64 histograms are
bit-identical to a literal per-sample loop, not just the uint8 result.
Speed: the 3-bin assignment is a per-voxel property (there is no rotation), so it is computed once per
voxel of the neighbourhoods in use, with a pre-selection of candidate bins and the exact element-wise
cosines for the final choice (a compiled loop, :func:`_top3_loop`, checked against its numpy reference).
The voxels a chunk of points reaches and their gradients are found in two compiled passes
(:func:`_chunk_voxels`), and the quantisation is one compiled pass per row (:func:`quantise`); both are
checked bit for bit against their numpy references (:func:`_chunk_voxels_numpy`, :func:`quantise_numpy`).
"""

from __future__ import annotations

import math
from functools import cache

import numpy as np

#: Fixed parameters of this variant (recorded in the .npz ``params``).
PARAMS = {
    "n_bins": 80,
    "half_width": 6,
    "sigma": 5.0,
    "n_subregions": [2, 2, 2],
    "power": 20,
    "clip": 0.2,
    "scale": 512,
    "dim": 640,
}
HALF = 6
SIGMA = 5.0
POWER = 20
N_BINS = 80
DIM = 8 * N_BINS
#: Frames of points handled together (bounds memory for long videos).
CHUNK_FRAMES = 32

_PHI = (1.0 + math.sqrt(5.0)) / 2.0
A = _PHI / math.sqrt(1.0 + _PHI * _PHI)
B = 1.0 / math.sqrt(1.0 + _PHI * _PHI)


@cache
def _icosahedron() -> tuple[np.ndarray, np.ndarray]:
    verts = []
    for sa in (A, -A):
        for sb in (B, -B):
            verts.append((sa, sb, 0.0))
    for sa in (A, -A):
        for sb in (B, -B):
            verts.append((0.0, sa, sb))
    for sa in (A, -A):
        for sb in (B, -B):
            verts.append((sb, 0.0, sa))
    v = np.array(verts, dtype=np.float64)
    # neighbours are at distance 2b (the edge); the next distance is 2a > 2b
    d2 = ((v[:, None, :] - v[None, :, :]) ** 2).sum(-1)
    edge = np.isclose(d2, 4 * B * B)
    faces = []
    n = len(v)
    for i in range(n):
        for j in range(i + 1, n):
            for k in range(j + 1, n):
                if edge[i, j] and edge[j, k] and edge[i, k]:
                    # orient counter-clockwise seen from outside
                    if np.dot(np.cross(v[j] - v[i], v[k] - v[i]), v[i] + v[j] + v[k]) < 0:
                        faces.append((i, k, j))
                    else:
                        faces.append((i, j, k))
    return v, np.array(faces, dtype=np.int64)


def icosahedron() -> tuple[np.ndarray, np.ndarray]:
    """(vertices (12, 3), faces (20, 3) vertex indices, outward counter-clockwise), in (g1, g2, g3)."""
    v, f = _icosahedron()
    return v.copy(), f.copy()


def _unit(x: np.ndarray) -> np.ndarray:
    return x / math.sqrt(float(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]))


@cache
def _bins() -> np.ndarray:
    v, faces = _icosahedron()
    out = []
    for i, j, k in faces:
        p, q, r = v[i], v[j], v[k]
        pq, qr, rp = _unit(p + q), _unit(q + r), _unit(r + p)
        for tri in ((p, pq, rp), (pq, q, qr), (rp, qr, r), (pq, qr, rp)):
            out.append(_unit(tri[0] + tri[1] + tri[2]))
    b = np.array(out, dtype=np.float64)
    b.setflags(write=False)
    return b


def orientation_bins() -> np.ndarray:
    """The 80 bin directions (80, 3): face f of :func:`icosahedron` gives bins 4f..4f+3 (corner
    triangles at its 1st, 2nd, 3rd vertex, then the middle one)."""
    return _bins().copy()


def gradients(volume: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(g1, g2, g3) float64 of a (frames, rows, cols) volume as defined in the module docstring."""
    from .sift3d import central_difference

    vol = np.asarray(volume, dtype=np.float64)
    return central_difference(vol, 2), -central_difference(vol, 1), central_difference(vol, 0)


def _gauss_table() -> np.ndarray:
    # math.exp (the C library), not np.exp (SIMD, differs in the last bit for ~5 % of arguments)
    return np.array([math.exp(-d2 / (2 * SIGMA**2)) for d2 in range(3 * HALF * HALF + 1)])


def _offsets() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Offsets (N, 3) (dt, dr, dc) in visiting order, their Gaussian weight, their sub-region index."""
    g = np.arange(-HALF, HALF + 1)
    dt, dr, dc = (a.reshape(-1) for a in np.meshgrid(g, g, g, indexing="ij"))
    gauss = _gauss_table()[dt * dt + dr * dr + dc * dc]
    sub = ((dt >= 0) * 2 + (dr >= 0)) * 2 + (dc >= 0)
    return np.stack([dt, dr, dc], axis=1), gauss, sub


#: Resolution of the cube map that lists candidate bins per direction cell (cells of about 2.8 degrees).
CUBE_RES = 32


@cache
def _candidate_table() -> tuple[np.ndarray, int]:
    """Per cube-map cell, the bins that can be among the top 3 for some direction in the cell.

    Cell (face, i, j) of the cube map is the gnomonic image of a square; every direction in it lies
    within angle rho of the cell's centre direction u0 (the maximum is at a corner, as the angular
    distance from u0 has convex level sets in gnomonic coordinates). For u in the cell the cosine to a
    bin at angle alpha from u0 lies in [cos(alpha + rho), cos(alpha - rho)]; at least three bins reach
    L3, the third largest lower bound, so a bin whose upper bound is below L3 can never be in the top 3
    nor tie with the third. Rows padded with -1, candidates in increasing bin index.
    """
    C = _bins()
    n = CUBE_RES
    edges = np.linspace(-1.0, 1.0, n + 1)
    mids = (edges[:-1] + edges[1:]) / 2
    lists = []
    for face in range(6):  # all cells of a face at once, in the order (face, i, j)
        corners = _cube_dirs(face, edges[:, None], edges[None, :])  # (n + 1, n + 1, 3)
        u0 = _cube_dirs(face, mids[:, None], mids[None, :]).reshape(-1, 3)  # (n * n, 3)
        cos_corner = np.stack([np.einsum("cd,cd->c", u0, corners[a:a + n, b:b + n].reshape(-1, 3))
                               for a in (0, 1) for b in (0, 1)], axis=1)
        rho = np.arccos(np.minimum(1.0, cos_corner)).max(axis=1) + 1e-6  # (n * n,)
        alpha = np.arccos(np.clip(u0 @ C.T, -1.0, 1.0))  # (n * n, bins)
        lower = np.cos(np.minimum(alpha + rho[:, None], np.pi))
        upper = np.cos(np.maximum(alpha - rho[:, None], 0.0))
        l3 = np.sort(lower, axis=1)[:, -3]
        ok = upper >= (l3 - 1e-9)[:, None]
        lists.extend(np.flatnonzero(row) for row in ok)
    k = max(len(x) for x in lists)
    table = np.full((len(lists), k), -1, dtype=np.int64)
    for r, x in enumerate(lists):
        table[r, : len(x)] = x
    return table, k


def _cube_dirs(face: int, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Unit directions (..., 3) through the points ``(x, y)`` (broadcast) of cube face ``face`` (axis
    ``face // 2``, at +1 for even faces, -1 for odd ones; ``x``, ``y`` the other two axes in order)."""
    axis, sign = divmod(face, 2)
    x, y = np.broadcast_arrays(np.asarray(x, dtype=np.float64), np.asarray(y, dtype=np.float64))
    v = np.empty(x.shape + (3,))
    v[..., axis] = 1.0 if sign == 0 else -1.0
    others = [a for a in range(3) if a != axis]
    v[..., others[0]], v[..., others[1]] = x, y
    return v / np.sqrt((v * v).sum(axis=-1))[..., None]


def _cube_cell(u1: np.ndarray, u2: np.ndarray, u3: np.ndarray) -> np.ndarray:
    u = np.stack([u1, u2, u3], axis=1)
    axis = np.argmax(np.abs(u), axis=1)
    rows = np.arange(len(u))
    major = u[rows, axis]
    sign = (major < 0).astype(np.int64)
    o0 = np.where(axis == 0, 1, 0)
    o1 = np.where(axis == 2, 1, 2)
    n = CUBE_RES
    # the cell containing the point's projection; rounding can only move it across a cell edge by far
    # less than the 1e-6 rad margin of the table
    x = np.clip(np.floor((u[rows, o0] / np.abs(major) + 1) * (n / 2)), 0, n - 1).astype(np.int64)
    y = np.clip(np.floor((u[rows, o1] / np.abs(major) + 1) * (n / 2)), 0, n - 1).astype(np.int64)
    return ((axis * 2 + sign) * n + x) * n + y


def _libm_pow_py(a: np.ndarray, p: float) -> np.ndarray:
    return np.array([x**p for x in a.tolist()], dtype=np.float64)


def _libm_pow_loop(a, p):  # compiled by numba: a[i] ** p with a float exponent is one call to the C pow
    out = np.empty_like(a)
    for i in range(a.size):
        out[i] = a[i] ** p
    return out


def _compiled(loop, fallback):
    """``loop`` compiled (:func:`vidstyle.compiled.compile_kernel`), or ``fallback`` without numba."""
    from ..compiled import compile_kernel

    return compile_kernel(loop, fallback)


@cache
def _pow_kernel():
    """The compiled ``_libm_pow_loop``, or the Python loop without numba. Both call the C library's pow
    once per element, so the results are the same to the last bit."""
    return _compiled(_libm_pow_loop, _libm_pow_py)


def _libm_pow(a: np.ndarray, p: float) -> np.ndarray:
    """``a ** p`` elementwise (float64, float exponent) exactly as Python's float power computes it."""
    return _pow_kernel()(np.ascontiguousarray(a, dtype=np.float64), float(p))


def _accumulate_loop(hist, base, flat_off, gauss, sub, slot, m, bins, w, n_bins):
    # compiled by numba: hist[p, sub[n] * n_bins + bin_k] += (m * G) * w_k for every point p, sample n in
    # visiting order and k = 0, 1, 2 -- per histogram entry the same additions in the same order as
    # np.bincount over the flattened (p, n, k) targets, without materialising them. ``slot`` maps a padded
    # voxel to its row of the compact m / bins / w (-1: outside the volume, which would add +0.0 and
    # leave every sum unchanged, so it is skipped)
    for p in range(base.shape[0]):
        for n in range(flat_off.shape[0]):
            j = slot[base[p] + flat_off[n]]
            if j < 0:
                continue
            mg = m[j] * gauss[n]
            s = sub[n] * n_bins
            for k in range(3):
                hist[p, s + bins[j, k]] += mg * w[j, k]


def _accumulate_numpy(hist, base, flat_off, gauss, sub, slot, m, bins, w, n_bins):
    """The same as :func:`_accumulate_loop` with numpy: the (P, N, 3) contributions and targets, summed
    by ``np.bincount`` (which adds in input order); the reference of the compiled kernel."""
    P = len(base)
    j = slot[base[:, None] + flat_off[None, :]]  # (P, N) rows in visiting order, -1 outside
    inside = j >= 0
    jj = np.where(inside, j, 0)
    mg = np.where(inside, m[jj], 0.0) * gauss[None, :]  # m * G (+0.0 outside)
    contrib = mg[:, :, None] * w[jj]  # (m * G) * w_k
    target = (np.arange(P)[:, None, None] * hist.shape[1] + sub[None, :, None] * n_bins) + bins[jj]
    # samples outside the volume add (+0.0), which leaves every sum unchanged
    hist += np.bincount(target.reshape(-1), contrib.reshape(-1), minlength=hist.size).reshape(hist.shape)


def gradients_at(vol: np.ndarray, t: np.ndarray, r: np.ndarray, c: np.ndarray, t_lo: int, t_hi: int):
    """(g1, g2, g3) of :func:`gradients` at the voxels (t, r, c) of ``vol`` (any real dtype; the values
    read are converted to float64 first) only, to the bit, where the
    frame axis is taken as the sub-volume ``vol[t_lo:t_hi]`` (one-sided at its ends) and rows and columns
    span the volume: per axis ``v[i+1] - v[i-1]``, and ``2 * (v[i+1] - v[i])`` on an end plane."""

    def diff(i, n, lo_end, hi_end, at):
        hi = np.minimum(i + 1, hi_end - 1)
        lo = np.maximum(i - 1, lo_end)
        d = vol[at(hi)].astype(np.float64) - vol[at(lo)].astype(np.float64)
        if hi_end - lo_end < 2:
            return np.zeros(len(i))
        return np.where(hi - lo == 1, 2 * d, d)

    T, H, W = vol.shape
    g1 = diff(c, W, 0, W, lambda k: (t, r, k))
    g2 = -diff(r, H, 0, H, lambda k: (t, k, c))
    g3 = diff(t, T, t_lo, t_hi, lambda k: (k, r, c))
    return g1, g2, g3


def _mark_loop(q, a, n_t, R, slot):
    # compiled by numba: the voxels of frames a..a+n_t-1 (rows, columns: all) that some point's cube
    # (offsets -R..R, clipped to the volume) reaches get slot -2 in the padded map (-1 elsewhere); returns
    # how many there are
    H, W = slot.shape[1] - 2 * R, slot.shape[2] - 2 * R
    n = 0
    for p in range(q.shape[0]):
        t, r, c = q[p, 0] - a, q[p, 1], q[p, 2]
        for tt in range(max(t - R, 0), min(t + R + 1, n_t)):
            for rr in range(max(r - R, 0), min(r + R + 1, H)):
                for cc in range(max(c - R, 0), min(c + R + 1, W)):
                    if slot[tt + R, rr + R, cc + R] == -1:
                        slot[tt + R, rr + R, cc + R] = -2
                        n += 1
    return n


def _gradient_loop(vol, a, n_t, t_lo, t_hi, R, slot, g1, g2, g3):
    # compiled by numba: numbers the marked voxels (slot -2) in raster order (frame, row, column) and
    # writes their gradients as gradients_at computes them: the voxels read converted to float64, per
    # axis v[i+1] - v[i-1], 2 * (v[i+1] - v[i]) on an end plane, zero along an axis shorter than 2 (g2
    # the negation, so -0.0 there as well); frames span t_lo..t_hi-1, rows and columns the volume
    T, H, W = vol.shape
    j = 0
    for tt in range(n_t):
        t = tt + a
        for r in range(H):
            for c in range(W):
                if slot[tt + R, r + R, c + R] != -2:
                    continue
                slot[tt + R, r + R, c + R] = j
                if W < 2:
                    g1[j] = 0.0
                else:
                    hi, lo = min(c + 1, W - 1), max(c - 1, 0)
                    d = np.float64(vol[t, r, hi]) - np.float64(vol[t, r, lo])
                    g1[j] = 2 * d if hi - lo == 1 else d
                if H < 2:
                    g2[j] = -0.0
                else:
                    hi, lo = min(r + 1, H - 1), max(r - 1, 0)
                    d = np.float64(vol[t, hi, c]) - np.float64(vol[t, lo, c])
                    g2[j] = -(2 * d if hi - lo == 1 else d)
                if t_hi - t_lo < 2:
                    g3[j] = 0.0
                else:
                    hi, lo = min(t + 1, t_hi - 1), max(t - 1, t_lo)
                    d = np.float64(vol[hi, r, c]) - np.float64(vol[lo, r, c])
                    g3[j] = 2 * d if hi - lo == 1 else d
                j += 1


@cache
def _voxel_kernels():
    """The compiled :func:`_mark_loop` and :func:`_gradient_loop`, or None without numba (then
    :func:`_chunk_voxels_numpy` runs)."""
    mark, grad = _compiled(_mark_loop, None), _compiled(_gradient_loop, None)
    return None if mark is None or grad is None else (mark, grad)


def _chunk_voxels_numpy(vol, q, a, b, ga, gb):
    """The voxels of frames a..b-1 that some point of ``q`` (frame, row, column) reaches with its cube
    (clipped to the volume), in raster order: their slot map (b - a + 2R, H + 2R, W + 2R) int32 (-1: no
    voxel) and their gradients (:func:`gradients_at` with frames ga..gb-1). The reference of
    :func:`_chunk_voxels`."""
    R = HALF
    _, H, W = vol.shape
    need = np.zeros((b - a, H, W), dtype=bool)
    for t, r, c in (q - (a, 0, 0)).tolist():  # each point's cube, clipped to the volume
        need[max(t - R, 0):t + R + 1, max(r - R, 0):r + R + 1, max(c - R, 0):c + R + 1] = True
    vox = np.flatnonzero(need)
    tt, rr, cc = np.unravel_index(vox, need.shape)
    g = gradients_at(vol, tt + a, rr, cc, ga, gb)
    slot = np.full((b - a + 2 * R, H + 2 * R, W + 2 * R), -1, dtype=np.int32)
    slot[tt + R, rr + R, cc + R] = np.arange(len(vox))
    return slot, g


def _chunk_voxels(vol, q, a, b, ga, gb):
    """:func:`_chunk_voxels_numpy` in two compiled passes over the chunk (mark the cubes, then number
    the marked voxels and compute their gradients), without the index arrays and fancy indexing; the
    same slot map and gradients to the bit."""
    kernels = _voxel_kernels()
    if kernels is None:  # pragma: no cover - numba is a dependency
        return _chunk_voxels_numpy(vol, q, a, b, ga, gb)
    mark, grad = kernels
    R = HALF
    _, H, W = vol.shape
    slot = np.full((b - a + 2 * R, H + 2 * R, W + 2 * R), -1, dtype=np.int32)
    n = mark(np.ascontiguousarray(q, dtype=np.int64), a, b - a, R, slot)
    g1, g2, g3 = np.empty(n), np.empty(n), np.empty(n)
    grad(vol, a, b - a, ga, gb, R, slot, g1, g2, g3)
    return slot, (g1, g2, g3)


@cache
def _accumulate_kernel():
    """The compiled :func:`_accumulate_loop`, or :func:`_accumulate_numpy` without numba."""
    return _compiled(_accumulate_loop, _accumulate_numpy)


def _top3_loop(u1, u2, u3, cands, C, top, dv):
    # compiled by numba: per voxel the exact cosines ((u1 * c1 + u2 * c2) + u3 * c3, no fused multiply-add)
    # of its candidate bins (-1 = padding: -inf, bin 0), then three times the first maximum, taken out
    # (-inf) after each pick -- what _top3_numpy's repeated np.argmax does
    K = cands.shape[1]
    d = np.empty(K)
    for i in range(cands.shape[0]):
        for c in range(K):
            b = cands[i, c]
            if b >= 0:
                d[c] = u1[i] * C[b, 0] + u2[i] * C[b, 1] + u3[i] * C[b, 2]
            else:
                d[c] = -np.inf
        for k in range(3):
            j = 0
            for c in range(1, K):
                if d[c] > d[j]:
                    j = c
            b = cands[i, j]
            top[i, k] = b if b >= 0 else 0
            dv[i, k] = d[j]
            d[j] = -np.inf


def _top3_numpy(u1, u2, u3, cands, C, top, dv):
    """The same as :func:`_top3_loop` with numpy (the reference of the compiled kernel)."""
    valid = cands >= 0
    cc = np.where(valid, cands, 0)
    # exact cosines, element-wise in the defined order (no BLAS, no fused multiply-add)
    d = u1[:, None] * C[cc, 0] + u2[:, None] * C[cc, 1] + u3[:, None] * C[cc, 2]
    d[~valid] = -np.inf
    rows = np.arange(len(cands))
    for k in range(3):
        j = np.argmax(d, axis=1)  # first maximum = lowest bin index among equal cosines
        top[:, k] = cc[rows, j]
        dv[:, k] = d[rows, j]
        d[rows, j] = -np.inf


@cache
def _top3_kernel():
    """The compiled :func:`_top3_loop`, or :func:`_top3_numpy` without numba."""
    return _compiled(_top3_loop, _top3_numpy)


def _assign_loop(g1, g2, g3, C, table, power, n, m, bins, wts):
    # compiled by numba: assign_bins_numpy voxel by voxel, the same float64 operations in the same order
    # (magnitude ((g1 g1 + g2 g2) + g3 g3) under sqrt, u = g / m, the cube-map cell, the exact cosines of
    # the cell's candidate bins, three first maxima, d ** power through the C library's pow, weights
    # p / ((p0 + p1) + p2)); no fast-math, no fused multiply-add
    K = table.shape[1]
    d = np.empty(K)
    half_n = n / 2
    for i in range(g1.shape[0]):
        a, b, c = g1[i], g2[i], g3[i]
        mi = np.sqrt(a * a + b * b + c * c)
        m[i] = mi
        if not (mi > 0):
            bins[i, 0] = bins[i, 1] = bins[i, 2] = 0
            wts[i, 0] = wts[i, 1] = wts[i, 2] = 0.0
            continue
        u1, u2, u3 = a / mi, b / mi, c / mi
        # the cube-map cell (_cube_cell): the first axis of largest |u|, its sign, the other two
        # coordinates over |major| in n cells of [-1, 1]
        axis, major = 0, u1
        if abs(u2) > abs(major):
            axis, major = 1, u2
        if abs(u3) > abs(major):
            axis, major = 2, u3
        sign = 1 if major < 0 else 0
        if axis == 0:
            p0, p1 = u2, u3
        elif axis == 1:
            p0, p1 = u1, u3
        else:
            p0, p1 = u1, u2
        am = abs(major)
        x = np.floor((p0 / am + 1) * half_n)
        y = np.floor((p1 / am + 1) * half_n)
        x = min(max(x, 0.0), n - 1.0)
        y = min(max(y, 0.0), n - 1.0)
        row = ((axis * 2 + sign) * n + int(x)) * n + int(y)
        for k in range(K):
            bk = table[row, k]
            if bk >= 0:
                d[k] = u1 * C[bk, 0] + u2 * C[bk, 1] + u3 * C[bk, 2]
            else:
                d[k] = -np.inf
        total = 0.0
        for k in range(3):
            j = 0
            for c2 in range(1, K):
                if d[c2] > d[j]:
                    j = c2
            bk = table[row, j]
            bins[i, k] = bk if bk >= 0 else 0
            pk = d[j] ** power
            wts[i, k] = pk
            d[j] = -np.inf
        total = (wts[i, 0] + wts[i, 1]) + wts[i, 2]
        for k in range(3):
            wts[i, k] = wts[i, k] / total


@cache
def _assign_kernel():
    """The compiled :func:`_assign_loop`, or None without numba (then :func:`assign_bins_numpy` runs)."""
    return _compiled(_assign_loop, None)


def assign_bins(g1: np.ndarray, g2: np.ndarray, g3: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per voxel (flat arrays): magnitude (V,), top-3 bins (V, 3) and their weights (V, 3).

    Voxels with zero magnitude get bins 0 and weights 0. Runs the compiled kernel (one pass, no
    (V, candidates) temporaries); :func:`assign_bins_numpy` is its reference, equal to the bit.
    """
    kernel = _assign_kernel()
    if kernel is None:  # pragma: no cover - numba is a dependency
        return assign_bins_numpy(g1, g2, g3)
    g1, g2, g3 = (np.ascontiguousarray(np.asarray(a, dtype=np.float64).reshape(-1)) for a in (g1, g2, g3))
    V = g1.size
    m = np.empty(V)
    bins = np.empty((V, 3), dtype=np.int64)
    wts = np.empty((V, 3), dtype=np.float64)
    table, _ = _candidate_table()
    kernel(g1, g2, g3, _bins(), table, float(POWER), CUBE_RES, m, bins, wts)
    return m, bins, wts


def assign_bins_numpy(g1: np.ndarray, g2: np.ndarray, g3: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`assign_bins` in numpy with the compiled top-3 and pow kernels (the reference)."""
    g1, g2, g3 = (np.asarray(a, dtype=np.float64).reshape(-1) for a in (g1, g2, g3))
    V = g1.size
    m = np.sqrt(g1 * g1 + g2 * g2 + g3 * g3)
    bins = np.zeros((V, 3), dtype=np.int64)
    wts = np.zeros((V, 3), dtype=np.float64)
    nz = np.flatnonzero(m > 0)
    if nz.size == 0:
        return m, bins, wts
    mm = m[nz]
    u1, u2, u3 = g1[nz] / mm, g2[nz] / mm, g3[nz] / mm
    C = _bins()
    table, _ = _candidate_table()
    cands = table[_cube_cell(u1, u2, u3)]  # (V, k), increasing bin index, -1 = padding
    top = np.empty((nz.size, 3), dtype=np.int64)
    dv = np.empty((nz.size, 3), dtype=np.float64)
    _top3_kernel()(u1, u2, u3, np.ascontiguousarray(cands, dtype=np.int64), C, top, dv)
    # d ** 20 through the C library's pow, as the literal definition (Python floats) computes it; numpy's
    # SIMD pow differs from it in the last bit for a few % of arguments
    p = _libm_pow(dv.reshape(-1), float(POWER)).reshape(-1, 3)
    total = (p[:, 0] + p[:, 1]) + p[:, 2]
    bins[nz] = top
    wts[nz] = p / total[:, None]
    return m, bins, wts


def quantise_numpy(hist: np.ndarray) -> np.ndarray:
    """:func:`quantise` in numpy (the reference of the compiled kernel and its fallback without numba)."""
    h = np.asarray(hist, dtype=np.float64)
    out = np.zeros(h.shape, dtype=np.uint8)
    for i in range(2):
        # sequential sum (cumsum) in index order, not numpy's pairwise sum, to match a literal loop
        n = np.sqrt(np.cumsum(h * h, axis=1)[:, -1:]) if h.shape[1] else np.zeros((len(h), 1))
        h = np.divide(h, n, out=np.zeros_like(h), where=n > 0)
        if i == 0:
            h = np.minimum(h, 0.2)
    v = h * 512
    t = np.trunc(v)
    r = t + (v - t >= 0.5)  # half away from zero (all values are >= 0); v - t is exact
    np.minimum(r, 255, out=r)
    out[:] = r.astype(np.uint8)
    return out


def _quantise_loop(h, out):
    # compiled by numba: quantise_numpy row by row, the same float64 operations in the same order (sum of
    # squares from index 0 up, sqrt, divide, or zeros when the norm is not > 0; the clip as np.minimum,
    # NaN kept; times 512, half away from zero, cap 255)
    n, D = h.shape
    row = np.empty(D)
    for i in range(n):
        for k in range(D):
            row[k] = h[i, k]
        for it in range(2):
            acc = 0.0
            for k in range(D):
                acc += row[k] * row[k]
            nrm = np.sqrt(acc)
            if nrm > 0:
                for k in range(D):
                    row[k] = row[k] / nrm
            else:
                for k in range(D):
                    row[k] = 0.0
            if it == 0:
                for k in range(D):
                    x = row[k]
                    if x > 0.2:
                        row[k] = 0.2
        for k in range(D):
            v = row[k] * 512
            t = np.trunc(v)
            r = t + 1.0 if v - t >= 0.5 else t
            if r > 255:
                r = 255.0
            out[i, k] = np.uint8(r)


@cache
def _quantise_kernel():
    """The compiled :func:`_quantise_loop`, or None without numba (then :func:`quantise_numpy` runs)."""
    return _compiled(_quantise_loop, None)


def quantise(hist: np.ndarray) -> np.ndarray:
    """Rows of float64 histograms (n, 640) -> uint8 descriptors as the released code does: L2-normalise
    (the sum of squares accumulated in index order), clip at 0.2, L2-normalise again, times 512, rounded
    half away from zero, capped at 255 (an all-zero row stays zero). One compiled pass
    (:func:`_quantise_loop`); :func:`quantise_numpy` is its reference, equal to the bit."""
    kernel = _quantise_kernel()
    h = np.ascontiguousarray(hist, dtype=np.float64)
    if kernel is None or h.ndim != 2:  # pragma: no cover - numba is a dependency
        return quantise_numpy(h)
    out = np.zeros(h.shape, dtype=np.uint8)
    kernel(h, out)
    return out


def histograms(volume: np.ndarray, points: np.ndarray) -> np.ndarray:
    """The float64 640-bin histograms (before quantisation) of ``points`` (n, 3: frame, row, col)."""
    from .sift3d import check_points, check_volume

    # the volume keeps its dtype: gradients_at converts the voxels it reads to float64 (exactly, before
    # any arithmetic), which spares a float64 copy of the whole window per call
    vol = np.asarray(check_volume(volume))
    pts = check_points(vol, points)
    T, H, W = vol.shape
    out = np.zeros((len(pts), DIM), dtype=np.float64)
    if len(pts) == 0:
        return out
    offs, gauss, sub = _offsets()
    accumulate = _accumulate_kernel()
    R = HALF
    Hp, Wp = H + 2 * R, W + 2 * R
    flat_off = ((offs[:, 0] * Hp + offs[:, 1]) * Wp + offs[:, 2]).astype(np.int64)
    order = np.argsort(pts[:, 0], kind="stable")
    frames = pts[order, 0]
    start = 0
    while start < len(order):
        f0 = int(frames[start])
        stop = int(np.searchsorted(frames, f0 + CHUNK_FRAMES, side="left"))
        f1 = int(frames[stop - 1]) + 1
        a, b = max(f0 - R, 0), min(f1 + R, T)  # frames sampled
        ga, gb = max(a - 1, 0), min(b + 1, T)  # frames their gradients read
        sel = order[start:stop]
        q = pts[sel]
        # only voxels inside some point's cube need a gradient and a bin assignment; the gradients are
        # those of frames ga..gb-1 (the extra frame on each side makes g3 central on frames a..b-1 unless
        # they border the volume)
        slot, (g1, g2, g3) = _chunk_voxels(vol, q, a, b, ga, gb)
        m, bins, wts = assign_bins(g1, g2, g3)
        base = ((q[:, 0] - a + R) * Hp + (q[:, 1] + R)) * Wp + (q[:, 2] + R)
        hist = np.zeros((len(sel), DIM))
        accumulate(hist, base.astype(np.int64), flat_off, gauss, sub, slot.reshape(-1), m, bins, wts, N_BINS)
        out[sel] = hist
        start = stop
    return out


def describe(volume: np.ndarray, points: np.ndarray) -> np.ndarray:
    """uint8 descriptors (n, 640) of ``points`` (n, 3 ints: frame, row, column) in ``volume``."""
    return quantise(histograms(volume, points))


# ------------------------------------------------------------------------------------------ mirror image
@cache
def _mirror_permutation() -> np.ndarray:
    C = _bins()
    flipped = C * np.array([-1.0, 1.0, 1.0])
    match = np.argmax(flipped @ C.T, axis=1)  # bin k of the video is bin match[k] of its mirror image
    if len(set(match.tolist())) != N_BINS:  # pragma: no cover - the icosahedron is symmetric in g1
        raise AssertionError("icosahedral bins are not closed under g1 -> -g1")
    perm = np.empty(DIM, dtype=np.int64)
    for st in range(2):
        for sr in range(2):
            for sc in range(2):
                src = ((st * 2 + sr) * 2 + sc) * N_BINS
                dst = ((st * 2 + sr) * 2 + (1 - sc)) * N_BINS
                perm[dst + match] = src + np.arange(N_BINS)
    perm.setflags(write=False)
    return perm


def mirror_permutation() -> np.ndarray:
    """Index array ``perm`` (640,): ``desc[:, perm]`` is (nearly) the descriptor of the left-right mirror
    image of the video at the mirrored point.

    Mirroring columns negates g1 and leaves g2, g3 alone; the icosahedral bins are closed under
    g1 -> -g1, so every bin has a mirror bin, and the column sub-regions swap. It is exact except for the
    column plane through the point (offset 0), which the hard sub-region split puts on the right side
    in both images: on smooth random video the cosine to the true mirror descriptor has median 0.97
    (0.52 without the permutation). Used to train on the mirror image of every video (a southpaw seen
    from the mirrored view) without computing features twice.
    """
    return _mirror_permutation().copy()


def mirror_descriptors(desc: np.ndarray) -> np.ndarray:
    """Descriptors (n, 640) of the mirror image; see :func:`mirror_permutation`."""
    desc = np.asarray(desc)
    if desc.ndim != 2 or desc.shape[1] != DIM:
        raise ValueError(f"scovanner2007 descriptors are (n, {DIM}), got {desc.shape}")
    return desc[:, _mirror_permutation()]
