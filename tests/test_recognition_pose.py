"""Pose-sequence recognizer (issue 28): features' invariances and derivatives checked analytically,
projection through a known camera, and a small train/predict on synthetic labelled motion."""

from __future__ import annotations

import math

import numpy as np
import pytest

from vidstyle.formats.keypoints import KEYPOINTS
from vidstyle.formats.poses import PoseFrame, Poses
from vidstyle.recognition.posefeatures import (
    NECK,
    PELVIS,
    PoseFeaturizer,
    PoseTrack,
    fill_gaps,
    mirror_track,
    track_from_poses,
)
from vidstyle.recognition.poserecognizer import PoseRecognizer
from vidstyle.recognition.posetraining import (
    KeypointNoise,
    LabelledMotion,
    camera_for,
    project_keypoints,
    virtual_views,
)
from vidstyle.render.camera import Camera

KP = {k: i for i, k in enumerate(KEYPOINTS)}
# a standing figure (world units, +Y up, facing +Z, performer's left = +X)
STAND = {
    "head_top": (0, 1.75, 0), "neck": (0, 1.5, 0), "pelvis": (0, 1.0, 0),
    "left_shoulder": (0.2, 1.45, 0), "right_shoulder": (-0.2, 1.45, 0),
    "left_elbow": (0.25, 1.2, 0.1), "right_elbow": (-0.25, 1.2, 0.1),
    "left_wrist": (0.2, 1.35, 0.3), "right_wrist": (-0.2, 1.35, 0.3),
    "left_hip": (0.12, 1.0, 0), "right_hip": (-0.12, 1.0, 0),
    "left_knee": (0.15, 0.5, 0.05), "right_knee": (-0.15, 0.5, 0.05),
    "left_ankle": (0.15, 0.05, 0), "right_ankle": (-0.15, 0.05, 0),
}
BASE3D = np.array([STAND[k] for k in KEYPOINTS], float)


def random_track(rng, F=40):
    xy = BASE3D[:, [0, 1]] * [100, -100] + [80, 200]
    return xy[None] + np.cumsum(rng.normal(0, 1.5, (F, 15, 2)), axis=0)


def test_features_invariant_to_translation_and_scale():
    rng = np.random.default_rng(0)
    xy = random_track(rng)
    f = PoseFeaturizer()
    X = f.transform(xy)
    assert X.shape == (40, f.dimension)
    # a camera panned (per-frame translation is not invariance: the root's motion is a feature) ->
    # a constant image translation and a zoom about any point leave every feature unchanged
    np.testing.assert_allclose(f.transform(xy + [37.0, -12.5]), X, atol=1e-9)
    np.testing.assert_allclose(f.transform(2.5 * (xy - [10, 20]) + [3, 4]), X, atol=1e-9)


def test_pose_block_is_root_centred_and_torso_scaled():
    xy = np.repeat((BASE3D[:, [0, 1]] * [100, -100] + [80, 200])[None], 5, axis=0)
    f = PoseFeaturizer(scale_window=0)
    Q, _root, scale, missing = f.normalised(xy)
    torso = np.linalg.norm(xy[0, NECK] - xy[0, PELVIS])
    assert torso == pytest.approx(50.0)
    np.testing.assert_allclose(scale, torso)
    np.testing.assert_allclose(Q[2, KP["head_top"]], (xy[2, KP["head_top"]] - xy[2, PELVIS]) / torso)
    np.testing.assert_allclose(Q[:, PELVIS], 0.0)
    assert not missing.any()


def test_mirror_is_a_signed_permutation_of_the_features():
    rng = np.random.default_rng(1)
    xy = random_track(rng)
    xy[10:13] = np.nan  # a gap too, filled the same way on both sides
    f = PoseFeaturizer()
    perm, sign = f.mirror_permutation()
    assert sorted(perm) == list(range(f.dimension))
    np.testing.assert_allclose(f.transform(mirror_track(xy)), f.transform(xy)[:, perm] * sign, atol=1e-9)
    # mirroring twice is the identity; mirroring once changes left-right asymmetric features
    np.testing.assert_allclose(mirror_track(mirror_track(xy)), xy)
    assert not np.allclose(f.transform(mirror_track(xy)), f.transform(xy))


def test_velocities_and_accelerations_are_finite_differences():
    t = np.arange(30, dtype=float)
    xy = np.repeat((BASE3D[:, [0, 1]] * [100, -100] + [80, 200])[None], 30, axis=0)
    wrist = KP["left_wrist"]
    xy[:, wrist, 0] += 0.5 * t**2          # x = 0.5 t^2: velocity t, acceleration 1 (pixels)
    xy[:, PELVIS] += np.c_[3.0 * t, 0 * t]  # the whole body (root) walks 3 px/frame to the right
    xy[:, [i for i in range(15) if i != PELVIS]] += np.c_[3.0 * t, 0 * t][:, None]
    f = PoseFeaturizer(velocity_steps=(1, 2), accel_steps=(2,), window_offsets=(4,), scale_window=0)
    X = f.transform(xy)
    torso = 50.0
    j = [i for i in range(15) if i != PELVIS].index(wrist)
    npose = 28
    blk = 30
    for b, k in enumerate((1, 2)):
        v = X[10:20, npose + b * blk + 2 * j]
        np.testing.assert_allclose(v, t[10:20] / torso, atol=1e-9)          # d/dt 0.5 t^2 = t (central diff exact)
        np.testing.assert_allclose(X[10:20, npose + b * blk + 28], 3.0 / torso)  # root velocity
    np.testing.assert_allclose(X[10:20, npose + 2 * blk + 2 * j], 1.0 / torso, atol=1e-9)  # acceleration
    d = X[10:20, npose + 3 * blk + 2 * j]
    np.testing.assert_allclose(d, (0.5 * (t[10:20] + 4) ** 2 - 0.5 * t[10:20] ** 2) / torso, atol=1e-9)


