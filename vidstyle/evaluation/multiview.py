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

The geometry (undistortion, projection, DLT and the robust reference, the views' poses files stacked on
their shared frames) is :mod:`vidstyle.pose.triangulation`, shared with the 3D reference of
:mod:`vidstyle.reconstruct.reference`; this module scores with it.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ..formats.calibration import CameraCalibration
from ..pose.triangulation import (  # noqa: F401 - project, triangulate, undistort: this module's API before the move
    load_view_poses,
    project,
    triangulate,
    triangulate_sequence,
    undistort,
    undistort_views,
)

THRESHOLDS = (0.1, 0.2)


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
    found, und = undistort_views(cameras, points, min_score)
    P = [cam.P for cam in cameras]
    errors = np.full((V, F, K), np.nan)
    torso_px = np.full((V, F), np.nan)
    for held in range(V):
        others = [v for v in range(V) if v != held]
        X, _ = triangulate_sequence([P[v] for v in others], und[others], reference, mirror, torso, outlier)
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
    views = load_view_poses(calib_cameras, poses_files)
    return views.names, views.points


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
