"""BlazePose backend (runs offline from the wheel's models; CI runs it, no skip when installed)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from vidstyle.mocap.keypoints import KEYPOINT_INDEX, KEYPOINTS, keypoint_joints, keypoint_positions
from vidstyle.pose.blazepose import BlazePoseEstimator, facing_azimuth, to_keypoints, to_world_keypoints

SHARED_REAL = __import__("tests.conftest", fromlist=["SHARED"]).SHARED / "data" / "video" / "real"
BODY = [KEYPOINT_INDEX[k] for k in ("left_shoulder", "right_shoulder", "left_elbow", "right_elbow", "left_knee",
                                    "right_knee", "left_ankle", "right_ankle")]


@pytest.fixture(scope="module")
def take():
    from vidstyle.demo import Performer, build_take, performance_plan

    rng = np.random.default_rng(3)
    p = Performer.random("p03", rng, video_fps=20)
    return build_take(p, performance_plan(p, 40, rng), rng, video_fps=20).motion.resample(20)[10:30:10]


@pytest.fixture(scope="module")
def estimator():
    est = BlazePoseEstimator()
    yield est
    est.close()


@pytest.mark.parametrize("view, azimuth", [("front", 0.0), ("left", 90.0)])
def test_rendered_frame_keypoints_and_view(take, estimator, view, azimuth):
    from vidstyle.render import Appearance, Camera, render_motion

    cam = Camera.for_view(take, view=azimuth, size=(320, 240))
    frames, _ = render_motion(take, cam, fps=take.fps, appearance=Appearance(), background="texture")
    truth, _ = cam.project(keypoint_positions(take))
    for f in range(len(frames)):
        pf = estimator.estimate(frames[f], f)
        torso = np.linalg.norm(truth[f, KEYPOINT_INDEX["neck"]] - truth[f, KEYPOINT_INDEX["pelvis"]])
        err = np.linalg.norm(pf.points[BODY, :2] - truth[f, BODY], axis=1)
        assert np.median(err) < 0.2 * torso, err
        assert pf.viewpoint == view and pf.viewpoint_scores[view] == max(pf.viewpoint_scores.values())
        # the azimuth of the camera about the performer, from the world landmarks (render: cam azimuth)
        assert abs((pf.azimuth - azimuth + 180) % 360 - 180) < 35
        assert np.all((pf.points[:, 2] >= 0) & (pf.points[:, 2] <= 1))
        # head_top (extrapolated from the face) near the true crown
        assert np.linalg.norm(pf.points[0, :2] - truth[f, 0]) < 0.5 * torso
        # the world keypoints: metres, hip-centred, y down (the head above the neck above the pelvis)
        w = pf.world
        assert w.shape == (15, 3) and np.all(np.isfinite(w))
        assert np.linalg.norm(w[KEYPOINT_INDEX["pelvis"]]) < 0.02
        assert w[0, 1] < w[KEYPOINT_INDEX["neck"], 1] < w[KEYPOINT_INDEX["pelvis"], 1]
        assert 0.3 < np.linalg.norm(w[KEYPOINT_INDEX["neck"]] - w[KEYPOINT_INDEX["pelvis"]]) < 0.8


def test_nobody_is_a_missing_frame_not_fake_points(estimator):
    pf = estimator.estimate(np.full((120, 160, 3), 90, np.uint8), 7)
    assert pf.viewpoint == "unknown" and pf.frame == 7 and not pf.found and pf.missing == "nobody found"
    assert np.isnan(pf.points).all() and pf.azimuth is None


def test_mapping_and_facing_geometry():
    lm = np.zeros((33, 3))
    lm[:, 2] = 1.0
    lm[11, :2], lm[12, :2] = (60, 40), (40, 40)  # performer's left shoulder on the image right: facing us
    lm[23, :2], lm[24, :2] = (56, 80), (44, 80)
    lm[7, :2], lm[8, :2] = (54, 20), (46, 20)
    lm[9, :2], lm[10, :2] = (52, 26), (48, 26)
    k = to_keypoints(lm)
    np.testing.assert_allclose(k[KEYPOINT_INDEX["neck"], :2], (50, 40))
    np.testing.assert_allclose(k[KEYPOINT_INDEX["pelvis"], :2], (50, 80))
    np.testing.assert_allclose(k[0, :2], (50, 20 - 1.6 * 6))
    # world landmarks map the same way (the image visibilities choose ears or eyes for head_top)
    xyz = np.column_stack([lm[:, :2], np.arange(33.0)])
    kw = to_world_keypoints(xyz, lm[:, 2])
    np.testing.assert_allclose(kw[:, :2], k[:, :2])
    assert kw[KEYPOINT_INDEX["left_wrist"], 2] == 15 and kw[KEYPOINT_INDEX["pelvis"], 2] == (23 + 24) / 2
    lm_eyes = lm.copy()
    lm_eyes[[7, 8], 2] = 0.2
    assert to_world_keypoints(xyz, lm_eyes[:, 2])[0, 2] == pytest.approx((2 + 5) / 2 + 1.6 * ((2 + 5) / 2 - 9.5))
    w = np.zeros((33, 3))
    w[11], w[12], w[23], w[24] = (0.2, -0.5, 0), (-0.2, -0.5, 0), (0.1, 0, 0), (-0.1, 0, 0)
    assert facing_azimuth(w) == pytest.approx(0.0, abs=1e-6)
    w2 = w.copy()
    w2[[11, 12, 23, 24], 0], w2[[11, 12, 23, 24], 2] = 0.0, -w[[11, 12, 23, 24], 0]  # left side faces the camera
    assert facing_azimuth(w2) == pytest.approx(90.0, abs=1e-6)


def test_pose_command_blazepose_in_input_pixels(tmp_path, take):
    """`vidstyle pose --backend blazepose` on a rendered video: points in the input video's pixels."""
    from typer.testing import CliRunner

    from vidstyle.cli import app
    from vidstyle.render import load_truth, render_to_file

    video = tmp_path / "clip.mp4"
    render_to_file(take, video, view="front", size=(640, 480), fps=take.fps, background="texture")
    truth = load_truth(video)
    out = tmp_path / "poses.json"
    # no --backend and no --model: BlazePose, the default for real footage, following the performer
    res = CliRunner().invoke(app, ["pose", str(video), "--frames", "1", "--out", str(out), "-j", "1"])
    assert res.exit_code == 0, res.output
    doc = json.loads(out.read_text())
    assert doc["backend"] == "blazepose" and doc["keypoints"] == list(KEYPOINTS) and len(doc["frames"]) == 1
    assert doc["params"]["tracked"] is True
    fr = doc["frames"][0]
    assert fr["frame"] == 1 and doc["schema_version"] == 3 and np.array(fr["world"]).shape == (15, 3)
    m = keypoint_joints(take.skeleton)
    pts = np.array(fr["points"])
    gt = np.array([truth["joints2d"][1, m[KEYPOINTS[i]].joint] for i in BODY])
    torso = np.linalg.norm(truth["joints2d"][1, m["neck"].joint] - truth["joints2d"][1, m["pelvis"].joint])
    assert np.median(np.linalg.norm(pts[BODY, :2] - gt, axis=1)) < 0.15 * torso


