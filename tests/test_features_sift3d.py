"""3D SIFT, thesis variant: gradients and angles on analytic volumes, bin geometry, dominant orientation
of moving edges, rotation invariance about the time axis, agreement with the naive per-point loop."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from vidstyle.errors import InputError
from vidstyle.features._reference import describe_thesis_loop
from vidstyle.features.sift3d import (
    Sift3DParams,
    bin_solid_angles,
    describe,
    direction,
    dominant_orientation,
    gradient_angles,
    gradients,
    orientation_weights,
    rotation_matrix,
)


def grid(T, H, W):
    return np.meshgrid(np.arange(T), np.arange(H), np.arange(W), indexing="ij")


def blobs(T=25, H=121, W=121):
    """Two smooth blobs, one moving right and one moving up: clear, distinct gradient modes."""
    t, r, c = grid(T, H, W)
    v = np.exp(-((r - 60) ** 2 / (2 * 10**2) + (c - 45 - 1.0 * t) ** 2 / (2 * 5**2)))
    v += 0.6 * np.exp(-((r - 75 + 0.5 * t) ** 2 + (c - 70) ** 2) / (2 * 7**2))
    return v.astype(np.float32)


BLOB_POINTS = np.array([[12, 60, 50], [12, 68, 62], [12, 52, 55], [12, 72, 66]])


# --- gradients and angles ----------------------------------------------------------------------------


def test_gradient_of_linear_ramp_is_exact_everywhere_including_borders():
    t, r, c = grid(6, 7, 8)
    vol = 3.0 * c - 2.0 * r + 5.0 * t  # y is up, so d/dy = +2 per row upwards
    gx, gy, gt = gradients(vol)
    # raw central differences (not halved), one-sided x 2 on the border planes: same value everywhere
    assert np.array_equal(gx, np.full(vol.shape, 6.0))
    assert np.array_equal(gy, np.full(vol.shape, 4.0))
    assert np.array_equal(gt, np.full(vol.shape, 10.0))


def test_smoothing_keeps_linear_ramp_gradient_inside():
    t, r, c = grid(12, 14, 16)
    vol = (0.5 * c + 0.25 * r - 0.75 * t).astype(np.float32)
    gx, gy, gt = gradients(vol, smooth_sigma=1.0)
    inner = (slice(4, -4),) * 3
    np.testing.assert_allclose(gx[inner], 1.0, atol=1e-4)
    np.testing.assert_allclose(gy[inner], -0.5, atol=1e-4)
    np.testing.assert_allclose(gt[inner], -1.5, atol=1e-4)


def test_gradient_of_a_quadratic_is_the_central_difference():
    t, r, c = grid(5, 6, 7)
    vol = (c**2 + r * c + t**2).astype(np.float64)
    gx, gy, gt = gradients(vol)
    # f(c+1) - f(c-1) = 4c + 2r for the interior; y up negates the row derivative 2c
    assert np.array_equal(gx[:, :, 1:-1], (4 * c + 2 * r)[:, :, 1:-1])
    assert np.array_equal(gy[:, 1:-1], -(2 * c)[:, 1:-1])
    assert np.array_equal(gt[1:-1], (4 * t)[1:-1])


@pytest.mark.parametrize(
    "g, theta, phi",
    [
        ((1, 0, 0), 0.0, 0.0),
        ((0, 1, 0), math.pi / 2, 0.0),
        ((0, 0, 1), 0.0, math.pi / 2),
        ((-1, -1, math.sqrt(2)), -3 * math.pi / 4, math.pi / 4),
        ((0, -2, -2), -math.pi / 2, -math.pi / 4),
    ],
)
def test_gradient_angles(g, theta, phi):
    m, th, ph = gradient_angles(*(np.array([v], dtype=np.float64) for v in g))
    assert m[0] == pytest.approx(math.sqrt(sum(v * v for v in g)))
    assert th[0] == pytest.approx(theta)
    assert ph[0] == pytest.approx(phi)


# --- bin geometry --------------------------------------------------------------------------------------


def test_solid_angles_sum_to_sphere_and_match_quadrature():
    om = bin_solid_angles(8, 4)
    assert om.sum() == pytest.approx(4 * math.pi)
    # midpoint quadrature of cos(phi) dphi dtheta over each bin (phi is the elevation)
    phis = np.linspace(-math.pi / 2, math.pi / 2, 4001)
    mid = (phis[:-1] + phis[1:]) / 2
    band = [
        np.sum(np.cos(mid[(mid >= lo) & (mid < lo + math.pi / 4)])) * (phis[1] - phis[0])
        for lo in (-math.pi / 2, -math.pi / 4, 0, math.pi / 4)
    ]
    np.testing.assert_allclose(om[0], np.array(band) * (2 * math.pi / 8), rtol=1e-5)
    assert om[0, 0] < om[0, 1]  # polar bins are the small ones


def test_solid_angle_normalisation_equalises_uniform_directions():
    rng = np.random.default_rng(0)
    v = rng.standard_normal((200_000, 3))
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    th = np.arctan2(v[:, 1], v[:, 0])
    ph = np.arctan2(v[:, 2], np.hypot(v[:, 0], v[:, 1]))
    h = orientation_weights(th, ph, 8, 4).sum(0)
    assert h.max() / h.min() < 1.2
    raw = (h.reshape(8, 4) * bin_solid_angles(8, 4)).reshape(-1)  # without the 1/omega
    assert raw.max() / raw.min() > 2


def test_orientation_weights_are_bilinear_and_wrap():
    # exactly on a bin centre: all weight (1/omega) in that bin
    om = bin_solid_angles(8, 4)
    w = orientation_weights(np.array([-math.pi + math.pi / 8]), np.array([-math.pi / 2 + math.pi / 8]))
    assert w.reshape(8, 4)[0, 0] == pytest.approx(1 / om[0, 0])
    assert np.count_nonzero(w > 1e-9) == 1
    # theta = pi - tiny lies between the last and the first theta bin: split half/half (wrap)
    w = orientation_weights(np.array([math.pi - 1e-9]), np.array([math.pi / 8]))
    w = w.reshape(8, 4) * om
    assert w[7, 2] == pytest.approx(0.5, abs=1e-6) and w[0, 2] == pytest.approx(0.5, abs=1e-6)
    # beyond the polar bin centre everything goes to the polar bin
    w = orientation_weights(np.array([0.3]), np.array([1.5])).reshape(8, 4) * om
    assert w[:, 3].sum() == pytest.approx(1.0) and w[:, :3].sum() == 0


def test_rotation_matrix_maps_x_to_the_direction():
    rng = np.random.default_rng(1)
    th, ph = rng.uniform(-math.pi, math.pi, 20), rng.uniform(-1.5, 1.5, 20)
    M = rotation_matrix(th, ph)
    np.testing.assert_allclose(M[:, :, 0], direction(th, ph), atol=1e-12)
    np.testing.assert_allclose(M @ M.transpose(0, 2, 1), np.broadcast_to(np.eye(3), M.shape), atol=1e-12)
    np.testing.assert_allclose(np.linalg.det(M), 1.0)


# --- dominant orientation -------------------------------------------------------------------------------


@pytest.mark.parametrize("smooth", [0.0, 1.0])
def test_edge_moving_right_at_one_pixel_per_frame(smooth):
    # bright on the right of an edge moving right: Lx > 0, and each pixel darkens as the edge passes,
    # Lt = -Lx exactly for a speed of 1 px/frame, whatever the edge profile: direction (1, 0, -1)/sqrt 2
    t, _, c = grid(21, 40, 60)
    vol = 1 / (1 + np.exp(-(c - 20 - t) / 1.5))
    th, ph = dominant_orientation(vol, np.array([[10, 20, 30], [10, 5, 29]]), smooth_sigma=smooth)
    np.testing.assert_allclose(th, 0.0, atol=1e-4)
    np.testing.assert_allclose(ph, -math.pi / 4, atol=1e-4)


def test_ramp_edge_moving_up_at_two_pixels_per_frame():
    # a wide linear ramp (bright below) moving up (towards row 0) at 2 px/frame, sampled inside the ramp:
    # (y is up), each pixel brightens: Lt = +2 -> theta = -pi/2, phi = atan(2)
    t, r, _ = grid(21, 80, 50)
    vol = np.clip((r - 60 + 2 * t) / 40.0, 0, 1)
    th, ph = dominant_orientation(vol, np.array([[10, 60, 25]]), smooth_sigma=0.0)
    assert th[0] == pytest.approx(-math.pi / 2, abs=1e-4)
    assert ph[0] == pytest.approx(math.atan(2.0), abs=1e-4)


def test_static_diagonal_edge():
    _, r, c = grid(9, 40, 40)
    vol = np.tanh(((c - 20) - (r - 20)) / 3.0)  # brighter to the right and upwards (rows decrease)
    th, ph = dominant_orientation(vol, np.array([[4, 20, 20]]))
    assert th[0] == pytest.approx(math.pi / 4, abs=1e-4)
    assert ph[0] == pytest.approx(0.0, abs=1e-4)


# --- descriptor -----------------------------------------------------------------------------------------


def rot90_points(pts, H, W, k):
    p = pts.copy()
    for _ in range(k):  # np.rot90 (counter-clockwise): (r, c) -> (W - 1 - c, r); the new width is H
        p = np.stack([p[:, 0], W - 1 - p[:, 2], p[:, 1]], axis=1)
        H, W = W, H
    return p


@pytest.mark.parametrize("k", [1, 2, 3])
def test_rotation_by_quarter_turns_gives_the_same_descriptor(k):
    vol = blobs(H=121, W=131)
    _, H, W = vol.shape
    rot = np.ascontiguousarray(np.rot90(vol, k=k, axes=(1, 2)))
    a = describe(vol, BLOB_POINTS)
    b = describe(rot, rot90_points(BLOB_POINTS, H, W, k))
    np.testing.assert_allclose(a, b, atol=2e-5)
    # ... which the plain (non-rotated) descriptor does not have
    p = Sift3DParams(rotate=False)
    a0, b0 = describe(vol, BLOB_POINTS, params=p), describe(rot, rot90_points(BLOB_POINTS, H, W, k), params=p)
    assert np.min(np.sum(a0 * b0, axis=1)) < 0.5


@pytest.mark.parametrize("angle", [30.0, 137.0])
def test_rotation_by_arbitrary_angles_with_interpolation(angle):
    vol = blobs()
    _, H, W = vol.shape
    M = cv2.getRotationMatrix2D((60, 60), angle, 1.0)
    rot = np.stack(
        [cv2.warpAffine(f, M, (W, H), flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE) for f in vol]
    )
    xy = np.column_stack([BLOB_POINTS[:, 2], BLOB_POINTS[:, 1], np.ones(len(BLOB_POINTS))]) @ M.T
    pts_r = np.column_stack([BLOB_POINTS[:, 0], np.rint(xy[:, 1]), np.rint(xy[:, 0])]).astype(int)
    sim = np.sum(describe(vol, BLOB_POINTS) * describe(rot, pts_r), axis=1)
    p = Sift3DParams(rotate=False)
    sim0 = np.sum(describe(vol, BLOB_POINTS, params=p) * describe(rot, pts_r, params=p), axis=1)
    assert sim.min() > 0.98  # despite resampling and points rounded to the pixel grid
    assert np.all(sim > sim0 + 0.15)


@pytest.mark.parametrize(
    "kw",
    [
        {},
        {"rotate": False},
        {"n_subregions": 4, "subregion_size": 3},
        {"n_subregions": (1, 2, 3), "subregion_size_t": 2, "smooth_sigma": 0.0},
    ],
)
def test_matches_naive_per_point_loop(kw):
    rng = np.random.default_rng(2)
    vol = rng.random((18, 26, 31)).astype(np.float32)
    pts = np.array([[9, 13, 15], [0, 0, 0], [17, 25, 30], [3, 2, 29], [9, 5, 5], [9, 13, 16]])
    p = Sift3DParams(**kw)
    np.testing.assert_allclose(describe(vol, pts, params=p), describe_thesis_loop(vol, pts, p), atol=2e-5)


def test_shapes_norms_determinism_and_chunking():
    rng = np.random.default_rng(3)
    vol = rng.random((30, 24, 28)).astype(np.float32)
    pts = np.column_stack([rng.integers(0, 30, 40), rng.integers(0, 24, 40), rng.integers(0, 28, 40)])
    a = describe(vol, pts)
    assert a.shape == (40, 256) and a.dtype == np.float32
    np.testing.assert_allclose(np.linalg.norm(a, axis=1), 1.0, atol=1e-5)
    assert np.array_equal(a, describe(vol, pts))
    small = describe(vol, pts, chunk_frames=1, batch_points=3)
    np.testing.assert_allclose(a, small, atol=1e-6)
    assert describe(vol, pts[:5], n_subregions=4).shape == (5, 4 * 4 * 4 * 32)
    assert describe(vol, np.zeros((0, 3), int)).shape == (0, 256)
    assert not describe(np.zeros((5, 9, 9)), [[2, 4, 4]]).any()  # no gradient: all zeros


def test_bad_input():
    vol = np.zeros((4, 5, 6))
    with pytest.raises(InputError, match="volume"):
        describe(np.zeros((4, 5)), [[0, 0, 0]])
    with pytest.raises(InputError, match="points"):
        describe(vol, [[4, 0, 0]])
    with pytest.raises(InputError, match="points"):
        describe(vol, [[0, 0]])
    with pytest.raises(InputError, match="variant"):
        describe(vol, [[0, 0, 0]], variant="sift4d")
    with pytest.raises(InputError, match="n_subregions"):
        Sift3DParams(n_subregions=0)
