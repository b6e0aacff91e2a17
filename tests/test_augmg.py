"""AugMG: demo transition styles, library, projection/matching, enhanced distance, transitions, CLI."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from vidstyle.augmg.enhance import (
    KEYPOINT_WEIGHTS,
    enhanced_distance,
    place_segment,
    plain_transition,
    two_half_transition,
    window_distance,
)
from vidstyle.augmg.index import LibraryClip, PoseIndex, coherent_ranking
from vidstyle.augmg.keypoints import KP, keypoint_positions
from vidstyle.formats.library import read_library
from vidstyle.augmg.projection import (
    angle_features,
    facing_normalised,
    facing_of_keypoints,
    project,
    relative_azimuth,
)
from vidstyle.cli import app
from vidstyle.augmg import defaults as augmg_defaults
from vidstyle.demo.dataset import DatasetParams, make_performer, make_take
from vidstyle.demo.timeline import apply_transition_styles, build_take, performance_plan
from vidstyle.demo.transitions import TRANSITION_KINDS


@pytest.fixture(scope="module")
def take():
    params = DatasetParams(performance_seconds=30.0)
    p = make_performer(params, 2)
    return p, make_take(params, p, 2, 100)


@pytest.fixture(scope="module")
def library(tmp_path_factory):
    from vidstyle.demo.library import LibraryParams, make_library

    out = tmp_path_factory.mktemp("lib") / "lib"
    make_library(out, LibraryParams(performers=2, action_seconds=3.0), jobs=1)
    return out


# ------------------------------------------------------------------------------------------ demo styles
def test_styled_transitions_sit_in_guard_pauses_between_their_pair(take):
    p, tk = take
    assert tk.transitions, "performer 2 has styled transitions in a 30 s performance"
    plan_frames = np.cumsum([0] + [s.frames for s in tk.plan]) * tk.ratio
    for t in tk.transitions:
        assert (t["from"], t["to"], t["kind"]) in p.transitions
        assert set(tk.labels[t["start"]:t["end"]]) == {"Guard"}
        assert tk.labels[t["start"] - 1] == t["from"] and tk.labels[t["end"]] == t["to"]
        assert t["start"] in plan_frames and t["end"] in plan_frames  # whole segments, on video frames
        assert t["start"] < t["key"] < t["end"]


def test_transition_pose_differs_from_guard_and_is_drawn_from_the_motion(take):
    _, tk = take
    pts = keypoint_positions(tk.motion)
    for t in tk.transitions:
        guard_end = pts[t["start"] - 1]
        key = pts[t["key"]]
        # the transition pose is far from the guard around it: > 5 cm mean keypoint displacement
        rel = lambda x: x - x[KP["pelvis"]] * [1, 0, 1]
        assert np.linalg.norm(rel(key) - rel(guard_end), axis=1).mean() * 0.0564 > 0.05


def test_plans_without_a_styled_pair_are_unchanged():
    params = DatasetParams()
    p = make_performer(params, 0)
    rng = np.random.default_rng(0)
    plan = performance_plan(p.__class__(p.id, p.body, p.style, p.chain), 400, rng)  # a performer with no habits
    again = apply_transition_styles(p.__class__(p.id, p.body, p.style, p.chain), plan, 400)
    assert [(s.label, s.frames) for s in plan] == [(s.label, s.frames) for s in again]
    styled = apply_transition_styles(p, plan, 400)
    assert sum(s.frames for s in styled) == 400


def test_single_action_takes_are_those_of_a_performer_without_styles():
    params = DatasetParams.small()
    p = make_performer(params, 1)
    plain = p.__class__(p.id, p.body, p.style, p.chain)
    from vidstyle.demo.dataset import _take_rng
    from vidstyle.demo.timeline import single_action_plan

    a = build_take(p, single_action_plan(p, "Jab", 60, _take_rng(params, 1, 0)), _take_rng(params, 1, 0))
    b = build_take(plain, single_action_plan(plain, "Jab", 60, _take_rng(params, 1, 0)), _take_rng(params, 1, 0))
    np.testing.assert_array_equal(a.motion.rotations, b.motion.rotations)
    assert not a.transitions


# ------------------------------------------------------------------------------------------ library
def test_library_holds_each_pose_in_a_context_clip_but_no_action_to_action_transition(library):
    doc = read_library(library / "library.json")
    holds = {c["holds_pose"] for c in doc["clips"] if c["holds_pose"]}
    assert holds == set(TRANSITION_KINDS)
    for c in doc["clips"]:
        labels = json.loads((library / c["labels"]).read_text())["labels"]
        actions = {x for x in labels if x not in ("Guard", "Step", "Dodge", "Switch", "Stop")}
        assert len(actions) <= 1, f"{c['name']} chains two actions"
    assert all(not c["performer"].startswith("p") for c in doc["clips"])  # no dataset performer


def test_cmu_retarget_keeps_every_unbranched_bone_direction(cmu_dir):
    from vidstyle.mocap.retarget import retarget_rest_corrected
    from vidstyle.demo.skeleton import build_skeleton
    from vidstyle.mocap import forward_kinematics, read_bvh

    m = read_bvh(cmu_dir / "01_01.bvh")[1:40]
    target = build_skeleton()
    r = retarget_rest_corrected(m, target)
    p0, _ = forward_kinematics(m)
    p1, _ = forward_kinematics(r)
    for j in range(m.skeleton.n_joints):
        par = m.skeleton.parents[j]
        if par < 0 or len(m.skeleton.children(par)) != 1:
            continue
        d0 = p0[:, j] - p0[:, par]
        d1 = p1[:, j] - p1[:, par]
        cos = np.sum(d0 * d1, -1) / (np.linalg.norm(d0, axis=-1) * np.linalg.norm(d1, axis=-1) + 1e-12)
        assert cos.min() > 0.999, m.skeleton.names[j]


# ------------------------------------------------------------------------------------------ projection
def test_projection_matches_the_renderer_camera_up_to_perspective(take):
    from vidstyle.render.camera import Camera

    _, tk = take
    pts = keypoint_positions(tk.motion)[::30]
    cam = Camera.for_view(tk.motion, "left", elevation_deg=10.0)
    uv, _ = cam.project(pts)
    fac = facing_of_keypoints(pts)
    az = relative_azimuth(cam.center, pts[:, KP["pelvis"]], fac)
    ortho = np.stack([project(facing_normalised(pts[i:i + 1], fac[i:i + 1]), az[i], 10.0)[0] for i in range(len(pts))])
    cos = np.sum(angle_features(uv).reshape(len(pts), -1, 2) * angle_features(ortho).reshape(len(pts), -1, 2), -1)
    assert np.median(cos) > 0.99  # bone directions agree (perspective bends them only slightly)


def test_features_are_scale_and_translation_free(rng):
    pts = rng.normal(size=(4, 15, 2))
    np.testing.assert_allclose(angle_features(pts), angle_features(3.7 * pts + [5.0, -2.0]), atol=1e-6)


def test_knn_equals_brute_force_and_self_query_finds_itself(rng):
    clips = [LibraryClip(f"c{i}.bvh", rng.normal(size=(60, 15, 3)) + [0, 1, 0], 60.0) for i in range(3)]
    idx = PoseIndex(n_views=4, stride=3).fit(clips)
    q = rng.normal(size=(5, 15, 2))
    i, d = idx.query(q, azimuth_deg=92.0, k=6)
    feats = idx.features_[1].astype(np.float64)  # 92 degrees -> the 90-degree view
    brute = np.linalg.norm(feats[None] - angle_features(q)[:, None], axis=-1)
    np.testing.assert_allclose(d, np.sort(brute, axis=1)[:, :6], rtol=1e-5, atol=1e-5)
    # a library frame projected at a view is its own nearest neighbour there
    pts = clips[1].points[30:31]
    own = project(facing_normalised(pts, facing_of_keypoints(pts)), 180.0, 10.0)
    i, d = idx.query(own, 180.0, k=1)
    assert idx.clip_[i[0, 0]] == 1 and idx.frame_[i[0, 0]] == 30 and d[0, 0] < 1e-5


def test_coherent_ranking_is_the_brute_force_best_path(rng):
    clips = [LibraryClip(f"c{i}.bvh", rng.normal(size=(90, 15, 3)), 60.0) for i in range(2)]
    idx = PoseIndex(n_views=1, stride=3).fit(clips)
    Q, k = 3, 4
    ids = rng.choice(idx.n_frames, size=(Q, k), replace=False)
    ids[1, 0], ids[2, 0] = ids[0, 0] + 1, ids[0, 0] + 2  # one coherent path (stride 3 frames = 1/20 s)
    cost = rng.uniform(0.1, 1.0, (Q, k))
    frames = np.array([10, 11, 12])
    new_ids, total = coherent_ranking(idx, ids, cost, frames, 20.0, jump_cost=0.5)
    import itertools

    t = idx.time_of(ids)
    best = np.inf
    for path in itertools.product(range(k), repeat=Q):
        c = sum(cost[q, path[q]] for q in range(Q))
        for q in range(1, Q):
            a, b = ids[q - 1, path[q - 1]], ids[q, path[q]]
            ok = idx.clip_[a] == idx.clip_[b] and abs((t[q, path[q]] - t[q - 1, path[q - 1]]) - 0.05) <= 0.5 * 0.05 + 0.05
            c += 0.0 if ok else 0.5
        best = min(best, c)
    assert total[:, 0].min() == pytest.approx(best)


# ------------------------------------------------------------------------------------------ enhanced distance
def test_enhanced_distance_is_the_brute_force_minimum_and_zero_on_its_own_clip(rng):
    w = np.cumsum(rng.normal(0, 0.05, (80, 15, 3)), axis=0)
    src, dst = w.copy(), w.copy()
    z, h, k = 40, 6, 4
    # leaving src at i0 = z - h and entering dst at j0 = z + h is the clip itself: zero cost
    e = enhanced_distance(src, z - h, w, z, dst, z + h, h, k=k)
    assert e.cost == pytest.approx(0.0, abs=1e-6)
    e = enhanced_distance(src, 30, w, z, dst, 50, h, k=k, max_x=5, max_y=5, lam=0.1, fps=60.0)
    brute_in = min(window_distance(src[30 - x - k + 1:31 - x], w[z - h - k + 1:z - h + 1]) + 0.1 * x / 60 for x in range(6))
    brute_out = min(window_distance(w[z + h:z + h + k], dst[50 + y:50 + y + k]) + 0.1 * y / 60 for y in range(6))
    assert e.cost == pytest.approx(float(brute_in + brute_out))


def test_window_distance_ignores_a_yaw_and_floor_shift(rng):
    p = rng.normal(size=(5, 15, 3))
    th = 0.7
    R = np.array([[np.cos(th), 0, np.sin(th)], [0, 1, 0], [-np.sin(th), 0, np.cos(th)]])
    q = p @ R.T + [1.0, 0.0, -2.0]
    assert window_distance(p, q) == pytest.approx(0.0, abs=1e-9)
    assert len(KEYPOINT_WEIGHTS) == 15


def test_two_half_transition_passes_exactly_through_w_z(rng):
    from scipy.spatial.transform import Rotation

    J, n = 5, 21
    q = lambda m: Rotation.random(m, random_state=int(rng.integers(1 << 30))).as_quat()
    seg = q(13 * J).reshape(13, J, 4)
    ra, rb = q(J), q(J)
    rot, root = two_half_transition(ra, np.zeros(3), seg, np.ones((13, 3)), rb, np.full(3, 2.0), n, centre=6)
    mid = n // 2
    np.testing.assert_allclose(np.abs(np.sum(rot[mid] * seg[6], -1)), 1.0, atol=1e-9)
    # the frame after the transition is b itself: the last transition frame is almost there
    d = [np.abs(np.sum(r * rb, -1)).min() for r in rot[mid:]]
    assert d[-1] > 0.999 and d[-1] == max(d)
    assert np.allclose(root[mid], 1.0)
    prot, proot = plain_transition(ra, np.zeros(3), rb, np.full(3, 2.0), n)
    assert np.all(np.diff(proot[:, 0]) > 0) and proot[-1, 0] < 2.0  # monotone, not yet arrived


def test_two_half_transition_hold_follows_the_segment_over_the_held_middle(rng):
    from scipy.spatial.transform import Rotation

    J, n, m, c = 4, 41, 21, 10
    q = lambda k: Rotation.random(k, random_state=int(rng.integers(1 << 30))).as_quat()
    seg = np.repeat(q(J)[None], m, axis=0)  # a held library pose: every segment frame is w_z
    seg_root = np.tile([0.5, 1.0, -0.5], (m, 1))
    ra, rb = q(J), q(J)
    args = (ra, np.zeros(3), seg, seg_root, rb, np.full(3, 2.0), n)
    mid = n // 2
    for hold in (0.0, 0.2, 0.5):
        rot, root = two_half_transition(*args, centre=c, hold=hold)
        on = np.isclose(np.abs(np.sum(rot * seg[0], -1)).min(-1), 1.0, atol=1e-9) & np.isclose(root, seg_root[0]).all(-1)
        # the frames with full segment weight: first half f + 1 >= (mid + 1)(1 - hold), second half
        # f - mid <= hold (n - mid) (the blend weight's own ramps, written independently here)
        f = np.arange(n)
        want = np.where(f <= mid, f + 1 >= (mid + 1) * (1 - hold) - 1e-9, f - mid <= hold * (n - mid) + 1e-9)
        np.testing.assert_array_equal(on, want)
        assert on[mid] and not on[0] and not on[-1]
    assert two_half_transition(*args, centre=c, hold=0.0)[1][mid - 1, 0] < 0.5  # hold 0: one frame only
    assert np.count_nonzero(np.isclose(two_half_transition(*args, centre=c, hold=0.5)[1], seg_root[0]).all(-1)) >= n // 2
    from vidstyle.errors import ParameterError

    with pytest.raises(ParameterError, match="hold"):
        two_half_transition(*args, hold=1.0)


def test_place_segment_anchored_at_nodes_recovers_the_rigid_move(rng):
    """A library clip that is the performer's departure moved by a known floor transform T, then travels
    on its own (a step back): aligning its node (the departure look-alike) undoes T exactly, so the placed
    segment is T^-1 of the library segment, whatever pose the segment itself is cut in."""
    from types import SimpleNamespace

    from vidstyle.mocap.placement import Placement

    dep = rng.normal(size=(15, 3)) * [0.3, 1.0, 0.3] + [0.0, 1.0, 0.0]
    T = Placement(0.9, 1.5, -2.0)
    node = T.apply_points(dep)
    m, J = 7, 3
    lib_root = T.apply_points(np.c_[np.zeros(m), np.full(m, 1.0), -0.1 * np.arange(m)])  # travelling back
    lib_rot = np.tile([0.0, 0.0, 0.0, 1.0], (m, J, 1))
    seg = SimpleNamespace(root_positions=lib_root, rotations=lib_rot)
    seg_pts = rng.normal(size=(m, 15, 3))  # the segment's own frames look nothing like the departure
    inv = T.inverse()
    for place in ("first", "both", "drift"):
        arrival = dep if place != "first" else None
        rot, root = place_segment(seg, seg_pts, dep, 1.0, arrival, drift=place == "drift",
                                  align_points=(node, node), align_frames=(-3, m + 2))
        np.testing.assert_allclose(root, inv.apply_points(lib_root), atol=1e-6)
        np.testing.assert_allclose(np.abs(np.sum(rot[:, 0] * inv.apply_frames(lib_rot, lib_root)[0][:, 0], -1)), 1.0,
                                   atol=1e-9)
        np.testing.assert_allclose(rot[:, 1:], lib_rot[:, 1:])
    # anchored at its own (unrelated) first frame instead, the placement is not T^-1
    _, root_ends = place_segment(seg, seg_pts, dep, 1.0)
    assert np.abs(root_ends - inv.apply_points(lib_root)).max() > 0.1


def test_reduction_interval_brackets_the_estimate_and_is_exact_for_a_constant_ratio(rng):
    from vidstyle.evaluation.augmg import reduction_interval

    plain = rng.uniform(50, 200, 17)
    assert reduction_interval(plain, 0.6 * plain) == pytest.approx([0.4, 0.4])  # every resample: 1 - 0.6
    aug = plain * rng.uniform(0.2, 1.1, 17)
    lo, hi = reduction_interval(plain, aug, seed=3)
    est = 1 - aug.mean() / plain.mean()
    assert lo < est < hi and hi - lo > 0.05
    assert reduction_interval(plain, aug, seed=3) == [lo, hi]  # seeded
    # more queries from the same population: a narrower interval
    big = np.tile(plain, 8), np.tile(aug, 8)
    lo2, hi2 = reduction_interval(*big, seed=3)
    assert hi2 - lo2 < (hi - lo) * 0.6
    assert reduction_interval(plain[:1], aug[:1]) is None


@pytest.mark.parametrize("ci,ok", [([0.41, 0.58], True), (None, True), ([0.58, 0.41], False), ([0.4], False),
                                   ([0.4, float("nan")], False)])
def test_metrics_reader_checks_the_reduction_interval(tmp_path, ci, ok):
    from vidstyle.formats import FormatError
    from vidstyle.formats.metrics import read_metrics

    src = {"queries": 17, "retrieval_mpjpe_mm": 61.8, "transition_plain_mm": 169.0, "transition_augmg_mm": 84.7,
           "recall_at_1": 0.76, "recall_at_10": 1.0, "transition_reduction_ci95": ci}
    p = tmp_path / "augmg.json"
    p.write_text(json.dumps({"kind": "vidstyle.metrics.augmg", "schema_version": 1, "seed": 0,
                             "by_source": {"model": src}, "headline": {}}))
    if ok:
        read_metrics(p)
    else:
        with pytest.raises(FormatError) as e:  # NaN is refused as JSON already, before the field
            read_metrics(p)
        assert str(p) in str(e.value) and ("transition_reduction_ci95" in str(e.value) or "NaN" in str(e.value))


# ------------------------------------------------------------------------------------------ formats + CLI
def _poses_file(tmp_path: Path, take, view: str = "front") -> tuple[Path, int]:
    from vidstyle.formats.poses import PoseFrame, Poses, write_poses
    from vidstyle.render.camera import Camera

    _, tk = take
    t = tk.transitions[0]
    pts = keypoint_positions(tk.motion)
    cam = Camera.for_view(tk.motion, view)
    uv, _ = cam.project(pts[t["key"]])
    frame = t["key"] // tk.ratio
    path = tmp_path / "v.poses.json"
    write_poses(path, Poses("v.mp4", "ps", [PoseFrame(frame, view, np.c_[uv, np.ones(15)])]))
    return path, frame


def test_match_pose_writes_matches_that_read_back(tmp_path, take, library):
    from vidstyle.formats.matches import read_matches

    poses, frame = _poses_file(tmp_path, take)
    out = tmp_path / "m.json"
    r = CliRunner().invoke(app, ["match-pose", str(poses), "--library", str(library / "clips"), "--out", str(out),
                                 "--k", "5"])
    assert r.exit_code == 0, r.output
    m = read_matches(out)
    assert m.frames[0].frame == frame and len(m.frames[0].candidates) == 5
    c = m.frames[0].candidates
    assert all(a.cost <= b.cost for a, b in zip(c, c[1:]))
    kind = take[1].transitions[0]["kind"]
    holder = {"crouch": "dodge", "hop": "switch", "step_back": "stop"}[kind]
    assert holder in Path(c[0].clip).stem  # the pose is found in the clip that holds it


def test_match_pose_cli_and_library_defaults_write_the_same_bytes(tmp_path, take, library):
    """A Python user calling vidstyle.augmg.match_poses with its defaults gets the CLI's file exactly."""
    from vidstyle.augmg import match_poses
    from vidstyle.formats.matches import write_matches

    poses, _ = _poses_file(tmp_path, take)
    cli, lib = tmp_path / "cli.json", tmp_path / "lib.json"
    r = CliRunner().invoke(app, ["match-pose", str(poses), "--library", str(library / "clips"), "--out", str(cli)])
    assert r.exit_code == 0, r.output
    write_matches(lib, match_poses(poses, [library / "clips"]))
    assert cli.read_bytes() == lib.read_bytes()
    assert len(json.loads(lib.read_text())["frames"][0]["candidates"]) == augmg_defaults.K


