"""Multi-view geometry of 2D poses: undistortion, projection and triangulation of keypoints seen by
calibrated, synchronised cameras (:mod:`vidstyle.formats.calibration`: world in mm, OpenCV camera
frame), and the views' ``poses.json`` files stacked on the frames they share.

Two ways to triangulate a take (:func:`triangulate_sequence`): ``"dlt"``, every keypoint by linear DLT
from every view that found it; and ``"robust"``, which per frame first picks the left/right labelling of
each view that makes the views agree best (the least total reprojection error; of equal ones, the one
that swaps the fewest views: a view whose estimator swapped left and right limbs would otherwise pull
the point towards the swap; Pose2Sim handles swaps the same way), then, with three or more views,
triangulates each keypoint from the largest set of views that agree within ``outlier`` of their 2D torso
length (every pair of views tried as the seed, RANSAC-style), so that one view far off does not drag it.

Used by the leave-one-view-out 2D score (:mod:`vidstyle.evaluation.multiview`) and the triangulated 3D
reference of reconstructions (:mod:`vidstyle.reconstruct.reference`); it lives here, below both, so that
neither imports the other.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..formats.calibration import CameraCalibration


def undistort(points: np.ndarray, cam: CameraCalibration) -> np.ndarray:
    """(N, 2) pixel points -> (N, 2) undistorted pixel points (same K)."""
    import cv2

    pts = np.asarray(points, dtype=np.float64).reshape(-1, 1, 2)
    if len(pts) == 0 or not np.any(cam.dist):
        return pts.reshape(-1, 2).copy()
    return cv2.undistortPoints(pts, cam.K, cam.dist, P=cam.K).reshape(-1, 2)


def project(X: np.ndarray, cam: CameraCalibration) -> np.ndarray:
    """(N, 3) world points (mm) -> (N, 2) distorted pixel points; NaN rows stay NaN."""
    import cv2

    X = np.asarray(X, dtype=np.float64).reshape(-1, 3)
    out = np.full((len(X), 2), np.nan)
    ok = np.all(np.isfinite(X), axis=1)
    if ok.any():
        rvec = cv2.Rodrigues(np.asarray(cam.R, dtype=np.float64))[0]
        p, _ = cv2.projectPoints(X[ok], rvec, np.asarray(cam.t, dtype=np.float64), cam.K, cam.dist)
        out[ok] = p.reshape(-1, 2)
    return out


def triangulate(points: np.ndarray, projections: Sequence[np.ndarray], weights: np.ndarray | None = None) -> np.ndarray:
    """Linear (DLT) triangulation of one point seen in several views.

    ``points`` (V, 2) undistorted pixels, NaN where unseen; ``projections`` V (3, 4) matrices; ``weights``
    (V,) optional confidences. Returns (3,), or NaN when fewer than two views see the point."""
    points = np.asarray(points, dtype=np.float64)
    seen = np.all(np.isfinite(points), axis=1)
    if weights is not None:
        seen &= np.asarray(weights) > 0
    if seen.sum() < 2:
        return np.full(3, np.nan)
    rows = []
    for v in np.flatnonzero(seen):
        P = projections[v]
        w = 1.0 if weights is None else float(weights[v])
        x, y = points[v]
        rows += [w * (x * P[2] - P[0]), w * (y * P[2] - P[1])]
    A = np.asarray(rows)
    _, _, vt = np.linalg.svd(A)
    h = vt[-1]
    if abs(h[3]) < 1e-12:
        return np.full(3, np.nan)
    return h[:3] / h[3]


def reprojection_error(X: np.ndarray, und: np.ndarray, P: np.ndarray) -> np.ndarray:
    """(K,) pixel distances between undistorted points ``und`` (K, 2) and ``X`` (K, 3) projected by ``P``
    (NaN where either is NaN)."""
    h = np.hstack([X, np.ones((len(X), 1))]) @ P.T
    return np.linalg.norm(h[:, :2] / h[:, 2:3] - und, axis=1)


def _robust_frame(und: np.ndarray, P: Sequence[np.ndarray], mirror: np.ndarray, torso: tuple[int, int],
                  outlier: float) -> tuple[np.ndarray, np.ndarray]:
    """(K, 3) reference of one frame from reference views ``und`` (R, K, 2): the left/right labelling per
    view with the least total reprojection error (of equal ones, the fewest swapped views), then per
    keypoint the view whose error exceeds ``outlier`` torso lengths dropped when at least two others
    remain. Also returns the views' points (R, K, 2) in the chosen labelling."""
    R, K, _ = und.shape
    best, best_key = None, (np.inf, R)
    for mask in range(1 << R):  # swapping every view is the same 3D with mirrored labels: fewest swaps win
        cand = und.copy()
        for r in range(R):
            if mask >> r & 1:
                cand[r] = und[r][mirror]
        X = np.stack([triangulate(cand[:, k], P) for k in range(K)])
        errs = [reprojection_error(X, cand[r], P[r]) for r in range(R)]
        key = (round(float(np.nansum(np.concatenate(errs))), 6), bin(mask).count("1"))
        if key < best_key:
            best, best_key = (cand, X), key
    cand, X = best
    if R >= 3:
        tl = np.array([np.linalg.norm(cand[r, torso[0]] - cand[r, torso[1]]) for r in range(R)])
        tl = np.where(tl > 0, tl, np.nan)

        for k in range(K):
            seen = [r for r in range(R) if np.all(np.isfinite(cand[r, k]))]
            if len(seen) < 3:
                continue
            # consensus over view pairs (RANSAC with every minimal sample): the largest set of views that
            # agree with a pair's point within ``outlier`` torso lengths, then the least error
            best_key, best_views = None, None
            for i, a in enumerate(seen):
                for b in seen[i + 1:]:
                    Xp = triangulate(cand[[a, b], k], [P[a], P[b]])
                    if not np.all(np.isfinite(Xp)):
                        continue
                    errs = {r: reprojection_error(Xp[None], cand[r, k:k + 1], P[r])[0] / tl[r] for r in seen}
                    inl = [r for r in seen if errs[r] <= outlier]
                    if len(inl) < 2:
                        continue
                    key = (-len(inl), float(np.mean([errs[r] for r in inl])))
                    if best_key is None or key < best_key:
                        best_key, best_views = key, inl
            if best_views is not None and len(best_views) < len(seen):
                X[k] = triangulate(cand[best_views, k], [P[r] for r in best_views])
    return X, cand


