"""Graph construction: blend weights, transition clips, SCC pruning, labels, save/load, synthesis."""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy.sparse.csgraph import shortest_path
from scipy.spatial.transform import Rotation

from vidstyle.errors import InputError
from vidstyle.mocap import Motion, Skeleton, global_positions, write_bvh
from vidstyle.motiongraph import (
    Clip,
    EdgeKind,
    LabelBook,
    MotionGraph,
    Step,
    blend_weight,
    cmu_action,
    has_tpose_first_frame,
    load_clips,
    parse_sequence,
    plan_walk,
    render_walk,
    slerp,
)
from vidstyle.mocap.placement import Placement
from vidstyle.motiongraph.blend import blend_frames


# ------------------------------------------------------------------------------------------ blend
def test_blend_weight_is_c1_and_ends_exactly():
    k = 7
    assert blend_weight(-1, k) == 1.0 and blend_weight(k - 1, k) == 0.0
    h = 1e-6
    for p in (-1.0, k - 1.0):
        assert abs((blend_weight(p + h, k) - blend_weight(p - h, k)) / (2 * h)) < 1e-6  # slope 0 at both ends
    w = blend_weight(np.arange(-1, k), k)
    assert np.all(np.diff(w) < 0)
    assert np.isclose(blend_weight((k - 2) / 2, k), 0.5)  # symmetric about the middle


def test_slerp_endpoints_and_midpoint(rng):
    q0 = Rotation.random(5, random_state=1).as_quat()
    q1 = Rotation.random(5, random_state=2).as_quat()
    assert np.allclose(np.abs(np.sum(slerp(q0, q1, np.zeros(5)) * q0, -1)), 1)
    assert np.allclose(np.abs(np.sum(slerp(q0, q1, np.ones(5)) * q1, -1)), 1)
    mid = Rotation.from_quat(slerp(q0, q1, np.full(5, 0.5)))
    d0 = (mid * Rotation.from_quat(q0).inv()).magnitude()
    d1 = (Rotation.from_quat(q1) * mid.inv()).magnitude()
    assert np.allclose(d0, d1)


def test_placement_frames_and_composition_are_rigid_floor_transforms(rng):
    rot = Rotation.random(4, random_state=3).as_quat()[:, None, :]
    root = rng.normal(size=(4, 3))
    P1, P2 = Placement(0.3, 1.0, 2.0), Placement(-0.5, -3.0, 0.5)
    r1, p1 = P1.apply_frames(rot, root)
    r2, p2 = P2.apply_frames(r1, p1)
    r3, p3 = P2.then(P1).apply_frames(rot, root)
    assert np.allclose(p2, p3) and np.allclose(np.abs(np.sum(r2 * r3, -1)), 1)
    assert np.allclose(p1[:, 1], root[:, 1])
    # the root rotation turns by exactly theta about +Y (scipy as the reference)
    ref = (Rotation.from_rotvec([0, 0.3, 0]) * Rotation.from_quat(rot[:, 0])).as_quat()
    assert np.allclose(np.abs(np.sum(r1[:, 0] * ref, -1)), 1)
    assert np.allclose(P1.inverse().apply_points(p1), root)
    assert np.allclose(Rotation.from_rotvec([0, 0.3, 0]).apply(root) + [1.0, 0, 2.0], p1)


def test_blend_frames_start_near_a_end_at_b(rng):
    k = 6
    ra = Rotation.random(k, random_state=4).as_quat()[:, None]
    rb = Rotation.random(k, random_state=5).as_quat()[:, None]
    pa, pb = rng.normal(size=(k, 3)), rng.normal(size=(k, 3))
    rot, root = blend_frames(ra, pa, rb, pb, k)
    assert np.allclose(root[-1], pb[-1]) and np.allclose(np.abs(np.sum(rot[-1] * rb[-1], -1)), 1)
    a0 = blend_weight(0, k)
    assert np.allclose(root[0], a0 * pa[0] + (1 - a0) * pb[0])


# ------------------------------------------------------------------------------------------ data
def _skeleton():
    names = ["Hips", "LeftUpLeg", "LeftFoot", "RightUpLeg", "RightFoot", "Spine", "Head"]
    parents = [-1, 0, 1, 0, 3, 0, 5]
    offsets = [[0, 0, 0], [1, -1, 0], [0, -4, 0], [-1, -1, 0], [0, -4, 0], [0, 2, 0], [0, 2, 0]]
    return Skeleton(names, np.array(parents), np.array(offsets, float), end_sites={2: np.array([0, -1.0, 1]), 4: np.array([0, -1.0, 1]), 6: np.array([0, 1.0, 0])})


