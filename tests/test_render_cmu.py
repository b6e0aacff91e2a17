"""The renderer on real CMU clips (31 joints, 120 fps, zero-length and tiny bones). Skips without ../shared."""

from __future__ import annotations

import numpy as np
import pytest

from vidstyle.mocap import read_bvh
from vidstyle.render import Appearance, Camera, build_body, render_motion

pytestmark = pytest.mark.shared


@pytest.mark.parametrize("name", ["01_01.bvh", "02_01.bvh", "05_02.bvh", "08_01.bvh"])
def test_cmu_clip_renders(cmu_dir, name):
    m = read_bvh(cmu_dir / name)[:240]  # 2 s
    for view in ("front", "left", "right"):
        cam = Camera.for_view(m, view=view, size=(160, 120))
        frames, truth, masks = render_motion(m, cam, fps=20.0, appearance=Appearance.random(1),
                                             background="texture", return_masks=True)
        assert frames.shape == (40, 120, 160, 3)
        assert truth["joints2d"].shape == (40, 31, 2)
        cover = (masks >= 0).mean(axis=(1, 2))
        assert np.all(cover > 0.005), (name, view)
        vis = truth["visible"]
        assert vis.mean() > 0.4, (name, view)
        f, j = np.nonzero(vis)
        uv = np.rint(truth["joints2d"][f, j]).astype(int)
        assert np.all(masks[f, uv[:, 1], uv[:, 0]] >= 0)


def test_cmu_body_model_skips_degenerate_bones(cmu_dir):
    m = read_bvh(cmu_dir / "02_01.bvh")
    body = build_body(m.skeleton)
    H = body.height
    assert 20 < H < 35  # CMU units: ~0.056 m each
    kinds = body.kind
    assert kinds.count("thigh") == 2 and kinds.count("shin") == 2 and kinds.count("head") == 1
    assert kinds.count("upperarm") == 2 and kinds.count("forearm") == 2
    # zero-length bones (LHipJoint, Neck, LeftFingerBase ...) and tiny ones give no capsule
    from vidstyle.mocap import forward_kinematics

    pos, mats = forward_kinematics(m[0])
    ends = body.capsule_ends(body.keypoints(pos, mats))[0]
    lengths = np.linalg.norm(ends[:, 1] - ends[:, 0], axis=1)
    assert np.all(lengths > 0.014 * H)
    assert body.n_capsules < 35


def test_cmu_t_pose_left_right_mirror(cmu_dir):
    """Frame 0 of a CMU clip is a near-symmetric T-pose: left and right views are near mirror images."""
    m = read_bvh(cmu_dir / "02_01.bvh")[:2]
    look = Appearance()
    masks = {}
    for view in ("left", "right", "front"):
        cam = Camera.for_view(m, view=view, size=(160, 120))
        _, _, mk = render_motion(m, cam, fps=120.0, appearance=look, return_masks=True)
        masks[view] = mk[0] >= 0
    left, right = masks["left"], masks["right"][:, ::-1]
    iou = (left & right).sum() / (left | right).sum()
    assert iou > 0.9
    front, side = masks["front"], masks["left"]
    assert (front & side).sum() / (front | side).sum() < 0.7