def undistort_views(cameras: Sequence[CameraCalibration], points: np.ndarray,
                    min_score: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """``points`` (V, F, K, 3) x, y, score per view, frame and keypoint -> ``found`` (V, F, K) (finite and
    score > ``min_score``) and the undistorted pixels (V, F, K, 2), NaN where not found."""
    points = np.asarray(points, dtype=np.float64)
    V, F, K, _ = points.shape
    if len(cameras) != V:
        raise ValueError(f"{V} views of poses but {len(cameras)} cameras")
    found = np.all(np.isfinite(points[..., :2]), axis=-1) & (np.nan_to_num(points[..., 2], nan=0.0) > min_score)
    und = np.full((V, F, K, 2), np.nan)
    for v, cam in enumerate(cameras):
        flat = points[v, ..., :2].reshape(-1, 2)
        ok = found[v].reshape(-1)
        u = np.full_like(flat, np.nan)
        u[ok] = undistort(flat[ok], cam)
        und[v] = u.reshape(F, K, 2)
    return found, und


def triangulate_sequence(projections: Sequence[np.ndarray], und: np.ndarray, reference: str = "dlt",
                         mirror: np.ndarray | None = None, torso: tuple[int, int] | None = None,
                         outlier: float = 0.2) -> tuple[np.ndarray, np.ndarray]:
    """Every frame's keypoints triangulated from views ``und`` (V, F, K, 2) undistorted pixels (NaN: not
    seen) with projection matrices ``projections`` (V of (3, 4)), by ``reference`` ``"dlt"`` or
    ``"robust"`` (module docstring; needs ``mirror`` and ``torso``). Returns the world points (F, K, 3)
    (NaN where fewer than two views see a keypoint) and the views' points in the labelling used
    (V, F, K, 2): ``und`` itself for ``"dlt"``, with the chosen left/right swaps for ``"robust"``."""
    if reference not in ("dlt", "robust"):
        raise ValueError(f"reference: 'dlt' or 'robust', got {reference!r}")
    if reference == "robust" and (mirror is None or torso is None):
        raise ValueError("reference 'robust' needs the keypoints' mirror map and the torso keypoints")
    und = np.asarray(und, dtype=np.float64)
    F, K = und.shape[1:3]
    X = np.full((F, K, 3), np.nan)
    labelled = und.copy()
    for f in range(F):
        if reference == "robust":
            X[f], labelled[:, f] = _robust_frame(und[:, f], projections, np.asarray(mirror), torso, outlier)
            continue
        for k in range(K):
            X[f, k] = triangulate(und[:, f, k], projections)
    return X, labelled




@dataclass
class ViewPoses:
    """Poses of synchronised views on the frames they share (:func:`load_view_poses`)."""

    names: list[str]
    """the calibration's camera name of each view"""
    files: list[str]
    """the poses file of each view"""
    frames: np.ndarray
    """(F,) the shared frame indices"""
    points: np.ndarray
    """(V, F, 15, 3) x, y (pixels), score; NaN where the view has no pose"""
    world: np.ndarray
    """(V, F, 15, 3) the backend's world keypoints (metres, camera-aligned, hip-centred); NaN where absent"""


def load_view_poses(calib_cameras: Sequence[CameraCalibration], poses_files: Sequence) -> ViewPoses:
    """:func:`load_views` with the shared frame indices, the files in view order and the world keypoints."""
    from pathlib import Path

    from ..errors import InputError
    from ..formats.poses import read_poses

    names = [c.name for c in calib_cameras]
    files = [Path(p) for p in poses_files]
    if len(files) < 2:
        raise InputError("give at least two calibrated views' poses files (got "
                         f"{', '.join(map(str, files)) or 'none'})")
    by_name = {}
    for f in files:
        hits = [n for n in names if n.lower() in f.name.lower()]
        if len(hits) == 1:
            by_name[hits[0]] = f
    if len(by_name) == len(files):
        order = [n for n in names if n in by_name]
        files = [by_name[n] for n in order]
    elif len(files) <= len(names):
        order = names[:len(files)]
    else:
        raise InputError(f"{len(files)} poses files but the calibration has {len(names)} cameras")
    docs = [read_poses(f) for f in files]
    common = sorted(set.intersection(*[{fr.frame for fr in d.frames} for d in docs]))
    if not common:
        raise InputError(f"{files[0]}: the views' poses files share no frame")
    pts = np.full((len(docs), len(common), 15, 3), np.nan)
    world = np.full((len(docs), len(common), 15, 3), np.nan)
    for v, d in enumerate(docs):
        index = {fr.frame: fr for fr in d.frames}
        for i, fr in enumerate(common):
            pf = index[fr]
            if pf.found:
                pts[v, i] = pf.points
                if pf.world is not None:
                    world[v, i] = pf.world
    return ViewPoses(order, [str(f) for f in files], np.asarray(common, dtype=np.int64), pts, world)