def _gait(n, freq, amp, speed, phase=0.0, fps=30.0):
    """A periodic synthetic gait: legs swing, the root moves forward along +Z."""
    sk = _skeleton()
    t = np.arange(n) / fps
    ang = np.zeros((n, sk.n_joints, 3))
    ang[:, 1, 0] = amp * np.sin(2 * np.pi * freq * t + phase)
    ang[:, 3, 0] = -amp * np.sin(2 * np.pi * freq * t + phase)
    ang[:, 5, 0] = 0.2 * amp * np.sin(4 * np.pi * freq * t + phase)
    root = np.stack([0 * t, 5.0 + 0.2 * np.cos(4 * np.pi * freq * t), speed * t], axis=1)
    return Motion.from_euler(sk, ang, root, fps, order="XYZ")


def _clips():
    return [
        Clip("walk_a", _gait(90, 1.0, 30, 4.0), ["walk"] * 90),
        Clip("walk_b", _gait(75, 1.0, 30, 4.0, phase=1.0), ["walk"] * 75),
        Clip("run_a", _gait(80, 1.6, 45, 9.0), ["run"] * 40 + ["walk"] * 40),
        Clip("run_b", _gait(70, 1.6, 45, 9.0, phase=2.0), ["run"] * 70),
    ]


@pytest.fixture(scope="module")
def graph():
    return MotionGraph(window=6, fps=30, threshold_quantile=0.1, random_state=0).fit(_clips())


def test_graph_scc_every_frame_reaches_every_other(graph):
    N = graph.n_frames
    keep = np.flatnonzero(graph.scc_)
    assert len(keep) > 0.5 * N
    adj = np.zeros((N, N))
    for f in range(N - 1):
        if graph.frame_clip_[f] == graph.frame_clip_[f + 1]:
            adj[f, f + 1] = 1
    # the table holds exactly those playback edges, plus the blends
    play = graph.edges(EdgeKind.PLAYBACK)
    assert int(adj.sum()) == len(play) and adj[graph.edge_src_[play], graph.edge_dst_[play]].all()
    for e in graph.edges(EdgeKind.BLEND, in_scc=True):
        adj[graph.edge_src_[e], graph.edge_dst_[e]] = 1
    sub = adj[np.ix_(keep, keep)]
    dist = shortest_path(sub, unweighted=True)
    assert np.isfinite(dist).all()
    # no dead end: every kept frame has a successor inside the component
    assert (sub.sum(1) > 0).all()


