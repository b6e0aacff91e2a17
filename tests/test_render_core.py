"""Rendering: determinism, ground truth consistency, views, masks, body model, video files."""

from __future__ import annotations

import numpy as np
import pytest

from vidstyle.errors import InputError
from vidstyle.mocap import global_positions
from vidstyle.render import (
    Appearance,
    Camera,
    build_body,
    classify_bone,
    load_truth,
    render_motion,
    render_to_file,
    sidecar_path,
)
from vidstyle.render.samples import humanoid_skeleton, sample_motion
from vidstyle.video import VideoReader, write_video


def read_video(path):
    with VideoReader(path) as r:
        return r.read_all()

TRUTH_KEYS = {
    "joints2d", "joints3d", "visible", "depth", "joint_names", "parents", "K", "R", "t", "azimuth_deg",
    "elevation_deg", "fps", "size", "labels", "transition", "source_time",
}


@pytest.fixture(scope="module")
def motion():
    return sample_motion(24, fps=20.0)


def _render(m, view="front", seed=0, size=(160, 120), **kw):
    cam = Camera.for_view(m, view=view, size=size)
    return render_motion(m, cam, fps=m.fps, seed=seed, return_masks=True, **kw)


def test_shapes_and_schema(motion):
    frames, truth, masks = _render(motion, background="texture")
    F, J = motion.n_frames, motion.n_joints
    assert frames.shape == (F, 120, 160, 3) and frames.dtype == np.uint8
    assert masks.shape == (F, 120, 160) and masks.dtype == np.int8
    assert TRUTH_KEYS <= set(truth)
    assert truth["joints2d"].shape == (F, J, 2)
    assert truth["joints3d"].shape == (F, J, 3)
    assert truth["visible"].shape == (F, J) and truth["visible"].dtype == bool
    assert truth["depth"].shape == (F, J)
    assert list(truth["joint_names"]) == motion.skeleton.names
    assert np.array_equal(truth["parents"], motion.skeleton.parents)
    assert tuple(truth["size"]) == (160, 120)
    assert truth["labels"].shape == (F,) and set(truth["labels"]) == {""}
    assert truth["transition"].shape == (F,) and not truth["transition"].any()
    assert np.allclose(truth["source_time"], np.arange(F) / 20.0)
    # the figure is drawn: a sizeable part of each frame is covered, and the figure differs from background
    cover = (masks >= 0).mean(axis=(1, 2))
    assert np.all(cover > 0.02)


def test_same_seed_same_frames_other_seed_other_noise(motion):
    a, ta, ma = _render(motion, seed=5, background="texture")
    b, tb, mb = _render(motion, seed=5, background="texture")
    assert np.array_equal(a, b)
    for k in ta:
        assert np.array_equal(ta[k], tb[k]), k
    c, tc, mc = _render(motion, seed=6, background="plain:200,200,200")
    d, td, md = _render(motion, seed=7, background="plain:200,200,200")
    assert not np.array_equal(c, d)
    assert np.array_equal(mc, md)  # the figure does not depend on the seed, only noise/background do
    assert np.array_equal(tc["visible"], td["visible"])
    diff = c.astype(int) - d.astype(int)
    assert 1.5 < diff.std() < 5.0  # two independent sigma-2 noises: std ~ 2.8


def test_noise_free_plain_background_is_exact(motion):
    frames, truth, masks = _render(motion, background="plain:10,20,30", noise_sigma=0.0)
    bg = masks < 0
    # pixels away from the figure are exactly the background colour
    far = bg.copy()
    for axis in (1, 2):
        for shift in (-1, 1):
            far &= np.roll(bg, shift, axis=axis)
    assert np.all(frames[far] == np.array([10, 20, 30], dtype=np.uint8))


def test_projection_matches_independent_computation(motion):
    frames, truth, masks = _render(motion, view=40.0)
    X = global_positions(motion)
    assert np.allclose(truth["joints3d"], X, atol=1e-4)
    xc = X @ truth["R"].T + truth["t"]
    h = xc @ truth["K"].T
    uv = h[..., :2] / h[..., 2:]
    assert np.allclose(truth["joints2d"], uv, atol=1e-3)
    assert np.allclose(truth["depth"], xc[..., 2], atol=1e-4)
    assert truth["azimuth_deg"] == 40.0


@pytest.mark.parametrize("view", ["front", "left", "right", 135.0])
def test_visible_joints_lie_on_the_figure(motion, view):
    frames, truth, masks = _render(motion, view=view)
    F = len(frames)
    uv = np.rint(truth["joints2d"]).astype(int)
    vis = truth["visible"]
    assert vis.mean() > 0.4
    f_idx, j_idx = np.nonzero(vis)
    cols, rows = uv[f_idx, j_idx, 0], uv[f_idx, j_idx, 1]
    assert np.all((cols >= 0) & (cols < 160) & (rows >= 0) & (rows < 120))
    assert np.all(masks[f_idx, rows, cols] >= 0)
    assert F == len(masks)  # (the pixels themselves are checked against a projection in test_render_pixels.py)


