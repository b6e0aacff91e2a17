"""Mocap from several sources: retargeting one joint layout across bone lengths and units, keypoint
mapping of other layouts shown by ``vidstyle mocap info`` (issue 11, item 6)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from vidstyle.cli import main
from vidstyle.errors import InputError
from vidstyle.mocap import Motion, Skeleton, global_positions, read_bvh, write_bvh
from vidstyle.mocap.keypoints import KEYPOINTS
from vidstyle.mocap.retarget import leg_length, rescale, retarget
from vidstyle.motiongraph import MotionGraph, load_clips

from test_motiongraph_graph import _gait, _skeleton


def test_leg_length_is_the_chain_to_the_lowest_point():
    # Hips -> LeftUpLeg (1, -1, 0) -> LeftFoot (0, -4, 0) -> End Site (0, -1, 1)
    assert leg_length(_skeleton()) == pytest.approx(np.sqrt(2) + 4 + np.sqrt(2))
    assert leg_length(rescale(_gait(3, 1, 30, 4), 0.25).skeleton) == pytest.approx(0.25 * (2 * np.sqrt(2) + 4))


def test_retarget_across_units_recovers_the_motion_exactly():
    m = _gait(40, 1.0, 30, 4.0)
    small = rescale(m, 0.0564)
    assert np.allclose(global_positions(small), 0.0564 * global_positions(m))
    back, scale = retarget(small, m.skeleton, "small.bvh")
    assert scale == pytest.approx(1 / 0.0564)
    assert back.skeleton is m.skeleton
    np.testing.assert_allclose(global_positions(back), global_positions(m), atol=1e-9)


def test_retarget_other_bone_lengths_keeps_rotations_and_scales_the_root_by_leg_length():
    m = _gait(40, 1.0, 30, 4.0)
    sk = m.skeleton
    long_legs = sk.offsets.copy()
    long_legs[[2, 4]] *= 1.5  # shins 1.5x: leg 2*sqrt(2)+6 instead of 2*sqrt(2)+4
    other = Motion(Skeleton(sk.names, sk.parents, long_legs, sk.channels, sk.end_sites), m.rotations,
                   None, m.fps, root_positions=m.root_positions * 1.3)
    out, scale = retarget(other, sk, "other.bvh")
    assert scale == pytest.approx((2 * np.sqrt(2) + 4) / (2 * np.sqrt(2) + 6))
    np.testing.assert_array_equal(out.rotations, m.rotations)
    np.testing.assert_allclose(out.root_positions, m.root_positions * 1.3 * scale)
    np.testing.assert_array_equal(out.skeleton.offsets, sk.offsets)


def test_namespace_prefix_is_the_same_layout_and_another_layout_is_refused():
    m = _gait(10, 1.0, 30, 4.0)
    sk = m.skeleton
    mixamo = Skeleton([f"mixamorig:{n}" for n in sk.names], sk.parents, sk.offsets * 2, sk.channels,
                      {j: 2 * v for j, v in sk.end_sites.items()})
    out, scale = retarget(Motion(mixamo, m.rotations, None, m.fps, root_positions=m.root_positions * 2), sk)
    assert scale == pytest.approx(0.5)
    np.testing.assert_allclose(global_positions(out), global_positions(m), atol=1e-9)
    other = Skeleton(sk.names[:-1], sk.parents[:-1], sk.offsets[:-1], sk.channels[:-1], {2: sk.end_sites[2]})
    with pytest.raises(InputError, match=r"odd.bvh: joint layout differs .*6 vs 7 joints"):
        retarget(Motion(other, m.rotations[:, :-1], None, m.fps), sk, "odd.bvh")


def test_graph_of_two_clips_of_one_layout_in_different_units():
    from vidstyle.motiongraph import Clip

    m = _gait(90, 1.0, 30, 4.0)
    g = MotionGraph(window=6, fps=30, threshold_quantile=0.1).fit(
        [Clip("a", m, ["walk"] * 90), Clip("b", rescale(m, 0.0564), ["walk"] * 90)])
    assert g.clips_["scale"] == pytest.approx([1.0, 1 / 0.0564])
    a, b = g.clips_["start"]
    n = g.clips_["frames"][0]
    np.testing.assert_allclose(g.root_positions_[b : b + n], g.root_positions_[a : a + n], atol=1e-9)


def test_build_graph_on_a_cmu_clip_and_the_same_clip_in_metres(cmu_dir, tmp_path):
    src = cmu_dir / "02_01.bvh"
    metres = tmp_path / "02_01_m.bvh"
    write_bvh(rescale(read_bvh(src), 0.0564), metres)
    other = tmp_path / "05_01.bvh"  # another subject (first 4 s, to stay fast)
    write_bvh(read_bvh(cmu_dir / "05_01.bvh")[:480], other)
    # what build-graph runs (load_clips + fit), with a smaller threshold sample than its 200k default
    g = MotionGraph(n_samples=5000).fit(load_clips([src, metres, other]))
    s = g.clips_["scale"]
    assert s[0] == 1.0 and s[1] == pytest.approx(1 / 0.0564, rel=1e-5)
    ref = read_bvh(src).skeleton
    assert s[2] == pytest.approx(leg_length(ref) / leg_length(read_bvh(cmu_dir / "05_01.bvh").skeleton))
    assert s[2] != pytest.approx(1.0, abs=1e-3)  # another subject: other bone lengths
    a, b, _ = g.clips_["start"]
    n = g.clips_["frames"][0]
    np.testing.assert_allclose(g.root_positions_[b : b + n], g.root_positions_[a : a + n], atol=1e-3)
    # the two copies are the same motion: transitions between them cost ~0
    blends = g.edges(kind=1)
    across = blends[(g.frame_clip_[g.edge_src_[blends]] == 0) & (g.frame_clip_[g.edge_dst_[blends]] == 1)]
    assert len(across) and g.edge_cost_[across].min() < 1e-3


# ------------------------------------------------------------------------------------------ keypoints
MIXAMO_22 = [
    ("Hips", -1, (0, 100, 0)), ("Spine", 0, (0, 10, 0)), ("Spine1", 1, (0, 12, 0)), ("Spine2", 2, (0, 12, 0)),
    ("Neck", 3, (0, 15, 0)), ("Head", 4, (0, 10, 0)),
    ("LeftShoulder", 3, (6, 10, 0)), ("LeftArm", 6, (12, 0, 0)), ("LeftForeArm", 7, (28, 0, 0)), ("LeftHand", 8, (25, 0, 0)),
    ("RightShoulder", 3, (-6, 10, 0)), ("RightArm", 10, (-12, 0, 0)), ("RightForeArm", 11, (-28, 0, 0)),
    ("RightHand", 12, (-25, 0, 0)),
    ("LeftUpLeg", 0, (9, -5, 0)), ("LeftLeg", 14, (0, -42, 0)), ("LeftFoot", 15, (0, -40, 0)), ("LeftToeBase", 16, (0, -6, 12)),
    ("RightUpLeg", 0, (-9, -5, 0)), ("RightLeg", 18, (0, -42, 0)), ("RightFoot", 19, (0, -40, 0)),
    ("RightToeBase", 20, (0, -6, 12)),
]
EXPECTED = {"head_top": "Head", "neck": "Neck", "pelvis": "Hips", "left_shoulder": "LeftArm",
            "right_shoulder": "RightArm", "left_elbow": "LeftForeArm", "right_elbow": "RightForeArm",
            "left_wrist": "LeftHand", "right_wrist": "RightHand", "left_hip": "LeftUpLeg", "right_hip": "RightUpLeg",
            "left_knee": "LeftLeg", "right_knee": "RightLeg", "left_ankle": "LeftFoot", "right_ankle": "RightFoot"}


def _mixamo_bvh(path, prefix="mixamorig:", rename=None):
    names = [prefix + n for n, _, _ in MIXAMO_22] if rename is None else rename
    ends = {5: np.array([0, 18.0, 0]), 9: np.array([10.0, 0, 0]), 13: np.array([-10.0, 0, 0]),
            17: np.array([0, 0, 5.0]), 21: np.array([0, 0, 5.0])}
    sk = Skeleton(names, [p for _, p, _ in MIXAMO_22], [o for _, _, o in MIXAMO_22], end_sites=ends)
    rot = np.tile([0.0, 0, 0, 1], (3, 22, 1))
    write_bvh(Motion(sk, rot, None, 30.0, root_positions=np.tile([0, 100.0, 0], (3, 1))), path)
    return names


@pytest.mark.parametrize("style", ["mixamo", "topology"])
def test_mocap_info_shows_the_keypoint_mapping_of_a_22_joint_skeleton(tmp_path, capsys, style):
    p = tmp_path / "m.bvh"
    names = _mixamo_bvh(p, rename=None if style == "mixamo" else [f"j{i:02d}" for i in range(22)])
    assert main(["mocap", "info", str(p), "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert info["joints"] == 22 and list(info["keypoints"]) == list(KEYPOINTS)
    plain = [n for n, _, _ in MIXAMO_22]
    got = {k: plain[names.index(v["joint"])] for k, v in info["keypoints"].items()}
    assert got == EXPECTED
    assert info["keypoints"]["head_top"]["end_site"] is True
    assert {v["how"] for v in info["keypoints"].values()} == ({"name"} if style == "mixamo" else {"topology"})
    assert info["leg_length"] == pytest.approx(np.hypot(9, 5) + 42 + 40 + np.hypot(6, 12), rel=1e-6)  # hip .. toe
    assert main(["mocap", "info", str(p)]) == 0
    table = capsys.readouterr().out
    assert "keypoint left_elbow" in table and names[8] in table


def test_mocap_info_on_cmu_and_on_a_skeleton_without_keypoints(cmu_dir, tmp_path, capsys):
    assert main(["mocap", "info", str(cmu_dir / "01_01.bvh"), "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert info["keypoints"]["left_elbow"]["joint"] == "LeftForeArm" and info["keypoints"]["head_top"]["end_site"]
    from bvh_samples import TWO_JOINT

    p = tmp_path / "two.bvh"
    p.write_text(TWO_JOINT)
    assert main(["mocap", "info", str(p), "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert info["keypoints"] is None and "keypoint" in info["keypoint_error"]


def test_build_graph_names_the_clip_of_another_joint_layout(tmp_path, capsys):
    from bvh_samples import TWO_JOINT

    a, b = tmp_path / "a.bvh", tmp_path / "b.bvh"
    write_bvh(_gait(40, 1.0, 30, 4.0), a)
    b.write_text(TWO_JOINT)
    out = tmp_path / "g.npz"
    assert main(["build-graph", str(a), str(b), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and str(b) in err and "joint layout differs" in err
    assert not out.exists()


def test_library_keypoints_of_other_layouts_and_units_are_comparable(cmu_dir, tmp_path):
    from vidstyle.mocap.keypoints import keypoint_positions
    from vidstyle.mocap.retarget import library_keypoints

    m = read_bvh(cmu_dir / "02_01.bvh")[:30]
    metres = rescale(m, 0.0564)
    np.testing.assert_allclose(library_keypoints(metres, m.skeleton), keypoint_positions(m), atol=1e-9)
    # a 22-joint Mixamo-like clip: keypoints by name, scaled onto the CMU body's leg length
    p = tmp_path / "mx.bvh"
    _mixamo_bvh(p)
    mx = read_bvh(p)
    pts = library_keypoints(mx, m.skeleton)
    assert pts.shape == (3, 15, 3)
    i_hip, i_ankle = KEYPOINTS.index("left_hip"), KEYPOINTS.index("left_ankle")
    ratio = leg_length(m.skeleton) / leg_length(mx.skeleton)
    np.testing.assert_allclose(np.linalg.norm(pts[0, i_hip] - pts[0, i_ankle]), 82 * ratio, rtol=1e-9)
    from bvh_samples import TWO_JOINT

    with pytest.raises(InputError, match="keypoints"):
        library_keypoints(read_bvh_text(TWO_JOINT, tmp_path))


def read_bvh_text(text, tmp_path):
    p = tmp_path / "t.bvh"
    p.write_text(text)
    return read_bvh(p)
