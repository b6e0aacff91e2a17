"""2D SIFT ablation descriptor (variant "sift2d"): analytic ramp, rotation invariance, layout, determinism."""

from __future__ import annotations

import numpy as np
import pytest

from vidstyle.errors import InputError
from vidstyle.features.sift2d import Sift2DParams, _dominant
from vidstyle.features.sift2d import describe as describe_2d
from vidstyle.features.sift3d import describe


def ramp(angle: float, size: int = 41, frames: int = 3) -> np.ndarray:
    """Intensity increasing along direction ``angle`` (x = column right, y = up)."""
    r, c = np.mgrid[0:size, 0:size].astype(np.float64)
    x, y = c, -r
    img = 0.01 * (np.cos(angle) * x + np.sin(angle) * y)
    return np.repeat(img[None], frames, axis=0)


def expected_cells(n=4, cell=4.0) -> np.ndarray:
    """Cell weights of a constant gradient, by a plain loop over the sample disc, SIFT-normalised."""
    radius = np.sqrt(2.0) * (n / 2 + 0.5) * cell
    sigma = n * cell / 2
    w = np.zeros((n, n))
    R = int(radius)
    for dr in range(-R, R + 1):
        for dc in range(-R, R + 1):
            if dr * dr + dc * dc > radius * radius:
                continue
            x, y = dc, -dr
            g = np.exp(-(x * x + y * y) / (2 * sigma * sigma))
            ux, uy = x / cell + n / 2 - 0.5, y / cell + n / 2 - 0.5
            for i in range(n):
                for j in range(n):
                    w[i, j] += g * max(0.0, 1 - abs(uy - i)) * max(0.0, 1 - abs(ux - j))
    w /= np.linalg.norm(w)
    w = np.minimum(w, 0.2)
    return w / np.linalg.norm(w)


@pytest.mark.parametrize("angle", [0.0, 0.7, 2.0, -2.5])
def test_ramp_analytic(angle):
    """A linear ramp has one gradient direction and magnitude everywhere. After rotation to the dominant
    orientation every sample falls in orientation bin 0 of its cells, so bin 0 of the 4x4 cells holds the
    SIFT-normalised Gaussian x bilinear cell weights (computed independently by :func:`expected_cells`;
    the dominant orientation is off by at most a degree or so, hence the tolerance) and every other bin 0."""
    vol = ramp(angle)
    d = describe(vol, [[1, 20, 20]], variant="sift2d")
    assert d.shape == (1, 128) and d.dtype == np.float32
    h = d[0].reshape(4, 4, 8)
    np.testing.assert_allclose(h[:, :, 0], expected_cells(), atol=2e-3)
    # the parabola-refined dominant orientation is within 2 degrees (see the test below), which leaks at
    # most 2/45 of a cell's mass (<= 0.27) into bins 1 and 7
    np.testing.assert_allclose(h[:, :, [1, 7]], 0.0, atol=0.012)
    np.testing.assert_allclose(h[:, :, 2:7], 0.0, atol=1e-6)


@pytest.mark.parametrize("angle", [0.3, 1.9, -1.2])
def test_dominant_orientation_of_ramp(angle):
    theta = np.full((1, 50), angle)
    d = _dominant(theta, np.ones((1, 50)))
    # linear spreading + symmetric smoothing + parabolic refinement: within 2 degrees of the truth
    assert abs(np.angle(np.exp(1j * (d[0] - angle)))) < np.deg2rad(2.0)


def test_unrotated_ramp_goes_to_its_bin():
    """Without rotation, a ramp at 90 degrees (gradient up) lands in orientation bin 2 of 8."""
    d = describe_2d(ramp(np.pi / 2), np.array([[1, 20, 20]]), Sift2DParams(rotate=False))[0].reshape(4, 4, 8)
    np.testing.assert_allclose(d[:, :, 2], expected_cells(), atol=1e-5)
    assert np.abs(np.delete(d, 2, axis=2)).max() < 1e-5


@pytest.mark.parametrize("k", [1, 2, 3])
def test_rotation_invariance_90(k):
    """Rotating the frame by 90 degrees (about the point) gives the same descriptor: the sample disc maps
    onto itself and the dominant orientation turns with the image."""
    rng = np.random.default_rng(1)
    img = rng.random((3, 45, 45))
    from scipy.ndimage import gaussian_filter

    img = np.stack([gaussian_filter(f, 2.0) for f in img])
    # a strong asymmetric blob so the dominant orientation is well separated
    r, c = np.mgrid[0:45, 0:45]
    img = img + 0.8 * np.exp(-((r - 16.0) ** 2 + (c - 26.0) ** 2) / 30.0)[None]
    rot = np.stack([np.rot90(f, k) for f in img])
    a = describe(img, [[1, 22, 22]], variant="sift2d")
    b = describe(rot, [[1, 22, 22]], variant="sift2d")
    np.testing.assert_allclose(a, b, atol=2e-3)


def test_determinism_points_order_and_zero_patch():
    rng = np.random.default_rng(0)
    vol = rng.random((5, 30, 40)).astype(np.float32)
    pts = np.array([[0, 5, 5], [4, 29, 39], [2, 15, 20], [2, 0, 0]])
    a = describe(vol, pts, variant="sift2d")
    b = describe(vol, pts[::-1], variant="sift2d")[::-1]
    np.testing.assert_array_equal(a, b)
    n = np.linalg.norm(a, axis=1)
    np.testing.assert_allclose(n, 1.0, atol=1e-5)
    assert (a <= 0.2 / 0.2 + 1e-6).all() and (a >= 0).all()
    z = describe(np.zeros((2, 20, 20)), [[0, 10, 10]], variant="sift2d")
    assert z.shape == (1, 128) and not z.any()
    assert describe(vol, np.zeros((0, 3), int), variant="sift2d").shape == (0, 128)


def test_params_and_errors():
    assert Sift2DParams(n_cells=2, n_bins=4).dim == 16
    d = describe(ramp(0.0), [[1, 20, 20]], variant="sift2d", n_cells=2, n_bins=4)
    assert d.shape == (1, 16)
    with pytest.raises(InputError, match="n_cells"):
        Sift2DParams(n_cells=0)
    with pytest.raises(InputError, match="cell_size"):
        Sift2DParams(cell_size=0)
    with pytest.raises(InputError, match="points"):
        describe(np.zeros((2, 5, 5)), [[2, 0, 0]], variant="sift2d")


def test_extract_features_sift2d():
    from vidstyle.features.extract import extract_features

    rng = np.random.default_rng(0)
    vol = np.zeros((8, 40, 50), np.float32)
    for t in range(8):
        vol[t, 10:25, 5 + 3 * t : 20 + 3 * t] = 0.8
    vol += 0.02 * rng.random(vol.shape).astype(np.float32)
    out = extract_features(vol, variant="sift2d")
    assert out["descriptors"].shape == (len(out["points"]), 128)
    assert out["params"]["variant"] == "sift2d"
    assert out["params"]["descriptor"]["n_cells"] == 4
