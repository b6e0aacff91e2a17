"""Leave-one-view-out scoring of calibrated views and the calibration readers, against analytic truth:
points projected through known cameras triangulate back exactly, the Qualisys convention read from a
file written here reproduces the cameras it was written from, and known pixel offsets give known
normalised errors."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from vidstyle.errors import FormatError
from vidstyle.evaluation.multiview import leave_one_view_out, project, summarise, triangulate, undistort
from vidstyle.formats.calibration import (
    Calibration,
    CameraCalibration,
    read_calibration,
    write_calibration,
)


def _look_at(centre, target=(0.0, 0.0, 1000.0), up=(0.0, 0.0, 1.0)):
    """World -> camera rotation of a camera at ``centre`` looking at ``target`` (OpenCV axes: y down)."""
    z = np.asarray(target, float) - np.asarray(centre, float)
    z /= np.linalg.norm(z)
    x = np.cross(z, up)
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    return np.stack([x, y, z])


def _cameras(n=4, dist=True):
    cams = []
    for i in range(n):
        a = 2 * np.pi * i / n + 0.3
        C = np.array([3000 * np.cos(a), 3000 * np.sin(a), 1600.0])
        R = _look_at(C)
        K = np.array([[1500.0, 0, 540], [0, 1500.0, 960], [0, 0, 1]])
        d = np.array([-0.04, 0.12, 0.0006, 0.0007, 0.0]) if dist else np.zeros(5)
        cams.append(CameraCalibration(f"cam{i + 1:02d}", (1080, 1920), K, R, -R @ C, d))
    return cams


def _skeleton(rng, frames=6):
    """(F, 15, 3) world points of a standing figure (mm), neck index 1, pelvis index 2."""
    base = np.array([[0, 0, 1750], [0, 0, 1500], [0, 0, 1000], [180, 0, 1480], [-180, 0, 1480], [250, 0, 1200],
                     [-250, 0, 1200], [280, 0, 950], [-280, 0, 950], [100, 0, 980], [-100, 0, 980],
                     [110, 0, 520], [-110, 0, 520], [110, 0, 80], [-110, 0, 80]], float)
    return base[None] + rng.normal(0, 30, (frames, 15, 3))


def test_triangulation_recovers_a_point_exactly():
    cams = _cameras(dist=False)
    X = np.array([120.0, -340.0, 1210.0])
    pts = np.stack([project(X[None], c)[0] for c in cams])
    assert np.allclose(triangulate(pts, [c.P for c in cams]), X, atol=1e-6)
    pts[1:] = np.nan
    assert np.isnan(triangulate(pts, [c.P for c in cams])).all()


def test_distortion_round_trip():
    cam = _cameras()[0]
    X = _skeleton(np.random.default_rng(1))[0]
    p = project(X, cam)
    und = undistort(p, cam)
    ideal = (cam.K @ (cam.R @ X.T + cam.t[:, None])).T
    assert np.allclose(und, ideal[:, :2] / ideal[:, 2:], atol=1e-3)
    assert np.abs(p - und).max() > 0.5  # the distortion is not a no-op here


def test_perfect_views_score_zero_and_known_offsets_score_their_ratio():
    cams = _cameras()
    X = _skeleton(np.random.default_rng(2))
    pts = np.stack([np.concatenate([project(X.reshape(-1, 3), c).reshape(X.shape[0], 15, 2),
                                    np.ones((X.shape[0], 15, 1))], axis=-1) for c in cams])
    errors, torso = leave_one_view_out(cams, pts, torso=(1, 2))
    assert np.nanmax(errors) < 1e-6
    s = summarise(errors, [c.name for c in cams], [str(k) for k in range(15)])
    assert s["overall"]["pck@0.2"] == 1.0 and s["overall"]["n"] == 4 * X.shape[0] * 15
    # move one keypoint of view 0 by 0.15 torso lengths, another by 0.3: one PCK@0.2 miss, two @0.1
    shifted = pts.copy()
    shifted[0, 0, 5, 0] += 0.15 * torso[0, 0]
    shifted[0, 0, 7, 1] += 0.3 * torso[0, 0]
    e, _ = leave_one_view_out(cams, shifted, torso=(1, 2))
    assert e[0, 0, 5] == pytest.approx(0.15, abs=1e-6) and e[0, 0, 7] == pytest.approx(0.3, abs=1e-6)
    # a keypoint missing in the held-out view is a miss; missing in all but one other view: unscored
    shifted[1, 1, 3, 2] = 0.0
    shifted[[0, 2], 2, 4, 2] = 0.0
    e, _ = leave_one_view_out(cams, shifted, torso=(1, 2))
    assert np.isinf(e[1, 1, 3])
    assert np.isnan(e[3, 2, 4]) and np.isnan(e[1, 2, 4])


def _qca(cams) -> str:
    """A Qualisys calibration of ``cams`` written by the file's convention (independent of the reader)."""
    flip = np.diag([1.0, -1.0, -1.0])
    parts = ["<?xml version='1.0' encoding='ASCII'?>\n<calibration><cameras>"]
    for c in cams:
        M = flip @ c.R  # R = diag(1,-1,-1) M
        C = c.centre
        r = " ".join(f'r{a + 1}{b + 1}="{M[a, b]}"' for a in range(3) for b in range(3))
        w, h = c.size
        parts.append(
            f'<camera serial="{c.name}"><fov_video left="0" top="0" right="{w - 1}" bottom="{h - 1}"/>'
            f'<transform {r} x="{C[0]}" y="{C[1]}" z="{C[2]}"/>'
            f'<intrinsic focalLengthU="{c.K[0, 0] * 64}" focalLengthV="{c.K[1, 1] * 64}" '
            f'centerPointU="{c.K[0, 2] * 64}" centerPointV="{c.K[1, 2] * 64}" radialDistortion1="{c.dist[0]}" '
            f'radialDistortion2="{c.dist[1]}" radialDistortion3="{c.dist[4]}" tangentalDistortion1="{c.dist[2]}" '
            f'tangentalDistortion2="{c.dist[3]}" skew="0"/></camera>')
    parts.append("</cameras></calibration>\n")
    return "".join(parts)