def test_transitions_are_local_minima_with_consistent_alignment(graph):
    k = graph.window
    blends = graph.edges(EdgeKind.BLEND)
    assert graph.stats_["transitions"] == len(blends) > 0 and np.all(graph.edge_cost_[blends] <= graph.threshold_ + 1e-9)
    pos = global_positions(graph.motion())
    from vidstyle.motiongraph import align_windows

    W = graph.joint_weights_.sum() * k
    clip = graph.frame_clip_
    N = len(clip)

    def window_ok(s, c):  # a k-frame window starting at s inside clip c
        return 0 <= s and s + k - 1 < N and clip[s] == c and clip[s + k - 1] == c

    checked_neighbours = 0
    for e in blends[:: max(1, len(blends) // 25)]:
        i, j = graph.edge_src_[e] + 1, graph.edge_dst_[e]  # Kovar's transition i -> j is the edge i-1 -> j
        a, b = i, j - k + 1  # the departing and arriving windows
        d, th, x0, z0 = align_windows(pos[a : a + k], pos[b : b + k], graph.joint_weights_)
        assert np.isclose(np.sqrt(d / W), graph.edge_cost_[e], rtol=1e-6, atol=1e-6)
        assert np.isclose(np.cos(th - graph.edge_align_[e, 0]), 1.0)
        assert np.allclose([x0, z0], graph.edge_align_[e, 1:], atol=1e-6)
        # local minimum: no window pair one window earlier or later on either side (same clips) is closer
        for da in (-1, 0, 1):
            for db in (-1, 0, 1):
                if (da, db) == (0, 0) or not (window_ok(a + da, clip[a]) and window_ok(b + db, clip[b])):
                    continue
                dn = align_windows(pos[a + da : a + da + k], pos[b + db : b + db + k], graph.joint_weights_)[0]
                assert d <= dn * (1 + 1e-4) + 1e-6, (e, da, db, d, dn)
                checked_neighbours += 1
        # transitions never jump within a window of themselves
        same = clip[i] == clip[j]
        assert not same or abs((j - k + 1) - i) >= 2 * k
    assert checked_neighbours > 50


def test_save_load_roundtrip(graph, tmp_path):
    path = tmp_path / "g.npz"
    graph.save(path)
    g2 = MotionGraph.load(path)
    for name in ("rotations_", "root_positions_", "labels_", "scc_", "edge_src_", "edge_dst_", "edge_kind_", "edge_cost_",
                 "edge_segment_", "edge_align_", "edge_in_scc_"):
        assert np.allclose(getattr(g2, name), getattr(graph, name), atol=1e-6)
    assert g2.label_names_ == graph.label_names_ and g2.get_params() == graph.get_params()
    z = np.load(path)
    assert json.loads(str(z["params_json"]))["random_state"] == 0
    assert str(z["kind"]) == "vidstyle.motiongraph" and int(z["schema_version"]) == 2
    with pytest.raises(InputError, match="kind"):
        np.savez(tmp_path / "x.npz", a=np.zeros(2))
        MotionGraph.load(tmp_path / "x.npz")


def test_walk_realises_sequence_and_is_continuous(graph):
    steps = [Step("walk", 45), Step("run", 40), Step("walk", 50)]
    walk = plan_walk(graph, steps)
    assert len(walk.frames) == 135
    names = graph.label_names_
    got = np.array([names[x] for x in graph.labels_[walk.frames]])
    assert np.mean(got == np.array(walk.requested)) > 0.8
    motion = render_walk(graph, walk)
    pos = global_positions(motion)
    step = np.linalg.norm(np.diff(pos, axis=0), axis=-1).max(1)
    orig = np.linalg.norm(np.diff(global_positions(graph.motion()), axis=0), axis=-1).max(1)
    orig = orig[graph.frame_clip_[1:] == graph.frame_clip_[:-1]]
    assert step.max() < 3 * orig.max()  # no teleports at seams
    # the walk only uses playback and transitions of the component
    for t in range(1, len(walk.frames)):
        if walk.transition[t] < 0 and walk.transition[t - 1] < 0:
            assert walk.frames[t] == walk.frames[t - 1] + 1
    assert all(graph.edge_in_scc_[e] and graph.edge_kind_[e] == EdgeKind.BLEND for e in walk.transitions_used)


def _reference_walk_cost(graph, req, mismatch=5.0, penalty=0.2):
    """Least walk cost by a plain frame-by-frame DP over (output frame, graph frame), written from the
    objective in vidstyle.motiongraph.synthesis' docstring (no blocking, no vectorisation)."""
    k, lab, clip = graph.window, graph.labels_, graph.frame_clip_
    scc = np.flatnonzero(graph.scc_)
    thr = graph.threshold_ or 1.0
    trans = []
    for e in np.flatnonzero(graph.edge_in_scc_ & (graph.edge_kind_ == EdgeKind.BLEND)):
        i, j = int(graph.edge_src_[e]) + 1, int(graph.edge_dst_[e])
        blend = [lab[i + p] if blend_weight(p, k) >= 0.5 else lab[j - (k - 1) + p] for p in range(k)]
        trans.append((i - 1, j, graph.edge_cost_[e] / thr + penalty, blend))
    V = [{i: mismatch * (lab[i] != req[0]) for i in scc}]
    for t in range(1, len(req)):
        cur = {}
        for i in scc:
            if i - 1 in V[t - 1] and clip[i - 1] == clip[i]:
                cur[i] = V[t - 1][i - 1] + mismatch * (lab[i] != req[t])
        if t >= k:
            for dep, arr, c, blend in trans:
                if dep in V[t - k]:
                    v = V[t - k][dep] + c + mismatch * sum(b != r for b, r in zip(blend, req[t - k + 1 : t + 1]))
                    if v < cur.get(arr, np.inf):
                        cur[arr] = v
        V.append(cur)
    return min(V[-1].values())


@pytest.mark.parametrize("steps", [[("walk", 20)], [("walk", 14), ("run", 16)], [("run", 10), ("walk", 12), ("run", 9)]])
def test_walk_cost_is_minimal_among_alternatives(graph, steps):
    """The planner's walk costs what a brute-force DP over every (output frame, graph frame) finds, and
    the walk it returns really costs that much (re-added from its frames and transitions)."""
    steps = [Step(a, n) for a, n in steps]
    walk = plan_walk(graph, steps)
    names = list(graph.label_names_)
    req = np.concatenate([np.full(s.frames, names.index(s.action)) for s in steps])
    assert np.isclose(walk.cost, _reference_walk_cost(graph, req), rtol=1e-9, atol=1e-9)
    # the returned walk: legal moves only, and its own cost equals the reported optimum
    thr = graph.threshold_ or 1.0
    own = 5.0 * float((graph.labels_[walk.frames] != req).sum())
    own += sum(graph.edge_cost_[e] / thr + 0.2 for e in walk.transitions_used)
    assert np.isclose(own, walk.cost, rtol=1e-9, atol=1e-9)
    assert graph.scc_[walk.frames].all()
    for t in range(1, len(req)):
        if walk.transition[t] < 0 and walk.transition[t - 1] < 0:
            assert walk.frames[t] == walk.frames[t - 1] + 1
            assert graph.frame_clip_[walk.frames[t]] == graph.frame_clip_[walk.frames[t - 1]]
    if len(steps) > 1:  # the request changes action: the optimum uses transitions and matches most frames
        assert walk.transitions_used and own < 5.0 * len(req) / 2


def test_unrealisable_sequences_name_the_step(graph):
    with pytest.raises(InputError, match=r"step 1 \('jump'"):
        plan_walk(graph, [Step("walk", 10), Step("jump", 10)])


def test_sequence_parsing():
    steps = parse_sequence({"classes": ["walk", "run"], "sequence": [{"action": 1, "frames": 14}, {"action": "walk", "frames": 20}], "fps": 20}, 30)
    assert [(s.action, s.frames) for s in steps] == [("run", 21), ("walk", 30)]
    assert [(s.action, s.frames) for s in parse_sequence(["walk", "run"], 30, 0.5)] == [("walk", 15), ("run", 15)]
    with pytest.raises(InputError, match="step 0"):
        parse_sequence([{"frames": 3}], 30)


# ------------------------------------------------------------------------------------------ labels
def test_cmu_keywords():
    assert cmu_action("playground - climb, hang, jump down") == "climb"
    assert cmu_action("playground - forward jumps, turn around") == "jump"
    assert cmu_action("run/jog") == "run"
    assert cmu_action("slow walk/stride") == "walk"
    assert cmu_action("punch/strike") == "punch"
    assert cmu_action("basketball - forward dribble") == "basketball"
    assert cmu_action("wash self") == "other"


def test_label_files(tmp_path):
    (tmp_path / "a.labels.json").write_text(json.dumps({"bvh": "mocap/a.bvh", "fps": 60, "classes": ["Guard", "Jab"],
                                                        "events": [{"label": "Jab", "start": 2, "end": 4}]}))
    (tmp_path / "l.csv").write_text("file,label,start,end\nb.bvh,Kick,,\nb.bvh,Jab,1,3\n")
    book = LabelBook().load(tmp_path / "a.labels.json").load(tmp_path / "l.csv")
    assert book.frame_labels("x/a.bvh", 5) == ["unlabelled", "unlabelled", "Jab", "Jab", "unlabelled"]
    assert book.frame_labels("b.bvh", 4) == ["Kick", "Jab", "Jab", "Kick"]
    with pytest.raises(InputError):
        LabelBook().load(tmp_path / "missing.csv")


def test_load_clips_uses_sidecar_labels(tmp_path):
    m = _gait(20, 1.0, 30, 4.0)
    write_bvh(m, tmp_path / "t.bvh")
    (tmp_path / "t.labels.json").write_text(json.dumps({"bvh": "mocap/t.bvh", "labels": ["Jab"] * 20}))
    [clip] = load_clips([tmp_path])
    assert clip.labels == ["Jab"] * 20 and len(clip.sha256) == 64


def test_tpose_detection():
    m = _gait(30, 1.0, 40, 4.0, phase=1.5)  # frame 0 far from the rest pose
    assert not has_tpose_first_frame(m)
    rot = m.rotations.copy()
    rot[0] = [0, 0, 0, 1]
    assert has_tpose_first_frame(Motion(m.skeleton, rot, m.translations, m.fps))


def test_inverse_placements_equal_the_objects_to_the_bit():
    # the graph's blend alignments are computed in one pass instead of one Placement per candidate pair,
    # on the promise that the stored numbers stay the same: every one must be equal, not close
    from vidstyle.mocap.placement import Placement, inverse_placements

    rng = np.random.default_rng(7)
    t, x, z = rng.uniform(-4, 4, 3000), rng.normal(scale=50, size=3000), rng.normal(scale=50, size=3000)
    ref = np.array([Placement(a, b, c).inverse().as_array() for a, b, c in zip(t, x, z)])
    got = inverse_placements(t, x, z)
    assert got.shape == (3000, 3)
    assert np.array_equal(got, ref)
    # and an inverse undoes its placement (independent truth)
    pts = rng.normal(size=(5, 3))
    p = Placement(*ref[0]).then(Placement(t[0], x[0], z[0]))
    assert np.allclose(p.apply_points(pts), pts, atol=1e-9)