def test_library_parameter_checks_come_before_any_file_is_read(tmp_path):
    from vidstyle.augmg import augment, match_poses
    from vidstyle.errors import ParameterError
    from vidstyle.evaluation.augmg import evaluate

    none = tmp_path / "none"
    for call, param in ((lambda: match_poses(none, [none], k=0), "k"),
                        (lambda: augment(none, none, [none], context=-1), "context"),
                        (lambda: augment(none, none, [none], max_match_cost={"model": float("nan")}), "max_match_cost"),
                        (lambda: evaluate(none, none, segment="middle"), "segment"),
                        (lambda: evaluate(none, none, min_gain=float("inf")), "min_gain"),
                        (lambda: evaluate(none, none, enh_window=0), "enh_window")):
        with pytest.raises(ParameterError) as e:
            call()
        assert e.value.param == param


def test_bad_matches_file_names_the_field(tmp_path):
    from vidstyle.formats import FormatError
    from vidstyle.formats.matches import read_matches

    bad = tmp_path / "m.json"
    bad.write_text(json.dumps({"kind": "vidstyle.matches", "schema_version": 1, "poses": "p", "video": "",
                               "library": [], "params": {}, "frames": [{"frame": 1, "viewpoint_deg": 0,
                                                                          "candidates": [{"clip": "a", "time": -1, "cost": 0}]}]}))
    with pytest.raises(FormatError, match=r"frames\[0\]\.candidates\[0\]\.time"):
        read_matches(bad)
    from vidstyle.cli import main

    # a matches file is not a poses file: one line naming the file, exit 2, no output
    assert main(["match-pose", str(bad), "--library", str(tmp_path), "--out", str(tmp_path / "o.json")]) == 2
    assert not (tmp_path / "o.json").exists()


