"""The static pinhole camera of a video from its 2D keypoints and a 3D pose per frame (issue 29).

Conventions (those of :mod:`vidstyle.render.camera`, OpenCV): camera coordinates have +x to the right
of the image, +y down, +z forward (the viewing direction); the pixel of a camera-frame point ``Y`` is
``(u, v) = (K @ Y)[:2] / (K @ Y)[2]`` with ``u`` the column and ``v`` the row, integer values at pixel
centres, so the image centre of a ``W x H`` image is ``((W - 1) / 2, (H - 1) / 2)``.

Inputs per frame: ``X`` (15, 3), the pose's keypoints already rotated into the camera's axes and known
up to a translation (e.g. root-relative; any unit, the library's), ``uv`` (15, 2) the detected keypoints
in pixels and ``w`` (15,) their confidences (weights >= 0). A keypoint is *used* when ``uv``, ``w`` and
``X`` are finite and ``w > min_confidence``; it then counts with weight ``w``. A frame with fewer than
``min_keypoints`` (default 4) used keypoints gets no translation (NaN).

Translation (:func:`fit_translations`): the ``t`` (3,) minimising the confidence-weighted squared
reprojection error ``sum_i w_i ||pi(K (X_i + t)) - uv_i||^2`` (pixels^2), found from two closed-form
starts, whichever reprojects better:

- weak perspective: in normalised image coordinates ``n = K^-1 (u, v, 1)``, ``n_i ~ s X_i,xy + c``; the
  scale ``s = 1 / Z`` is the weighted least-squares fit of the keypoints' spread about their weighted
  centroids (the ratio of the spreads' RMS if that fit is not positive), the centroid's depth is
  ``Z = 1 / s`` and ``t_xy`` follows from the weighted centroid;
- the algebraic (DLT-like) solution: ``(K_0 - u_i K_2) . (X_i + t) = 0`` and the same for ``v`` are
  linear in ``t`` (``K_j`` the rows of K); their weighted least squares is exact for noise-free data
  (used only when it puts every used keypoint in front of the camera);

then refined by Levenberg-Marquardt on the 3 unknowns, all frames at once, a step being accepted only
when it lowers the cost and keeps every used keypoint in front of the camera (``z > 0``).

Focal length. :func:`default_intrinsics` is the assumption when nothing is known: square pixels, the
principal point at the image centre and a 60-degree field of view across the image's *longer* side (so
a portrait video of the same lens gets the same focal length). Phone main cameras are ~26 mm
equivalent, about 65-70 degrees across a 16:9 frame, less with video stabilisation's crop (~60);
webcams are 60-70 degrees; the project's own renderer (40 degrees vertical) gives 52 degrees across a 4:3
and 66 across a 16:9 frame. A wrong focal length mostly rescales the recovered depth: under weak
perspective only ``f / Z`` is observed.

:func:`estimate_focal` picks the focal length ``f`` (square pixels, centred principal point) minimising
the RMS reprojection error ``sqrt(sum w r^2 / sum w)`` over all used keypoints of all fitted frames,
each frame with its own best translation: a grid of ``grid`` focal lengths, geometrically spaced over
the fields of view ``fov_range`` (degrees across the longer side), then a bounded 1-D search between the
best grid point's neighbours. Only perspective distortion within each pose constrains ``f`` (depth
differences inside the body relative to its distance), so it is weakly observable: well when the
performer comes close to the camera, hardly at all far away, not at all for a flat pose, and any error
of the 3D pose leaks into it. Rule: the default focal length is returned unless the minimum is inside the
searched range (not at its first or last grid point: a focal length pushed to the edge of plausible
lenses says more about the pose's errors than about the lens) and lowers the RMS error below the
default's by more than ``max(min_gain_px, min_gain * rms_default)`` (defaults 0.5 px and 5 %). With
3D poses as inaccurate as a library search gives, expect the default most of the time.
"""

from __future__ import annotations

import math

import numpy as np

from ..formats.keypoints import KEYPOINTS

DEFAULT_FOV_DEG = 60.0
MIN_KEYPOINTS = 4
_N = len(KEYPOINTS)


