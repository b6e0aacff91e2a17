"""Keyframe in-betweening (``vidstyle.inbetween``, Molina Tanco & Hilton 2000 + baselines) against
independent truth: brute-force enumeration of cluster paths, scipy's rotations, exact key poses."""

from __future__ import annotations

import itertools
from types import SimpleNamespace

import numpy as np
import pytest
from bvh_samples import TWO_JOINT
from scipy.spatial.transform import Rotation

from vidstyle.errors import ParameterError
from vidstyle.inbetween import (
    Keypose,
    MarkovInbetweener,
    best_cluster_path,
    path_score,
    pin,
    segment_path,
    slerp_inbetween,
)
from vidstyle.inbetween.markov import duration_tables, run_lengths
from vidstyle.inbetween.poses import SlerpInbetweener, hermite_root
from vidstyle.mocap import parse_bvh


def _library(seed: int = 0, clips: int = 3, frames: int = 90):
    """A tiny library on a 4-joint skeleton: smooth periodic joint angles, a root walking forward."""
    sk = parse_bvh(TWO_JOINT).skeleton
    rng = np.random.default_rng(seed)
    rots, roots, clip = [], [], []
    for c in range(clips):
        t = np.arange(frames) / 30.0
        f = 0.8 + 0.4 * c
        ang = np.zeros((frames, sk.n_joints, 3))
        for j in range(sk.n_joints):
            ang[:, j] = 40 * np.sin(2 * np.pi * f * t[:, None] + rng.uniform(0, 6, 3)) * rng.uniform(0.3, 1, 3)
        ang[:, 0, 1] += 20 * c  # some heading
        q = Rotation.from_euler("ZYX", ang.reshape(-1, 3), degrees=True).as_quat().reshape(frames, sk.n_joints, 4)
        r = np.stack([0.1 * np.sin(t), 3 + 0.2 * np.sin(4 * t), 1.5 * t], 1)
        rots.append(q)
        roots.append(r)
        clip.append(np.full(frames, c))
    return SimpleNamespace(skeleton_=sk, rotations_=np.concatenate(rots), root_positions_=np.concatenate(roots),
                           frame_clip_=np.concatenate(clip), fps=30.0)


def _brute_force(log_a, log_d, log_s, start, end, n, K):
    best, arg = -np.inf, None
    for mid in itertools.product(range(K), repeat=n - 2):
        path = np.array([start, *mid, end]) if n > 1 else np.array([start])
        s = path_score(path, log_a, log_d, log_s)
        if s > best:
            best, arg = s, path
    return arg, best


@pytest.mark.parametrize("seed", [0, 1, 2])
@pytest.mark.parametrize("n", [2, 3, 5, 6])
def test_cluster_path_dp_equals_brute_force(seed, n):
    rng = np.random.default_rng(seed)
    K = 3
    a = rng.random((K, K)) + 0.05
    np.fill_diagonal(a, 0)
    with np.errstate(divide="ignore"):
        log_a = np.log(a / a.sum(1, keepdims=True))
    np.fill_diagonal(log_a, -np.inf)
    counts = rng.integers(0, 5, (K, 5)).astype(float)
    log_d, log_s = duration_tables(counts, n, 0.1)
    for start, end in [(0, 2), (1, 1), (2, 0)]:
        path, score = best_cluster_path(log_a, start, end, n, log_d, log_s)
        _ref, ref_score = _brute_force(log_a, log_d, log_s, start, end, n, K)
        assert score == pytest.approx(ref_score)
        assert path_score(path, log_a, log_d, log_s) == pytest.approx(ref_score)
        assert path[0] == start and path[-1] == end and len(path) == n


def test_duration_tables_are_distributions_and_survivals():
    counts = np.array([[0, 3, 1, 0], [0, 0, 0, 4]], float)
    log_d, log_s = duration_tables(counts, 6, 0.5)
    p = np.exp(log_d[:, 1:])
    # probabilities over 1..6 of the padded table: counts + 0.5 each, normalised over 1..max(L, n) = 6
    assert np.allclose(p[0], (np.array([3, 1, 0, 0, 0, 0]) + 0.5) / 7.0)
    assert np.allclose(np.exp(log_s[:, 1]), 1.0)
    assert np.allclose(np.exp(log_s[0, 2]), 1 - p[0, 0])


