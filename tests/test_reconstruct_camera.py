"""The reconstruction's camera from 2D keypoints (issue 29): poses projected with a known K and known
translations, then recovered (exactly without noise, within tolerance with noise and missing keypoints),
and the focal length recovered when the performer comes close (the default when the curve is flat)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from vidstyle.reconstruct import camera as C

# a standing performer in metres, camera axes (x right, y down, z forward), pelvis at the origin
STAND = np.array([
    (0, -0.80, 0), (0, -0.55, 0), (0, 0.0, 0),
    (0.18, -0.50, 0), (-0.18, -0.50, 0), (0.20, -0.20, 0.05), (-0.20, -0.20, 0.05), (0.21, 0.07, 0.1),
    (-0.21, 0.07, 0.1), (0.10, 0.02, 0), (-0.10, 0.02, 0), (0.11, 0.45, 0.03), (-0.11, 0.45, 0.03),
    (0.11, 0.87, 0), (-0.11, 0.87, 0),
])
W, H = 1920, 1080


def _K(f, cx=(W - 1) / 2, cy=(H - 1) / 2):
    return np.array([[f, 0.0, cx], [0.0, f, cy], [0.0, 0.0, 1.0]])


def _poses(F, rng, flat=False):
    """F randomly turned (mostly about the vertical) and slightly bent copies of the performer."""
    out = np.empty((F, 15, 3))
    for i in range(F):
        R = Rotation.from_euler("yxz", [rng.uniform(-np.pi, np.pi), rng.uniform(-0.3, 0.3),
                                        rng.uniform(-0.2, 0.2)]).as_matrix()
        out[i] = (STAND + rng.normal(scale=0.03, size=STAND.shape)) @ R.T
    if flat:
        out[..., 2] = 0.0
    return out


def _project(P, K):
    h = P @ K.T
    return h[..., :2] / h[..., 2:3]


def _scene(F, rng, depth=(2.0, 8.0), f=1400.0, flat=False):
    X = _poses(F, rng, flat)
    z = rng.uniform(*depth, size=F)
    t = np.stack([rng.uniform(-0.4, 0.4, F) * z, rng.uniform(-0.1, 0.2, F) * z, z], axis=1)
    K = _K(f)
    uv = _project(X + t[:, None], K)
    w = rng.uniform(0.3, 1.0, size=(F, 15))
    return X, t, uv, w, K


def test_default_intrinsics():
    K = C.default_intrinsics(W, H)
    assert K[0, 2] == (W - 1) / 2 and K[1, 2] == (H - 1) / 2 and K[0, 0] == K[1, 1]
    assert math.degrees(2 * math.atan((W / 2) / K[0, 0])) == pytest.approx(60.0)
    # portrait: the same lens, the same focal length
    np.testing.assert_allclose(C.default_intrinsics(H, W)[0, 0], K[0, 0])
    assert C.default_intrinsics(640, 480, fov_deg=90.0)[0, 0] == pytest.approx(320.0)


def test_project_matches_the_pinhole_formula():
    K = _K(1000.0, 300.0, 200.0)
    uv = C.project(np.array([[0.5, -0.25, 2.0], [0.0, 0.0, -1.0]]), K)
    np.testing.assert_allclose(uv[0], [1000.0 * 0.25 + 300.0, 1000.0 * -0.125 + 200.0])
    assert np.isnan(uv[1]).all()


def test_translations_exact_without_noise():
    rng = np.random.default_rng(0)
    X, t, uv, w, K = _scene(50, rng)
    got = C.fit_translations(X, uv, w, K)
    np.testing.assert_allclose(got, t, atol=1e-7)
    np.testing.assert_allclose(C.fit_translation(X[3], uv[3], w[3], K), t[3], atol=1e-7)
    assert np.nanmax(C.reprojection_errors(X, got, uv, K)) < 1e-5


def test_translations_with_missing_keypoints_and_noise():
    rng = np.random.default_rng(1)
    X, t, uv, w, K = _scene(200, rng)
    uv = uv + rng.normal(scale=2.0, size=uv.shape)
    # drop some keypoints: NaN rows, zero confidence, and frames left with 3 keypoints
    drop = rng.random((200, 15)) < 0.2
    uv[drop] = np.nan
    w[rng.random((200, 15)) < 0.1] = 0.0
    few = np.arange(190, 200)
    uv[few, 3:] = np.nan
    got = C.fit_translations(X, uv, w, K)
    assert np.isnan(got[few]).all()
    good = np.ones(200, dtype=bool)
    good[few] = False
    enough = ((np.isfinite(uv).all(-1) & (w > 0)).sum(1) >= 4) & good
    assert enough.sum() > 150
    assert np.isnan(got[~enough]).all()
    rel = np.linalg.norm(got[enough] - t[enough], axis=1) / t[enough, 2]
    assert np.median(rel) < 0.01 and rel.max() < 0.06
    # the fit is at least as good as the truth in its own criterion
    err_fit = np.nansum(w * C.reprojection_errors(X, np.where(np.isnan(got), 0, got), uv, K) ** 2, axis=1)
    err_true = np.nansum(w * C.reprojection_errors(X, t, uv, K) ** 2, axis=1)
    assert np.all(err_fit[enough] <= err_true[enough] * (1 + 1e-9))


def test_translation_with_an_off_centre_principal_point_and_skew():
    rng = np.random.default_rng(2)
    X = _poses(10, rng)
    t = np.stack([rng.uniform(-1, 1, 10), rng.uniform(-0.5, 0.5, 10), rng.uniform(3, 6, 10)], axis=1)
    K = np.array([[900.0, 3.0, 700.0], [0.0, 950.0, 300.0], [0.0, 0.0, 1.0]])
    uv = _project(X + t[:, None], K)
    np.testing.assert_allclose(C.fit_translations(X, uv, np.ones((10, 15)), K), t, atol=1e-7)


def test_estimate_focal_recovers_a_close_performers_camera():
    rng = np.random.default_rng(3)
    f_true = 1400.0  # ~69 degrees across 1920 px; the default is 60 degrees (~1663 px)
    X, _, uv, w, _ = _scene(120, rng, depth=(1.5, 8.0), f=f_true)
    uv = uv + rng.normal(scale=1.0, size=uv.shape)
    f = C.estimate_focal(X, uv, w, W, H)
    assert f == pytest.approx(f_true, rel=0.03)
    default = C.focal_from_fov(W, H, 60.0)
    assert abs(f - default) > 100.0


def test_estimate_focal_returns_the_default_on_a_flat_curve():
    rng = np.random.default_rng(4)
    default = C.default_intrinsics(W, H)[0, 0]
    # a flat pose facing the camera: every focal length fits exactly
    X, _, uv, w, _ = _scene(40, rng, f=1400.0, flat=True)
    curve = C.focal_curve(X, uv, w, W, H, np.array([800.0, 1400.0, 3000.0]))
    assert np.all(curve < 1e-6)
    assert C.estimate_focal(X, uv, w, W, H) == pytest.approx(default)
    # far away with pixel noise: perspective is lost in the noise
    X, _, uv, w, _ = _scene(40, rng, depth=(40.0, 60.0), f=1400.0)
    uv = uv + rng.normal(scale=1.0, size=uv.shape)
    assert C.estimate_focal(X, uv, w, W, H) == pytest.approx(default)


def test_bad_shapes():
    X = np.zeros((3, 15, 3))
    K = _K(1000.0)
    with pytest.raises(ValueError, match="uv"):
        C.fit_translations(X, np.zeros((3, 14, 2)), np.ones((3, 15)), K)
    with pytest.raises(ValueError, match="w must"):
        C.fit_translations(X, np.zeros((3, 15, 2)), np.ones((3, 14)), K)
    with pytest.raises(ValueError, match="X must"):
        C.fit_translations(np.zeros((15, 3)), np.zeros((3, 15, 2)), np.ones((3, 15)), K)
    with pytest.raises(ValueError, match="K must"):
        C.fit_translations(X, np.zeros((3, 15, 2)), np.ones((3, 15)), np.eye(2))
    with pytest.raises(ValueError, match="one frame"):
        C.fit_translation(X, np.zeros((15, 2)), np.ones(15), K)
    with pytest.raises(ValueError, match="fov"):
        C.default_intrinsics(W, H, fov_deg=180.0)


def test_estimate_focal_subsamples_long_videos():
    rng = np.random.default_rng(5)
    X, _, uv, w, _ = _scene(300, rng, depth=(1.5, 8.0), f=1000.0)
    uv = uv + rng.normal(scale=1.0, size=uv.shape)
    assert C.estimate_focal(X, uv, w, W, H, max_frames=60) == pytest.approx(1000.0, rel=0.05)
    # no frame with enough keypoints: the default
    assert C.estimate_focal(X, np.full_like(uv, np.nan), w, W, H) == pytest.approx(C.focal_from_fov(W, H, 60.0))
