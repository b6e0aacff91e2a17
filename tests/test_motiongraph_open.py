"""The open motion graph: segments, enhancement edges, per-edge costs, re-pruning (issue 11)."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from scipy.sparse.csgraph import shortest_path
from scipy.spatial.transform import Rotation
from test_motiongraph_graph import _clips, _gait

from vidstyle.mocap import global_positions
from vidstyle.motiongraph import (
    Clip,
    EdgeKind,
    MotionGraph,
    Step,
    align_windows,
    edge_frames,
    plan_walk,
    render_walk,
)


@pytest.fixture(scope="module")
def base():
    return MotionGraph(window=6, fps=30, threshold_quantile=0.1, random_state=0).fit(_clips())


def _copy(graph):
    import copy

    return copy.deepcopy(graph)


def _segment_from(graph, centre_frame, bend=1.0):
    """A 2k-1 frame window of the graph around ``centre_frame`` with the spine bent far (a pose the
    clips never show)."""
    k = graph.window
    f = np.arange(centre_frame - k + 1, centre_frame + k)
    rot = graph.rotations_[f].copy()
    spine = graph.skeleton_.index("Spine")
    rot[:, spine] = (Rotation.from_rotvec([bend, 0, 0]) * Rotation.from_quat(rot[:, spine])).as_quat()
    return rot, graph.root_positions_[f].copy()


def _walk_run_pair(graph):
    """A walk frame a (kept, in a walk-only clip) and a run frame b (kept, in a run-only clip)."""
    k = graph.window
    names = graph.label_names_
    lab = np.array([names[x] for x in graph.labels_])
    a_clip, b_clip = graph.clips_["names"].index("walk_a"), graph.clips_["names"].index("run_b")
    a = graph.clips_["start"][a_clip] + 40
    b = graph.clips_["start"][b_clip] + 30
    assert graph.scc_[a] and graph.scc_[b] and lab[a] == "walk" and lab[b] == "run"
    assert (lab[a + 1 : a + k + 1] == "walk").all() and (lab[b - k + 1 : b + 1] == "run").all()
    return a, b


def test_enhancement_edge_is_taken_and_passes_through_the_segment_middle(base):
    graph = _copy(base)
    k = graph.window
    a, b = _walk_run_pair(graph)
    rot, root = _segment_from(graph, graph.clips_["start"][1] + 30)
    sid = graph.add_segment(rot, root, source="test")
    steps = [Step("walk", 40), Step("run", 40)]
    plain = plan_walk(graph, steps)
    [e] = graph.add_edges(a, b, EdgeKind.ENHANCEMENT, cost=0.0, segment=sid)
    assert graph.edge_in_scc_[e] and graph.edge_segment_[e] == sid
    walk = plan_walk(graph, steps)
    assert e in walk.transitions_used and walk.cost < plain.cost
    t0 = int(np.flatnonzero(walk.transition == e)[0])
    assert (walk.transition[t0 : t0 + 2 * k] == e).all()
    np.testing.assert_array_equal(walk.frames[t0 - 1], a)
    np.testing.assert_array_equal(walk.frames[t0 + 2 * k - 1], b)
    motion = render_walk(graph, walk, foot_lock=False)
    S = graph.segments_[sid]
    # output frame t0 + k - 1 is w_z exactly: every non-root local rotation equal, the whole pose equal up
    # to a floor placement (the alignment of W onto A)
    mid = motion.rotations[t0 + k - 1]
    assert np.allclose(np.abs(np.sum(mid[1:] * S.rotations[S.centre, 1:], -1)), 1.0, atol=1e-12)
    p_out = global_positions(motion[t0 + k - 1 : t0 + k])
    p_seg = graph._positions(S.rotations[S.centre : S.centre + 1], S.root_positions[S.centre : S.centre + 1])
    D, *_ = align_windows(p_out, p_seg, graph.joint_weights_)
    assert D < 1e-18
    # ... and the frames after the edge are B's, exactly (placed)
    p_b = global_positions(graph.motion(np.array([b, b + 1])))
    D, *_ = align_windows(global_positions(motion[t0 + 2 * k - 1 : t0 + 2 * k + 1]), p_b, graph.joint_weights_)
    assert D < 1e-18
    # no teleport anywhere
    pos = global_positions(motion)
    orig = np.linalg.norm(np.diff(global_positions(graph.motion()), axis=0), axis=-1).max(1)
    assert np.linalg.norm(np.diff(pos, axis=0), axis=-1).max() < 3 * orig.max()
    # foot locking runs over the enhancement's frames too (contacts from the departing/arriving frames)
    locked = render_walk(graph, walk)
    assert np.isfinite(locked.rotations).all() and walk.foot_lock["enabled"]
    # removing (discarding) the edge leaves the plain walk
    graph.remove_edges([e])
    graph.prune()
    again = plan_walk(graph, steps)
    assert again.cost == plain.cost and again.transitions_used == plain.transitions_used
    np.testing.assert_array_equal(again.frames, plain.frames)


def _anchored_segment(graph, a, b, middle, T):
    """A library-like segment: A's departing window (a+1..a+k), ``middle`` frames, B's arriving window
    (b-k+1..b), all moved by the floor transform ``T`` (the library clip's own coordinates), with its
    nodes on those windows and its centre in the middle."""
    k = graph.window
    f = np.concatenate([np.arange(a + 1, a + k + 1), middle, np.arange(b - k + 1, b + 1)])
    rot, root = T.apply_frames(graph.rotations_[f], graph.root_positions_[f])
    m = len(middle)
    return rot, root, k - 1 + (m + 1) // 2, (k - 1, k + m)


def test_anchored_enhancement_is_aligned_by_its_nodes_and_holds_w_z(base):
    from vidstyle.mocap.placement import Placement

    graph = _copy(base)
    k = graph.window
    a, b = _walk_run_pair(graph)
    T = Placement(1.1, 3.0, -2.0)
    middle = np.arange(graph.clips_["start"][1] + 20, graph.clips_["start"][1] + 29)  # 9 frames of another clip
    rot, root, centre, anchors = _anchored_segment(graph, a, b, middle, T)
    plain_sid = graph.add_segment(rot, root, centre=centre)
    sid = graph.add_segment(rot, root, centre=centre, anchors=anchors, hold=0.3)
    [e_plain, e] = graph.add_edges([a, a], [b, b], EdgeKind.ENHANCEMENT, cost=0.0, segment=[plain_sid, sid])
    # the node windows ARE A's and B's windows moved by T: the segment is placed by T^-1 exactly and B
    # lands where it was (composite identity), both halves cost 0
    np.testing.assert_allclose(graph.edge_align_segment_[e], T.inverse().as_array(), atol=1e-7)
    np.testing.assert_allclose(graph.edge_align_[e], 0.0, atol=1e-7)
    assert graph.edge_cost_[e] == 0.0
    # aligned by the windows beside w_z instead, the placement is something else
    assert np.abs(graph.edge_align_segment_[e_plain] - T.inverse().as_array()).max() > 1e-2
    graph.remove_edges([e_plain])
    graph.edge_cost_[graph.edges(EdgeKind.ENHANCEMENT)] = 0.0
    walk = plan_walk(graph, [Step("walk", 40), Step("run", 40)])
    [e] = [x for x in walk.transitions_used if graph.edge_kind_[x] == EdgeKind.ENHANCEMENT]
    t0 = int(np.flatnonzero(walk.transition == e)[0])
    motion = render_walk(graph, walk, foot_lock=False)
    S = graph.segments_[sid]
    held = int(round(0.3 * k))
    # hold: output frames k-1-held .. k-1+held of the edge are W's w_{z-held} .. w_{z+held} alone
    # (every non-root local rotation equal), the frames just outside are still blends
    out = motion.rotations[t0 + k - 1 - held : t0 + k + held, 1:]
    want = S.rotations[S.centre - held : S.centre + held + 1, 1:]
    np.testing.assert_allclose(np.abs(np.sum(out * want, -1)), 1.0, atol=1e-9)
    before = motion.rotations[t0 + k - 2 - held, 1:]
    assert np.abs(np.sum(before * S.rotations[S.centre - held - 1, 1:], -1)).min() < 1 - 1e-6
    with pytest.raises(ValueError, match="anchors"):
        graph.add_segment(rot, root, centre=centre, anchors=(centre + 1, anchors[1]))
    with pytest.raises(ValueError, match="hold"):
        graph.add_segment(rot, root, centre=centre, hold=1.0)


def test_blend_frames_ramp_moves_the_weight_only_inside_its_frames():
    from vidstyle.motiongraph import blend_frames, blend_weight

    k, r, start = 10, 6, 3
    q = np.tile([0.0, 0.0, 0.0, 1.0], (k, 2, 1))
    _, root = blend_frames(q, np.zeros(3), q, np.ones(3), k, ramp=r, start=start)
    t = root[:, 0]
    np.testing.assert_allclose(t[:start], 0.0)  # A before the ramp
    np.testing.assert_allclose(t[start : start + r], 1.0 - blend_weight(np.arange(r), r))
    np.testing.assert_allclose(t[start + r - 1 :], 1.0)  # B from the ramp's last frame on
    _, full = blend_frames(q, np.zeros(3), q, np.ones(3), k)
    np.testing.assert_allclose(full[:, 0], 1.0 - blend_weight(np.arange(k), k))
    with pytest.raises(ValueError, match="ramp"):
        blend_frames(q, np.zeros(3), q, np.ones(3), k, ramp=8, start=3)


def test_enhancement_is_not_taken_for_another_action_pair_or_when_dearer(base):
    graph = _copy(base)
    a, b = _walk_run_pair(graph)
    sid = graph.add_segment(*_segment_from(graph, graph.clips_["start"][1] + 30))
    [e] = graph.add_edges(a, b, EdgeKind.ENHANCEMENT, cost=0.0, segment=sid)
    assert e not in plan_walk(graph, [Step("walk", 80)]).transitions_used
    graph.edge_cost_[e] = 1e6
    assert e not in plan_walk(graph, [Step("walk", 40), Step("run", 40)]).transitions_used


def test_default_costs_are_the_kovar_window_distances(base):
    graph = _copy(base)
    k = graph.window
    blends = graph.edges(EdgeKind.BLEND)[:20]
    new = graph.add_edges(graph.edge_src_[blends], graph.edge_dst_[blends], EdgeKind.BLEND)
    np.testing.assert_allclose(graph.edge_cost_[new], graph.edge_cost_[blends], rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(np.cos(graph.edge_align_[new, 0] - graph.edge_align_[blends, 0]), 1.0)
    # an enhancement through a segment that IS the frames around a_{i+k}: its first half costs 0
    a, b = _walk_run_pair(graph)
    f = np.arange(a + 1, a + 2 * k + 1)
    sid = graph.add_segment(graph.rotations_[f], graph.root_positions_[f], centre=k - 1)
    [e] = graph.add_edges(a, b, EdgeKind.ENHANCEMENT, segment=sid)
    W = graph.joint_weights_.sum() * k
    pb = global_positions(graph.motion(np.arange(b - k + 1, b + 1)))
    pw = global_positions(graph.motion(f[k:]))
    D2, *_ = align_windows(pw, pb, graph.joint_weights_)
    assert graph.edge_cost_[e] == pytest.approx(np.sqrt(D2 / W), abs=1e-6)  # sqrt of a ~0 first half
    assert np.allclose(graph.edge_align_segment_[e], 0, atol=1e-9)
    with pytest.raises(ValueError, match="segment"):
        graph.add_edges(a, b, EdgeKind.ENHANCEMENT)
    with pytest.raises(ValueError, match="inside one clip"):
        graph.add_edges(graph.clips_["start"][1] - 2, b, EdgeKind.BLEND)
    with pytest.raises(ValueError, match="centre"):
        graph.add_segment(graph.rotations_[f], graph.root_positions_[f], centre=1)


def test_prune_after_add_keeps_every_node_with_an_in_and_out_edge(base):
    graph = _copy(base)
    clip = graph.clips_["names"].index("walk_b")
    in_clip = graph.frame_clip_ == clip
    # cut clip walk_b off: remove every blend into or out of it, re-prune: it leaves the component
    touch = (graph.edge_kind_ == EdgeKind.BLEND) & (in_clip[graph.edge_src_] | in_clip[graph.edge_dst_])
    into = np.flatnonzero(touch & in_clip[graph.edge_dst_] & ~in_clip[graph.edge_src_])
    out = np.flatnonzero(touch & in_clip[graph.edge_src_] & ~in_clip[graph.edge_dst_])
    e_in, e_out = into[0], out[-1]
    src = graph.edge_src_[[e_in, e_out]].copy()
    dst = graph.edge_dst_[[e_in, e_out]].copy()
    before = graph.scc_.copy()
    graph.remove_edges(touch)
    graph.prune()
    assert not (graph.scc_ & in_clip).any() and graph.scc_.sum() < before.sum()
    # one edge in, one edge out again: prune brings the part of the clip between them back
    graph.add_edges(src, dst, EdgeKind.BLEND)
    assert not graph.edge_in_scc_[-2:].any()  # not walkable until prune
    graph.prune()
    back = graph.scc_ & in_clip
    assert back.any() and np.flatnonzero(back).min() == dst[0] and np.flatnonzero(back).max() == src[1]
    N = graph.n_frames
    keep = np.flatnonzero(graph.scc_)
    use = graph.edge_in_scc_
    adj = np.zeros((N, N))
    adj[graph.edge_src_[use], graph.edge_dst_[use]] = 1
    sub = adj[np.ix_(keep, keep)]
    assert (sub.sum(0) > 0).all() and (sub.sum(1) > 0).all()  # an in and an out edge at every node
    assert np.isfinite(shortest_path(sub, unweighted=True)).all()
    assert np.array_equal(use, graph.scc_[graph.edge_src_] & graph.scc_[graph.edge_dst_])


# ----------------------------------------------------------------------------------- brute force
def _tiny_graph():
    clips = [
        Clip("walk", _gait(14, 1.0, 30, 4.0), ["walk"] * 14),
        Clip("run", _gait(14, 1.6, 45, 9.0, phase=2.0), ["run"] * 7 + ["walk"] * 7),
        Clip("walk2", _gait(12, 1.0, 30, 4.0, phase=1.0), ["walk"] * 12),
    ]
    return MotionGraph(window=2, fps=30, threshold_quantile=0.5, min_gap=3, random_state=0).fit(clips)


def _brute_force(graph, req, mismatch=5.0, penalty=0.2):
    """Least cost over every walk of len(req) frames, by enumerating them (no DP)."""
    names = graph.label_names_
    use = np.flatnonzero(graph.edge_in_scc_)
    out = {}
    for e in use:
        out.setdefault(int(graph.edge_src_[e]), []).append(int(e))
    thr = graph.threshold_
    T = len(req)
    best = [np.inf, None]

    def frames_of(e):
        if graph.edge_kind_[e] == EdgeKind.PLAYBACK:
            return [int(graph.edge_dst_[e])]
        return list(edge_frames(graph, np.array([e]))[0])

    def go(f, t, cost, path):
        if cost >= best[0]:
            return
        if t == T:
            best[0], best[1] = cost, list(path)
            return
        for e in out.get(f, []):
            fr = frames_of(e)
            if t + len(fr) > T:
                continue
            c = cost + (0.0 if graph.edge_kind_[e] == EdgeKind.PLAYBACK else graph.edge_cost_[e] / thr + penalty)
            c += mismatch * sum(names[graph.labels_[x]] != req[t + i] for i, x in enumerate(fr))
            path.append(e)
            go(fr[-1], t + len(fr), c, path)
            path.pop()

    for f in np.flatnonzero(graph.scc_):
        go(int(f), 1, mismatch * (names[graph.labels_[f]] != req[0]), [])
    return best[0], [e for e in best[1] if graph.edge_kind_[e] != EdgeKind.PLAYBACK]


def test_costs_choose_the_brute_force_minimal_path(rng):
    graph = _tiny_graph()
    k = graph.window
    assert len(graph.edges(EdgeKind.BLEND, in_scc=True)) >= 4
    sid = graph.add_segment(*_segment_from(graph, 6, bend=0.5))
    # a few enhancement edges walk -> run, run -> walk, with costs drawn from the seed
    kept = np.flatnonzero(graph.scc_)
    ok_src = [f for f in kept if f + k < graph.n_frames and graph.frame_clip_[f + k] == graph.frame_clip_[f]]
    ok_dst = [f for f in kept if f - k + 1 >= 0 and graph.frame_clip_[f - k + 1] == graph.frame_clip_[f]]
    lab = np.array([graph.label_names_[x] for x in graph.labels_])
    walk_src = [f for f in ok_src if (lab[f + 1 : f + k + 1] == "walk").all()]
    run_dst = [f for f in ok_dst if (lab[f - k + 1 : f + 1] == "run").all()]
    pairs = [(a, b) for a in walk_src[:: max(1, len(walk_src) // 3)] for b in run_dst[:: max(1, len(run_dst) // 3)]]
    other = list(zip(rng.choice(ok_src, 3), rng.choice(ok_dst, 3)))
    src, dst = np.array(pairs + other).T
    cost = np.concatenate([np.zeros(len(pairs)), rng.uniform(0, 2 * graph.threshold_, 3)])
    enh = graph.add_edges(src, dst, EdgeKind.ENHANCEMENT, cost=cost, segment=sid)
    graph.prune()
    req = ["walk"] * 5 + ["run"] * 4 + ["walk"] * 4
    seen = set()
    for trial in range(6):
        walk = plan_walk(graph, [Step("walk", 5), Step("run", 4), Step("walk", 4)], strict=False)
        ref, _ = _brute_force(graph, req)
        assert walk.cost == pytest.approx(ref, abs=1e-9)
        seen.add(tuple(walk.transitions_used))
        # make the edges the walk used dearer: the DP must follow the brute force to another path
        for e in walk.transitions_used:
            graph.edge_cost_[e] += 3 * graph.threshold_
    assert len(seen) > 1  # the costs changed the chosen path
    assert set(enh) & set(itertools.chain(*seen))  # an enhancement edge was the cheapest at some point


def test_checkpointed_history_with_two_block_edges_gives_the_same_walk(base):
    graph = _copy(base)
    a, b = _walk_run_pair(graph)
    sid = graph.add_segment(*_segment_from(graph, graph.clips_["start"][1] + 30))
    graph.add_edges([a, a + 3], [b, b + 2], EdgeKind.ENHANCEMENT, cost=[0.0, 0.05], segment=sid)
    steps = [Step("walk", 40), Step("run", 33), Step("walk", 41), Step("run", 20)]
    full = plan_walk(graph, steps)
    tiny = plan_walk(graph, steps, max_history_bytes=1)
    assert any(graph.edge_kind_[e] == EdgeKind.ENHANCEMENT for e in full.transitions_used)
    assert tiny.cost == full.cost and tiny.transitions_used == full.transitions_used
    np.testing.assert_array_equal(tiny.frames, full.frames)


def test_segment_from_a_library_motion_in_another_unit_and_rate(base):
    from vidstyle.mocap.retarget import rescale

    graph = _copy(base)
    k = graph.window
    m = _gait(120, 1.0, 30, 4.0, fps=60.0)  # the base clips' skeleton, at 60 fps, in other units
    sid = graph.add_segment_from(rescale(m, 0.01), 1.0, source="lib.bvh@1s")
    S = graph.segments_[sid]
    ref = m.resample(30.0)
    assert S.n_frames == 2 * k and S.centre == k - 1
    np.testing.assert_allclose(S.root_positions, ref.root_positions[30 - k + 1 : 30 + k + 1], atol=1e-9)
    np.testing.assert_allclose(np.abs(np.sum(S.rotations * ref.rotations[30 - k + 1 : 30 + k + 1], -1)), 1, atol=1e-9)
    with pytest.raises(ValueError, match="closer than"):
        graph.add_segment_from(m, 0.05)


def test_library_errors_name_parameters_and_the_cli_its_flags(base, tmp_path, capsys):
    from vidstyle.cli import main
    from vidstyle.errors import InputError
    from vidstyle.mocap import write_bvh

    with pytest.raises(InputError, match=r"^window: must be at least 2"):
        MotionGraph(window=1).fit(_clips())
    with pytest.raises(InputError, match=r"^steps: step 0 \('jump'"):
        plan_walk(base, [Step("jump", 10)])
    clip = tmp_path / "a.bvh"
    write_bvh(_gait(40, 1.0, 30, 4.0), clip)
    assert main(["build-graph", str(clip), "--window", "1", "--out", str(tmp_path / "g.npz")]) == 2
    assert "--window: must be at least 2" in capsys.readouterr().err
    graph = tmp_path / "g2.npz"
    base.save(graph)
    seq = tmp_path / "s.json"
    seq.write_text('["jump"]')
    assert main(["synthesize", "--graph", str(graph), "--sequence", str(seq), "--out", str(tmp_path / "o.bvh")]) == 2
    assert "--sequence: step 0 ('jump'" in capsys.readouterr().err