def focal_from_fov(width: int, height: int, fov_deg: float) -> float:
    """The focal length (pixels) that gives a field of view of ``fov_deg`` degrees across the longer
    side of a ``width x height`` image."""
    if not (width > 0 and height > 0):
        raise ValueError(f"image size must be positive, got {width} x {height}")
    if not 0.0 < fov_deg < 180.0:
        raise ValueError(f"fov_deg must be in (0, 180), got {fov_deg}")
    return 0.5 * max(width, height) / math.tan(math.radians(fov_deg) / 2.0)


def intrinsics_for_focal(width: int, height: int, focal: float) -> np.ndarray:
    """(3, 3) K with focal length ``focal`` (pixels, square pixels) and the principal point at the image
    centre ``((W - 1) / 2, (H - 1) / 2)``."""
    if not (width > 0 and height > 0):
        raise ValueError(f"image size must be positive, got {width} x {height}")
    if not (math.isfinite(focal) and focal > 0):
        raise ValueError(f"focal length must be positive, got {focal}")
    return np.array([[focal, 0.0, (width - 1) / 2.0], [0.0, focal, (height - 1) / 2.0], [0.0, 0.0, 1.0]])


def default_intrinsics(width: int, height: int, fov_deg: float = DEFAULT_FOV_DEG) -> np.ndarray:
    """(3, 3) K assumed for a ``width x height`` video of unknown lens: ``fov_deg`` (default 60) degrees
    across the longer side, square pixels, principal point at the image centre (see the module text)."""
    return intrinsics_for_focal(width, height, focal_from_fov(width, height, fov_deg))


def _check_K(K: np.ndarray) -> np.ndarray:
    K = np.asarray(K, dtype=np.float64)
    if K.shape != (3, 3) or not np.all(np.isfinite(K)):
        raise ValueError(f"K must be a finite (3, 3) matrix, got shape {K.shape}")
    if abs(np.linalg.det(K)) < 1e-12:
        raise ValueError("K must be invertible")
    return K


def project(points: np.ndarray, K: np.ndarray) -> np.ndarray:
    """(..., 2) pixels of camera-frame points (..., 3) (see the module text); NaN for points with
    ``z <= 0``."""
    K = _check_K(K)
    p = np.asarray(points, dtype=np.float64)
    if p.shape[-1:] != (3,):
        raise ValueError(f"points must be (..., 3), got shape {p.shape}")
    h = p @ K.T
    with np.errstate(divide="ignore", invalid="ignore"):
        uv = h[..., :2] / h[..., 2:3]
    return np.where((p[..., 2:3] > 0) & np.isfinite(uv), uv, np.nan)


def _inputs(X, uv, w, min_confidence):
    X = np.asarray(X, dtype=np.float64)
    uv = np.asarray(uv, dtype=np.float64)
    w = np.asarray(w, dtype=np.float64)
    if X.ndim != 3 or X.shape[1:] != (_N, 3):
        raise ValueError(f"X must be an (F, {_N}, 3) array, got shape {X.shape}")
    F = len(X)
    if uv.shape != (F, _N, 2):
        raise ValueError(f"uv must be an ({F}, {_N}, 2) array like X, got shape {uv.shape}")
    if w.shape != (F, _N):
        raise ValueError(f"w must be an ({F}, {_N}) array like X, got shape {w.shape}")
    used = (np.isfinite(X).all(axis=-1) & np.isfinite(uv).all(axis=-1) & np.isfinite(w)
            & (w > min_confidence))
    weight = np.where(used, w, 0.0)
    return np.where(used[..., None], X, 0.0), np.where(used[..., None], uv, 0.0), weight, used


