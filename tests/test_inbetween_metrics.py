"""LAFAN1's L2Q / L2P (``vidstyle.evaluation.inbetween``) on hand-computed tiny inputs, the window
normalisation, and the benchmark's metrics document."""

from __future__ import annotations

import numpy as np
import pytest
from bvh_samples import TWO_JOINT
from scipy.spatial.transform import Rotation

from vidstyle.evaluation.inbetween import global_pose, l2p, l2q, sign_continuous, windows
from vidstyle.formats.metrics import INBETWEEN, parse_metrics
from vidstyle.mocap import Motion, parse_bvh


def test_l2q_hand_computed():
    ident = np.array([0.0, 0.0, 0.0, 1.0])
    turn = np.array([0.0, 0.0, np.sin(np.pi / 4), np.cos(np.pi / 4)])  # 90 degrees about z
    truth = np.stack([ident, ident])[None, :, None]  # (1 window, 2 frames, 1 joint, 4)
    pred = np.stack([turn, ident])[None, :, None]
    # frame 0: sqrt(sin^2 45 + (1 - cos 45)^2) = sqrt(0.5 + 0.0857864) = 0.7653669; frame 1: 0
    assert l2q(pred, truth) == pytest.approx(0.7653669 / 2, abs=1e-7)
    # two joints: the norm runs over joints and components together
    pred2 = np.concatenate([pred, pred], axis=2)
    truth2 = np.concatenate([truth, truth], axis=2)
    assert l2q(pred2, truth2) == pytest.approx(np.sqrt(2) * 0.7653669 / 2, abs=1e-7)


def test_sign_continuity_makes_a_flipped_prediction_free():
    q = Rotation.from_euler("z", np.linspace(0, 60, 5)[:, None], degrees=True).as_quat()[:, None]  # (5, 1, 4)
    flipped = q * np.array([1, -1, 1, -1, -1])[:, None, None]
    anchor = q[0]
    assert l2q(sign_continuous(flipped[1:], anchor), sign_continuous(q[1:], anchor)) == pytest.approx(0.0)
    assert l2q(flipped[1:], q[1:]) > 1.0  # without the sign fix, a flipped quaternion costs ~2


def test_l2p_hand_computed_with_normalisation():
    truth = np.zeros((1, 2, 2, 3))
    pred = np.zeros((1, 2, 2, 3))
    pred[0, 0, 0] = [3.0, 0.0, 4.0]  # frame 0, joint 0
    pred[0, 1, 1] = [0.0, 2.0, 0.0]  # frame 1, joint 1
    mean = np.full((2, 3), 7.0)  # cancels
    std = np.array([[1.0, 1.0, 2.0], [1.0, 4.0, 1.0]])
    # frame 0: sqrt(3^2 + (4/2)^2) = sqrt(13); frame 1: 2/4 = 0.5
    assert l2p(pred, truth, mean, std) == pytest.approx((np.sqrt(13) + 0.5) / 2)


def test_global_pose_of_a_known_chain():
    sk = parse_bvh(TWO_JOINT).skeleton
    rot = np.tile([0.0, 0.0, 0.0, 1.0], (1, sk.n_joints, 1))
    rot[0, 0] = Rotation.from_euler("z", [90], degrees=True).as_quat()
    q, p = global_pose(sk, rot, np.array([[1.0, 2.0, 3.0]]))
    chest = sk.index("Chest")
    assert p[0, chest] == pytest.approx([1.0 - 2.0, 2.0, 3.0])  # offset (0, 2, 0) turned 90 degrees about z
    assert np.abs(np.sum(q[0, chest] * rot[0, 0])) == pytest.approx(1.0)


def test_windows_are_centred_and_face_one_way_at_the_last_context_frame():
    sk = parse_bvh(TWO_JOINT).skeleton
    F = 200
    ang = np.zeros((F, sk.n_joints, 3))
    ang[:, 0, 1] = np.linspace(0, 180, F)  # turning about the vertical
    t = np.arange(F) / 30
    m = Motion.from_euler(sk, ang, np.stack([t, np.full(F, 3.0), 2 * t], 1), 30.0)
    ws = windows(m, 65, 40)
    assert len(ws) == 4  # i + 65 < 200: i = 0, 40, 80, 120
    for w in ws:
        assert np.allclose(w.root_positions[:, [0, 2]].mean(0), 0.0, atol=1e-9)
        assert w.facing_angles()[9] == pytest.approx(0.0, abs=1e-9)


def test_metrics_document_is_checked():
    doc = {"kind": INBETWEEN, "schema_version": 1, "seed": 0, "gaps": [15],
           "methods": {"slerp": {"15": {"l2p": 1.0, "l2q": 0.5, "ms_per_request": 2.0, "windows": 3}}},
           "split": {}, "params": {}}
    assert parse_metrics(doc).kind == INBETWEEN
    bad = {**doc, "methods": {"slerp": {"15": {"l2p": -1.0, "l2q": 0.5, "ms_per_request": 2.0, "windows": 3}}}}
    with pytest.raises(Exception, match="l2p"):
        parse_metrics(bad)
    with pytest.raises(Exception, match="30"):
        parse_metrics({**doc, "gaps": [15, 30]})


def test_the_goal_asks_markov_below_slerp_on_both_measures_per_gap():
    from vidstyle.evaluation.inbetween import markov_goal

    res = {"markov": {"15": {"l2p": 0.9, "l2q": 0.51}, "45": {"l2p": 3.2, "l2q": 1.4}},
           "slerp": {"15": {"l2p": 1.0, "l2q": 0.50}, "45": {"l2p": 3.4, "l2q": 1.5}}}
    assert markov_goal(res, [15, 45]) == {"markov_below_slerp_l2p_15": True, "markov_below_slerp_l2p_45": True,
                                          "markov_below_slerp_l2q_15": False, "markov_below_slerp_l2q_45": True}
    assert markov_goal({"slerp": res["slerp"]}, [15]) == {}