def _annotations(tmp_path: Path, frame: int, a: str, b: str, status: str = "accepted") -> Path:
    from vidstyle.formats.annotations import Annotations, Transition, VideoAnnotations, write_annotations

    path = tmp_path / f"ann_{status}.json"
    write_annotations(path, Annotations(sorted({a, b}), [VideoAnnotations("v.mp4", "0" * 64, 100000, 20.0,
                                                                           [Transition(frame, a, b, status)])]))
    return path


@pytest.mark.slow
def test_augment_adds_enhancement_edges_and_a_discarded_mark_adds_none(tmp_path, take, library):
    from vidstyle.motiongraph import MotionGraph, plan_walk
    from vidstyle.motiongraph.graph import EdgeKind, load_clips
    from vidstyle.motiongraph.synthesis import Step

    clips = load_clips(sorted((library / "clips").glob("lib00_*.bvh")))
    g = MotionGraph(window=6, fps=20.0).fit(clips)
    gpath = tmp_path / "g.npz"
    g.save(gpath)
    poses, frame = _poses_file(tmp_path, take)
    t = take[1].transitions[0]
    for status, expect in (("accepted", True), ("discarded", False)):
        ann = _annotations(tmp_path, frame, t["from"], t["to"], status)
        out = tmp_path / f"g2_{status}.npz"
        r = CliRunner().invoke(app, ["augment", "--graph", str(gpath), "--annotations", str(ann), "--poses", str(poses),
                                     "--library", str(library / "clips"), "--out", str(out)])
        assert r.exit_code == 0, r.output
        g2 = MotionGraph.load(out)
        n_enh = len(g2.edges(EdgeKind.ENHANCEMENT))
        assert (n_enh > 0) == expect
        if expect:
            assert len(g2.segments_) == 1 and g2.segments_[0].label == f"{t['from']}->{t['to']}"
            S = g2.segments_[0]  # the CLI's validated defaults: anchored at the clip's nodes, with a hold
            assert S.hold == pytest.approx(augmg_defaults.HOLD)
            assert (S.anchors is not None) == (augmg_defaults.ANCHOR == "nodes")
        # synthesis of that pair goes through the enhancement exactly when the mark is accepted
        walk = plan_walk(g2, [Step(t["from"], 20), Step(t["to"], 20)], strict=False)
        used = {int(g2.edge_kind_[e]) for e in walk.transitions_used}
        assert (int(EdgeKind.ENHANCEMENT) in used) == expect


