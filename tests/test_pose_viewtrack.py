"""Viewpoint tracking through a video (vidstyle.pose.viewtrack): the Viterbi path against a brute-force
search over every view sequence, the ring's rules (no half turn between two frames, one quarter step per
frame of gap), left and right exchanged on a half turn, and what is left alone."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from vidstyle.formats.poses import PoseFrame, Poses
from vidstyle.mocap.keypoints import KEYPOINT_INDEX, MIRROR
from vidstyle.pose.viewtrack import RING, track_views, viterbi_views


def _cost(seq, costs, gaps, step, dwell):
    """The total cost of a view sequence, inf when it breaks a rule (one quarter step per frame, and at
    least d * dwell frames since the previous move for a move of d steps)."""
    at = np.concatenate([[0], np.cumsum(gaps)])  # frame numbers
    total, last = sum(costs[t][s] for t, s in enumerate(seq)), -math.inf
    for t in range(1, len(seq)):
        d = min((seq[t] - seq[t - 1]) % 4, (seq[t - 1] - seq[t]) % 4)
        if d == 0:
            continue
        if d > gaps[t - 1] or at[t] - last < d * dwell:
            return math.inf
        total, last = total + d * step, at[t]
    return total


@pytest.mark.parametrize("seed", range(8))
def test_viterbi_matches_brute_force(seed):
    rng = np.random.default_rng(seed)
    T = 6
    costs = rng.exponential(1.5, (T, 4))
    gaps = rng.choice([1, 1, 1, 2], T - 1)
    step = float(rng.uniform(0.2, 4.0))
    dwell = int(rng.integers(1, 4))
    got = viterbi_views(costs, gaps, step, dwell)
    best = min(_cost(seq, costs, gaps, step, dwell) for seq in itertools.product(range(4), repeat=T))
    assert _cost(list(got), costs, gaps, step, dwell) == pytest.approx(best)  # a legal path of least cost


def test_dwell_makes_a_quick_flip_too_costly_to_be_a_turn():
    # back for 3 frames then front: with dwell 3 a half turn needs 3 frames at a side, dearer than reading
    # the first frames as front
    costs = np.array([[5.0, 9, 0.2, 9]] * 3 + [[0.1, 9, 6.0, 9]] * 6)
    gaps = np.ones(8, dtype=int)
    # dwell 1: back, back, a side (left: the lower index of the two equal sides), then front (cost 12.0,
    # against 12.1 with the side one frame later and 15.6 for front throughout)
    assert list(viterbi_views(costs, gaps, 1.0, dwell=1)) == [2, 2, 1, 0, 0, 0, 0, 0, 0]
    assert list(viterbi_views(costs, gaps, 1.0, dwell=3)) == [0] * 9


def _frame(i, view, scores, points=None):
    pts = np.column_stack([np.arange(30.0).reshape(15, 2) + i, np.full(15, 0.8)]) if points is None else points
    return PoseFrame(i, view, pts, dict(zip(RING, scores)))


def test_a_short_confident_run_of_back_inside_a_front_video_becomes_front_with_sides_exchanged():
    front, back = (0.9, 0.04, 0.02, 0.04), (0.1, 0.05, 0.8, 0.05)
    frames = [_frame(i, "front", front) for i in range(10)]
    frames[4:7] = [_frame(i, "back", back) for i in range(4, 7)]
    poses = Poses("v.mp4", "ps", frames)
    got = track_views(poses, 3.0)
    assert [f.viewpoint for f in got.frames] == ["front"] * 10
    for i in range(10):  # half-turned frames: left and right names exchanged; the others untouched
        want = poses.frames[i].points[MIRROR] if 4 <= i < 7 else poses.frames[i].points
        np.testing.assert_array_equal(got.frames[i].points, want)
    lw, rw = KEYPOINT_INDEX["left_wrist"], KEYPOINT_INDEX["right_wrist"]
    np.testing.assert_array_equal(got.frames[5].points[lw], poses.frames[5].points[rw])
    assert [f.viewpoint for f in poses.frames][4] == "back"  # the input is not modified
    # without a step cost, or cheap steps, each frame keeps its own view
    assert [f.viewpoint for f in track_views(poses, 0.0).frames] == [f.viewpoint for f in poses.frames]
    assert [f.viewpoint for f in track_views(poses, 0.05).frames][4:7] != ["front"] * 3


def test_a_real_turn_through_a_side_is_kept():
    seq = ["front"] * 4 + ["left"] * 3 + ["back"] * 4
    onehot = {v: tuple(0.85 if w == v else 0.05 for w in RING) for v in RING}
    poses = Poses("v.mp4", "ps", [_frame(i, v, onehot[v]) for i, v in enumerate(seq)])
    got = track_views(poses, 1.0)
    assert [f.viewpoint for f in got.frames] == seq
    for a, b in zip(got.frames, poses.frames):
        np.testing.assert_array_equal(a.points, b.points)


def test_frames_without_pose_or_scores_or_with_their_own_azimuth_are_left_alone():
    front, back = (0.9, 0.04, 0.02, 0.04), (0.2, 0.05, 0.7, 0.05)
    frames = [_frame(0, "front", front), PoseFrame.none(1, "no performer"), _frame(2, "back", back),
              _frame(3, "front", front)]
    measured = _frame(4, "back", back)
    measured.azimuth = 178.0  # a backend that measures its azimuth (BlazePose) is not tracked
    frames.append(measured)
    got = track_views(Poses("v.mp4", "ps", frames), 5.0)
    assert [f.viewpoint for f in got.frames] == ["front", "unknown", "front", "front", "back"]
    assert not got.frames[1].found
    np.testing.assert_array_equal(got.frames[4].points, measured.points)
    with pytest.raises(ValueError, match="step_cost"):
        track_views(Poses("v.mp4", "ps", frames), float("nan"))