def _cost(X, uv, weight, t, K):
    """(F,) weighted squared reprojection error, and (F,) whether every weighted point is in front."""
    Y = X + t[:, None, :]
    h = Y @ K.T
    front = np.where(weight > 0, Y[..., 2] > 0, True).all(axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        r = h[..., :2] / h[..., 2:3] - uv
        c = np.where(weight > 0, weight * (r ** 2).sum(axis=-1), 0.0).sum(axis=1)
    c = np.where(front & np.isfinite(c), c, np.inf)
    return c, front


def _weak_perspective(X, uv, weight, K):
    Kinv = np.linalg.inv(K)
    n = np.concatenate([uv, np.ones(uv.shape[:-1] + (1,))], axis=-1) @ Kinv.T
    n = n[..., :2] / n[..., 2:3]
    W = np.maximum(weight.sum(axis=1, keepdims=True), 1e-300)  # (F, 1)
    mx = (weight[..., None] * X).sum(axis=1) / W  # (F, 3)
    mn = (weight[..., None] * n).sum(axis=1) / W  # (F, 2)
    A = X[..., :2] - mx[:, None, :2]
    B = n - mn[:, None, :]
    sxx = (weight * (A ** 2).sum(-1)).sum(1)
    sxy = (weight * (A * B).sum(-1)).sum(1)
    syy = (weight * (B ** 2).sum(-1)).sum(1)
    with np.errstate(divide="ignore", invalid="ignore"):
        s_ls = sxy / sxx
        s_spread = np.sqrt(syy / sxx)
    s = np.where(s_ls > 0, s_ls, s_spread)
    s = np.where(np.isfinite(s) & (s > 0), s, 1.0)
    Z = 1.0 / s
    tz = Z - mx[:, 2]
    extent = np.sqrt(sxx / W[:, 0])
    # every used keypoint in front of the camera, by at least 5 % of the pose's extent
    zmin = np.where(weight > 0, X[..., 2], np.inf).min(axis=1)
    tz = np.maximum(tz, -zmin + 0.05 * np.where(extent > 0, extent, 1.0))
    Zc = mx[:, 2] + tz
    txy = mn * Zc[:, None] - mx[:, :2]
    return np.concatenate([txy, tz[:, None]], axis=1)


def _algebraic(X, uv, weight, K):
    # rows (K_0 - u K_2) and (K_1 - v K_2): a . t = -a . X
    a_u = K[0][None, None, :] - uv[..., 0:1] * K[2][None, None, :]
    a_v = K[1][None, None, :] - uv[..., 1:2] * K[2][None, None, :]
    A = np.concatenate([a_u, a_v], axis=1)  # (F, 2N, 3)
    b = -np.concatenate([(a_u * X).sum(-1), (a_v * X).sum(-1)], axis=1)  # (F, 2N)
    ww = np.concatenate([weight, weight], axis=1)
    AtA = np.einsum("fni,fn,fnj->fij", A, ww, A)
    Atb = np.einsum("fni,fn,fn->fi", A, ww, b)
    t = np.full((len(X), 3), np.nan)
    ok = np.abs(np.linalg.det(AtA)) > 1e-300
    if ok.any():
        t[ok] = np.linalg.solve(AtA[ok], Atb[ok][..., None])[..., 0]
    return t


def _refine(X, uv, weight, t, K, iterations, tol=1e-12):
    lam = np.full(len(X), 1e-3)
    cost, _ = _cost(X, uv, weight, t, K)
    active = np.isfinite(cost)
    for _ in range(iterations):
        if not active.any():
            break
        Y = X[active] + t[active][:, None, :]
        h = Y @ K.T
        z = np.where(weight[active] > 0, h[..., 2], 1.0)
        u = h[..., 0] / z
        v = h[..., 1] / z
        wa = weight[active]
        Ju = (K[0][None, None, :] - u[..., None] * K[2][None, None, :]) / z[..., None]
        Jv = (K[1][None, None, :] - v[..., None] * K[2][None, None, :]) / z[..., None]
        ru = u - uv[active][..., 0]
        rv = v - uv[active][..., 1]
        JtJ = np.einsum("fn,fni,fnj->fij", wa, Ju, Ju) + np.einsum("fn,fni,fnj->fij", wa, Jv, Jv)
        Jtr = np.einsum("fn,fni,fn->fi", wa, Ju, ru) + np.einsum("fn,fni,fn->fi", wa, Jv, rv)
        diag = np.einsum("fii->fi", JtJ)
        damped = JtJ + (lam[active][:, None] * np.maximum(diag, 1e-12))[:, :, None] * np.eye(3)
        try:
            step = -np.linalg.solve(damped, Jtr[..., None])[..., 0]
        except np.linalg.LinAlgError:
            break
        cand = t[active] + step
        new_cost, _ = _cost(X[active], uv[active], wa, cand, K)
        better = new_cost < cost[active]
        idx = np.flatnonzero(active)
        t[idx[better]] = cand[better]
        small = np.abs(cost[active] - new_cost) <= tol * np.maximum(cost[active], 1e-30)
        cost[idx[better]] = new_cost[better]
        lam[idx] = np.where(better, np.maximum(lam[idx] / 10.0, 1e-12), lam[idx] * 10.0)
        step_small = np.linalg.norm(step, axis=1) <= 1e-12 * np.maximum(np.linalg.norm(t[idx], axis=1), 1.0)
        done = (better & (small | step_small)) | (lam[idx] > 1e12)
        active[idx[done]] = False
    return t, cost


def fit_translations(X: np.ndarray, uv: np.ndarray, w: np.ndarray, K: np.ndarray,
                     min_keypoints: int = MIN_KEYPOINTS, min_confidence: float = 0.0,
                     iterations: int = 50) -> np.ndarray:
    """(F, 3) camera-frame translation of each frame's pose (the unit of ``X``) minimising the
    confidence-weighted reprojection error (see the module text).

    ``X`` (F, 15, 3) poses in camera axes up to translation, ``uv`` (F, 15, 2) detected keypoints in
    pixels, ``w`` (F, 15) confidences (NaN rows of ``uv``/``w``/``X`` are missing keypoints), ``K``
    (3, 3) intrinsics. A frame with fewer than ``min_keypoints`` keypoints of ``w > min_confidence`` gets
    NaN. ``X + t[:, None]`` are the keypoints in camera coordinates.
    """
    K = _check_K(K)
    if min_keypoints < 2:
        raise ValueError(f"min_keypoints must be >= 2 (two keypoints give 4 equations), got {min_keypoints}")
    Xz, uvz, weight, used = _inputs(X, uv, w, min_confidence)
    F = len(Xz)
    out = np.full((F, 3), np.nan)
    ok = used.sum(axis=1) >= min_keypoints
    if not ok.any():
        return out
    Xo, uvo, wo = Xz[ok], uvz[ok], weight[ok]
    t0 = _weak_perspective(Xo, uvo, wo, K)
    t1 = _algebraic(Xo, uvo, wo, K)
    c0, _ = _cost(Xo, uvo, wo, t0, K)
    c1, _ = _cost(Xo, uvo, wo, np.where(np.isfinite(t1), t1, 0.0), K)
    c1 = np.where(np.isfinite(t1).all(axis=1), c1, np.inf)
    t = np.where((c1 < c0)[:, None], t1, t0)
    t, _ = _refine(Xo, uvo, wo, t, K, iterations)
    out[ok] = t
    return out


def fit_translation(X: np.ndarray, uv: np.ndarray, w: np.ndarray, K: np.ndarray,
                    min_keypoints: int = MIN_KEYPOINTS, min_confidence: float = 0.0) -> np.ndarray:
    """(3,) :func:`fit_translations` of one frame: ``X`` (15, 3), ``uv`` (15, 2), ``w`` (15,)."""
    X = np.asarray(X, dtype=np.float64)
    uv = np.asarray(uv, dtype=np.float64)
    w = np.asarray(w, dtype=np.float64)
    if X.shape != (_N, 3) or uv.shape != (_N, 2) or w.shape != (_N,):
        raise ValueError(f"one frame needs X ({_N}, 3), uv ({_N}, 2) and w ({_N},), got "
                         f"{X.shape}, {uv.shape}, {w.shape}")
    return fit_translations(X[None], uv[None], w[None], K, min_keypoints, min_confidence)[0]


def reprojection_errors(X: np.ndarray, t: np.ndarray, uv: np.ndarray, K: np.ndarray) -> np.ndarray:
    """(F, 15) pixel distance between the projection of ``X + t[:, None]`` (X (F, 15, 3), t (F, 3)) and
    ``uv`` (F, 15, 2); NaN where either is missing or the point is not in front of the camera."""
    X = np.asarray(X, dtype=np.float64)
    t = np.asarray(t, dtype=np.float64)
    uv = np.asarray(uv, dtype=np.float64)
    if X.ndim != 3 or X.shape[2] != 3 or t.shape != (len(X), 3) or uv.shape != X.shape[:2] + (2,):
        raise ValueError(f"need X (F, N, 3), t (F, 3) and uv (F, N, 2), got {X.shape}, {t.shape}, {uv.shape}")
    return np.linalg.norm(project(X + t[:, None, :], K) - uv, axis=-1)


def focal_curve(X: np.ndarray, uv: np.ndarray, w: np.ndarray, width: int, height: int,
                focals: np.ndarray, min_keypoints: int = MIN_KEYPOINTS,
                min_confidence: float = 0.0) -> np.ndarray:
    """(len(focals),) RMS reprojection error (pixels; ``sqrt(sum w r^2 / sum w)`` over the used keypoints
    of frames with at least ``min_keypoints``) with each focal length (centred principal point, square
    pixels) and every frame's best translation; NaN when no frame can be fitted."""
    Xz, uvz, weight, used = _inputs(X, uv, w, min_confidence)
    ok = used.sum(axis=1) >= min_keypoints
    out = np.full(len(np.atleast_1d(focals)), np.nan)
    if not ok.any():
        return out
    total_w = weight[ok].sum()
    for i, f in enumerate(np.atleast_1d(np.asarray(focals, dtype=np.float64))):
        K = intrinsics_for_focal(width, height, float(f))
        t = fit_translations(X[ok], uv[ok], w[ok], K, min_keypoints, min_confidence)
        c, _ = _cost(Xz[ok], uvz[ok], weight[ok], np.where(np.isfinite(t), t, 0.0), K)
        out[i] = math.sqrt(c.sum() / total_w) if total_w > 0 else math.nan
    return out


def estimate_focal(X: np.ndarray, uv: np.ndarray, w: np.ndarray, width: int, height: int,
                   fov_range: tuple[float, float] = (20.0, 120.0), grid: int = 41,
                   min_gain: float = 0.05, min_gain_px: float = 0.5,
                   default_fov_deg: float = DEFAULT_FOV_DEG, min_keypoints: int = MIN_KEYPOINTS,
                   min_confidence: float = 0.0, max_frames: int | None = 1000) -> float:
    """Focal length (pixels) of a static camera with centred principal point and square pixels, from
    poses ``X`` (F, 15, 3) in camera axes up to translation, keypoints ``uv`` (F, 15, 2) and confidences
    ``w`` (F, 15) of a ``width x height`` video: the minimiser of :func:`focal_curve`, or the default of
    :func:`default_intrinsics` (``default_fov_deg``) when the curve is too flat (rule in the module
    text). ``default_intrinsics(...)`` / ``intrinsics_for_focal(width, height, f)`` make the K. At most
    ``max_frames`` frames (evenly spaced among those with enough keypoints; None: all) are used: every
    evaluation of the curve fits all of them (~0.05 s per 1000 frames), and ~60 evaluations are made."""
    from scipy.optimize import minimize_scalar

    _, _, _, used = _inputs(X, uv, w, min_confidence)
    fit = np.flatnonzero(used.sum(axis=1) >= min_keypoints)
    if max_frames is not None:
        if max_frames < 1:
            raise ValueError(f"max_frames must be >= 1 or None, got {max_frames}")
        if len(fit) > max_frames:
            fit = fit[np.round(np.linspace(0, len(fit) - 1, max_frames)).astype(np.int64)]
    X = np.asarray(X, dtype=np.float64)[fit]
    uv = np.asarray(uv, dtype=np.float64)[fit]
    w = np.asarray(w, dtype=np.float64)[fit]

    lo_fov, hi_fov = fov_range
    if not 0.0 < lo_fov < hi_fov < 180.0:
        raise ValueError(f"fov_range must be increasing degrees in (0, 180), got {fov_range}")
    if grid < 3:
        raise ValueError(f"grid must be >= 3, got {grid}")
    f_default = focal_from_fov(width, height, default_fov_deg)
    # longer focal = narrower view; geometric spacing
    fs = np.geomspace(focal_from_fov(width, height, hi_fov), focal_from_fov(width, height, lo_fov), grid)
    curve = focal_curve(X, uv, w, width, height, fs, min_keypoints, min_confidence)
    if not np.isfinite(curve).any():
        return f_default
    i = int(np.nanargmin(curve))
    if i == 0 or i == grid - 1:
        return f_default

    def rms(logf: float) -> float:
        v = focal_curve(X, uv, w, width, height, np.array([math.exp(logf)]), min_keypoints,
                        min_confidence)[0]
        return v if math.isfinite(v) else math.inf

    res = minimize_scalar(rms, bounds=(math.log(fs[i - 1]), math.log(fs[i + 1])), method="bounded",
                          options={"xatol": 1e-4})
    f_best, e_best = (math.exp(res.x), res.fun) if res.fun <= curve[i] else (float(fs[i]), float(curve[i]))
    e_default = rms(math.log(f_default))
    if not math.isfinite(e_default):
        return f_best
    if e_default - e_best > max(min_gain_px, min_gain * e_default):
        return float(f_best)
    return f_default
