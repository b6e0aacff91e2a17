"""Salient points: frame-difference silhouette, optical flow, greedy non-maximum suppression."""

from __future__ import annotations

import numpy as np
import pytest

from vidstyle.errors import InputError
from vidstyle.features.salient import (
    SalientParams,
    frame_points,
    frame_points_numpy,
    salient_points,
    select_points,
    silhouette,
)


def moving_disc(T=12, H=60, W=80, speed=3, radius=9):
    t, r, c = np.meshgrid(np.arange(T), np.arange(H), np.arange(W), indexing="ij")
    inside = (r - 30) ** 2 + (c - 15 - speed * t) ** 2 <= radius**2
    rng = np.random.default_rng(0)
    texture = 0.15 * rng.random((H, W))  # moves with the disc, so the flow inside it is well defined
    frames = np.full((T, H, W), 0.2, dtype=np.float32)
    for k in range(T):
        frames[k] = np.where(inside[k], 0.7 + np.roll(texture, speed * k, axis=1), 0.2)
    return frames, inside


def test_silhouette_is_the_thresholded_difference_of_next_and_previous():
    rng = np.random.default_rng(1)
    f = rng.random((5, 6, 7)).astype(np.float32)
    assert np.array_equal(silhouette(f, 2, 0.3), np.abs(f[3] - f[1]) > 0.3)
    assert np.array_equal(silhouette(f, 0, 0.3), np.abs(f[1] - f[0]) > 0.3)  # one-sided at the ends
    assert np.array_equal(silhouette(f, 4, 0.3), np.abs(f[4] - f[3]) > 0.3)
    assert not silhouette(f[:1], 0, 0.0).any()


def greedy_reference(score, n, min_distance):
    H, W = score.shape
    cand = [(-score[r, c], r * W + c, r, c) for r in range(H) for c in range(W) if np.isfinite(score[r, c])]
    cand.sort()
    out = []
    for _, _, r, c in cand:
        if len(out) == n:
            break
        if all((r - a) ** 2 + (c - b) ** 2 >= min_distance**2 for a, b in out):
            out.append((r, c))
    return np.array(out, dtype=np.int64).reshape(-1, 2)


@pytest.mark.parametrize("min_distance", [0.0, 1.0, 2.5, 5.0, 7.3])
def test_select_points_equals_brute_force_greedy(min_distance):
    rng = np.random.default_rng(2)
    for trial in range(5):
        score = rng.integers(0, 6, size=(23, 31)).astype(np.float32)  # many ties
        score[rng.random(score.shape) < 0.4] = -np.inf
        got = select_points(score, 12, min_distance)
        assert np.array_equal(got, greedy_reference(score, 12, min_distance)), (trial, min_distance)


def test_select_points_respects_distance_and_count():
    rng = np.random.default_rng(3)
    score = rng.random((50, 50)).astype(np.float32)
    pts = select_points(score, 10, 6.0)
    assert len(pts) == 10
    d = np.sqrt(((pts[:, None] - pts[None]) ** 2).sum(-1)) + np.eye(10) * 100
    assert d.min() >= 6.0
    assert len(select_points(np.full((4, 4), -np.inf, dtype=np.float32), 10, 1.0)) == 0


@pytest.mark.parametrize("flow", ["dis", "farneback"])
def test_points_lie_on_the_moving_silhouette(flow):
    frames, _ = moving_disc()
    p = SalientParams(n_points=10, threshold=0.05, min_distance=4.0, flow=flow)
    pts = salient_points(frames, p)
    assert pts.dtype == np.int32 and pts.shape[1] == 3
    counts = np.bincount(pts[:, 0], minlength=len(frames))
    assert counts.max() <= 10 and counts[1:-1].min() >= 5
    for t, r, c in pts:
        assert silhouette(frames, t, 0.05)[r, c]
    # per frame: sorted by frame, and at least min_distance apart
    assert np.all(np.diff(pts[:, 0]) >= 0)
    for t in np.unique(pts[:, 0]):
        q = pts[pts[:, 0] == t, 1:].astype(float)
        d = np.sqrt(((q[:, None] - q[None]) ** 2).sum(-1)) + np.eye(len(q)) * 100
        assert d.min() >= 4.0
    assert np.array_equal(pts, salient_points(frames, p))  # deterministic


def test_static_and_single_frame_videos_have_no_points():
    frames = np.full((6, 20, 20), 0.5, dtype=np.float32)
    assert salient_points(frames).shape == (0, 3)
    assert salient_points(frames[:1]).shape == (0, 3)


def test_bad_parameters():
    with pytest.raises(InputError, match="flow"):
        SalientParams(flow="lucas-kanade")
    with pytest.raises(InputError, match="n_points"):
        SalientParams(n_points=-1)
    with pytest.raises(InputError, match="frames"):
        salient_points(np.zeros((3, 4)))