def test_run_lengths_split_at_clip_boundaries():
    labels = np.array([0, 0, 1, 1, 1, 1, 2])
    cont = np.array([False, True, True, True, False, True, True])  # a clip starts at frame 4
    assert run_lengths(labels, cont) == [(0, 2), (1, 2), (1, 2), (2, 1)]


def test_segment_path_equals_brute_force_on_a_tiny_library():
    rng = np.random.default_rng(3)
    labels = np.array([0, 1, 1, 2, 0, 2, 1])
    cont = np.array([False, True, True, True, False, True, True])
    N, n = len(labels), 4
    path = np.array([0, 1, 2, 1])
    first, last = rng.random(N), rng.random(N)
    emission = rng.random((N, 3))
    entry = np.where(cont, np.roll(labels, 1), labels)
    for warp in (None, 0.3):
        _frames, cost = segment_path(labels, cont, path, first, last, 0.7, 0.9, emission, warp)
        best = np.inf
        for seq in itertools.product(range(N), repeat=n):
            c = first[seq[0]] + last[seq[-1]] + sum(0.7 * emission[seq[t], path[t]] for t in range(n))
            for a, b in itertools.pairwise(seq):
                steps = [0.0 if b == a + 1 and cont[b] else np.inf,
                         0.9 if labels[a] == entry[b] else np.inf]
                if warp is not None:
                    steps += [warp if a == b else np.inf, warp if b == a + 2 and cont[b] and cont[b - 1] else np.inf]
                c += min(steps)
            best = min(best, c)
        assert cost == pytest.approx(best)


def test_compiled_segment_path_equals_the_numpy_reference():
    # the compiled forward pass replaces the numpy one on the promise of the same frames and cost: random
    # libraries with integer costs (ties everywhere), hard and soft mismatch, with and without the time warp
    from vidstyle.inbetween import markov

    rng = np.random.default_rng(8)
    for trial in range(60):
        N, K, n = int(rng.integers(3, 40)), int(rng.integers(1, 5)), int(rng.integers(1, 9))
        labels = rng.integers(0, K, N)
        cont = rng.random(N) < 0.8
        path = rng.integers(0, K, n)
        first, last = rng.integers(0, 4, N).astype(float), rng.integers(0, 4, N).astype(float)
        emission = rng.integers(0, 3, (N, K)).astype(float) if trial % 2 else None
        warp = float(rng.integers(0, 3)) if trial % 3 else None
        got = segment_path(labels, cont, path, first, last, 1.0, 2.0, emission, warp)
        Kc = int(max(labels.max(), path.max())) + 1
        entry = np.where(cont, np.roll(labels, 1), labels)
        cont2 = np.zeros(N, bool)
        cont2[2:] = cont[2:] & cont[1:-1]
        ref = markov._segment_path_numpy(labels, cont, path, first, last, 1.0, 2.0, emission, warp, Kc, entry, cont2)
        assert np.array_equal(got[0], ref[0]) and got[1] == ref[1], trial
        if emission is not None:  # the caller's kept transpose (MarkovInbetweener.plan) gives the same
            kept = segment_path(labels, cont, path, first, last, 1.0, 2.0, emission, warp,
                                emission_t=np.ascontiguousarray(emission.T))
            assert np.array_equal(kept[0], ref[0]) and kept[1] == ref[1], trial


def test_slerp_midpoint_of_two_known_rotations():
    J = 2
    a = Rotation.from_euler("y", [[0], [0]], degrees=True).as_quat()
    b = Rotation.from_euler("y", [[90], [30]], degrees=True).as_quat()
    rot, root = slerp_inbetween(Keypose(a, np.zeros(3)), Keypose(b, np.array([2.0, 4.0, -6.0])), 3)
    mid = Rotation.from_quat(rot[1]).as_euler("yxz", degrees=True)[:, 0]
    assert mid == pytest.approx([45, 15])
    assert root[1] == pytest.approx([1.0, 2.0, -3.0])
    assert rot.shape == (3, J, 4)


