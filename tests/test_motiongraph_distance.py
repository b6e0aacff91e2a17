"""All-pairs distance by tiled GEMMs against the per-pair reference; candidates; tiling, joblib, Dask."""

from __future__ import annotations

import numpy as np
import pytest

from test_motiongraph_reference import reference_distance_matrix
from vidstyle.motiongraph.distance import (
    WindowSet,
    all_pair_candidates,
    compute_tile,
    distance_matrix,
    joint_weights,
    tile_ranges,
)

K = 4


def _database(rng, n_clips=3, frames=40, J=6):
    """Smooth random point trajectories far from the origin (tests cancellation), several clips."""
    pos, clip = [], []
    for c in range(n_clips):
        t = np.arange(frames)[:, None, None]
        base = rng.normal(size=(1, J, 3)) + [200.0, 10.0, -300.0]
        wave = np.sin(0.3 * t + rng.uniform(0, 6, size=(1, J, 3))) * rng.uniform(0.2, 1.0, size=(1, J, 3))
        walk = np.concatenate([0.5 * t * rng.normal(size=(1, 1, 1)), 0 * t, 0.3 * t], axis=2)
        pos.append(base + wave + walk)
        clip.append(np.full(frames, c))
    return np.concatenate(pos), np.concatenate(clip)


def _windows(rng, **kw):
    pos, clip = _database(rng, **kw)
    return WindowSet.from_clips(pos, clip, rng.uniform(0.5, 2.0, size=pos.shape[1]), K)


def test_windows_never_cross_clips(rng):
    ws = _windows(rng)
    assert ws.n_windows == 3 * (40 - K + 1)
    frames = ws.starts[:, None] + np.arange(K)
    clip_of = np.repeat(np.arange(3), 40)
    assert np.all(clip_of[frames] == ws.clip[:, None])


def test_gemm_matrix_matches_per_pair_reference(rng):
    ws = _windows(rng)
    ref = reference_distance_matrix(ws.positions, ws.starts, ws.weights, K)
    d64 = distance_matrix(ws, np.float64)
    scale = ref.max()
    assert np.allclose(d64, ref, atol=1e-9 * scale)
    d32 = distance_matrix(ws, np.float32)
    # float32 GEMM on centred coordinates: error relative to the largest distance stays small
    assert np.abs(d32 - ref).max() < 1e-5 * scale
    assert np.allclose(d64, d64.T, atol=1e-9 * scale)


def _reference_candidates(ref, ws, thr, min_gap):
    n = ws.n_windows
    out = set()
    for a in range(n):
        for b in range(a + 1, n):
            if ws.clip[a] == ws.clip[b] and b - a < min_gap or not ref[a, b] < thr:
                continue
            ok = True
            for da in (-1, 0, 1):
                for db in (-1, 0, 1):
                    if (da, db) == (0, 0):
                        continue
                    na, nb = a + da, b + db
                    if not (0 <= na < n and 0 <= nb < n) or ws.clip[na] != ws.clip[a] or ws.clip[nb] != ws.clip[b]:
                        continue
                    if ref[na, nb] < ref[a, b] or (ref[na, nb] == ref[a, b] and (da, db) < (0, 0)):
                        ok = False
            if ok:
                out.add((a, b))
    return out


@pytest.mark.parametrize("tile", [7, 16, 1000])
def test_tiled_candidates_equal_reference_local_minima(rng, tile):
    ws = _windows(rng)
    ref = reference_distance_matrix(ws.positions, ws.starts, ws.weights, K)
    offdiag = ref[np.triu_indices(ws.n_windows, 1)]
    thr = float(np.quantile(offdiag, 0.2))
    expect = _reference_candidates(ref, ws, thr, min_gap=2 * K)
    res = all_pair_candidates(ws, thr, 2 * K, tile=tile, dtype=np.float64, progress=False)
    assert set(zip(res.a.tolist(), res.b.tolist())) == expect
    assert len(expect) > 3
    assert np.allclose(res.D, ref[res.a, res.b], atol=1e-9 * ref.max())
    n_below = sum(1 for a in range(ws.n_windows) for b in range(a + 1, ws.n_windows)
                  if ref[a, b] < thr and not (ws.clip[a] == ws.clip[b] and b - a < 2 * K))
    assert res.n_below == n_below