@pytest.mark.skipif(not (SHARED_REAL / "pose2sim_single_cam01.mp4").is_file(), reason="real footage absent")
def test_real_footage_finds_the_person(estimator):
    from vidstyle.video import VideoReader

    with VideoReader(SHARED_REAL / "pose2sim_single_cam01.mp4", height=640) as r:
        frame = np.asarray(r.frame(50))
    pf = estimator.estimate(frame, 50)
    assert pf.viewpoint != "unknown"
    body = pf.points[BODY]
    assert np.mean(body[:, 2]) > 0.5
    torso = abs(pf.points[KEYPOINT_INDEX["pelvis"], 1] - pf.points[KEYPOINT_INDEX["neck"], 1])
    assert torso > 0.05 * frame.shape[0]  # the standing person is not a speck


def test_rotated_phone_video_gives_the_upright_videos_poses(tmp_path, take):
    """A video stored sideways with a display matrix (as phones do) gives the same poses, in the displayed
    frame's pixels, as the upright video (lossless copies of one rendered clip, so the pixels agree)."""
    from video_util import write_lossless

    from vidstyle.pose.run import estimate_video
    from vidstyle.render import render_to_file
    from vidstyle.video import VideoReader

    video = tmp_path / "clip.mp4"
    render_to_file(take, video, view="front", size=(320, 240), fps=take.fps, background="texture")
    with VideoReader(video) as r:
        frames = [np.asarray(f) for f in r]

    write_lossless(tmp_path / "up.mov", frames)
    write_lossless(tmp_path / "side.mov", [np.ascontiguousarray(np.rot90(f, 1)) for f in frames], -90)  # stored sideways
    up = estimate_video(tmp_path / "up.mov", "blazepose", frames=[0, 1], jobs=1)
    side = estimate_video(tmp_path / "side.mov", "blazepose", frames=[0, 1], jobs=1)
    for a, b in zip(up.frames, side.frames):
        assert a.found and b.found and a.viewpoint == b.viewpoint
        np.testing.assert_array_equal(a.points, b.points)