@pytest.mark.parametrize("n", [2, 3, 17, 47])
def test_slerp_inbetween_is_scipys_slerp_of_every_joint(n):
    # all joints at once must give exactly what scipy's Slerp gives joint by joint
    from scipy.spatial.transform import Slerp

    J = 31
    a = Rotation.random(J, random_state=1).as_quat()
    b = Rotation.random(J, random_state=2).as_quat()
    rot, _ = slerp_inbetween(Keypose(a, np.zeros(3)), Keypose(b, np.ones(3)), n)
    w = np.linspace(0.0, 1.0, n)
    ref = np.stack([Slerp([0.0, 1.0], Rotation.from_quat(np.stack([a[j], b[j]])))(w).as_quat() for j in range(J)], 1)
    ref[0], ref[-1] = a, b
    assert np.array_equal(rot, ref)


def test_pin_passes_exactly_through_both_keys():
    lib = _library()
    rot, root = lib.rotations_[:20], lib.root_positions_[:20]
    s = Keypose(lib.rotations_[100], lib.root_positions_[100])
    e = Keypose(lib.rotations_[150], lib.root_positions_[150] + 5)
    out, r = pin(rot, root, s, e)
    assert np.array_equal(out[0], s.rotations) and np.array_equal(r[0], s.root)
    assert np.array_equal(out[-1], e.rotations) and np.array_equal(r[-1], e.root)
    assert np.allclose(np.linalg.norm(out, axis=-1), 1.0)


def test_pin_keeps_a_motion_that_already_meets_the_keys():
    lib = _library()
    rot, root = lib.rotations_[10:40], lib.root_positions_[10:40]
    out, r = pin(rot, root, Keypose(rot[0], root[0]), Keypose(rot[-1], root[-1]))
    assert np.allclose(np.abs(np.sum(out * rot, -1)), 1.0) and np.allclose(r, root)


@pytest.mark.parametrize("gap", [5, 16, 31])
def test_markov_output_passes_through_the_keys_at_their_frames(gap):
    lib = _library()
    model = MarkovInbetweener(n_clusters=6, n_components=4, random_state=0).fit(lib)
    s = Keypose(lib.rotations_[95], lib.root_positions_[95], Keypose(lib.rotations_[94], lib.root_positions_[94]))
    e = Keypose(lib.rotations_[200], lib.root_positions_[200] + np.array([1.0, 0.0, 2.0]))
    rot, root = model.inbetween(s, e, gap + 2)
    assert rot.shape == (gap + 2, lib.skeleton_.n_joints, 4) and root.shape == (gap + 2, 3)
    assert np.allclose(rot[0], s.rotations) and np.allclose(root[0], s.root)
    assert np.allclose(rot[-1], e.rotations) and np.allclose(root[-1], e.root)
    assert np.isfinite(rot).all() and np.allclose(np.linalg.norm(rot, axis=-1), 1.0)


def test_markov_reproduces_a_library_stretch_between_its_own_frames():
    # without the sketch's mismatch cost and time warps, the library's own stretch between the two keys is the
    # only zero-cost segment path: rendering and pinning must give it back exactly
    lib = _library()
    model = MarkovInbetweener(n_clusters=6, n_components=4, mismatch_cost=0.0, warp_cost=None, root_path="library",
                              random_state=0).fit(lib)
    a, b = 100, 130
    s = Keypose(lib.rotations_[a], lib.root_positions_[a], Keypose(lib.rotations_[a - 1], lib.root_positions_[a - 1]))
    e = Keypose(lib.rotations_[b], lib.root_positions_[b])
    plan = model.plan(s, e, b - a + 1)
    assert plan["frames"][0] == a and plan["frames"][-1] == b
    rot, root = model.inbetween(s, e, b - a + 1)
    assert np.allclose(np.abs(np.sum(rot * lib.rotations_[a : b + 1], -1)), 1.0, atol=1e-6)
    assert np.allclose(root, lib.root_positions_[a : b + 1], atol=1e-6)