def test_missing_frames_short_gaps_filled_long_gaps_flagged():
    rng = np.random.default_rng(2)
    xy = random_track(rng, 40)
    holes = xy.copy()
    holes[5:8] = np.nan    # 3 frames: filled
    holes[20:30] = np.nan  # 10 frames: missing
    filled = fill_gaps(holes, 5)
    np.testing.assert_allclose(filled[6], (2 * xy[4] + 2 * xy[8]) / 4)  # linear between frames 4 and 8
    assert np.isnan(filled[20:30]).all()
    X = PoseFeaturizer(max_gap=5).transform(holes)
    assert (X[20:30, -2] == 1).all() and (X[:20, -2] == 0).all() and (X[30:, -2] == 0).all()
    assert (X[20:30, :-2] == 0).all()
    assert np.isfinite(X).all()


def test_track_from_poses_marks_absent_and_null_frames_missing():
    pts = np.c_[np.arange(30.0).reshape(15, 2), np.ones(15)]
    poses = Poses("v.mp4", "blazepose", [PoseFrame(0, "front", pts), PoseFrame.none(1, "performer not found"),
                                         PoseFrame(3, "front", pts + 1)])
    tr = track_from_poses(poses, 20.0, 5)
    assert tr.n_frames == 5
    np.testing.assert_allclose(tr.xy[3], pts[:, :2] + 1)
    assert np.isnan(tr.xy[[1, 2, 4]]).all() and np.isfinite(tr.xy[[0, 3]]).all()


def test_projection_of_a_known_skeleton_through_a_known_camera():
    m = LabelledMotion(BASE3D[None].repeat(3, 0), ["Guard"] * 3, 20.0, facing=0.0)
    cam = camera_for(m, azimuth_deg=0.0, elevation_deg=0.0, distance=3.0, vfov_deg=40.0, size=(160, 120))
    f = 60.0 / math.tan(math.radians(20.0))
    target = (BASE3D.min(0) + BASE3D.max(0)) / 2
    d = 3.0 * m.height
    uv = project_keypoints(m.points, cam)[0]
    # in front of the performer looking along -Z: the performer's left (+X) is the image's right
    for k, p in enumerate(BASE3D):
        z = d - (p[2] - target[2])
        u = 79.5 + f * (p[0] - target[0]) / z
        v = 59.5 - f * (p[1] - target[1]) / z
        np.testing.assert_allclose(uv[k], [u, v], atol=1e-6)
    # from the performer's left (+90): the camera on +X looks along -X, image right is -Z (the
    # performer's front, +Z, is on the image's left)
    side = project_keypoints(m.points, camera_for(m, 90.0, 0.0, 3.0, 40.0))[0]
    for k, p in enumerate(BASE3D):
        z = d - (p[0] - target[0])
        np.testing.assert_allclose(side[k], [79.5 - f * (p[2] - target[2]) / z, 59.5 - f * (p[1] - target[1]) / z],
                                   atol=1e-6)
    # behind the camera: missing
    back = Camera(cam.K, cam.R, cam.t - [0, 0, 100.0])
    assert np.isnan(project_keypoints(m.points, back)).all()


def synthetic_motion(rng, action: str, F: int) -> np.ndarray:
    """(F, 15, 3): a figure that punches (wrists out and back along +Z) or kicks (ankles up and forward)."""
    t = np.arange(F) / 20.0
    pts = np.repeat(BASE3D[None], F, axis=0) + rng.normal(0, 0.005, (F, 15, 3))
    phase = np.sin(2 * np.pi * rng.uniform(1.5, 2.5) * t + rng.uniform(0, 6)) ** 2
    if action == "Punch":
        for k in ("left_wrist", "right_wrist"):
            pts[:, KP[k], 2] += 0.45 * phase
            pts[:, KP[k], 1] += 0.05 * phase
    else:
        for k, s in (("right_ankle", 0.9), ("right_knee", 0.45)):
            pts[:, KP[k], 1] += s * phase
            pts[:, KP[k], 2] += 0.5 * s * phase
    return pts


def labelled_set(rng, n):
    motions = []
    for i in range(n):
        a = ("Punch", "Kick")[i % 2]
        motions.append(LabelledMotion(synthetic_motion(rng, a, 60), [a] * 60, 20.0, rng.uniform(0, 2 * np.pi), f"{a}{i}"))
    return motions


