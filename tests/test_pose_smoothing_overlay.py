"""One-Euro smoothing of keypoint tracks and the pose overlay frames."""

from __future__ import annotations

import math

import numpy as np
import pytest

from vidstyle.errors import ParameterError
from vidstyle.formats.keypoints import KEYPOINTS
from vidstyle.formats.poses import PoseFrame, Poses
from vidstyle.pose.overlay import draw_pose
from vidstyle.pose.run import smooth_poses
from vidstyle.pose.smoothing import one_euro


def test_one_euro_is_the_published_filter_on_a_step():
    """With beta = 0 the filter is a first-order low-pass with alpha = 1 / (1 + tau / dt),
    tau = 1 / (2 pi f_c): after a unit step the output is 1 - (1 - alpha)^n exactly."""
    t = np.arange(20) / 30.0
    x = np.where(np.arange(20) >= 1, 1.0, 0.0)
    y = one_euro(x, t, min_cutoff=2.0, beta=0.0)
    alpha = 1.0 / (1.0 + (1.0 / (2 * math.pi * 2.0)) / (1 / 30.0))
    n = np.arange(20)
    np.testing.assert_allclose(y[1:], 1 - (1 - alpha) ** n[1:], rtol=1e-12)


def test_one_euro_removes_jitter_of_a_still_point_and_follows_fast_motion():
    rng = np.random.default_rng(0)
    t = np.arange(300) / 30.0
    still = 100 + rng.normal(0, 2.0, 300)
    assert np.std(one_euro(still, t)[30:]) < 0.5 * np.std(still[30:])
    fast = 400.0 * t  # 400 px/s: the speed raises the cut-off, so the lag stays small
    lag = np.abs(one_euro(fast, t, beta=0.05) - fast)[30:].max()
    assert lag < np.abs(one_euro(fast, t, beta=0.0) - fast)[30:].max() / 3


def test_gaps_restart_the_filter():
    t = np.arange(6) / 10.0
    x = np.array([0.0, 0.0, np.nan, 5.0, 5.0, 5.0])
    y = one_euro(x, t, beta=0.0)
    assert np.isnan(y[2]) and y[3] == 5.0 and y[5] == 5.0


@pytest.mark.parametrize("kw", [{"min_cutoff": 0.0}, {"beta": -1.0}, {"d_cutoff": float("nan")}])
def test_parameters_are_checked(kw):
    with pytest.raises(ParameterError):
        one_euro(np.zeros(3), np.arange(3.0), **kw)


def test_smooth_poses_keeps_missing_frames_and_unsure_keypoints():
    rng = np.random.default_rng(1)
    frames = []
    for i in range(10):
        pts = np.column_stack([50 + rng.normal(0, 3, 15), 60 + rng.normal(0, 3, 15), np.full(15, 0.9)])
        frames.append(PoseFrame(i, "front", pts, {"front": 1.0}) if i != 4 else PoseFrame.none(4, "nobody found"))
    frames[6].points[3, 2] = 0.0
    raw = frames[6].points[3].copy()
    out = smooth_poses(Poses("v.mp4", "blazepose", frames), fps=20.0)
    assert not out.frames[4].found and np.isnan(out.frames[4].points).all()
    np.testing.assert_array_equal(out.frames[6].points[3], raw)  # a keypoint with score 0 is left as it is


def test_overlay_draws_at_the_keypoints_and_names_a_missing_frame():
    frame = np.zeros((120, 160, 3), np.uint8)
    pts = np.column_stack([np.linspace(20, 140, 15), np.linspace(10, 110, 15), np.ones(15)])
    img = draw_pose(frame, PoseFrame(0, "left", pts, {"left": 1.0}, azimuth=90.0))
    for x, y, _ in pts:
        assert img[round(y), round(x)].sum() > 0
    assert img.shape == frame.shape and frame.sum() == 0  # the input is not drawn on
    missing = draw_pose(frame, PoseFrame.none(3, "performer not found"))
    assert missing[:20, :, 2].sum() > 0 and missing[40:].sum() == 0  # red text in the top band only
    assert len(KEYPOINTS) == 15