@pytest.mark.slow
def test_evaluate_augmg_beats_the_plain_transition_with_true_2d(tmp_path, library):
    from vidstyle.demo.dataset import make_dataset

    ds = tmp_path / "ds"
    make_dataset(ds, DatasetParams.small(performances=1, performance_seconds=40.0, render=False), jobs=1)
    out = tmp_path / "augmg.json"
    r = CliRunner().invoke(app, ["evaluate", "augmg", "--dataset", str(ds), "--library", str(library), "--out", str(out)])
    assert r.exit_code == 0, r.output
    m = json.loads(out.read_text())
    gt = m["by_source"]["gt"]
    assert gt["queries"] > 0
    assert gt["transition_augmg_mm"] < gt["transition_plain_mm"]
    assert m["by_source"]["noisy"]["retrieval_mpjpe_mm"] >= gt["oracle_mpjpe_mm"]
    assert set(m["headline"]) >= {"augmg.retrieval_mpjpe", "augmg.transition_error_plain", "augmg.transition_error_augmg"}


@pytest.mark.slow
def test_evaluate_augmg_cli_equals_the_library_and_reports_in_the_datasets_unit(tmp_path, library):
    """vidstyle evaluate augmg and vidstyle.evaluation.augmg.evaluate with defaults write the same metrics
    file byte for byte; the millimetres come from the dataset manifest's mocap unit (twice the unit: twice
    every distance that does not depend on the acceptance thresholds), and a manifest without it is refused."""
    import shutil

    from vidstyle.demo.dataset import make_dataset
    from vidstyle.errors import InputError
    from vidstyle.evaluation.augmg import evaluate
    from vidstyle.formats.metrics import AUGMG, write_metrics

    ds = tmp_path / "ds"
    make_dataset(ds, DatasetParams.small(performers=1, views=("front",), performances=1, performance_seconds=24.0,
                                         render=False), jobs=1)
    cli, lib = tmp_path / "cli.json", tmp_path / "lib.json"
    r = CliRunner().invoke(app, ["evaluate", "augmg", "--dataset", str(ds), "--library", str(library), "--out", str(cli)])
    assert r.exit_code == 0, r.output
    metrics, doc = evaluate(ds, library)
    assert doc is None
    write_metrics(lib, metrics, kind=AUGMG)
    assert cli.read_bytes() == lib.read_bytes()
    gt = metrics["by_source"]["gt"]
    assert gt["queries"] > 0 and metrics["params"]["thresholds"]["gt"]["min_gain_mm"] == augmg_defaults.MIN_GAIN["gt"]
    double, _ = evaluate(ds, library, unit_mm=2 * 56.4, min_gain=None, max_match_cost=None, max_enh_cost=None)
    single, _ = evaluate(ds, library, min_gain=None, max_match_cost=None, max_enh_cost=None)
    for key in ("transition_plain_mm", "transition_enhanced_mm", "retrieval_mpjpe_mm", "oracle_mpjpe_mm"):
        assert double["by_source"]["gt"][key] == pytest.approx(2 * single["by_source"]["gt"][key], rel=1e-12)
    man = json.loads((ds / "dataset.json").read_text())
    assert man["mocap_unit_m"] == pytest.approx(0.0564)
    bare = tmp_path / "bare"
    shutil.copytree(ds, bare)
    del man["mocap_unit_m"]
    (bare / "dataset.json").write_text(json.dumps(man))
    with pytest.raises(InputError, match="mocap_unit_m"):
        evaluate(bare, library)


