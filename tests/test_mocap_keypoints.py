"""Keypoint mapping: CMU names, other naming conventions, topology fallback, positions by FK."""

from __future__ import annotations

import numpy as np
import pytest

from vidstyle.demo import Body, build_skeleton
from vidstyle.mocap import Motion, Skeleton, end_site_positions, global_positions, read_bvh
from vidstyle.mocap.keypoints import (
    CMU_NAMES,
    KEYPOINTS,
    MIRROR,
    PART_KEYPOINTS,
    PART_NAMES,
    PART_PARENTS,
    PARTS,
    KeypointMappingError,
    keypoint_joints,
    keypoint_positions,
    split_side,
)

EXPECTED_KEYPOINTS = ("head_top", "neck", "pelvis", "left_shoulder", "right_shoulder", "left_elbow",
                      "right_elbow", "left_wrist", "right_wrist", "left_hip", "right_hip", "left_knee",
                      "right_knee", "left_ankle", "right_ankle")


def _renamed(sk: Skeleton, names: dict[str, str], drop_end_sites: bool = False) -> Skeleton:
    return Skeleton([names.get(n, n) for n in sk.names], sk.parents, sk.offsets, sk.channels,
                    {} if drop_end_sites else sk.end_sites)


def test_body_model_layout():
    assert KEYPOINTS == EXPECTED_KEYPOINTS
    assert len(PARTS) == 10 and PART_NAMES[0] == "torso" and PART_PARENTS["torso"] is None
    assert PARTS["head"] == ("neck", "head_top") and PARTS["left_forearm"] == ("left_elbow", "left_wrist")
    assert PARTS["right_lower_leg"] == ("right_knee", "right_ankle")
    # every keypoint is an end of some part, the tree is connected through the torso
    assert set(PART_KEYPOINTS.ravel()) == set(range(15))
    for p, parent in PART_PARENTS.items():
        if parent is not None:
            assert set(PARTS[p]) & set(PARTS[parent]) or parent == "torso"
    assert [KEYPOINTS[i] for i in MIRROR[3:5]] == ["right_shoulder", "left_shoulder"]
    assert MIRROR[0] == 0 and np.array_equal(MIRROR[MIRROR], np.arange(15))


def test_cmu_skeleton_maps_by_the_issue_names(cmu_dir):
    motion = read_bvh(cmu_dir / "01_01.bvh")
    m = keypoint_joints(motion.skeleton)
    assert list(m) == list(KEYPOINTS)
    assert {k: v.joint_name for k, v in m.items()} == CMU_NAMES
    assert m["head_top"].end_site and not any(v.end_site for k, v in m.items() if k != "head_top")
    motion = motion[:20]
    pts = keypoint_positions(motion)
    pos = global_positions(motion)
    owners, ends = end_site_positions(motion)
    sk = motion.skeleton
    assert pts.shape == (20, 15, 3)
    np.testing.assert_allclose(pts[:, 0], ends[:, owners.index(sk.index("Head"))])
    np.testing.assert_allclose(pts[:, KEYPOINTS.index("left_elbow")], pos[:, sk.index("LeftForeArm")])
    np.testing.assert_allclose(pts[:, KEYPOINTS.index("pelvis")], pos[:, sk.index("Hips")])


def test_cmu_topology_agrees_with_names(cmu_dir):
    """The topology fallback alone, on the CMU skeleton with its names scrambled, finds the same joints."""
    sk = read_bvh(cmu_dir / "02_01.bvh").skeleton
    anon = _renamed(sk, {n: f"joint{i:02d}" for i, n in enumerate(sk.names)})
    m = keypoint_joints(anon)
    assert all(v.how == "topology" for v in m.values())
    assert {k: sk.names[v.joint] for k, v in m.items()} == CMU_NAMES
    assert m["head_top"].end_site


def test_demo_topology_agrees_with_names():
    sk = build_skeleton(Body(height_m=1.65, arm_ratio=1.05))
    m = keypoint_joints(_renamed(sk, {n: f"b{i}" for i, n in enumerate(sk.names)}))
    assert {k: sk.names[v.joint] for k, v in m.items()} == CMU_NAMES