def test_qca_and_toml_readers_reproduce_the_cameras(tmp_path):
    cams = _cameras()
    (tmp_path / "c.qca.txt").write_text(_qca(cams))
    got = read_calibration(tmp_path / "c.qca.txt")
    write_calibration(tmp_path / "c.toml", got)
    again = read_calibration(tmp_path / "c.toml")
    X = _skeleton(np.random.default_rng(3))[0]
    for ref, a, b in zip(cams, got.cameras, again.cameras):
        assert a.name == ref.name == b.name and a.size == ref.size == b.size
        assert np.allclose(project(X, a), project(X, ref), atol=1e-6)
        assert np.allclose(project(X, b), project(X, ref), atol=1e-4)


REAL = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "video" / "real"


@pytest.mark.shared
def test_shared_pose2sim_calibration_reads():
    if not REAL.is_dir():
        pytest.skip("../shared/data/video/real is absent")
    calib = read_calibration(REAL / "pose2sim_single_Calib.qca.txt")
    assert calib.names() == ["cam01", "cam02", "cam03", "cam04"]
    for cam in calib.cameras:
        assert cam.size == (1088, 1920)
        # every camera sees a point 1 m above the floor's origin in front of it, inside its image
        p = project(np.array([[0.0, 0.0, 1000.0]]), cam)[0]
        assert 0 < p[0] < cam.size[0] and 0 < p[1] < cam.size[1]
        assert (cam.R @ np.array([0, 0, 1000.0]) + cam.t)[2] > 0


