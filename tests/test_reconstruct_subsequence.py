"""The subsequence graph (Tautges 2012, seed 001, section 4.3) against independent truth: the accumulated
DTW cost against every slope-bounded warping path enumerated by the definition, retrieval of exact
(and 2x / 0.5x resampled) copies of library segments, clip boundaries, the graph's shortest path
against every choice of nodes, the whole reconstruction of a query spliced from two clips, and the
compiled kernels against the numpy reference."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from vidstyle.reconstruct.subsequence import (
    accumulated_cost,
    best_ends,
    cost_matrix,
    crossfade_alpha,
    segment_bounds,
    skip_factors,
    ssg_shortest_path,
    subsequence_dtw,
    subsequence_reconstruct,
    warping_positions,
    window_bounds,
)

#: (query step, library step, cost factor) of eq. 4.2
STEPS = ((1, 1, 1.0), (1, 2, 1.0), (2, 1, 2.0))


def _brute_D(C, clip, w=None):
    """D(n, m): the least cost over every warping path from row 0 to (n, m) inside one clip, by
    enumeration (the path starts anywhere in row 0 at cost C(0, a); every step adds its factor x the
    cost of the cell it lands on). With per-row weights ``w`` (C already weighted) a (2, 1) step costs
    (w_{n-1} + w_n) d(n, m) and may not skip a weighted row to land on a weight-0 one."""
    L, N = C.shape
    D = np.full((L, N), np.inf)

    def walk(n, m, cost):
        D[n, m] = min(D[n, m], cost)
        for dn, dm, f in STEPS:
            n2, m2 = n + dn, m + dm
            if n2 < L and m2 < N and clip[m2] == clip[m]:
                if dn == 2 and w is not None:
                    if w[n2] == 0:
                        if w[n2 - 1] > 0:
                            continue
                        add = 2 * C[n2, m2]
                    else:
                        add = (w[n2 - 1] + w[n2]) * (C[n2, m2] / w[n2])
                else:
                    add = f * C[n2, m2]
                walk(n2, m2, cost + add)

    for a in range(N):
        walk(0, a, C[0, a])
    return D


def _path_cost(C, pos):
    """The eq. 4.2 cost of the path through positions ``pos`` (midpoints marking skipped rows)."""
    cost = C[0, int(pos[0])]
    n = 0
    while n < len(pos) - 1:
        if pos[n + 1] != int(pos[n + 1]):  # a skipped row: step (2, 1)
            n += 2
            cost += 2 * C[n, int(pos[n])]
        else:
            n += 1
            cost += C[n, int(pos[n])]
    return cost


@pytest.mark.parametrize("seed", range(10))
def test_accumulated_cost_equals_brute_force(seed):
    rng = np.random.default_rng(seed)
    L, N = int(rng.integers(1, 6)), int(rng.integers(1, 10))
    C = rng.random((L, N)).round(3)
    clip = np.sort(rng.integers(0, 3, size=N))
    first, _ = segment_bounds(clip)
    want = _brute_D(C, clip)
    for compiled in (True, False):
        D, S = accumulated_cost(C, first, compiled=compiled)
        assert np.array_equal(np.isinf(D), np.isinf(want))
        assert np.allclose(D[np.isfinite(D)], want[np.isfinite(want)], rtol=0, atol=1e-12)
        # weighted, some rows missing (weight 0)
        w = rng.random(L).round(2) * (rng.random(L) > 0.3)
        Dw, _ = accumulated_cost(C * w[:, None], first, skip_factors(w), compiled=compiled)
        ww = _brute_D(C * w[:, None], clip, w)
        assert np.array_equal(np.isinf(Dw), np.isinf(ww))
        assert np.allclose(Dw[np.isfinite(Dw)], ww[np.isfinite(ww)], rtol=0, atol=1e-12)
        # every finite end backtracks to a valid path of exactly that cost
        for m in np.flatnonzero(np.isfinite(D[-1])):
            pos = warping_positions(S, m, compiled=compiled)
            held = np.ceil(pos - 0.5).astype(int)
            assert pos[-1] == m and len(set(clip[held])) == 1
            d = np.diff(pos)
            assert np.all((d >= 0.5) & (d <= 2))
            assert _path_cost(C, pos) == pytest.approx(D[-1, m], abs=1e-12)


def test_brute_force_sees_clip_first_frames_as_fresh_starts():
    C = np.ones((3, 6))
    clip = np.array([0, 0, 0, 1, 1, 1])
    D, _ = accumulated_cost(C, segment_bounds(clip)[0])
    assert np.all(np.isinf(D[1:, [0, 3]]))
    assert np.array_equal(D, _brute_D(C, clip))


def _library(rng, lengths, dim=12):
    clip = np.concatenate([np.full(n, i) for i, n in enumerate(lengths)])
    return rng.normal(size=(len(clip), dim)), clip


@pytest.mark.parametrize("speed", [1.0, 0.5, 2.0])
def test_exact_copy_retrieved_at_its_place(speed):
    rng = np.random.default_rng(3)
    F, clip = _library(rng, [120, 200, 90])
    first, _last = segment_bounds(clip)
    L, s = 15, 150  # library frame 150 lies in clip 1 (frames 120..319)
    t = s + speed * np.arange(L)
    lo = np.floor(t).astype(int)
    frac = (t - lo)[:, None]
    q = (1 - frac) * F[lo] + frac * F[np.minimum(lo + 1, len(F) - 1)]  # resampled (midpoints at 0.5x)
    C = cost_matrix(q, F.astype(np.float32))
    D, S = accumulated_cost(C, first)
    ends = best_ends(D[-1], first, k=16, exclusion=7)
    assert ends[0] == round(t[-1])
    assert D[-1, ends[0]] < 1e-5
    assert D[-1, ends[1]] > 1.0
    pos = warping_positions(S, ends[0])
    assert pos[0] == s
    ids = np.ceil(pos - 0.5).astype(int)
    assert np.array_equal(ids, np.floor(t).astype(int))  # 0.5x: the skipped frames hold the frame


def test_cost_matrix_is_the_weighted_euclidean_distance():
    rng = np.random.default_rng(4)
    q, F, w = rng.normal(size=(5, 7)), rng.normal(size=(40, 7)), rng.random(5)
    want = w[:, None] * np.linalg.norm(q[:, None] - F[None], axis=-1)
    assert np.allclose(cost_matrix(q, F, w, chunk=16), want, rtol=1e-12, atol=1e-12)


def test_retrieval_excludes_shifted_ends_and_follows_the_minimum():
    cost = np.array([5.0, 1.0, 0.5, 0.7, 9.0, 0.6, 3.0, np.inf, 0.1, 0.2])
    first = np.array([0, 0, 0, 0, 0, 0, 0, 7, 7, 7])
    # Müller by hand: 8 (0.1); 9 excluded (shift 1); 2 (0.5); 3, 1 excluded; 5 (0.6); then 6 excluded,
    # 0 (5.0) is 2 away from 2: excluded; 4 is 1 from 5: excluded
    assert best_ends(cost, first, k=5, exclusion=1).tolist() == [8, 2, 5, 0]
    # a neighbour in another clip is not a shift of the end
    assert best_ends(np.array([1.0, 0.5, 0.2]), np.array([0, 0, 2]), k=3, exclusion=1).tolist() == [2, 1]


def test_paths_never_cross_a_clip_boundary():
    rng = np.random.default_rng(5)
    F, clip = _library(rng, [30, 30, 30, 30])
    first, _last = segment_bounds(clip)
    q = F[20:35]  # the last 10 frames of clip 0 and the first 5 of clip 1: adjacent in the index
    D, S = accumulated_cost(cost_matrix(q, F), first)
    for m in best_ends(D[-1], first, k=16, exclusion=2):
        ids = np.ceil(warping_positions(S, m) - 0.5).astype(int)
        assert len(set(clip[ids])) == 1
    assert D[-1, 34] > 1.0  # the straight copy across the boundary is not a path
    # the whole reconstruction, over many random queries
    P = rng.normal(size=(len(clip), 15, 3))
    for seed in range(5):
        r = np.random.default_rng(seed)
        out = subsequence_reconstruct(r.normal(size=(40, 12)), np.ones(40, bool), np.zeros(40, int), F, clip,
                                      P,
                                      window=9, overlap=3, k=4)
        for i, (s, e) in enumerate(out.windows):
            assert len(set(clip[out.window_ids[i, :e - s]])) == 1


@pytest.mark.parametrize("seed", range(8))
def test_ssg_shortest_path_equals_brute_force(seed):
    rng = np.random.default_rng(seed)
    ks = rng.integers(1, 4, size=int(rng.integers(1, 5)))
    nodes = [rng.random(k).round(2) for k in ks]
    edges = [rng.random((a, b)).round(2) for a, b in itertools.pairwise(ks)]
    lam = float(rng.choice([0.0, 0.5, 2.0]))
    best = np.inf
    for ch in itertools.product(*[range(k) for k in ks]):
        c = sum(nodes[i][ch[i]] for i in range(len(ks))) + lam * sum(edges[i][ch[i], ch[i + 1]]
                                                                      for i in range(len(ks) - 1))
        best = min(best, c)
    choice, total = ssg_shortest_path(nodes, edges, lam)
    got = sum(nodes[i][choice[i]] for i in range(len(ks))) + lam * sum(edges[i][choice[i], choice[i + 1]]
                                                                         for i in range(len(ks) - 1))
    assert total == pytest.approx(best, abs=1e-12)
    assert got == pytest.approx(best, abs=1e-12)


def _spliced(seed, views=2):
    """A library of 3 clips seen at ``views`` views (random features per view, smooth random 3D poses)
    and a query copying frames 10..49 of clip 0 then 30..69 of clip 2 at view 1."""
    rng = np.random.default_rng(seed)
    lengths = [80, 60, 100]
    clip = np.concatenate([np.full(n, i) for i, n in enumerate(lengths)])
    N = len(clip)
    F = rng.normal(size=(views, N, 28)).astype(np.float32)
    P = np.cumsum(rng.normal(scale=0.02, size=(N, 15, 3)), axis=0)
    truth = np.concatenate([np.arange(10, 50), 140 + np.arange(30, 70)])
    return F, clip, P, F[1][truth], truth


def _check_outside_seam(out, truth, seam):
    """Every query frame whose windows all lie on one side of ``seam`` maps to its truth in both ids."""
    checked = 0
    for t in range(len(truth)):
        wins = [(s, e) for s, e in out.windows if s <= t < e]
        if all(e <= seam or s >= seam for s, e in wins):
            assert out.ids[t, 0] == truth[t] and out.ids[t, 1] == truth[t], t
            checked += 1
    return checked


def test_whole_reconstruction_of_a_spliced_query():
    F, clip, P, q, truth = _spliced(7)
    T = len(q)
    out = subsequence_reconstruct(q, np.ones(T, bool), np.ones(T, int), F, clip, P)
    assert np.array_equal(out.windows, window_bounds(T, 15, 6))
    assert _check_outside_seam(out, truth, 40) == 56  # frames 0..26 and 51..79
    assert np.all(out.view == 1)
    assert out.ids.shape == (T, 2) and out.alpha.shape == (T,)
    # alpha: 1 outside overlaps, the smoothstep ramp inside, ids equal outside overlaps
    for i in range(len(out.windows) - 1):
        s1, e0 = out.windows[i + 1, 0], out.windows[i, 1]
        assert np.allclose(out.alpha[s1:e0], crossfade_alpha(e0 - s1))
    inside = np.zeros(T, bool)
    for i in range(len(out.windows) - 1):
        inside[out.windows[i + 1, 0]:out.windows[i, 1]] = True
    assert np.all(out.alpha[~inside] == 1) and np.array_equal(out.ids[~inside, 0], out.ids[~inside, 1])
    assert out.cost == pytest.approx(out.node_cost.sum() + out.transition_cost.sum())
    assert np.array_equal(out.start, out.window_ids[np.arange(len(out.windows)), 0])


def test_all_views_finds_the_view_and_missing_frames_are_interpolated():
    F, clip, P, q, truth = _spliced(8, views=3)
    T = len(q)
    valid = np.ones(T, bool)
    valid[[3, 4, 20, 60, 61, 62, 79]] = False
    q = q.copy()
    q[~valid] = 1e3  # garbage where the detector failed: must be ignored
    out = subsequence_reconstruct(q, valid, None, F, clip, P, all_views=True)
    assert np.all(out.view == 1)
    assert _check_outside_seam(out, truth, 40) == 56  # frames 0..26 and 51..79


def test_crossfade_alpha_is_a_c1_ramp():
    a = crossfade_alpha(6)
    assert a[0] == 1 and a[-1] == 0 and np.all(np.diff(a) < 0)
    # zero slope at both ends: the first and last steps are smaller than the middle ones
    assert abs(a[1] - a[0]) < abs(a[3] - a[2]) and abs(a[-1] - a[-2]) < abs(a[3] - a[2])
    assert crossfade_alpha(1).tolist() == [0.5] and len(crossfade_alpha(0)) == 0


def test_window_bounds():
    assert window_bounds(40, 15, 6).tolist() == [[0, 15], [9, 24], [18, 33], [27, 40]]
    assert window_bounds(15, 15, 6).tolist() == [[0, 15]]
    assert window_bounds(7, 15, 6).tolist() == [[0, 7]]
    assert window_bounds(16, 15, 6).tolist() == [[0, 15], [9, 16]]
    for bad in [(10, 0, 0), (10, 5, 3), (10, 5, -1), (0, 5, 2)]:
        with pytest.raises(ValueError):
            window_bounds(*bad)


def test_compiled_and_reference_agree_exactly():
    rng = np.random.default_rng(11)
    F, clip = _library(rng, [50, 7, 80, 1, 40])
    first, _ = segment_bounds(clip)
    C = cost_matrix(rng.normal(size=(15, 12)), F)
    C[:, ::7] = C[:, 3:4]  # ties between the steps
    D1, S1 = accumulated_cost(C, first, compiled=True)
    D2, S2 = accumulated_cost(C, first, compiled=False)
    assert np.array_equal(D1, D2) and np.array_equal(S1, S2)
    for m in np.flatnonzero(np.isfinite(D1[-1])):
        p1, p2 = warping_positions(S1, m, compiled=True), warping_positions(S2, m, compiled=False)
        assert np.array_equal(p1, p2)
    # the fused kernel (local costs computed inside the DP) against cost matrix + numpy DP, weighted,
    # with missing rows, float32 library
    q = rng.normal(size=(15, 12))
    q[5] = F[60]  # an exact match: distances near 0, where max(., 0) matters
    w = rng.random(15) * (rng.random(15) > 0.3)
    F32 = F.astype(np.float32)
    D1, S1 = subsequence_dtw(q, F32, first, w, compiled=True)
    D2, S2 = subsequence_dtw(q, F32, first, w, compiled=False)
    assert np.array_equal(D1, D2) and np.array_equal(S1, S2)
    D3, S3 = accumulated_cost(cost_matrix(q, F32, w), first, skip_factors(w), compiled=False)
    assert np.array_equal(D1, D3) and np.array_equal(S1, S3)
    Fv, clipv, P, q, _ = _spliced(12)
    T = len(q)
    valid = rng.random(T) > 0.2
    views = np.random.default_rng(13).integers(0, 2, T)
    a = subsequence_reconstruct(q, valid, views, Fv, clipv, P, k=5, compiled=True)
    b = subsequence_reconstruct(q, valid, views, Fv, clipv, P, k=5, compiled=False)
    fields = ("ids", "alpha", "windows", "start", "end", "node_cost", "transition_cost", "view", "window_ids",
              "n_candidates")
    for f in fields:
        assert np.array_equal(getattr(a, f), getattr(b, f)), f
    assert a.cost == b.cost


@pytest.mark.parametrize("change", [
    {"features_q": np.zeros((10, 5))},
    {"valid": np.ones(9, bool)},
    {"valid": np.ones(10)},
    {"views": np.full(10, 2)},
    {"views": None},
    {"clip": np.zeros(5)},
    {"points3d": np.zeros((30, 15, 2))},
    {"k": 0},
    {"window": 4, "overlap": 3},
    {"transition_weight": -1.0},
    {"weights": -np.ones(10)},
    {"index_features": np.zeros((2, 30, 4))},
])
def test_bad_input_raises_value_error(change):
    args = {"features_q": np.zeros((10, 6)), "valid": np.ones(10, bool), "views": np.zeros(10, int),
            "index_features": np.zeros((2, 30, 6)), "clip": np.zeros(30, int),
            "points3d": np.zeros((30, 15, 3)), "window": 5, "overlap": 2}
    args.update(change)
    with pytest.raises(ValueError):
        subsequence_reconstruct(**args)


def test_too_short_clips_raise():
    with pytest.raises(ValueError, match="shorter"):
        subsequence_reconstruct(np.zeros((15, 6)), np.ones(15, bool), np.zeros(15, int), np.zeros((1, 30, 6)),
                                np.arange(30) // 3, np.zeros((30, 15, 3)))


def test_a_gap_longer_than_a_window_still_reconstructs():
    F, clip, P, q, truth = _spliced(9)
    T = len(q)
    valid = np.ones(T, bool)
    valid[45:65] = False  # windows [45, 60) and part of its neighbours see nothing
    out = subsequence_reconstruct(q, valid, np.ones(T, int), F, clip, P)
    assert out.ids.shape == (T, 2) and np.all((out.ids >= 0) & (out.ids < len(clip)))
    assert np.all((out.alpha >= 0) & (out.alpha <= 1)) and np.isfinite(out.cost)
    assert np.array_equal(out.ids[:27, 0], truth[:27])  # the frames before the seam's windows