def test_side_view_hides_the_far_leg():
    m = sample_motion(2, speed=0.0)
    names = m.skeleton.names
    knees = names.index("LeftLeg"), names.index("RightLeg")
    _, t_left, _ = _render(m, view="left")
    _, t_right, _ = _render(m, view="right")
    _, t_front, _ = _render(m, view="front")
    # frame 0 is symmetric: legs side by side. From the left the right knee is hidden, and vice versa.
    assert t_left["visible"][0, knees[0]] and not t_left["visible"][0, knees[1]]
    assert t_right["visible"][0, knees[1]] and not t_right["visible"][0, knees[0]]
    assert t_front["visible"][0, knees[0]] and t_front["visible"][0, knees[1]]


def test_central_joints_stay_visible_from_the_side():
    m = sample_motion(2, speed=0.0, arm_drop_deg=0.0)  # T-pose: nothing hangs beside the torso
    _, t_left, _ = _render(m, view="left")
    names = m.skeleton.names
    for j in ("Hips", "Spine", "Head"):
        assert t_left["visible"][0, names.index(j)], j


def test_arm_across_the_chest_hides_what_is_behind_it():
    from vidstyle.mocap import Motion

    sk = humanoid_skeleton("cmu")
    ang = np.zeros((2, sk.n_joints, 3))
    ang[1, sk.index("LeftArm"), 1] = -90  # upper arm pointing forward (+Z) ...
    ang[1, sk.index("LeftForeArm"), 1] = -90  # ... forearm across the front of the chest
    m = Motion.from_euler(sk, ang, np.tile([0.0, 0.95, 0.0], (2, 1)), 20.0)
    _, truth, masks = _render(m, view="front")
    collar = sk.index("LeftShoulder")
    assert truth["visible"][0, collar] and not truth["visible"][1, collar]
    u, v = np.rint(truth["joints2d"][1, collar]).astype(int)
    assert masks[1, v, u] == sk.index("LeftForeArm")  # the forearm is what the camera sees there
    # seen from behind, the arm is on the far side: the collar is visible again
    _, back, _ = _render(m, view="back")
    assert back["visible"][1, sk.index("Spine1")]


def _iou(a, b):
    return (a & b).sum() / max((a | b).sum(), 1)


def test_left_and_right_views_of_symmetric_pose_are_mirror_images():
    m = sample_motion(2, speed=0.0)  # frame 0 is left-right symmetric
    _, _, ml = _render(m, view="left")
    _, _, mr = _render(m, view="right")
    _, _, mf = _render(m, view="front")
    left, right, front = ml[0] >= 0, mr[0] >= 0, mf[0] >= 0
    assert _iou(left, right[:, ::-1]) > 0.97
    # ... and not the same picture: the figure faces the other way (a renderer that ignored the view, or
    # drew both sides alike, gives an IoU near 1 here)
    assert _iou(left, right) < 0.6
    # the front view of a symmetric pose is itself mirror-symmetric
    assert _iou(front, front[:, ::-1]) > 0.97
    # and front and side views differ a lot (arms out to the sides are visible only from the front)
    assert _iou(front, left) < 0.8


def test_masks_name_the_owning_joint(motion):
    frames, truth, masks = _render(motion, view="front")
    body = build_body(motion.skeleton)
    ids = set(np.unique(masks)) - {-1}
    assert ids <= set(int(o) for o in body.owner)
    head = motion.skeleton.index("Head")
    assert head in ids
    # the head joint's pixel shows the head
    u, v = np.rint(truth["joints2d"][0, head]).astype(int)
    assert truth["visible"][0, head] and masks[0, v, u] == head


def test_labels_and_transitions_map_by_time():
    m = sample_motion(121, fps=120.0)  # 1 s at 120 fps -> 21 video frames at 20 fps
    labels = [f"a{i // 30}" for i in range(121)]
    trans = np.zeros(121, dtype=bool)
    trans[[7, 61, 120]] = True
    cam = Camera.for_view(m, size=(64, 48))
    frames, truth = render_motion(m, cam, fps=20.0, labels=labels, transitions=trans)
    assert len(frames) == 21
    assert list(truth["labels"]) == [labels[6 * i] for i in range(21)]
    assert np.flatnonzero(truth["transition"]).tolist() == [1, 10, 20]
    assert truth["source_time"][-1] == pytest.approx(1.0)
    with pytest.raises(ValueError):
        render_motion(m, cam, fps=20.0, labels=labels[:-1])
    with pytest.raises(ValueError):
        render_motion(m, cam, fps=20.0, transitions=trans[:-1])


def test_resampling_to_video_rate():
    m = sample_motion(61, fps=60.0)
    cam = Camera.for_view(m, size=(64, 48))
    frames, truth = render_motion(m, cam, fps=20.0)
    assert len(frames) == 21 and truth["fps"] == 20.0
    assert np.allclose(truth["joints3d"][5], global_positions(m)[15], atol=1e-6)


