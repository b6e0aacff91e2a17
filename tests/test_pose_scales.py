"""Multi-scale pose inference (PoseModel.estimate with scales): the zoom map, the choice of the most
confident scale, and the mapping of its keypoints back to the frame, on a model whose answer is known
exactly (it finds a bright square and is most confident when the square has a chosen size)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from vidstyle.formats.poses import PoseFrame, Poses, read_poses, write_poses
from vidstyle.pose.estimator import PoseModel, check_scales, zoom_about


class SquareFinder(PoseModel):
    """Every keypoint at the bright square's centre; score 1 when it is ``best`` pixels wide, falling
    linearly to 0 at twice or zero that width."""

    best = 20.0

    def _estimate_once(self, frame, index, view, detectors, background):
        ys, xs = np.nonzero(frame.max(axis=2) > 127 if frame.ndim == 3 else frame > 127)
        c = np.array([xs.mean(), ys.mean()])
        width = xs.max() - xs.min() + 1.0
        score = max(0.0, 1.0 - abs(width - self.best) / self.best)
        return PoseFrame(index, "front", np.column_stack([np.tile(c, (15, 1)), np.full(15, score)]))


def _frame(cx: int, cy: int, half: int, size=(160, 120)) -> np.ndarray:
    img = np.zeros((size[1], size[0], 3), np.uint8)
    img[cy - half:cy + half, cx - half:cx + half] = 255
    return img


def test_zoom_about_moves_the_centre_to_the_middle_and_scales_distances():
    A = zoom_about(np.array([30.0, 40.0]), 2.0, (160, 120))
    q = A[:, :2] @ np.array([30.0, 40.0]) + A[:, 2]
    np.testing.assert_allclose(q, [79.5, 59.5])
    q2 = A[:, :2] @ np.array([35.0, 40.0]) + A[:, 2]
    assert q2[0] - q[0] == pytest.approx(10.0)


def test_check_scales():
    assert check_scales([1.4, 1.2]) == (1.0, 1.4, 1.2)
    assert check_scales([1.0, 0.8, 1.0]) == (1.0, 0.8)
    for bad in ([], [0.0], [5.0], [float("nan")], [1.0, -1.0]):
        with pytest.raises(ValueError, match="zoom"):
            check_scales(bad)


def test_the_most_confident_zoom_wins_and_maps_back():
    m = SquareFinder()
    frame = _frame(40, 50, 5)  # a 10-px square: zoom 2 makes it the model's favourite 20 px
    one = m.estimate(frame)
    assert one.points[0, 2] == pytest.approx(0.5)
    m.set_inference(scales=(1.0, 2.0))
    two = m.estimate(frame)
    assert two.points[0, 2] == pytest.approx(1.0, abs=0.06)
    np.testing.assert_allclose(two.points[:, :2], np.tile([39.5, 49.5], (15, 1)), atol=0.3)  # back in frame pixels
    m.set_inference(scales=(1.0, 0.5))  # shrinking makes it worse: the scale-1 pose stays
    kept = m.estimate(frame)
    np.testing.assert_array_equal(kept.points, one.points)


def test_a_zoom_that_finds_a_wrong_place_maps_back_consistently():
    # the square sits off-centre; whatever zoom wins, the reported centre is where the square is
    m = SquareFinder().set_inference(scales=(1.5, 2.0, 2.5))
    for cx, cy in ((30, 30), (120, 90), (80, 60)):
        got = m.estimate(_frame(cx, cy, 4))
        np.testing.assert_allclose(got.points[0, :2], [cx - 0.5, cy - 0.5], atol=0.35)
        assert got.points[0, 2] > 0.9  # 8 px x 2.5 = 20 px


def test_poses_params_round_trip(tmp_path):
    pts = np.column_stack([np.arange(30.0).reshape(15, 2), np.full(15, 0.5)])
    p = Poses("v.mp4", "ps", [PoseFrame(3, "front", pts, {"front": 1.0})], params={"scales": [1.0, 1.2]})
    write_poses(tmp_path / "p.json", p)
    assert read_poses(tmp_path / "p.json").params == {"scales": [1.0, 1.2]}
    write_poses(tmp_path / "q.json", Poses("v.mp4", "ps", []))
    assert "params" not in (tmp_path / "q.json").read_text()
    from vidstyle.formats._base import FormatError

    doc = json.loads((tmp_path / "p.json").read_text())
    doc["params"] = [doc["params"]]
    (tmp_path / "r.json").write_text(json.dumps(doc))
    with pytest.raises(FormatError, match="params: expected an object"):
        read_poses(tmp_path / "r.json")


def test_zoom_candidates_are_the_scale_one_pose_then_each_zoom_mapped_back():
    m = SquareFinder()
    frame = _frame(40, 50, 5)  # 10 px wide: zoom 2 gives 20 px (score 1), zoom 0.5 gives 5 px (score 0.25)
    got = m.zoom_candidates(frame, (2.0, 0.5))
    assert len(got) == 3
    np.testing.assert_array_equal(got[0].points, m.estimate(frame).points)  # scales (1,): the first
    np.testing.assert_allclose([c.points[0, 2] for c in got], [0.5, 1.0, 0.25], atol=0.06)
    for c in got:  # every candidate in the frame's pixels
        np.testing.assert_allclose(c.points[:, :2], np.tile([39.5, 49.5], (15, 1)), atol=0.3)
    m.set_inference(scales=(1.0, 2.0, 0.5))  # estimate keeps the most confident candidate
    np.testing.assert_array_equal(m.estimate(frame).points, got[1].points)


def test_default_scales_are_the_validation_choice_and_the_pose_command_uses_them():
    from pathlib import Path

    from vidstyle.formats.validation import POSE_SCALES, read_validation
    from vidstyle.pose.defaults import PS_SCALES
    from vidstyle.pose.run import check_estimate_params

    doc = read_validation(Path(__file__).resolve().parents[1] / "pipelines" / "kickboxing" / "validation"
                          / "pose_scales.json", POSE_SCALES)
    assert tuple(doc["chosen"]) == PS_SCALES
    rows = doc["candidates"]
    for r in rows:  # a candidate's score is its figure-size bins' mean, its cost one pass per distinct zoom
        assert r["pck@0.2"] == pytest.approx(np.mean([b["pck@0.2"] for b in r["by_figure_scale"]]))
        assert r["passes"] == len(check_scales(r["scales"]))
    best = max(r["pck@0.2"] for r in rows)  # the rule, reapplied to the recorded table
    near = [r for r in rows if r["pck@0.2"] >= best - doc["tolerance"]]
    assert min(near, key=lambda r: (r["passes"], -r["pck@0.2"]))["scales"] == doc["chosen"]
    assert doc["split"].startswith("val") and "CMU" in doc["split"]  # validation performers only
    assert check_estimate_params("ps", None, None) == PS_SCALES
    assert check_estimate_params("blazepose", None, None) == (1.0,)
