"""The triangulated 3D reference (vidstyle.reconstruct.reference) against independent truth: synthetic 3D
keypoints projected by known cameras into four views' poses files come back exactly (after a calibration
and poses files written and read by their owners), outliers and left/right swaps of one view are not
used, the world's up axis is found whichever axis it is, and the comparison tools give 0 for a rotated
copy of the truth. On the shared real take: plausible, steady bone lengths and +Z up."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from vidstyle.errors import InputError
from vidstyle.formats.calibration import Calibration, CameraCalibration, write_calibration
from vidstyle.formats.keypoints import KEYPOINTS
from vidstyle.formats.poses import PoseFrame, Poses, write_poses
from vidstyle.mocap.keypoints import MIRROR
from vidstyle.pose.triangulation import project
from vidstyle.reconstruct.reference import (
    PELVIS,
    bone_lengths,
    compare_root_relative,
    detect_up,
    reference_in_y_up,
    rotation_between,
    triangulated_reference,
    view_to_world,
    view_to_y_up,
    y_up_rotation,
)

KI = {k: i for i, k in enumerate(KEYPOINTS)}
REAL = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "video" / "real"

# a standing body (mm) in a frame with x to its left, y forward, z up; ankles about 80 mm above the floor
BODY = {"head_top": (0, 0, 1720), "neck": (0, 0, 1450), "pelvis": (0, 0, 950),
        "left_shoulder": (180, 0, 1420), "right_shoulder": (-180, 0, 1420),
        "left_elbow": (220, 40, 1140), "right_elbow": (-220, 40, 1140),
        "left_wrist": (240, 200, 950), "right_wrist": (-240, 200, 950),
        "left_hip": (100, 0, 930), "right_hip": (-100, 0, 930),
        "left_knee": (110, 30, 500), "right_knee": (-110, 30, 500),
        "left_ankle": (110, 0, 80), "right_ankle": (-110, 0, 80)}


def _motion(F=12, up=(0, 0, 1)):
    """(F, 15, 3) truth: the body turning and walking on the floor of a world whose up is ``up``."""
    base = np.array([BODY[k] for k in KEYPOINTS], dtype=float)
    R_up = rotation_between((0, 0, 1), up)
    out = []
    for f in range(F):
        a = 0.25 * f
        Rz = np.array([[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1]])
        X = base @ Rz.T + [40.0 * f, -25.0 * f, 0.0]
        X[KI["left_ankle"], 2] += 60 * (f % 3 == 0)  # a lifted foot now and then
        out.append(X @ R_up.T)
    return np.stack(out)


def _look_at(centre, target, up):
    z = np.asarray(target, float) - np.asarray(centre, float)
    z /= np.linalg.norm(z)
    x = np.cross(z, up)
    x /= np.linalg.norm(x)
    return np.stack([x, np.cross(z, x), z])


def _calibration(up=(0, 0, 1), dist=True) -> Calibration:
    up = np.asarray(up, float)
    R_up = rotation_between((0, 0, 1), up)
    cams = []
    for i in range(4):
        a = 2 * np.pi * i / 4 + 0.4
        C = R_up @ np.array([3500 * np.cos(a), 3500 * np.sin(a), 1700.0])
        R = _look_at(C, R_up @ np.array([0, 0, 1000.0]), up)
        K = np.array([[1400.0, 0, 540], [0, 1400.0, 960], [0, 0, 1]])
        d = np.array([-0.05, 0.02, 0.0, 0.0, 0.0]) if dist and i % 2 else np.zeros(5)
        cams.append(CameraCalibration(f"cam0{i + 1}", (1080, 1920), K, R, -R @ C, d))
    return Calibration(cams)


def _write_take(tmp_path, truth, calib, edit=None):
    """A TOML calibration and one poses.json per camera (names contain the camera), from ``truth``."""
    cal = tmp_path / "calib.toml"
    write_calibration(cal, calib)
    files = []
    rng = np.random.default_rng(0)
    for v, cam in enumerate(calib.cameras):
        frames = []
        for f, X in enumerate(truth):
            xy = project(X, cam)
            if edit is not None:
                xy = edit(v, f, xy)
            seen = np.isfinite(xy).all(axis=1)  # a keypoint the view did not find: score 0 (files hold no NaN)
            pts = np.column_stack([np.where(seen[:, None], xy, 0.0), np.where(seen, 0.9, 0.0)])
            frames.append(PoseFrame(f, "front", pts, {"front": 1.0}, world=rng.normal(0, 0.3, (15, 3))))
        path = tmp_path / f"take_{cam.name}.poses.json"
        write_poses(path, Poses(f"take_{cam.name}.mp4", "blazepose", frames))
        files.append(path)
    return cal, files[::-1]  # out of order: matched to the cameras by name


def test_reference_recovers_projected_points_exactly(tmp_path):
    truth = _motion()
    calib = _calibration()
    cal, files = _write_take(tmp_path, truth, calib)
    ref = triangulated_reference(cal, files)
    assert ref.names == ["cam01", "cam02", "cam03", "cam04"] and list(ref.frames) == list(range(len(truth)))
    assert ref.valid.all() and ref.agree.all() and not ref.swapped.any()
    # poses.json keeps 1/1000 px: the points come back to well under a millimetre
    np.testing.assert_allclose(ref.positions, truth, atol=0.5)
    assert np.nanmax(ref.reprojection_px) < 0.01
    assert ref.up_axis == "+Z" and np.array_equal(ref.up, [0, 0, 1]) and ref.up_tilt_deg < 1
    lowest = truth[:, [KI["left_ankle"], KI["right_ankle"]], 2].min(axis=1)
    assert ref.floor_mm == pytest.approx(np.percentile(lowest, 5), abs=0.5)
    # the project's +Y-up frame: Y is the world's Z, and the frame stays right-handed
    y = reference_in_y_up(ref)
    np.testing.assert_allclose(y[..., 1], truth[..., 2], atol=0.5)
    np.testing.assert_allclose(y, truth @ np.array([[1, 0, 0], [0, 0, 1], [0, -1, 0]]).T, atol=0.5)
    assert reference_in_y_up(ref, floor_at_zero=True)[..., 1].min() == pytest.approx(lowest.min() - ref.floor_mm, abs=0.5)
    for name, x in bone_lengths(ref.positions).items():
        np.testing.assert_allclose(x, bone_lengths(truth)[name], atol=1.0)


def test_camera_frame_estimates_come_back_to_the_reference(tmp_path):
    truth = _motion()
    calib = _calibration()
    cal, files = _write_take(tmp_path, truth, calib)
    ref = triangulated_reference(cal, files)
    cam = calib.camera("cam02")
    in_cam = truth @ cam.R.T + cam.t  # what a reconstruction from cam02 would give, in its camera frame
    R, C = view_to_world(cal, "cam02")
    np.testing.assert_allclose(in_cam @ R.T + C, truth, atol=1e-6)
    M = view_to_y_up(ref, "cam02")
    y = reference_in_y_up(ref)
    assert compare_root_relative(in_cam @ M.T, y, ref.valid, "none").mpjpe_mm < 0.5
    # without the camera's rotation only an alignment makes them agree: one rotation for the take
    raw = compare_root_relative(in_cam, y, ref.valid, "none")
    seq = compare_root_relative(in_cam, y, ref.valid, "sequence")
    assert raw.mpjpe_mm > 100 and seq.mpjpe_mm < 0.5 and np.allclose(seq.rotation, M, atol=1e-4)
    assert seq.n == len(truth) * 14 and seq.frames == len(truth) and "pelvis" not in seq.per_keypoint_mm
    # a per-frame error is not removed by the sequence rotation, but the per-frame one does remove a turn
    turned = in_cam.copy()
    turned[3] = (turned[3] - turned[3, PELVIS]) @ rotation_between((1, 0, 0), (0, 0, 1)).T + turned[3, PELVIS]
    assert compare_root_relative(turned @ M.T, y, ref.valid, "sequence").per_frame_mm[3] > 100
    assert compare_root_relative(turned @ M.T, y, ref.valid, "frame").mpjpe_mm < 0.5
    with pytest.raises(InputError, match="cam09"):
        view_to_world(cal, "cam09")


def test_outliers_swaps_and_single_views_are_not_a_reference(tmp_path):
    truth = _motion()
    calib = _calibration()
    L = KI["left_wrist"]

    def edit(v, f, xy):
        xy = xy.copy()
        if v == 2 and f == 4:
            xy[L] += (300.0, 0.0)  # one view far off on one keypoint
        if v == 1 and f == 6:
            xy = xy[MIRROR]  # one view swapped left and right in one frame
        if v >= 1 and f == 8:
            xy[KI["right_knee"]] = np.nan  # only cam01 sees the right knee: no reference
        return xy

    cal, files = _write_take(tmp_path, truth, calib, edit=edit)
    ref = triangulated_reference(cal, files)
    assert not ref.agree[2, 4, L] and ref.valid[4, L]
    np.testing.assert_allclose(ref.positions[4, L], truth[4, L], atol=0.5)
    assert ref.swapped[1, 6] and ref.swapped[1].sum() == 1 and not ref.swapped[[0, 2, 3]].any()
    np.testing.assert_allclose(ref.positions[6], truth[6], atol=0.5)
    assert not ref.valid[8, KI["right_knee"]] and np.isnan(ref.positions[8, KI["right_knee"]]).all()
    assert ref.valid.sum() == ref.valid.size - 1
    np.testing.assert_allclose(ref.positions[ref.valid], truth[ref.valid], atol=0.5)


@pytest.mark.parametrize("up", [(0, 0, 1), (0, -1, 0), (1, 0, 0)])
def test_up_axis_is_found_whichever_world_axis_it_is(tmp_path, up):
    truth = _motion(up=up)
    axis, tilt = detect_up(truth)
    assert np.array_equal(axis, up) and tilt < 1
    cal, files = _write_take(tmp_path, truth, _calibration(up=up, dist=False))
    ref = triangulated_reference(cal, files)
    assert np.array_equal(ref.up, up)
    y = reference_in_y_up(ref)
    np.testing.assert_allclose(y[..., 1], truth @ np.asarray(up, float), atol=0.5)  # height along up is Y
    assert np.allclose(y_up_rotation(np.asarray(up, float)) @ up, (0, 1, 0))
    assert np.isclose(np.linalg.det(y_up_rotation(np.asarray(up, float))), 1.0)


def test_no_head_and_ankles_is_an_input_error_naming_the_file():
    X = np.full((3, 15, 3), np.nan)
    with pytest.raises(InputError, match="take.json.*up axis"):
        detect_up(X, "take.json")


def test_sequence_alignment_is_a_rotation_not_a_reflection():
    truth = _motion()
    mirrored = truth * [-1, 1, 1]
    c = compare_root_relative(mirrored, truth, align="sequence")
    assert np.isclose(np.linalg.det(c.rotation), 1.0) and c.mpjpe_mm > 10


@pytest.mark.shared
def test_real_take_reference_has_plausible_steady_bones(tmp_path):
    if not (REAL / "pose2sim_single_cam01.mp4").is_file():
        pytest.skip("../shared/data/video/real is absent")
    pytest.importorskip("mediapipe")
    from vidstyle.formats.poses import write_poses as write
    from vidstyle.pose.run import estimate_video
    from vidstyle.reconstruct.reference import summary

    files = []
    for i in range(1, 5):
        path = tmp_path / f"cam0{i}.poses.json"
        write(path, estimate_video(REAL / f"pose2sim_single_cam0{i}.mp4", "blazepose", frames=list(range(0, 100, 9)),
                                   jobs=1))
        files.append(path)
    ref = triangulated_reference(REAL / "pose2sim_single_Calib.qca.txt", files)
    assert ref.up_axis == "+Z"  # the Qualisys lab frame
    assert ref.valid.mean() > 0.9
    lengths = {k: np.nanmean(v) for k, v in bone_lengths(ref.positions).items()}
    assert 400 < lengths["torso"] < 650 and 150 < lengths["head"] < 330
    for side in ("left", "right"):
        assert 220 < lengths[f"{side}_upper_arm"] < 360 and 180 < lengths[f"{side}_forearm"] < 330
        assert 300 < lengths[f"{side}_upper_leg"] < 500 and 300 < lengths[f"{side}_lower_leg"] < 480
    assert max(np.nanstd(v) for v in bone_lengths(ref.positions).values()) < 40
    assert np.nanmean(ref.reprojection_px) < 30
    s = summary(ref)
    b = s["per_view"]["cam01"]["blazepose_world_mpjpe_mm"]
    assert 20 < b["sequence_kabsch"] < 250 and b["per_frame_procrustes"] <= b["sequence_kabsch"] + 1e-6
