"""2D pose accuracy on real footage without labels: leave-one-view-out consistency of calibrated views.

For synchronised views with a calibration (:mod:`vidstyle.formats.calibration`), each keypoint of each
frame is triangulated (linear DLT on undistorted points) from the *other* views in which it was found,
reprojected (with distortion) into the held-out view, and compared with that view's estimate. The error
is divided by the held-out view's torso length (neck to pelvis of the reprojected skeleton), so it reads
like PCK's normalisation: PCK@0.2 counts errors under a fifth of the torso. A keypoint the estimator did
not find in the held-out view is a miss; a keypoint that fewer than two other views found has no
reference and is not scored (counted as ``unscored``).

``reference="dlt"`` is that definition. One mislabelled view corrupts it for the others: a view whose
estimator swapped left and right limbs pulls every other view's reference towards the swap (on the real
pose2sim take, 26 frames of one view do, and every view's score falls in those frames). ``reference=
"robust"`` therefore chooses, per frame, the left/right labelling of each *reference* view that makes
the reference views agree best (of the labellings that agree equally, the one that swaps the fewest
views; Pose2Sim handles swaps the same way), and, with three or more reference views, triangulates each
keypoint from the largest set of views that agree within a fifth of their torso (every pair of views
tried as the seed, RANSAC-style), so one view that is far off does not drag the reference. The held-out view's estimate is never changed, so its own swaps
still count as errors. Both are reported; the issue's figures are the plain DLT.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ..formats.calibration import CameraCalibration

THRESHOLDS = (0.1, 0.2)


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


def _reproj_error(X: np.ndarray, und: np.ndarray, P: np.ndarray) -> np.ndarray:
    """(K,) pixel distances between undistorted points ``und`` (K, 2) and ``X`` (K, 3) projected by ``P``."""
    h = np.hstack([X, np.ones((len(X), 1))]) @ P.T
    return np.linalg.norm(h[:, :2] / h[:, 2:3] - und, axis=1)


def _robust_frame(und: np.ndarray, P: Sequence[np.ndarray], mirror: np.ndarray, torso: tuple[int, int],
                  outlier: float) -> np.ndarray:
    """(K, 3) reference of one frame from reference views ``und`` (R, K, 2): the left/right labelling per
    view (first view fixed) with the least total reprojection error, then per keypoint the view whose
    error exceeds ``outlier`` torso lengths dropped when at least two others remain."""
    R, K, _ = und.shape
    best, best_key = None, (np.inf, R)
    for mask in range(1 << R):  # swapping every view is the same 3D with mirrored labels: fewest swaps win
        cand = und.copy()
        for r in range(R):
            if mask >> r & 1:
                cand[r] = und[r][mirror]
        X = np.stack([triangulate(cand[:, k], P) for k in range(K)])
        errs = [_reproj_error(X, cand[r], P[r]) for r in range(R)]
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
                    errs = {r: _reproj_error(Xp[None], cand[r, k:k + 1], P[r])[0] / tl[r] for r in seen}
                    inl = [r for r in seen if errs[r] <= outlier]
                    if len(inl) < 2:
                        continue
                    key = (-len(inl), float(np.mean([errs[r] for r in inl])))
                    if best_key is None or key < best_key:
                        best_key, best_views = key, inl
            if best_views is not None and len(best_views) < len(seen):
                X[k] = triangulate(cand[best_views, k], [P[r] for r in best_views])
    return X


def leave_one_view_out(cameras: Sequence[CameraCalibration], points: np.ndarray, torso: tuple[int, int],
                       min_score: float = 0.0, reference: str = "dlt", mirror: np.ndarray | None = None,
                       outlier: float = 0.2) -> tuple[np.ndarray, np.ndarray]:
    """Normalised errors of every held-out view.

    ``points`` (V, F, K, 3): x, y, score per view, frame and keypoint (NaN or score <= ``min_score``:
    not found). ``torso``: the (neck, pelvis) keypoint indices. ``reference``: ``"dlt"`` or ``"robust"``
    (module docstring; needs ``mirror``, each keypoint's left/right counterpart). Returns ``errors`` (V, F, K): error /
    torso length, ``inf`` where the held-out view missed a keypoint the others located, NaN where there is
    no reference; and ``torso_px`` (V, F) the reference torso length in pixels."""
    if reference not in ("dlt", "robust"):
        raise ValueError(f"reference: 'dlt' or 'robust', got {reference!r}")
    if reference == "robust" and mirror is None:
        raise ValueError("reference 'robust' needs the keypoints' mirror map")
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
    P = [cam.P for cam in cameras]
    errors = np.full((V, F, K), np.nan)
    torso_px = np.full((V, F), np.nan)
    for held in range(V):
        others = [v for v in range(V) if v != held]
        Pv = [P[v] for v in others]
        X = np.full((F, K, 3), np.nan)
        for f in range(F):
            if reference == "robust":
                X[f] = _robust_frame(und[others, f], Pv, np.asarray(mirror), torso, outlier)
                continue
            for k in range(K):
                X[f, k] = triangulate(und[others, f, k], Pv)
        ref = project(X.reshape(-1, 3), cameras[held]).reshape(F, K, 2)
        t = np.linalg.norm(ref[:, torso[0]] - ref[:, torso[1]], axis=-1)
        torso_px[held] = t
        scorable = np.all(np.isfinite(ref), axis=-1) & (np.isfinite(t) & (t > 0))[:, None]
        d = np.linalg.norm(points[held, ..., :2] - ref, axis=-1) / t[:, None]
        e = np.where(found[held], d, np.inf)
        errors[held] = np.where(scorable, e, np.nan)
    return errors, torso_px


def summarise(errors: np.ndarray, view_names: Sequence[str], keypoint_names: Sequence[str],
              thresholds: Sequence[float] = THRESHOLDS) -> dict:
    """Median normalised error and PCK at ``thresholds``: overall, per view and per keypoint."""

    def block(e: np.ndarray) -> dict:
        e = e[~np.isnan(e)]
        out = {"n": int(e.size), "missed": int(np.isinf(e).sum())}
        out["median_error"] = float(np.median(e)) if e.size else None
        for th in thresholds:
            out[f"pck@{th:g}"] = float(np.mean(e < th)) if e.size else None
        return out

    return {
        "overall": block(errors),
        "unscored": int(np.isnan(errors).sum()),
        "per_view": {name: block(errors[v]) for v, name in enumerate(view_names)},
        "per_keypoint": {name: block(errors[:, :, k]) for k, name in enumerate(keypoint_names)},
        "thresholds": list(thresholds),
    }


def load_views(calib_cameras: Sequence[CameraCalibration], poses_files: Sequence) -> tuple[list[str], np.ndarray]:
    """Match ``poses_files`` (``poses.json`` of synchronised views) to the calibration's cameras and stack
    their frames: a file whose name contains a camera's name goes to that camera, otherwise files are taken
    in the calibration's order. Returns (camera names, (V, F, 15, 3) points with NaN where a view has no
    pose); frames are those every file has."""
    from pathlib import Path

    from ..errors import InputError
    from ..formats.poses import read_poses

    names = [c.name for c in calib_cameras]
    files = [Path(p) for p in poses_files]
    if len(files) < 2:
        raise InputError("evaluate pose --calibration: give at least two views' poses files")
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
    for v, d in enumerate(docs):
        index = {fr.frame: fr for fr in d.frames}
        for i, fr in enumerate(common):
            pf = index[fr]
            if pf.found:
                pts[v, i] = pf.points
    return order, pts


def evaluate_views(calibration, poses_files: Sequence, references: Sequence[str] = ("dlt", "robust"),
                   min_score: float = 0.0) -> dict:
    """The multi-view metrics document (``vidstyle.metrics.multiview_pose``) of poses files of
    calibrated, synchronised views: leave-one-view-out scores with each reference."""
    from ..formats.calibration import read_calibration
    from ..formats.keypoints import KEYPOINTS
    from ..mocap.keypoints import MIRROR

    calib = read_calibration(calibration) if not hasattr(calibration, "cameras") else calibration
    names, pts = load_views(calib.cameras, poses_files)
    cams = [calib.camera(n) for n in names]
    torso = (KEYPOINTS.index("neck"), KEYPOINTS.index("pelvis"))
    out = {"views": names, "frames": int(pts.shape[1]), "references": {},
           "params": {"calibration": str(getattr(calib, "source", "")), "poses": [str(p) for p in poses_files],
                      "min_score": min_score}}
    for ref in references:
        errors, _ = leave_one_view_out(cams, pts, torso, min_score=min_score, reference=ref, mirror=np.asarray(MIRROR))
        out["references"][ref] = summarise(errors, names, KEYPOINTS)
    return out


def format_table(metrics: dict) -> str:
    """The printed table: PCK@0.2 / PCK@0.1 / median error per view, per reference."""
    lines = []
    for ref, r in metrics["references"].items():
        lines.append(f"reference {ref}: {metrics['frames']} frames x {len(metrics['views'])} views")
        lines.append(f"  {'view':<12} {'PCK@0.2':>8} {'PCK@0.1':>8} {'median':>8} {'n':>6}")
        rows = [*r["per_view"].items(), ("all", r["overall"])]
        for name, b in rows:
            def f(x):
                return "-" if x is None else f"{x:.3f}"
            lines.append(f"  {name:<12} {f(b['pck@0.2']):>8} {f(b['pck@0.1']):>8} {f(b['median_error']):>8} {b['n']:>6}")
    return "\n".join(lines)