def test_bundled_demo_annotations_mark_frames_inside_the_true_transitions():
    from vidstyle.augmg.annotations_io import read_marks
    from vidstyle.demo.dataset import video_transitions

    path = Path(__file__).resolve().parents[1] / "annotations" / "demo.json"
    marks = read_marks(path)
    assert marks and {m["status"] for m in marks} == {"accepted", "discarded"}
    params = DatasetParams()  # the pipeline's seed 0; a take does not depend on the dataset's size
    by_video: dict[str, list] = {}
    for m in marks:
        by_video.setdefault(m["video"], []).append(m)
    for vid, ms in list(by_video.items())[:2]:
        i = int(vid[1:3])
        tk = make_take(params, make_performer(params, i), i, 100)
        styled = video_transitions(tk)
        for m in ms:
            t = next(t for t in styled if t["start"] <= m["frame"] < t["end"])
            assert (t["from"], t["to"]) == (m["from"], m["to"])


@pytest.mark.parametrize("option,value", [("--place", "last"), ("--anchor", "middle"), ("--hold", "1"),
                                          ("--hold", "-0.1")])
def test_evaluate_augmg_placement_options_are_checked_before_any_work(tmp_path, capsys, option, value):
    from vidstyle.cli import main

    out = tmp_path / "augmg.json"
    # the dataset and library do not exist: the options are refused before either is read
    assert main(["evaluate", "augmg", "--dataset", str(tmp_path / "none"), "--library", str(tmp_path / "none"),
                 option, value, "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"vidstyle: error: {option}:") and not out.exists()


def test_augment_pose_scales_are_checked_before_any_work(tmp_path, capsys):
    from vidstyle.cli import main
    from vidstyle.formats.annotations import (
        Annotations,
        Transition,
        VideoAnnotations,
        file_sha256,
        write_annotations,
    )

    video = tmp_path / "v.mp4"
    video.write_bytes(b"not decoded before the options are checked")
    ann = tmp_path / "a.json"
    write_annotations(ann, Annotations(["jab", "kick"], [VideoAnnotations("v.mp4", file_sha256(video), 100, 20.0,
                                                                           [Transition(10, "jab", "kick", "accepted")])]))
    for bad in ("0", "1,x"):
        out = tmp_path / "g2.npz"
        assert main(["augment", "--graph", str(tmp_path / "g.npz"), "--annotations", str(ann), "--video", str(video),
                     "--pose-model", str(tmp_path / "m.joblib"), "--pose-scales", bad, "--library", str(tmp_path),
                     "--out", str(out)]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and err[0].startswith("vidstyle: error: --pose-scales") and not out.exists()