def _cubic_keys(seed: int, T: int):
    """Keys at t = 0 and t = T of a random cubic root path p(t), each with the neighbour frame that gives its
    exact derivative as a one-frame step (the previous frame of the start, the following frame of the end)."""
    rng = np.random.default_rng(seed)
    c = rng.normal(size=(4, 3)) / np.array([1.0, 1.0, T, T * T])[:, None]
    t = np.arange(T + 1.0)[:, None]
    p = c[0] + c[1] * t + c[2] * t**2 + c[3] * t**3
    v = lambda x: c[1] + 2 * c[2] * x + 3 * c[3] * x**2
    q = np.tile(np.array([0.0, 0.0, 0.0, 1.0]), (2, 1))
    s = Keypose(q, p[0], previous=Keypose(q, p[0] - v(0.0)))
    e = Keypose(q, p[-1], following=Keypose(q, p[-1] + v(float(T))))
    return s, e, p


@pytest.mark.parametrize("seed,T", [(0, 15), (1, 30), (2, 46)])
def test_hermite_root_reproduces_any_cubic_path_from_its_ends(seed, T):
    # the cubic Hermite basis spans the cubics: end values and end derivatives determine the path exactly
    s, e, p = _cubic_keys(seed, T)
    assert np.allclose(hermite_root(s, e, T + 1), p, atol=1e-9)


def test_hermite_root_is_the_straight_line_for_keys_moving_along_the_chord():
    q = np.tile(np.array([0.0, 0.0, 0.0, 1.0]), (2, 1))
    a, b, T = np.array([1.0, 2.0, 3.0]), np.array([7.0, 2.0, -3.0]), 12
    step = (b - a) / T
    s = Keypose(q, a, previous=Keypose(q, a - step))
    e = Keypose(q, b, previous=Keypose(q, b - step))  # an end key's velocity from its previous frame
    lerp = slerp_inbetween(s, e, T + 1)[1]
    assert np.allclose(hermite_root(s, e, T + 1), lerp)
    assert np.allclose(hermite_root(Keypose(q, a), Keypose(q, b), T + 1), lerp)  # no neighbours: the chord


def test_hermite_root_path_changes_only_the_root():
    lib = _library()
    s, e, p = _cubic_keys(3, 20)
    s = Keypose(lib.rotations_[100], s.root, Keypose(lib.rotations_[99], s.previous.root))
    e = Keypose(lib.rotations_[150], e.root, following=Keypose(lib.rotations_[151], e.following.root))
    rot, root = lib.rotations_[10:31], lib.root_positions_[10:31]
    r_lib, p_lib = pin(rot, root, s, e)
    r_her, p_her = pin(rot, root, s, e, root_path="hermite")
    assert np.array_equal(r_lib, r_her) and np.allclose(p_her, p) and not np.allclose(p_lib, p)
    model = MarkovInbetweener(n_clusters=6, n_components=4, random_state=0)
    m_lib = model.set_params(root_path="library").fit(lib).inbetween(s, e, 21)
    m_her = model.set_params(root_path="hermite").inbetween(s, e, 21)
    assert np.array_equal(m_lib[0], m_her[0]) and np.allclose(m_her[1], p)
    sl = SlerpInbetweener("hermite").inbetween(s, e, 21)
    assert np.array_equal(sl[0], slerp_inbetween(s, e, 21)[0]) and np.allclose(sl[1], p)


def test_coverage_weight_is_one_at_the_library_and_falls_as_a_gaussian():
    from vidstyle.inbetween.markov import coverage_weight

    assert coverage_weight(5.0, None) == 1.0 and coverage_weight(0.0, 1.5) == 1.0
    assert coverage_weight(1.5, 1.5) == pytest.approx(np.exp(-1.0))
    assert coverage_weight(3.0, 1.0) == pytest.approx(np.exp(-9.0))
    w = [coverage_weight(d, 2.0) for d in np.linspace(0, 10, 21)]
    assert all(a > b for a, b in itertools.pairwise(w))


