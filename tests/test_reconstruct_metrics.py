"""The reconstruction's 3D error metrics (issue 29) against independent truth: known rigid motions,
offsets worked out by hand, brute-force searches and explicit optimisation, synthetic sliding feet."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from scipy.optimize import minimize
from scipy.spatial.transform import Rotation

from vidstyle.formats.keypoints import KEYPOINTS
from vidstyle.reconstruct import metrics as M

KP = {k: i for i, k in enumerate(KEYPOINTS)}

# a standing performer in mm, +Y up, facing +Z, left = +X, ankles 80 mm above the floor at Y = 0
STAND = np.array([
    (0, 1750, 0), (0, 1500, 0), (0, 950, 0),
    (180, 1450, 0), (-180, 1450, 0), (200, 1150, 0), (-200, 1150, 0), (210, 880, 50), (-210, 880, 50),
    (100, 930, 0), (-100, 930, 0), (110, 500, 30), (-110, 500, 30), (110, 80, 0), (-110, 80, 0),
], dtype=float)


def _ry(theta: float) -> np.ndarray:
    """Right-handed rotation about +Y (turns +Z towards +X), written out independently of the module."""
    c, s = math.cos(theta), math.sin(theta)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def _sequence(F: int = 60, seed: int = 0) -> np.ndarray:
    """A skeleton-like motion: the standing pose with smooth per-keypoint wobble, walking along a curve."""
    rng = np.random.default_rng(seed)
    t = np.arange(F)[:, None, None]
    freq = rng.uniform(0.05, 0.3, size=(1, 15, 3))
    phase = rng.uniform(0, 2 * np.pi, size=(1, 15, 3))
    wobble = 40.0 * np.sin(freq * t + phase)
    wobble[..., 1] *= 0.3
    root = np.stack([300 * np.sin(0.03 * np.arange(F)), np.zeros(F), 20.0 * np.arange(F)], axis=1)
    return STAND[None] + wobble + root[:, None, :]


def _wrap(a: float) -> float:
    return (a + math.pi) % (2 * math.pi) - math.pi


def test_yaw_and_floor_translation_recovered():
    true = _sequence()
    theta, shift = 0.7, np.array([1234.0, 0.0, -567.0])
    pred = true @ _ry(theta).T + shift
    aligned, yaw, d = M.align_sequence(pred, true)
    assert _wrap(yaw + theta) == pytest.approx(0.0, abs=1e-12)
    np.testing.assert_allclose(d, -_ry(-theta) @ shift, atol=1e-8)
    np.testing.assert_allclose(aligned, true, atol=1e-8)
    assert M.mpjpe(pred, true) == pytest.approx(0.0, abs=1e-8)
    assert M.mpjpe_root_relative(pred, true) == pytest.approx(0.0, abs=1e-8)
    assert M.acceleration_error(pred, true) == pytest.approx(0.0, abs=1e-8)
    # the vertical offset is an error unless asked to align it too
    up = pred + [0.0, 30.0, 0.0]
    assert M.mpjpe(up, true) == pytest.approx(30.0, abs=1e-8)
    assert M.mpjpe(up, true, vertical=True) == pytest.approx(0.0, abs=1e-8)
    assert M.mpjpe_root_relative(up, true) == pytest.approx(0.0, abs=1e-8)


def test_rotate_yaw_convention():
    p = np.array([[0.0, 5.0, 1.0]])
    np.testing.assert_allclose(M.rotate_yaw(p, math.pi / 2), [[1.0, 5.0, 0.0]], atol=1e-12)
    q = np.random.default_rng(1).normal(size=(7, 3))
    np.testing.assert_allclose(M.rotate_yaw(q, 0.4), q @ _ry(0.4).T, atol=1e-12)


def test_yaw_alignment_matches_a_fine_grid_search():
    rng = np.random.default_rng(2)
    true = _sequence(F=20, seed=3)
    pred = true @ _ry(-2.2).T + rng.normal(scale=150.0, size=true.shape) + [50.0, 0.0, 80.0]
    _, yaw, _ = M.align_sequence(pred, true)

    def cost(theta):
        r = pred @ _ry(theta).T
        shift = (true - r).reshape(-1, 3).mean(axis=0)
        shift[1] = 0.0
        return float(((r + shift - true) ** 2).sum())

    grid = np.linspace(-math.pi, math.pi, 20001)
    costs = np.array([cost(g) for g in grid])
    best = grid[np.argmin(costs)]
    assert abs(_wrap(yaw - best)) < 2 * (grid[1] - grid[0])
    assert cost(yaw) <= costs.min() + 1e-9 * costs.min()
    aligned, _, _ = M.align_sequence(pred, true)
    assert float(((aligned - true) ** 2).sum()) == pytest.approx(cost(yaw), rel=1e-12)


def test_constant_offset_on_one_keypoint_by_hand():
    true = _sequence(seed=4)
    theta, shift = -1.1, np.array([300.0, 0.0, 200.0])
    pred = true.copy()
    pred[:, KP["left_wrist"], 1] += 60.0  # 60 mm up on one of 15 keypoints: 4 mm on average
    pred = pred @ _ry(theta).T + shift
    assert M.mpjpe(pred, true) == pytest.approx(4.0, abs=1e-8)
    assert M.mpjpe_root_relative(pred, true) == pytest.approx(4.0, abs=1e-8)
    # the pelvis moved up by 60 mm: root-relative, every other keypoint is 60 mm low -> 14 * 60 / 15
    pred2 = true.copy()
    pred2[:, M.PELVIS, 1] += 60.0
    assert M.mpjpe_root_relative(pred2, true) == pytest.approx(56.0, abs=1e-8)
    assert M.mpjpe(pred2, true) == pytest.approx(4.0, abs=1e-8)


def test_up_axis_z():
    true = _sequence(seed=5)[:, :, [0, 2, 1]]  # now Z is up
    pred = true.copy()
    pred[:, 3, 2] += 45.0
    c, s = math.cos(0.3), math.sin(0.3)
    rot = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    pred = pred @ rot.T + [10.0, 20.0, 0.0]
    assert M.mpjpe(pred, true, up=2) == pytest.approx(3.0, abs=1e-8)
    assert M.mpjpe(pred, true, up=1) > 50.0


def test_pa_mpjpe_similarity_per_frame():
    rng = np.random.default_rng(6)
    true = _sequence(F=30, seed=7)
    pred = np.empty_like(true)
    for f in range(len(true)):
        R = Rotation.random(random_state=rng).as_matrix()
        s = rng.uniform(0.5, 2.0)
        pred[f] = s * true[f] @ R.T + rng.normal(scale=1000.0, size=3)
    assert M.pa_mpjpe(pred, true) == pytest.approx(0.0, abs=1e-6)
    assert M.mpjpe(pred, true) > 100.0
    # a mirror image is not a similarity: no reflection allowed
    mirrored = true * [-1.0, 1.0, 1.0]
    assert M.pa_mpjpe(mirrored, true) > 10.0


def test_procrustes_is_optimal_against_explicit_minimisation():
    rng = np.random.default_rng(8)
    true = _sequence(F=3, seed=9)
    pred = true * [-1.0, 1.0, 1.0] + rng.normal(scale=80.0, size=true.shape)  # needs no-reflection care
    closed = M.procrustes_align(pred, true)
    for f in range(3):
        p, q = pred[f], true[f]

        def cost(x, p=p, q=q):
            R = Rotation.from_rotvec(x[:3]).as_matrix()
            return float(((math.exp(x[3]) * p @ R.T + x[4:] - q) ** 2).sum())

        best = math.inf
        for _ in range(20):
            x0 = np.concatenate([Rotation.random(random_state=rng).as_rotvec(), [0.0], q.mean(0) - p.mean(0)])
            best = min(best, minimize(cost, x0, method="BFGS", options={"gtol": 1e-10}).fun)
        ours = float(((closed[f] - q) ** 2).sum())
        assert ours <= best * (1 + 1e-6)
        assert ours == pytest.approx(best, rel=1e-4)


def test_acceleration_error():
    F = 40
    t = np.arange(F, dtype=float)[:, None, None]
    rng = np.random.default_rng(10)
    true = STAND[None] + rng.normal(scale=5.0, size=(1, 15, 3)) * t + [0.0, 0.0, 15.0] * t
    pred = STAND[None] + rng.normal(scale=5.0, size=(1, 15, 3)) * t  # another constant velocity
    assert M.acceleration_error(pred, true) == pytest.approx(0.0, abs=1e-9)
    # a known quadratic: 0.5 * 3 mm/frame^2 * t^2 upwards on every keypoint, seen from a turned camera
    true = _sequence(F=F, seed=11)
    quad = true + 0.5 * 3.0 * t ** 2 * np.array([0.0, 1.0, 0.0])
    pred = quad @ _ry(2.0).T + [400.0, 0.0, -90.0]
    assert M.acceleration_error(pred, true) == pytest.approx(3.0, abs=1e-7)
    # a frame missing in pred skips the three triplets touching it, a NaN at the end one more
    pred[10, 4, 0] = np.nan
    true[F - 1, 0, 2] = np.nan
    assert M.acceleration_triplets(pred, true).sum() == (F - 2) - 3 - 1
    assert M.acceleration_error(pred, true) == pytest.approx(3.0, abs=1e-7)


def _feet_sequence(v: float, F: int = 40) -> np.ndarray:
    """Left foot on the floor sliding along +X at ``v`` mm/frame for frames 0-19, then lifted to 300 mm
    (and moving fast); the right leg raised throughout."""
    pts = np.repeat(STAND[None], F, axis=0)
    la, ra = KP["left_ankle"], KP["right_ankle"]
    pts[:, la, 0] += v * np.arange(F)
    pts[20:, la, 1] = 300.0
    pts[20:, la, 0] += 40.0 * np.arange(F - 20)
    pts[:, ra, 1] = 400.0
    pts[:, KP["right_knee"], 1] = 650.0
    return pts


def test_foot_skate_counts_planted_feet_only():
    v = 7.0
    pts = _feet_sequence(v)
    assert M.foot_skate(pts) == pytest.approx(v, abs=1e-9)
    slides = M.foot_slides(pts)
    assert np.isfinite(slides[:, 0]).sum() == 19 and not np.isfinite(slides[:, 1]).any()
    # given contacts: all down -> lifted frames' motion counts too
    everywhere = np.ones((len(pts), 2), dtype=bool)
    assert M.foot_skate(pts, contacts=everywhere) > v
    assert math.isnan(M.foot_skate(pts, contacts=np.zeros((len(pts), 2), dtype=bool)))
    # contacts with an explicit small height tolerance still find the planted foot
    assert M.foot_skate(pts, height_tol=1.0) == pytest.approx(v, abs=1e-9)


def test_leg_length():
    by_hand = np.linalg.norm(STAND[9] - STAND[11]) + np.linalg.norm(STAND[11] - STAND[13])
    assert M.leg_length(np.repeat(STAND[None], 3, axis=0)) == pytest.approx(by_hand, rel=1e-12)


def test_foot_contacts_height_speed_and_units():
    fps = 30.0
    slow = _feet_sequence(5.0)  # 150 mm/s < 0.5 leg lengths/s (~425 mm/s)
    c = M.foot_contacts(slow, fps)
    assert c[:20, 0].all() and not c[21:, 0].any() and not c[:, 1].any()
    fast = _feet_sequence(30.0)  # 900 mm/s: sliding, not in contact
    assert not M.foot_contacts(fast, fps)[:, 0].any()
    # in metres, the relative defaults give the same answer
    np.testing.assert_array_equal(M.foot_contacts(slow / 1000.0, fps), c)
    # explicit tolerances in the points' unit
    assert M.foot_contacts(fast, fps, speed_tol=1000.0)[:20, 0].all()
    # a missing frame has no contact and its neighbours use one-sided differences
    gap = slow.copy()
    gap[5] = np.nan
    cg = M.foot_contacts(gap, fps)
    assert not cg[5].any() and cg[[4, 6], 0].all()
    np.testing.assert_allclose(M.horizontal_speed(gap, fps)[[4, 6], 0], 150.0)


def test_nan_frames_excluded_and_counted():
    true = _sequence(F=50, seed=12)
    rng = np.random.default_rng(13)
    pred = true @ _ry(0.5).T + rng.normal(scale=20.0, size=true.shape)
    pred[[3, 17], 2, 1] = np.nan
    true[[17, 30, 31], 0, 0] = np.nan
    ok = np.ones(50, dtype=bool)
    ok[[3, 17, 30, 31]] = False
    s = M.summarise(pred, true, fps=30.0)
    assert (s["frames"], s["valid_frames"], s["excluded_frames"]) == (50, 46, 4)
    assert s["mpjpe_mm"] == pytest.approx(M.mpjpe(pred[ok], true[ok]), rel=1e-12)
    assert s["pa_mpjpe_mm"] == pytest.approx(M.pa_mpjpe(pred[ok], true[ok]), rel=1e-12)
    assert s["mpjpe_root_relative_mm"] == pytest.approx(M.mpjpe_root_relative(pred[ok], true[ok]), rel=1e-12)
    assert s["yaw_deg"] == pytest.approx(-math.degrees(0.5), abs=1.0)
    assert s["acceleration_triplets"] == 48 - 3 - 3 - 4  # triplets touching 3; 17; 30 or 31
    assert np.isfinite(M.mpjpe(pred, true))
    json.dumps(s, allow_nan=False)
    empty = M.summarise(np.full((4, 15, 3), np.nan), true[:4], fps=30.0)
    assert empty["valid_frames"] == 0 and empty["mpjpe_mm"] is None
    json.dumps(empty, allow_nan=False)


def test_summary_of_a_sequence_with_feet():
    true = _feet_sequence(0.0)
    pred = _feet_sequence(6.0)
    s = M.summarise(pred, true, fps=30.0)
    assert s["true_foot_skate_mm_per_frame"] == pytest.approx(0.0, abs=1e-12)
    assert s["foot_skate_true_contacts_pairs"] == 19
    assert s["foot_skate_mm_per_frame"] == pytest.approx(6.0, abs=1e-9)


@pytest.mark.parametrize("bad", [np.zeros((5, 14, 3)), np.zeros((15, 3)), np.zeros((5, 15, 2))])
def test_bad_shapes(bad):
    with pytest.raises(ValueError, match="15, 3"):
        M.mpjpe(bad, bad)
    with pytest.raises(ValueError):
        M.foot_contacts(bad, 30.0)


def test_bad_arguments():
    x = _sequence(F=5)
    with pytest.raises(ValueError, match="one shape"):
        M.mpjpe(x, x[:4])
    with pytest.raises(ValueError, match="up"):
        M.mpjpe(x, x, up=3)
    with pytest.raises(ValueError, match="fps"):
        M.foot_contacts(x, 0.0)
    with pytest.raises(ValueError, match="contacts"):
        M.foot_skate(x, contacts=np.ones((4, 2), dtype=bool))


def test_library_bound_against_brute_force_and_exact_copies():
    rng = np.random.default_rng(21)
    library = _sequence(F=40, seed=22) / 56.44  # another unit: the similarity absorbs it
    library[5, 3] = np.nan  # a broken library frame is never chosen
    true = _sequence(F=6, seed=23)
    true[2] = 2.0 * library[17] @ Rotation.random(random_state=rng).as_matrix().T + [300.0, 0.0, -50.0]
    true[4, 0] = np.nan
    got = M.library_bound(library, true, chunk=7)  # chunks that do not divide the library
    assert got[2] == pytest.approx(0.0, abs=1e-6)  # an exact (similar) copy of library frame 17
    assert np.isnan(got[4])
    ok = np.isfinite(library).all(axis=(1, 2))
    for f in (0, 1, 3, 5):
        brute = min(M.pa_mpjpe(library[j][None], true[f][None]) for j in np.flatnonzero(ok))
        assert got[f] == pytest.approx(brute, rel=1e-9)
        assert got[f] > 1.0
    with pytest.raises(ValueError):
        M.library_bound(library[:, :14], true)