def test_tiles_cover_upper_triangle_once():
    n, tile = 23, 5
    cover = np.zeros((n, n), int)
    for r0, r1, c0, c1 in tile_ranges(n, tile):
        cover[r0:r1, c0:c1] += 1
    assert np.array_equal(np.triu(cover) > 0, np.triu(np.ones((n, n))) > 0)
    assert cover.max() == 1


def test_float32_candidates_refined_in_float64(rng):
    ws = _windows(rng)
    ref = reference_distance_matrix(ws.positions, ws.starts, ws.weights, K)
    thr = float(np.quantile(ref[np.triu_indices(ws.n_windows, 1)], 0.2))
    r64 = all_pair_candidates(ws, thr, 2 * K, tile=32, dtype=np.float64, progress=False)
    r32 = all_pair_candidates(ws, thr, 2 * K, tile=32, dtype=np.float32, progress=False)
    s64, s32 = set(zip(r64.a, r64.b)), set(zip(r32.a, r32.b))
    assert len(s64 ^ s32) <= max(1, len(s64) // 20)  # near-ties may flip
    common = sorted(s64 & s32)
    d32 = dict(zip(zip(r32.a, r32.b), r32.D))
    assert np.allclose([d32[c] for c in common], ref[tuple(np.array(common).T)], atol=1e-9 * ref.max())


def test_parallel_joblib_and_dask_give_identical_candidates(rng):
    ws = _windows(rng)
    thr = float(np.quantile(distance_matrix(ws)[np.triu_indices(ws.n_windows, 1)], 0.2))
    serial = all_pair_candidates(ws, thr, 2 * K, tile=20, progress=False)
    par = all_pair_candidates(ws, thr, 2 * K, tile=20, n_jobs=2, progress=False)
    for name in ("a", "b", "D", "theta", "x0", "z0"):
        assert np.array_equal(getattr(serial, name), getattr(par, name))
    import dask.distributed as distributed
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=False, dashboard_address=None) as cluster:
        dask_res = all_pair_candidates(ws, thr, 2 * K, tile=20, scheduler=cluster.scheduler_address, progress=False)
    for name in ("a", "b", "D", "theta", "x0", "z0"):
        assert np.array_equal(getattr(serial, name), getattr(dask_res, name))


def test_in_process_and_workers_agree_at_sizes_where_blas_threads():
    """Tiles the size of a real build (2048 windows of 10 frames x 27 joints, the demo skeleton's
    size): there a multi-threaded OpenBLAS blocks the float32 products differently from one thread
    (last bits), so the in-process path must run them on one thread as the workers do."""
    rng = np.random.default_rng(11)
    pos, clip = _database(rng, n_clips=6, frames=400, J=27)
    ws = WindowSet.from_clips(pos, clip, rng.uniform(0.5, 2.0, size=pos.shape[1]), 10)
    thr = float(np.quantile(distance_matrix(ws)[np.triu_indices(ws.n_windows, 1)], 0.1))
    serial = all_pair_candidates(ws, thr, 20, tile=2048, progress=False)
    par = all_pair_candidates(ws, thr, 20, tile=2048, n_jobs=2, progress=False)
    assert len(serial.a) > 100 and serial.n_below == par.n_below
    for name in ("a", "b", "D", "theta", "x0", "z0"):
        assert np.array_equal(getattr(serial, name), getattr(par, name))


def test_tile_keeps_only_candidates_not_the_matrix(rng):
    ws = _windows(rng)
    res = compute_tile(ws, 0, 30, 30, 60, threshold_sq=np.inf, min_gap=2 * K)
    assert res.a.shape == res.b.shape and len(res.a) < 30 * 30 // 4