@settings(max_examples=150, derandomize=True, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(data=st.binary(max_size=600), kind=st.sampled_from(["qca", "toml"]))
def test_calibration_readers_raise_only_format_errors(tmp_path, data, kind):
    base = _qca(_cameras(2)).encode() if kind == "qca" else None
    if kind == "toml":
        write_calibration(tmp_path / "ok.toml", Calibration(_cameras(2)))
        base = (tmp_path / "ok.toml").read_bytes()
    cut = len(data) % (len(base) + 1)
    blob = base[:cut] + data + base[cut + len(data) // 2:]
    path = tmp_path / ("x.qca.txt" if kind == "qca" else "x.toml")
    path.write_bytes(blob)
    try:
        read_calibration(path)
    except FormatError:
        pass


def test_robust_reference_is_not_pulled_by_another_views_left_right_swap():
    from vidstyle.mocap.keypoints import MIRROR

    cams = _cameras(dist=False)
    X = _skeleton(np.random.default_rng(4), frames=3)
    pts = np.stack([np.concatenate([project(X.reshape(-1, 3), c).reshape(X.shape[0], 15, 2),
                                    np.ones((X.shape[0], 15, 1))], axis=-1) for c in cams])
    pts[2] = pts[2][:, MIRROR]  # view 2's estimator swapped left and right in every frame
    limbs = [k for k in range(15) if MIRROR[k] != k]
    plain, _ = leave_one_view_out(cams, pts, torso=(1, 2))
    robust, _ = leave_one_view_out(cams, pts, torso=(1, 2), reference="robust", mirror=MIRROR)
    for v in (0, 1, 3):  # correct views: the swap corrupts their plain reference, not the robust one
        assert np.nanmax(plain[v][:, limbs]) > 0.05
        assert np.nanmax(robust[v]) < 1e-6
    # the swapped view itself is still scored against the truth: its error is the left-right distance
    true2 = project(X.reshape(-1, 3), cams[2]).reshape(X.shape[0], 15, 2)
    torso = np.linalg.norm(true2[:, 1] - true2[:, 2], axis=-1)
    expect = np.linalg.norm(true2[:, MIRROR] - true2, axis=-1) / torso[:, None]
    assert np.allclose(robust[2], expect, atol=1e-6)
    with pytest.raises(ValueError):
        leave_one_view_out(cams, pts, torso=(1, 2), reference="robust")


def test_evaluate_pose_calibration_cli_scores_poses_files(tmp_path):
    """`vidstyle evaluate pose --calibration C P1 P2 P3 P4` on poses files made from known cameras, one
    view's left and right swapped: the plain reference scores every view below 1, the robust one keeps
    the correct views at exactly 1 and the swapped view below; the metrics file is valid."""
    from vidstyle.mocap.keypoints import MIRROR

    from typer.testing import CliRunner

    from vidstyle.cli import app
    from vidstyle.formats.metrics import MULTIVIEW_POSE, read_metrics
    from vidstyle.formats.poses import PoseFrame, Poses, write_poses

    cams = _cameras()
    calib = Calibration(cams)
    write_calibration(tmp_path / "calib.toml", calib)
    X = _skeleton(np.random.default_rng(5), frames=4)
    files = []
    for v, c in enumerate(cams):
        uv = project(X.reshape(-1, 3), c).reshape(4, 15, 2)
        if v == 2:
            uv = uv[:, MIRROR]
        frames = [PoseFrame(f, "front", np.column_stack([uv[f], np.ones(15)]), {"front": 1.0}) for f in range(4)]
        frames.append(PoseFrame.none(4, "nobody found"))
        # files named after their cameras, given out of order: matched by name
        path = tmp_path / f"{c.name}.poses.json"
        write_poses(path, Poses(f"{c.name}.mp4", "blazepose", frames))
        files.append(path)
    out = tmp_path / "m.json"
    res = CliRunner().invoke(app, ["evaluate", "pose", "--calibration", str(tmp_path / "calib.toml"),
                                   *map(str, reversed(files)), "--out", str(out)])
    assert res.exit_code == 0, res.output
    m = read_metrics(out, MULTIVIEW_POSE).doc
    assert m["views"] == ["cam01", "cam02", "cam03", "cam04"]
    dlt = m["references"]["dlt"]["per_view"]
    robust = m["references"]["robust"]["per_view"]
    assert robust["cam03"]["pck@0.2"] < 0.8 and dlt["cam03"]["pck@0.2"] < 0.8
    for v in ("cam01", "cam02", "cam04"):  # the swapped view drags the plain reference, not the robust one
        assert robust[v]["pck@0.2"] == 1.0 and dlt[v]["pck@0.2"] < 1.0
    assert m["references"]["dlt"]["overall"]["n"] == 4 * 4 * 15  # frame 4 has no pose anywhere: unscored
    assert "cam03" in res.output
    from vidstyle.cli import main

    assert main(["evaluate", "pose", "--calibration", str(tmp_path / "calib.toml"), str(files[0])]) == 2
