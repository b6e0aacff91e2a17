"""Motion-quality metrics against analytic answers (independent truth, not the code's own output).

* foot skid: a foot sliding at a known speed while planted, another held still, a third lifted;
* seam velocity jump: a motion whose velocity changes by a known amount at a marked transition frame;
* aligned MPJPE: a candidate that is the truth under a rigid vertical-axis rotation + floor translation
  (error 0) plus a known vertical error (the alignment cannot remove it: error known exactly).
"""

from __future__ import annotations

import numpy as np
import pytest

from vidstyle.evaluation import augmg as augmg_eval
from vidstyle.evaluation import motion as motion_eval
from vidstyle.mocap import Motion
from vidstyle.mocap.skeleton import Skeleton

FPS = 30.0
T = 60
NAMES = ["Hips", "Head", "LeftFoot", "RightFoot", "RightToe"]
OFFSETS = np.array([[0, 90, 0], [0, 80, 0], [-10, -90, 0], [10, -90, 0], [20, -90, 0]], float)  # head 170, feet y=0


def _motion(translations: np.ndarray) -> Motion:
    sk = Skeleton(NAMES, [-1, 0, 0, 0, 0], OFFSETS)
    rot = np.zeros((len(translations), len(NAMES), 4))
    rot[..., 3] = 1.0
    return Motion(sk, rot, translations, fps=FPS)


def _base() -> np.ndarray:
    return np.broadcast_to(OFFSETS, (T, len(NAMES), 3)).copy()


def test_foot_skid_is_the_planted_feet_horizontal_speed():
    speed = 45.0  # length units per second, along a horizontal diagonal (x and z)
    step = speed / FPS * np.array([0.6, 0.0, 0.8])
    tr = _base()
    t = np.arange(T)[:, None]
    tr[:, 0] += t * step                         # the body slides ...
    tr[:, 2] -= t * step                         # ... the left foot's local offset cancels it: planted, speed 0
    # the right foot slides with the body; in the 2nd half it bobs 0 / 6 (low, 6 < 5 % of the body height
    # 170, but moving vertically: not planted)
    tr[T // 2::2, 3, 1] += 6.0
    tr[T // 2:, 4, 1] += 40.0                    # the toe slides with the body; lifted 40 in the 2nd half
    out = motion_eval.evaluate_walk(_motion(tr), {"labels": []})
    skid = out["foot_skid"]["inside"]
    # planted: all T frames of the left foot (speed 0) + the first T/2 of the right foot and of the toe
    # (speed `speed`); not the bobbing frames (vertical motion), not the lifted ones (not low)
    assert skid["n"] == 2 * T
    assert skid["mean"] == pytest.approx(speed / 2, rel=1e-9)
    assert skid["p95"] == pytest.approx(speed, rel=1e-9)
    assert out["foot_skid"]["seam"]["n"] == 0  # no transitions marked


def test_seam_velocity_jump_is_the_velocity_change_at_the_marked_frame():
    v1, v2, k = np.array([30.0, 0, 0]), np.array([-15.0, 0, 60.0]), 25  # velocities (units/s), seam frame
    t = np.arange(T)[:, None]
    root = np.where(t <= k, t * v1, k * v1 + (t - k) * v2) / FPS + OFFSETS[0]
    tr = _base()
    tr[:, 0] = root
    labels = {"labels": ["a"] * T, "source_labels": ["a"] * T, "transition": [-1] * T}
    labels["transition"][k] = 0
    out = motion_eval.evaluate_walk(_motion(tr), labels)
    jump = np.linalg.norm(v2 - v1) * FPS  # |v(t+1) - v(t)| * fps, the same for every joint (rigid motion)
    seam = out["velocity_jump"]["seam"]
    assert seam["n"] == 3  # frames k-1, k, k+1; only k has a velocity change
    assert seam["mean"] == pytest.approx(jump / 3, rel=1e-9)
    inside = out["velocity_jump"]["inside"]
    assert inside["n"] == T - 2 - 3 and inside["mean"] == pytest.approx(0, abs=1e-9)
    assert out["label_fidelity"] == 1.0


def _pose(rng) -> np.ndarray:
    p = rng.normal(scale=30.0, size=(15, 3))
    p[:, 1] = np.abs(p[:, 1]) * 3
    return p


@pytest.mark.parametrize("theta", [0.0, 0.7, -2.5, np.pi])
def test_aligned_mpjpe_removes_a_rigid_floor_transform_and_keeps_a_known_error(rng, theta):
    true = _pose(rng)
    c, s = np.cos(theta), np.sin(theta)
    rot = np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])
    moved = true @ rot.T + np.array([123.0, 0, -57.0])
    lifted = moved + np.array([0, 7.5, 0])       # every joint 7.5 too high: error exactly 7.5
    one = moved.copy()
    one[4, 1] += 30.0                             # one joint of 15 off by 30 vertically: error 2
    err = augmg_eval.aligned_mpjpe(true, np.stack([moved, lifted, one]))
    assert err == pytest.approx([0.0, 7.5, 2.0], abs=1e-6)


def test_aligned_mpjpe_does_not_align_away_a_pose_difference(rng):
    true = _pose(rng)
    other = _pose(rng)
    err = augmg_eval.aligned_mpjpe(true, other[None])[0]
    # the best vertical-axis rotation + floor shift leaves at least the vertical disagreement
    assert err >= np.abs(true[:, 1] - other[:, 1]).mean() - 1e-9
    assert err > 1.0