def test_large_preview_size(motion):
    cam = Camera.for_view(motion, view="front", size=(640, 480))
    frames, truth = render_motion(motion[:3], cam, fps=20.0, appearance=Appearance.random(1))
    assert frames.shape == (3, 480, 640, 3)
    assert truth["visible"].mean() > 0.5


@pytest.mark.parametrize("style", ["cmu", "joint"])
def test_body_model_for_naming_conventions(style):
    sk = humanoid_skeleton(style)
    body = build_body(sk)
    kinds = sorted(set(body.kind))
    for k in ("head", "torso", "thigh", "shin", "upperarm", "forearm"):
        assert k in kinds, (style, kinds)
    assert body.height == pytest.approx(1.75, rel=0.1)
    # thighs are thicker than forearms, the torso thicker still
    r = {k: body.radii[[i for i, kk in enumerate(body.kind) if kk == k]].max() for k in kinds}
    assert r["torso"] > r["thigh"] > r["forearm"]


def test_classify_bone_names():
    assert classify_bone("LeftArm", "LeftForeArm") == "upperarm"
    assert classify_bone("LeftForeArm", "LeftHand") == "forearm"
    assert classify_bone("LeftShoulder", "LeftArm") == "clavicle"
    assert classify_bone("l_shoulder", "l_elbow") == "upperarm"
    assert classify_bone("l_elbow", "l_wrist") == "forearm"
    assert classify_bone("LeftUpLeg", "LeftLeg") == "thigh"
    assert classify_bone("LeftLeg", "LeftFoot") == "shin"
    assert classify_bone("l_hip", "l_knee") == "thigh"
    assert classify_bone("LHipJoint", "LeftUpLeg") == "pelvis"
    assert classify_bone("Spine", "Spine1") == "torso"
    assert classify_bone("Head", None) == "head"
    assert classify_bone("mystery", "bone") == "other"


def test_unnamed_skeleton_still_renders():
    from vidstyle.mocap import Motion, Skeleton

    sk0 = humanoid_skeleton("cmu")
    sk = Skeleton([f"j{i}" for i in range(sk0.n_joints)], sk0.parents, sk0.offsets,
                  end_sites=sk0.end_sites)
    m = Motion(sk, np.tile([0.0, 0.0, 0.0, 1.0], (3, sk.n_joints, 1)), fps=20.0)
    cam = Camera.for_view(m, size=(80, 60))
    frames, truth, masks = render_motion(m, cam, fps=20.0, return_masks=True)
    assert (masks >= 0).mean() > 0.02


def test_render_errors(motion):
    cam = Camera.for_view(motion)
    with pytest.raises(ValueError):
        render_motion(motion, cam, fps=0)
    with pytest.raises(ValueError):
        render_motion(motion, cam, background="wallpaper")
    with pytest.raises(ValueError):
        render_motion(motion, cam, noise_sigma=-1)
    with pytest.raises(ValueError):
        render_motion(motion[0:0], cam)


def test_appearance_random_is_seeded():
    assert Appearance.random(3) == Appearance.random(3)
    assert len({Appearance.random(s) for s in range(20)}) > 15
    a = Appearance.random(4)
    assert Appearance.from_dict(a.to_dict()) == a


@pytest.mark.parametrize("suffix", [".mp4", ".avi"])
def test_render_to_file_roundtrip(tmp_path, motion, suffix):
    out = tmp_path / f"clip{suffix}"
    side = render_to_file(motion, out, view="left", size=(96, 72), fps=20.0, seed=3, labels=["jab"] * 24)
    assert side == sidecar_path(out) == tmp_path / "clip.truth.npz"
    video = read_video(out)
    assert video.shape == (24, 72, 96, 3)
    truth = load_truth(out)
    assert truth["joints2d"].shape == (24, motion.n_joints, 2)
    assert set(truth["labels"]) == {"jab"}
    assert int(truth["seed"]) == 3
    # lossy codec, but the decoded frames are close to what render_motion makes
    frames, _ = render_motion(motion, Camera.for_view(motion, view="left", size=(96, 72)), fps=20.0, seed=3)
    assert np.abs(video.astype(float) - frames).mean() < 6.0
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted([out.name, side.name])


def test_write_video_is_atomic(tmp_path):
    out = tmp_path / "v.mp4"

    def frames():
        for i in range(3):
            yield np.full((24, 32, 3), 40 * i, np.uint8)
        raise RuntimeError("boom")

    with pytest.raises(RuntimeError):
        write_video(frames(), out, 20.0)
    assert list(tmp_path.iterdir()) == []
    with pytest.raises(InputError):
        write_video([], out, 20.0)
    with pytest.raises(InputError):
        write_video(np.zeros((2, 8, 8, 3), np.uint8), tmp_path / "v.gif", 20.0)
    assert list(tmp_path.iterdir()) == []
    write_video(np.zeros((4, 24, 32, 3), np.uint8), out, 20.0)
    assert read_video(out).shape == (4, 24, 32, 3)