def test_coverage_gate_keeps_library_keys_and_gives_unknown_keys_slerp():
    lib = _library()
    free = MarkovInbetweener(n_clusters=6, n_components=4, coverage_scale=None, random_state=0).fit(lib)
    gated = MarkovInbetweener(n_clusters=6, n_components=4, coverage_scale=1.0, random_state=0).fit(lib)
    # keys that are library frames: distance 0, the library's motion as it is
    s = Keypose(lib.rotations_[95], lib.root_positions_[95], Keypose(lib.rotations_[94], lib.root_positions_[94]))
    e = Keypose(lib.rotations_[140], lib.root_positions_[140])
    assert gated.plan(s, e, 31)["key_distance"] < 1e-12
    for a, b in zip(free.inbetween(s, e, 31), gated.inbetween(s, e, 31)):
        assert np.array_equal(a, b)
    # keys no library frame resembles (every joint below the root turned 179 degrees): plain SLERP of the body,
    # the model's own root path
    turn = Rotation.from_rotvec([np.deg2rad(179.0), 0.0, 0.0])

    def far(k):
        r = k.rotations.copy()
        r[1:] = (turn * Rotation.from_quat(r[1:])).as_quat()
        return Keypose(r, k.root)

    s2, e2 = far(s), far(e)
    assert gated.plan(s2, e2, 31)["key_distance"] > 10
    rot, root = gated.inbetween(s2, e2, 31)
    want = slerp_inbetween(s2, e2, 31)[0]
    assert np.allclose(np.abs(np.sum(rot * want, -1)), 1.0, atol=1e-9)
    assert np.allclose(root, free.inbetween(s2, e2, 31)[1])
    assert not np.allclose(np.abs(np.sum(free.inbetween(s2, e2, 31)[0] * want, -1)), 1.0, atol=1e-3)


def test_unknown_root_path_is_refused():
    lib = _library()
    with pytest.raises(ParameterError, match="root_path"):
        MarkovInbetweener(n_clusters=6, n_components=4, root_path="spline").fit(lib)
    with pytest.raises(ParameterError, match="coverage_scale"):
        MarkovInbetweener(n_clusters=6, n_components=4, coverage_scale=0.0).fit(lib)
    with pytest.raises(ValueError, match="root_path"):
        pin(lib.rotations_[:5], lib.root_positions_[:5], Keypose(lib.rotations_[0], lib.root_positions_[0]),
            Keypose(lib.rotations_[4], lib.root_positions_[4]), root_path="spline")


def test_markov_follows_estimator_conventions_and_its_seed():
    lib = _library()
    m1 = MarkovInbetweener(n_clusters=5, n_components=3, random_state=7)
    params = m1.get_params()
    assert params["random_state"] == 7 and params["n_clusters"] == 5
    assert not hasattr(m1, "labels_")
    m1.fit(lib)
    m2 = MarkovInbetweener(**params).fit(lib)
    assert np.array_equal(m1.labels_, m2.labels_) and np.allclose(m1.transitions_, m2.transitions_)
    assert np.allclose(m1.transitions_.sum(1), 1.0) and np.all(np.diag(m1.transitions_) == 0)
    assert m1.set_params(n_clusters=4) is m1 and m1.n_clusters == 4
    from sklearn.base import clone

    assert clone(m2).get_params() == params


