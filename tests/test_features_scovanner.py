"""3D SIFT as the authors' released code computes it: bit-exact against a literal per-sample reference."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from scipy.spatial import ConvexHull

from vidstyle.errors import InputError
from vidstyle.features import scovanner2007 as sc
from vidstyle.features.sift3d import describe

# --- literal reference: one sample at a time, Python floats -------------------------------------------


def ref_gradient(vol, t, r, c):
    T, H, W = vol.shape

    def diff(lo, hi, n, i):  # lo(i) / hi(i) read the neighbour below / above along the axis
        if n == 1:
            return 0.0
        if i == 0:
            return 2 * (hi(1) - hi(0))
        if i == n - 1:
            return 2 * (hi(n - 1) - hi(n - 2))
        return hi(i + 1) - hi(i - 1)

    g1 = diff(None, lambda k: float(vol[t, r, k]), W, c)
    # g2 is positive towards row 0: I(r-1) - I(r+1), and on the border planes 2 * (I(0) - I(1)) etc.
    if H == 1:
        g2 = 0.0
    elif r == 0:
        g2 = 2 * (float(vol[t, 0, c]) - float(vol[t, 1, c]))
    elif r == H - 1:
        g2 = 2 * (float(vol[t, H - 2, c]) - float(vol[t, H - 1, c]))
    else:
        g2 = float(vol[t, r - 1, c]) - float(vol[t, r + 1, c])
    g3 = diff(None, lambda k: float(vol[k, r, c]), T, t)
    return g1, g2, g3


def ref_histogram(vol, point, bins):
    T, H, W = vol.shape
    bins = [tuple(float(x) for x in b) for b in bins]
    hist = [0.0] * 640
    t0, r0, c0 = (int(v) for v in point)
    for dt in range(-6, 7):
        for dr in range(-6, 7):
            for dc in range(-6, 7):
                t, r, c = t0 + dt, r0 + dr, c0 + dc
                if not (0 <= t < T and 0 <= r < H and 0 <= c < W):
                    continue
                g1, g2, g3 = ref_gradient(vol, t, r, c)
                m = math.sqrt(g1 * g1 + g2 * g2 + g3 * g3)
                if m == 0:
                    continue
                u1, u2, u3 = g1 / m, g2 / m, g3 / m
                d = [u1 * b[0] + u2 * b[1] + u3 * b[2] for b in bins]
                top = sorted(range(80), key=lambda k: (-d[k], k))[:3]
                p = [d[k] ** 20 for k in top]
                s = p[0] + p[1] + p[2]
                G = math.exp(-(dr * dr + dc * dc + dt * dt) / (2 * 5**2))
                sub = ((dt >= 0) * 2 + (dr >= 0)) * 2 + (dc >= 0)
                for k, pk in zip(top, p):
                    hist[sub * 80 + k] += m * G * (pk / s)
    return hist


def ref_quantise(hist):
    def normalise(h):
        acc = 0.0
        for x in h:
            acc += x * x
        n = math.sqrt(acc)
        return [x / n for x in h] if n > 0 else list(h)

    h = normalise(hist)
    h = normalise([min(x, 0.2) for x in h])
    out = []
    for x in h:
        v = x * 512
        f = math.floor(v)
        r = f + 1 if v - f >= 0.5 else f  # half away from zero
        out.append(min(r, 255))
    return np.array(out, dtype=np.uint8)


def border_and_inner_points(shape, rng, n_random):
    T, H, W = shape
    corners = [(t, r, c) for t in (0, T - 1) for r in (0, H - 1) for c in (0, W - 1)]
    near = [(1, 1, W - 2), (T // 2, 0, W // 2), (T // 2, H // 2, 5), (T - 2, H - 6, W // 2)]
    rand = [
        (int(rng.integers(0, T)), int(rng.integers(0, H)), int(rng.integers(0, W))) for _ in range(n_random)
    ]
    pts = np.array(corners[:4] + near + rand)
    return np.clip(pts, 0, np.array(shape) - 1)


# --- bit-exactness ---------------------------------------------------------------------------------------


@pytest.mark.parametrize("kind", ["uniform", "quantised", "thin"])
def test_matches_literal_reference_bit_for_bit(kind):
    rng = np.random.default_rng({"uniform": 10, "quantised": 11, "thin": 12}[kind])
    if kind == "uniform":
        vol = rng.random((15, 17, 19))
    elif kind == "quantised":
        # few grey levels: many axis-aligned and symmetric gradients, hence exact ties between bins
        vol = rng.integers(0, 3, size=(14, 16, 15)).astype(np.float64)
    else:
        vol = rng.random((1, 12, 20)) * 100  # one frame: g3 = 0 everywhere
    pts = border_and_inner_points(vol.shape, rng, 4)
    bins = sc.orientation_bins()
    hist = sc.histograms(vol, pts)
    got = describe(vol, pts, variant="scovanner2007")
    assert got.dtype == np.uint8 and got.shape == (len(pts), 640)
    for i, p in enumerate(pts):
        ref = ref_histogram(vol, p, bins)
        assert np.array_equal(hist[i], np.array(ref)), f"float64 histogram differs at point {p}"
        assert np.array_equal(got[i], ref_quantise(ref)), f"uint8 descriptor differs at point {p}"


def test_float32_input_is_computed_in_float64():
    rng = np.random.default_rng(13)
    vol = rng.random((13, 14, 15)).astype(np.float32)
    pts = np.array([[6, 7, 7], [0, 13, 0]])
    got = sc.describe(vol, pts)
    for i, p in enumerate(pts):
        assert np.array_equal(
            got[i], ref_quantise(ref_histogram(vol.astype(np.float64), p, sc.orientation_bins()))
        )


def test_chunks_do_not_change_the_result(monkeypatch):
    rng = np.random.default_rng(14)
    vol = rng.random((40, 12, 13))
    pts = np.column_stack([rng.integers(0, 40, 30), rng.integers(0, 12, 30), rng.integers(0, 13, 30)])
    whole = sc.histograms(vol, pts)
    monkeypatch.setattr(sc, "CHUNK_FRAMES", 3)
    assert np.array_equal(sc.histograms(vol, pts), whole)


def test_quantise_rules():
    h = np.zeros((3, 640))
    h[1, 0] = 5.0  # one entry: 1 -> clipped 0.2 -> renormalised 1 -> 512 -> capped 255
    h[2, :2] = 1.0  # two equal entries: 1/sqrt2 -> 0.2 each -> 1/sqrt2 -> 362.04 -> 255
    h[2, 2] = 0.0
    q = sc.quantise(h)
    assert not q[0].any()
    assert q[1, 0] == 255 and q[1, 1:].sum() == 0
    assert list(q[2, :3]) == [255, 255, 0]
    # half away from zero (np.round would give 2 for 2.5): build a histogram whose values are exact
    v = np.zeros((1, 640))
    v[0, :25] = 1.0  # 1/5 each (exact after normalising? 0.2 -> renormalised 0.2) -> 102.4 -> 102
    assert sc.quantise(v)[0, 0] == 102


def test_bad_input():
    with pytest.raises(InputError, match="no parameters"):
        describe(np.zeros((3, 3, 3)), [[1, 1, 1]], variant="scovanner2007", n_subregions=4)


# --- bins -----------------------------------------------------------------------------------------------


def test_icosahedron_constants_are_exact():
    phi = (1 + math.sqrt(5)) / 2
    assert sc.A == phi / math.sqrt(1 + phi * phi)
    assert sc.B == 1 / math.sqrt(1 + phi * phi)
    assert sc.A == pytest.approx(0.85065080835204, abs=1e-14)
    assert sc.B == pytest.approx(0.52573111211913, abs=1e-14)
    v, f = sc.icosahedron()
    assert v.shape == (12, 3) and f.shape == (20, 3)
    np.testing.assert_allclose(np.linalg.norm(v, axis=1), 1.0, atol=1e-15)
    edges = {tuple(sorted(e)) for tri in f for e in itertools.combinations(tri, 2)}
    assert len(edges) == 30
    assert all(np.isclose(np.linalg.norm(v[a] - v[b]), 2 * sc.B) for a, b in edges)
    assert np.all(np.bincount(f.reshape(-1)) == 5)
    # outward counter-clockwise
    n = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
    assert np.all(np.sum(n * v[f].sum(1), axis=1) > 0)


def solid_angle(a, b, c):
    """Van Oosterom & Strackee (1983): solid angle of the spherical triangle abc."""
    num = abs(np.dot(a, np.cross(b, c)))
    den = 1 + np.dot(a, b) + np.dot(b, c) + np.dot(c, a)
    return 2 * math.atan2(num, den)


def test_80_bins_match_an_independent_construction():
    bins = sc.orientation_bins()
    assert bins.shape == (80, 3)
    np.testing.assert_allclose(np.linalg.norm(bins, axis=1), 1.0, atol=1e-15)
    # independent: convex hull of the 12 vertices, subdivided, centroids normalised
    phi = (1 + math.sqrt(5)) / 2
    a, b = phi / math.sqrt(1 + phi * phi), 1 / math.sqrt(1 + phi * phi)
    verts = []
    for s1, s2 in itertools.product((1, -1), repeat=2):
        verts += [(s1 * a, s2 * b, 0), (0, s1 * a, s2 * b), (s2 * b, 0, s1 * a)]
    verts = np.array(verts)
    hull = ConvexHull(verts)
    assert len(hull.simplices) == 20
    unit = lambda x: x / np.linalg.norm(x)
    mine, areas = [], []
    for i, j, k in hull.simplices:
        p, q, r = verts[i], verts[j], verts[k]
        pq, qr, rp = unit(p + q), unit(q + r), unit(r + p)
        for tri in ((p, pq, rp), (pq, q, qr), (rp, qr, r), (pq, qr, rp)):
            mine.append(unit(sum(tri)))
            areas.append(solid_angle(*tri))
    mine = np.array(mine)
    # same set of directions
    d = np.abs(mine @ bins.T - 1)
    assert np.all(d.min(axis=1) < 1e-12) and np.all(d.min(axis=0) < 1e-12)
    assert sum(areas) == pytest.approx(4 * math.pi)
    assert max(areas) / min(areas) < 1.3  # equal-area-ish
    # nearly uniform spacing: nearest-neighbour angles all within 15 % of each other
    cos = bins @ bins.T - 2 * np.eye(80)
    nn = np.arccos(cos.max(axis=1))
    assert nn.max() / nn.min() < 1.15


def test_top3_bins_equal_brute_force_including_ties():
    rng = np.random.default_rng(15)
    g = rng.standard_normal((50_000, 3))
    # add directions with exact symmetric ties: axes, vertices, edge midpoints, face centres
    v, f = sc.icosahedron()
    special = np.concatenate([np.eye(3), -np.eye(3), v, v[f].sum(1), (v[:, None] + v[None]).reshape(-1, 3)])
    special = special[np.linalg.norm(special, axis=1) > 1e-9]
    g = np.concatenate([g, special, 3 * special])
    m, top, w = sc.assign_bins(g[:, 0], g[:, 1], g[:, 2])
    bins = sc.orientation_bins()
    u = g / m[:, None]
    d = u[:, 0:1] * bins[:, 0] + u[:, 1:2] * bins[:, 1] + u[:, 2:3] * bins[:, 2]
    want = np.argsort(-d, axis=1, kind="stable")[:, :3]
    assert np.array_equal(top, want)
    np.testing.assert_allclose(w.sum(1), 1.0)
    assert np.all(np.diff(np.take_along_axis(d, top, 1), axis=1) <= 0)
def test_compiled_pow_is_python_float_pow_to_the_last_bit(rng):
    """The descriptor's d ** 20 runs compiled; it must equal Python's float power (the C library's pow)
    bit for bit, including the cosines near 1 the top bins take and signed zeros."""
    from vidstyle.features.scovanner2007 import POWER, _libm_pow

    x = np.concatenate([rng.uniform(-1, 1, 20000), rng.uniform(0.95, 1, 20000), [0.0, -0.0, 1.0, -1.0, 1e-300]])
    ref = np.array([v ** float(POWER) for v in x.tolist()])
    assert np.array_equal(_libm_pow(x, POWER).view(np.int64), ref.view(np.int64))


def test_compiled_accumulation_is_bincount_to_the_last_bit(rng):
    """The numba accumulation (what histograms() runs) against the numpy reference that sums the
    flattened contributions with np.bincount: identical float64 histograms, on random magnitudes,
    bins and weights with many samples per entry (so any change of summation order would show)."""
    offs, gauss, sub = sc._offsets()
    R = sc.HALF
    T, H, W = 6, 20, 24
    Hp, Wp = H + 2 * R, W + 2 * R
    flat_off = ((offs[:, 0] * Hp + offs[:, 1]) * Wp + offs[:, 2]).astype(np.int64)
    size = (T + 2 * R) * Hp * Wp
    # compact voxels and the padded map to them (-1 outside), with unused rows too
    n = size // 2
    m = rng.random(n) * (rng.random(n) < 0.7)
    bins = rng.integers(0, sc.N_BINS, (n, 3))
    w = rng.dirichlet(np.ones(3), n)
    slot = np.where(rng.random(size) < 0.8, rng.integers(0, n, size), -1).astype(np.int32)
    q = np.stack([rng.integers(0, T, 40), rng.integers(0, H, 40), rng.integers(0, W, 40)], axis=1)
    base = (((q[:, 0] + R) * Hp + (q[:, 1] + R)) * Wp + (q[:, 2] + R)).astype(np.int64)
    got = np.zeros((len(base), sc.DIM))
    sc._accumulate_kernel()(got, base, flat_off, gauss, sub, slot, m, bins, w, sc.N_BINS)
    want = np.zeros((len(base), sc.DIM))
    sc._accumulate_numpy(want, base, flat_off, gauss, sub, slot, m, bins, w, sc.N_BINS)
    assert np.array_equal(got, want) and got.sum() > 0


def test_gradients_at_voxels_equal_the_whole_volume_gradients_to_the_bit(rng):
    """histograms() computes gradients only where a point's cube reaches: the same values as
    gradients() of the frame range (one-sided at its ends and at the image borders), bit for bit, on
    every voxel, including ranges of one and two frames and one-pixel-wide images."""
    for shape in [(9, 7, 8), (2, 5, 6), (1, 4, 4), (6, 1, 5), (5, 6, 2)]:
        vol = rng.random(shape) * 255
        T = shape[0]
        for lo, hi in [(0, T), (min(1, T - 1), T), (0, max(T - 1, 1))]:
            sub_vol = vol[lo:hi]
            want = sc.gradients(sub_vol)
            t, r, c = (a.reshape(-1) for a in np.meshgrid(np.arange(lo, hi), np.arange(shape[1]),
                                                          np.arange(shape[2]), indexing="ij"))
            got = sc.gradients_at(vol, t, r, c, lo, hi)
            for g, w_ in zip(got, want):
                assert g.tobytes() == w_.reshape(-1).tobytes(), (shape, lo, hi)


def test_compiled_bin_assignment_is_the_numpy_reference_to_the_bit(rng):
    """assign_bins (one compiled pass) against assign_bins_numpy: magnitudes, bins and weights equal bit
    for bit on random gradients, zero gradients, axis-aligned and cube-edge directions (ties of |u|),
    huge and tiny magnitudes."""
    g = rng.normal(size=(20000, 3)) * rng.choice([1e-300, 1e-3, 1.0, 255.0, 1e150], size=(20000, 1))
    g[:50] = 0.0
    special = np.array([[1, 0, 0], [0, -1, 0], [0, 0, 2], [1, 1, 0], [1, -1, 1], [-3, 3, -3], [0, 1, 1],
                        [2, 0, -2], [1e-320, 0, 0]], dtype=np.float64)
    g = np.vstack([g, special, -special])
    got = sc.assign_bins(g[:, 0], g[:, 1], g[:, 2])
    want = sc.assign_bins_numpy(g[:, 0], g[:, 1], g[:, 2])
    for a, b in zip(got, want):
        assert a.dtype == b.dtype and a.tobytes() == b.tobytes()


def test_compiled_top3_is_the_numpy_reference(rng):
    """The compiled top-3 selection (what assign_bins runs) against its numpy reference: the same bins
    and cosines to the last bit, with exact ties (repeated candidates) and padded rows (-1 entries,
    including rows with fewer than three real candidates)."""
    C = sc._bins()
    n, K = 5000, 8
    u = rng.standard_normal((n, 3))
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    cands = np.sort(rng.integers(0, sc.N_BINS, (n, K)), axis=1)  # repeats give exact ties
    cands[rng.random((n, K)) < 0.2] = -1
    cands[:50, 2:] = -1  # at most two real candidates
    got = (np.empty((n, 3), np.int64), np.empty((n, 3)))
    want = (np.empty((n, 3), np.int64), np.empty((n, 3)))
    sc._top3_kernel()(u[:, 0].copy(), u[:, 1].copy(), u[:, 2].copy(), cands, C, *got)
    sc._top3_numpy(u[:, 0].copy(), u[:, 1].copy(), u[:, 2].copy(), cands, C, *want)
    assert np.array_equal(got[0], want[0])
    assert np.array_equal(got[1].view(np.int64), want[1].view(np.int64))


def test_compiled_chunk_voxels_are_the_numpy_reference_to_the_bit(rng):
    """histograms() finds the voxels of a chunk that the points' cubes reach and their gradients in two
    compiled passes: the same slot map (which voxel, numbered in raster order) and the same gradients bit
    for bit as the numpy reference (need mask, gradients_at, scattered slots), on float32, float64 and
    uint8 volumes, one-frame, one-row and one-column volumes, chunks at and away from the volume's ends."""
    for shape in [(40, 30, 20), (1, 12, 20), (2, 1, 5), (9, 7, 1), (20, 13, 14)]:
        T, H, W = shape
        for dtype in (np.float32, np.float64, np.uint8):
            vol = (rng.random(shape) * 255).astype(dtype)
            q = np.stack([rng.integers(0, T, 25), rng.integers(0, H, 25), rng.integers(0, W, 25)], axis=1)
            for a, b in [(0, T), (min(2, T - 1), T), (0, max(T - 3, 1))]:
                qq = q[(q[:, 0] >= a) & (q[:, 0] < b)]
                ga, gb = max(a - 1, 0), min(b + 1, T)
                slot, g = sc._chunk_voxels(vol, qq, a, b, ga, gb)
                want_slot, want_g = sc._chunk_voxels_numpy(vol, qq, a, b, ga, gb)
                assert slot.dtype == want_slot.dtype and slot.tobytes() == want_slot.tobytes(), (shape, a, b)
                for x, y in zip(g, want_g):
                    assert x.dtype == y.dtype and x.tobytes() == y.tobytes(), (shape, dtype, a, b)


def test_compiled_quantise_is_the_numpy_reference_to_the_bit(rng):
    """quantise (one compiled pass) against quantise_numpy: the same uint8 descriptors on sparse, heavy-
    tailed histograms, all-zero rows, a single entry, entries exactly at the clip and rounding ties."""
    h = rng.random((400, sc.DIM)) ** 8 * (rng.random((400, sc.DIM)) < 0.3)
    h[:5] = 0.0
    h[5, 0] = 5.0
    h[6, :25] = 1.0
    h[7, :2] = 1.0
    h[8] = rng.integers(0, 4, sc.DIM)
    assert sc.quantise(h).tobytes() == sc.quantise_numpy(h).tobytes()


def _candidate_table_cell_by_cell():
    """The candidate table computed cell by cell, one direction at a time (the loop the vectorised
    :func:`sc._candidate_table` replaced), as the reference."""
    C = sc._bins()
    n = sc.CUBE_RES
    edges = np.linspace(-1.0, 1.0, n + 1)

    def cube_dir(face, x, y):
        axis, sign = divmod(face, 2)
        v = np.empty(3)
        v[axis] = 1.0 if sign == 0 else -1.0
        others = [a for a in range(3) if a != axis]
        v[others[0]], v[others[1]] = x, y
        return v / np.linalg.norm(v)

    lists = []
    for face in range(6):
        for i in range(n):
            for j in range(n):
                corners = [cube_dir(face, edges[i + a], edges[j + b]) for a in (0, 1) for b in (0, 1)]
                u0 = cube_dir(face, (edges[i] + edges[i + 1]) / 2, (edges[j] + edges[j + 1]) / 2)
                rho = max(math.acos(min(1.0, float(u0 @ c))) for c in corners) + 1e-6
                alpha = np.arccos(np.clip(C @ u0, -1.0, 1.0))
                lower = np.cos(np.minimum(alpha + rho, np.pi))
                upper = np.cos(np.maximum(alpha - rho, 0.0))
                l3 = np.sort(lower)[-3]
                lists.append(np.flatnonzero(upper >= l3 - 1e-9))
    return lists


def test_candidate_table_equals_the_cell_by_cell_construction():
    table, k = sc._candidate_table()
    want = _candidate_table_cell_by_cell()
    assert table.shape == (6 * sc.CUBE_RES ** 2, k) and k == max(len(x) for x in want)
    for row, x in zip(table, want):
        np.testing.assert_array_equal(row[row >= 0], x)
        assert (row[len(x):] == -1).all()


def test_every_direction_finds_its_top3_among_its_cells_candidates(rng):
    """The table's promise, against brute force: the three bins nearest a direction (largest cosines) are
    among the candidates of the cell it falls in, for random directions and directions at cell corners."""
    C = sc._bins()
    table, _ = sc._candidate_table()
    u = rng.standard_normal((20000, 3))
    g = np.linspace(-1, 1, sc.CUBE_RES + 1)
    corner = np.stack(np.meshgrid([1.0], g, g, indexing="ij"), axis=-1).reshape(-1, 3)
    u = np.concatenate([u, corner, -corner[:, [2, 0, 1]]])
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    cells = sc._cube_cell(u[:, 0], u[:, 1], u[:, 2])
    top = np.argsort(-(u @ C.T), axis=1, kind="stable")[:, :3]
    for t, cell in zip(top, cells):
        assert set(t.tolist()) <= set(table[cell][table[cell] >= 0].tolist())