def test_train_on_virtual_views_and_recognise_unseen_views():
    rng = np.random.default_rng(3)
    train = labelled_set(rng, 8)
    tracks, labels = virtual_views(train, 3, 0, KeypointNoise(sigma=0.02, outlier_rate=0.0, dropout_rate=0.0))
    assert len(tracks) == 24 and all(t.n_frames == 60 for t in tracks)
    rec = PoseRecognizer(C=10.0, max_frames_per_class=300, smoothing="vote", random_state=0).fit(tracks, labels)
    test = labelled_set(np.random.default_rng(4), 6)
    ttracks, tlabels = virtual_views(test, 2, 1, None, azimuth=(20.0, 340.0))
    acc = np.mean([np.mean(rec.classes_[rec.predict_video(t)["smoothed"]] == np.array(y))
                   for t, y in zip(ttracks, tlabels)])
    assert acc > 0.9
    # broken features that lose the limbs (every keypoint a fixed offset from the pelvis) cannot tell them apart
    def collapsed(t):
        return PoseTrack(t.xy[:, [PELVIS]] + (np.arange(15)[:, None] * [0, 1.0])[None], t.fps)

    bad = PoseRecognizer(C=10.0, max_frames_per_class=300, smoothing="vote", random_state=0).fit(
        [collapsed(t) for t in tracks], labels)
    bad_acc = np.mean([np.mean(bad.classes_[bad.predict_video(collapsed(t))["smoothed"]] == np.array(y))
                       for t, y in zip(ttracks, tlabels)])
    assert bad_acc < 0.75


def test_pose_model_file_round_trip(tmp_path):
    from vidstyle.formats.recognizer_model import read_recognizer_model
    from vidstyle.recognition.poserecognizer import save_pose_model

    rng = np.random.default_rng(5)
    tracks, labels = virtual_views(labelled_set(rng, 4), 1, 0, None)
    rec = PoseRecognizer(max_frames_per_class=100, random_state=0).fit(tracks, labels)
    save_pose_model(tmp_path / "m.joblib", rec, {"motions": 4})
    back, header = read_recognizer_model(tmp_path / "m.joblib", PoseRecognizer)
    assert header["input"] == "pose" and header["classes"] == ["Kick", "Punch"]
    np.testing.assert_array_equal(back.predict_video(tracks[0])["smoothed"], rec.predict_video(tracks[0])["smoothed"])


def test_train_from_labelled_mocap_clips(cmu_dir, tmp_path):
    """train-recognizer --features pose --clips --clip-labels: labelled real mocap (a punch clip's strikes,
    a walk) trains a recognizer that tells the two apart from a camera it was not trained at; only the
    labelled ranges train; bad combinations exit 2."""
    from vidstyle.cli import main
    from vidstyle.recognition.posetraining import LabelledMotion, clip_motions
    from vidstyle.recognition.recognizer import load_model

    csv = tmp_path / "labels.csv"
    csv.write_text("file,label,start,end\n02_05.bvh,Jab,100,900\n07_01.bvh,Step,1,300\n")
    clips = [str(cmu_dir / "02_05.bvh"), str(cmu_dir / "07_01.bvh")]
    motions = clip_motions(clips, [csv], 20.0)
    assert [m.name.split("[")[0] for m in motions] == ["02_05", "07_01"]
    assert [set(m.labels) for m in motions] == [{"Jab"}, {"Step"}]
    assert len(motions[0].labels) == pytest.approx(800 / 6, abs=1)  # 120 fps -> 20 fps
    out = tmp_path / "m.joblib"
    assert main(["train-recognizer", "--features", "pose", "--clips", *clips[:1], "--clips", clips[1],
                 "--clip-labels", str(csv), "--views", "6", "--seed", "0", "--out", str(out)]) == 0
    rec, header = load_model(out)
    assert list(rec.classes_) == ["Jab", "Step"] and header["input"] == "pose"
    # a camera the training did not sample (azimuths drawn from a different seed)
    from vidstyle.recognition.posetraining import virtual_views

    test = [LabelledMotion(m.points, m.labels, m.fps, m.facing, m.name) for m in motions]
    tracks, labels = virtual_views(test, 2, 123, None)
    acc = np.mean(np.concatenate([rec.classes_[rec.predict_video(t)["smoothed"]] == np.array(y)
                                  for t, y in zip(tracks, labels)]))
    assert acc > 0.85
    # errors: labels without clips, clips with 3D SIFT, labels that name no frame of the clips
    assert main(["train-recognizer", "--features", "pose", "--clip-labels", str(csv), "--out", str(tmp_path / "a.joblib")]) == 2
    assert main(["train-recognizer", "--clips", clips[0], "--out", str(tmp_path / "b.joblib")]) == 2
    (tmp_path / "none.csv").write_text("file,label\nother.bvh,Jab\n")
    assert main(["train-recognizer", "--features", "pose", "--clips", clips[0], "--clip-labels",
                 str(tmp_path / "none.csv"), "--out", str(tmp_path / "c.joblib")]) == 2
    assert not any((tmp_path / f).exists() for f in ("a.joblib", "b.joblib", "c.joblib"))