def test_evaluate_on_graph_slerp_is_exact_on_uniform_motion_and_windows_follow_lafan1(tmp_path):
    """evaluate inbetween --graph's evaluation on a clip whose every joint turns at a constant angular
    velocity about a fixed axis and whose root moves on a line: SLERP + LERP reproduce it exactly (L2P and
    L2Q zero), and so does the Markov method's default: the clip's poses are unlike every library pose, so
    the coverage gate gives the keys' SLERP, and the Hermite root of keys moving on a line is the line; the number of windows is LAFAN1's (start i every 40
    frames while i + 65 < frames); the graph's clips come back as motions frame for frame."""
    from vidstyle.evaluation.inbetween import evaluate_on_graph, graph_motions
    from vidstyle.mocap import Motion
    from vidstyle.mocap.bvh import write_bvh

    lib = _library(clips=3, frames=150)
    lib.n_frames = len(lib.frame_clip_)
    motions = graph_motions(lib)
    assert [m.n_frames for m in motions] == [150, 150, 150]
    np.testing.assert_allclose(np.concatenate([m.rotations for m in motions]), lib.rotations_, atol=1e-14)  # normalised
    np.testing.assert_array_equal(np.concatenate([m.root_positions for m in motions]), lib.root_positions_)
    F = 230
    t = np.arange(F) / 30.0
    rng = np.random.default_rng(3)
    J = lib.skeleton_.n_joints
    axes = rng.normal(size=(J, 3))
    axes /= np.linalg.norm(axes, axis=1, keepdims=True)
    q0 = Rotation.from_rotvec(rng.normal(scale=0.3, size=(J, 3)))
    rot = np.stack([(Rotation.from_rotvec(axes * 0.9 * ti) * q0).as_quat() for ti in t])  # 0.9 rad/s
    root = np.stack([0.4 * t, np.full(F, 3.0), 1.1 * t], 1)
    clip = tmp_path / "uniform.bvh"
    write_bvh(Motion(lib.skeleton_, rot, None, 30.0, root_positions=root), clip, precision=12)
    doc = evaluate_on_graph(lib, [clip], gaps=(15, 30, 45), methods=("markov", "slerp"), seed=0)
    assert doc["split"]["windows"] == len(range(0, F - 65, 40)) == 5
    for g in ("15", "30", "45"):
        assert doc["methods"]["slerp"][g]["l2p"] < 1e-6 and doc["methods"]["slerp"][g]["l2q"] < 1e-6
        assert doc["methods"]["markov"][g]["l2p"] < 1e-6 and doc["methods"]["markov"][g]["l2q"] < 1e-6
    few = evaluate_on_graph(lib, [clip], gaps=(15,), methods=("slerp",), max_windows=2)
    assert few["split"]["windows"] == 2 and few["params"]["max_windows"] == 2
    lib.clips_ = {"names": ["walk", "uniform"]}  # a clip of the library itself is refused: not held out
    with pytest.raises(ValueError, match="uniform"):
        evaluate_on_graph(lib, [clip], gaps=(15,), methods=("slerp",))


@pytest.mark.parametrize("args, needle", [
    ([], "--cmu"),
    (["--graph", "g.npz"], "--clips"),
    (["--graph", "g.npz", "--cmu", "x"], "--cmu"),
    (["--graph", "g.npz", "--clips", "absent.bvh"], "absent.bvh"),
    (["--graph", "g.npz", "--clips", "absent.bvh", "--max-windows", "0"], "--max-windows"),
])
def test_evaluate_inbetween_graph_bad_options_exit_2(tmp_path, capsys, monkeypatch, args, needle):
    from vidstyle.cli import main

    monkeypatch.chdir(tmp_path)
    assert main(["evaluate", "inbetween", *args, "--out", "m.json"]) == 2
    err = capsys.readouterr().err
    assert needle in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "m.json").exists()


def test_batched_global_poses_and_position_stats_equal_window_by_window():
    from vidstyle.evaluation.inbetween import _global_poses, global_pose, position_stats, windows
    from vidstyle.mocap.motion import Motion

    lib = _library(seed=3, clips=1, frames=200)
    m = Motion(lib.skeleton_, lib.rotations_, None, 30.0, root_positions=lib.root_positions_)
    wins = windows(m, 50, 20)
    assert len(wins) == 8
    # the window is turned to face +Z at frame n_past - 1, whatever frames around it
    assert all(abs(w.facing_angles()[9]) < 1e-9 for w in wins)
    rots = [w.rotations[3:30] for w in wins]
    roots = [w.root_positions[3:30] for w in wins]
    for (q, p), w, r, t in zip(_global_poses(wins, rots, roots), wins, rots, roots):
        q1, p1 = global_pose(w.skeleton, r, t)
        assert np.array_equal(q, q1) and np.array_equal(p, p1)
    mean, std = position_stats(wins)
    pos = np.concatenate([global_pose(w.skeleton, w.rotations, w.root_positions)[1] for w in wins])
    assert np.array_equal(mean, pos.mean(axis=0)) and np.array_equal(std, np.where(pos.std(axis=0) > 1e-9, pos.std(axis=0), 1.0))