def _flow_magnitude(a, b, flow, dis=[]):
    """|flow| of frame a towards b straight from OpenCV (the reference the selection must rank by). A fresh
    DIS object per frame pair, as in the library (a reused one carries state from call to call)."""
    import cv2

    if flow == "farneback":
        f = cv2.calcOpticalFlowFarneback(a, b, None, 0.5, 3, 15, 3, 5, 1.2, 0)
    else:
        f = cv2.DISOpticalFlow_create(cv2.DISOPTICAL_FLOW_PRESET_FAST).calc(a, b, None)
    return np.hypot(f[..., 0], f[..., 1])


@pytest.mark.parametrize("flow", ["dis", "farneback"])
def test_points_are_the_largest_flow_silhouette_pixels(flow):
    """Every frame's points are exactly the greedy choice of largest flow magnitude among silhouette
    pixels, with the flow computed independently by OpenCV."""
    frames, _ = moving_disc()
    p = SalientParams(n_points=10, threshold=0.05, min_distance=4.0, flow=flow)
    pts = salient_points(frames, p)
    import cv2

    u8 = [np.clip(np.rint(f * 255), 0, 255).astype(np.uint8) for f in frames]
    T = len(frames)
    dis = [cv2.DISOpticalFlow_create(cv2.DISOPTICAL_FLOW_PRESET_FAST)]
    for t in range(T):
        mag = _flow_magnitude(u8[t], u8[t + 1] if t < T - 1 else u8[t - 1], flow, dis)
        score = np.where(silhouette(frames, t, 0.05) & (mag > p.min_flow), mag, -np.inf)
        want = greedy_reference(score, 10, 4.0)
        got = pts[pts[:, 0] == t, 1:]
        assert np.array_equal(got, want), t
        if len(got):  # and no silhouette pixel left out has more flow than the weakest chosen one,
            # unless it lies within min_distance of a stronger chosen point
            weakest = score[got[:, 0], got[:, 1]].min()
            rr, cc = np.nonzero(score > weakest)
            for r, c in zip(rr, cc):
                assert (((got - [r, c]) ** 2).sum(1) < 16.0).any()


def test_fast_mover_wins_over_slow_mover():
    """Two textured discs, one moving 4 px/frame and one 1 px/frame: the few salient points go to the fast one."""
    T, H, W = 10, 60, 100
    rng = np.random.default_rng(4)
    tex = 0.2 * rng.random((H, W))
    frames = np.full((T, H, W), 0.2, dtype=np.float32)
    t, r, c = np.meshgrid(np.arange(T), np.arange(H), np.arange(W), indexing="ij")
    fast = (r - 20) ** 2 + (c - 10 - 4 * t) ** 2 <= 64
    slow = (r - 45) ** 2 + (c - 60 - 1 * t) ** 2 <= 64
    for k in range(T):
        frames[k] = np.where(fast[k], 0.6 + np.roll(tex, 4 * k, axis=1), frames[k])
        frames[k] = np.where(slow[k], 0.6 + np.roll(tex, k, axis=1), frames[k])
    pts = salient_points(frames, SalientParams(n_points=3, threshold=0.05, min_distance=2.0, flow="farneback"))
    inner = pts[(pts[:, 0] > 0) & (pts[:, 0] < T - 1)]
    assert len(inner) >= 3 * (T - 2) - 2
    assert (inner[:, 1] < 32).mean() >= 0.9  # rows of the fast disc (centre row 20, radius 8, plus flow spread)


def test_compiled_frame_points_are_the_numpy_reference(rng):
    """salient_points scores and selects a frame's points in one compiled pass (frame_points): the same
    points in the same order as the numpy reference (the float32 magnitude on the silhouette, then
    select_points), on random flows with exact ties, infinite and NaN flow, empty silhouettes, one-pixel
    frames and min_flow values that float32 rounds (numpy compares a float32 array in float32)."""
    for trial in range(300):
        H, W = (int(x) for x in rng.integers(1, 40, 2))
        mask = rng.random((H, W)) < rng.random()
        flow = rng.normal(size=(H, W, 2)) * rng.choice([0.1, 1.0, 5.0])
        if trial % 3 == 0:
            flow = np.round(flow)  # many exact ties
        if trial % 7 == 0:
            flow[rng.random((H, W)) < 0.1] = np.inf
        if trial % 11 == 0:
            flow[rng.random((H, W)) < 0.1] = np.nan
        flow = flow.astype(np.float32)
        p = SalientParams(n_points=int(rng.integers(1, 15)), min_distance=float(rng.choice([0.0, 1.0, 2.5, 5.0])),
                          min_flow=float(rng.choice([0.0, 0.05, 1.0, 0.1])))
        got, want = frame_points(mask, flow, p), frame_points_numpy(mask, flow, p)
        assert got.dtype == want.dtype and got.tobytes() == want.tobytes(), trial