def test_joint_weights_favour_the_trunk():
    parents = np.array([-1, 0, 1, 2, 0, 4, 5, 0, 7, 8, 9])  # hips, two legs, spine-neck-head-...
    w = joint_weights(parents)
    assert w[0] == w.max() and w[3] == w[6] == w.min() == 1.0
    assert w[7] > w[8] > w[9] > w[10]


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_compiled_tail_and_candidates_equal_numpy_reference(rng, dtype):
    """The numba kernels of the tile's element-wise tail and candidate scan against the numpy code they
    replace (kept as the reference), bit for bit: on a real tile and on rounded random values full of
    exact ties, with thresholds given as a Python float (rounded to the tile's dtype) and as float64."""
    from vidstyle.motiongraph import distance as dist

    if dist._candidates_kernel() is None:
        pytest.skip("numba is absent")
    ws = _windows(rng, n_clips=4, frames=60)
    n, m = 50, 70
    for A0, B0, Y0 in [
        tuple(rng.normal(size=(n, m)).astype(dtype) * 30 for _ in range(3)),
        tuple(np.round(rng.normal(size=(n, m)) * 4).astype(dtype) for _ in range(3)),
    ]:
        yr, yc = (rng.normal(size=s).astype(dtype) for s in (n, m))
        Sr, Sc = (rng.uniform(0, 1e4, size=s).astype(dtype) for s in (n, m))
        outs = []
        for tail1, tail2 in [(dist._tail1(), dist._tail2()), (dist._tail1_numpy, dist._tail2_numpy)]:
            A, B, Y = A0.copy(), B0.copy(), Y0.copy()
            tail1(A, B)
            tail2(A, Y, yr, yc, Sr, Sc, dtype(-2.0), dtype(ws.total_weight))
            assert A.dtype == dtype
            outs.append(A)
        assert np.array_equal(outs[0], outs[1])
        D = np.round(outs[0] / 2e3).astype(dtype)  # many exact ties between neighbours
        r0, c0 = 20, 60
        for thr in [float(np.quantile(D, 0.3)) + 1e-9, np.float64(np.quantile(D, 0.3)) + 1e-9, np.inf]:
            got = dist._candidates(D, r0, r0 + n - 2, c0, c0 + m - 2, r0 - 1, c0 - 1, ws.clip, 2 * K, thr,
                                   dist._Workspace())
            want = dist._candidates_numpy(D, r0, r0 + n - 2, c0, c0 + m - 2, r0 - 1, c0 - 1, ws.clip, 2 * K, thr)
            assert np.array_equal(got[0], want[0]) and np.array_equal(got[1], want[1]) and got[2] == want[2]
            assert len(want[0]) > 0
        # a threshold just above a tile value that rounds onto it in float32: not below in a float32 tile
        v = float(D[5, 40])
        for thr in (np.nextafter(v, np.inf), np.float64(np.nextafter(v, np.inf))):
            got = dist._candidates(D, r0, r0 + n - 2, c0, c0 + m - 2, r0 - 1, c0 - 1, ws.clip, 2 * K, thr,
                                   dist._Workspace())
            want = dist._candidates_numpy(D, r0, r0 + n - 2, c0, c0 + m - 2, r0 - 1, c0 - 1, ws.clip, 2 * K, thr)
            assert np.array_equal(got[0], want[0]) and np.array_equal(got[1], want[1]) and got[2] == want[2]
        # more candidates than the output arrays hold: counted, the first ones written
        kernel = dist._candidates_kernel()
        out_a, out_b = np.zeros(2, np.int64), np.zeros(2, np.int64)
        _, n_cand = kernel(D, r0, r0 + n - 2, c0, c0 + m - 2, r0 - 1, c0 - 1, ws.clip, 2 * K, np.inf, out_a, out_b)
        assert n_cand > 2 and np.array_equal(out_a, want[0][:2]) and np.array_equal(out_b, want[1][:2])


def test_tile_buffers_reused_and_features_cached_give_the_same_tiles(rng):
    """compute_tile with one workspace and a shared feature cache, tiles in the pass's order, against
    fresh buffers and features per tile."""
    from vidstyle.motiongraph import distance as dist

    ws = _windows(rng)
    thr = float(np.quantile(distance_matrix(ws, np.float32), 0.2))
    tile = 16
    blocks = dist._tile_order(dist.tile_ranges(ws.n_windows, tile), tile)
    assert sorted(blocks) == sorted(dist.tile_ranges(ws.n_windows, tile))
    cache, work = dist._FeatureCache(ws, np.float32, capacity=3), dist._Workspace()
    for b in blocks:
        r1, D1 = compute_tile(ws, *b, thr, 2 * K, features=cache, work=work, return_matrix=True)
        r2 = compute_tile(ws, *b, thr, 2 * K, work=dist._Workspace())
        r3 = compute_tile(ws, *b, thr, 2 * K, features=cache, work=work)
        for name in ("a", "b", "D", "theta", "x0", "z0", "n_below", "n_pairs"):
            assert np.array_equal(getattr(r1, name), getattr(r2, name))
            assert np.array_equal(getattr(r3, name), getattr(r2, name))
        assert not np.shares_memory(D1, work.get("A", (1,), np.float32))