def test_demo_skeleton_rest_pose_geometry():
    body = Body(height_m=1.80)
    sk = build_skeleton(body)
    m = keypoint_joints(sk)
    assert {k: v.joint_name for k, v in m.items()} == CMU_NAMES
    F = 3
    motion = Motion(sk, np.tile([0.0, 0.0, 0.0, 1.0], (F, sk.n_joints, 1)), np.tile(sk.offsets, (F, 1, 1)), 30.0)
    pts = keypoint_positions(motion)
    K = {k: pts[0, i] for i, k in enumerate(KEYPOINTS)}
    # T-pose facing +Z: the performer's left is +X; arms horizontal, legs straight down
    assert K["left_shoulder"][0] > 0 > K["right_shoulder"][0]
    assert K["left_wrist"][0] - K["left_shoulder"][0] == pytest.approx(body.upper_arm + body.forearm)
    assert K["left_hip"][1] - K["left_ankle"][1] == pytest.approx(body.thigh + body.shank)
    assert K["head_top"][1] > K["neck"][1] > K["pelvis"][1]
    np.testing.assert_allclose(pts[1], pts[0])


MIXAMO = {n: "mixamorig:" + n for n in CMU_NAMES.values()}
UNITY = {"LeftShoulder": "LeftShoulder", "LeftArm": "LeftUpperArm", "LeftForeArm": "LeftLowerArm",
         "RightArm": "RightUpperArm", "RightForeArm": "RightLowerArm", "LeftUpLeg": "LeftUpperLeg",
         "LeftLeg": "LeftLowerLeg", "RightUpLeg": "RightUpperLeg", "RightLeg": "RightLowerLeg"}
HANIM = {"Hips": "HumanoidRoot", "LeftShoulder": "l_sternoclavicular", "LeftArm": "l_shoulder",
         "LeftForeArm": "l_elbow", "LeftHand": "l_wrist", "RightShoulder": "r_sternoclavicular",
         "RightArm": "r_shoulder", "RightForeArm": "r_elbow", "RightHand": "r_wrist", "LeftUpLeg": "l_hip",
         "LeftLeg": "l_knee", "LeftFoot": "l_ankle", "RightUpLeg": "r_hip", "RightLeg": "r_knee",
         "RightFoot": "r_ankle", "Neck": "vc7", "Neck1": "skullbase", "Head": "head",
         "LHipJoint": "l_hipjoint", "RHipJoint": "r_hipjoint"}


@pytest.mark.parametrize("names", [MIXAMO, UNITY, HANIM], ids=["mixamo", "unity", "hanim"])
def test_other_conventions_find_the_same_joints(names):
    sk = build_skeleton(Body())
    other = _renamed(sk, names)
    m = keypoint_joints(other)
    assert {k: sk.names[v.joint] for k, v in m.items()} == CMU_NAMES


def test_mixamo_head_top_end_joint():
    """A HeadTop_End joint (Mixamo exports) is head_top itself, not an End Site."""
    sk = build_skeleton(Body())
    names = list(sk.names) + ["mixamorig:HeadTop_End"]
    parents = np.append(sk.parents, sk.index("Head"))
    offsets = np.vstack([sk.offsets, sk.end_sites[sk.index("Head")]])
    ends = {k: v for k, v in sk.end_sites.items() if k != sk.index("Head")}
    other = Skeleton(names, parents, offsets, list(sk.channels) + [("Zrotation", "Yrotation", "Xrotation")], ends)
    m = keypoint_joints(other)
    assert m["head_top"].joint_name == "mixamorig:HeadTop_End" and not m["head_top"].end_site


def test_split_side():
    assert split_side("mixamorig:LeftForeArm") == ("left", "forearm")
    assert split_side("r_elbow") == ("right", "elbow")
    assert split_side("Bip01 L Thigh") == ("left", "thigh")
    assert split_side("hand.R") == ("right", "hand")
    assert split_side("LowerBack") == (None, "lowerback")
    assert split_side("LHipJoint") == ("left", "hipjoint")


def test_missing_limb_is_a_clear_error():
    sk = build_skeleton(Body())
    # cut the left arm off (keep file order): no left shoulder/elbow/wrist by name or topology
    drop = {sk.index(n) for n in ("LeftArm", "LeftForeArm", "LeftHand", "LeftFingerBase", "LeftHandIndex1",
                                  "LThumb")}
    keep = [j for j in range(sk.n_joints) if j not in drop]
    remap = {j: i for i, j in enumerate(keep)}
    cut = Skeleton([f"j{i}" if sk.names[j] in ("Neck", "Neck1") else sk.names[j] for i, j in enumerate(keep)],
                   [remap.get(int(sk.parents[j]), -1) for j in keep], sk.offsets[keep],
                   [sk.channels[j] for j in keep], {remap[k]: v for k, v in sk.end_sites.items() if k in remap})
    with pytest.raises(KeypointMappingError, match="left_shoulder, left_elbow, left_wrist"):
        keypoint_joints(cut)
