"""A 3D reference for reconstructions on real footage: the keypoints of calibrated, synchronised views
triangulated into the calibration's world, and the tools to compare a 3D estimate with it.

**Triangulation** (:func:`triangulated_reference`). The views' 2D poses (``poses.json``, e.g. from
``vidstyle pose --backend blazepose``) are undistorted and triangulated with
:func:`vidstyle.pose.triangulation.triangulate_sequence`'s ``"robust"`` reference: per frame the
left/right labelling of each view that makes the views agree best (of equal ones, the fewest swapped
views: the reference's left and right are those of the majority of views, ``swapped`` marks the
others), then per keypoint the largest set of views that agree within ``outlier`` (a fraction of that
view's 2D torso, neck to pelvis; 0.2 by default). A view *agrees* on a keypoint when its reprojection
error is within ``outlier`` torso lengths; a keypoint is triangulated from its agreeing views only and
is a reference (``valid``) when at least two views agree, otherwise its position is NaN. Reprojection
errors are in pixels of the input video, measured on undistorted points (the pinhole image of
:attr:`CameraCalibration.P`).

**Units and axes.** Positions are millimetres in the calibration's world. The world's vertical axis is
not assumed: :func:`detect_up` takes the world axis (signed) closest to the mean direction from the
ankles to the head over the take (``up_tilt_deg``: the angle between them, which a forward lean or lunges
make non-zero; a warning above 30 degrees). On the pose2sim take's Qualisys calibration it is **+Z**, as
Qualisys sets up its lab frame (X and Y span the floor): the triangulated head is far above the ankles
along +Z, the pelvis-to-ankles direction is within a few degrees of it, and every camera's image-up
direction has a large +Z component (the cameras look slightly down). ``floor_mm`` is where the ankle
keypoints sit when a foot is on the ground: along ``up``, the 5th percentile over frames of the lower
ankle's height. It is the ankle keypoints' level, not the sole: the ground is lower by the ankle's height
above it (Qualisys usually puts the ground at height 0; ``scripts/real_reference.py`` reports the value,
compare it with that rather than trust either).

**The project convention** (+Y up, millimetres; see :mod:`vidstyle.render.camera`):
:func:`reference_in_y_up` rotates the world by the smallest rotation taking ``up`` to +Y (for +Z up:
``(x, y, z) -> (x, z, -y)``), keeping it right-handed; the horizontal origin stays the world's, and with
``floor_at_zero`` the ankle level ``floor_mm`` is moved to Y = 0.

**A camera-frame estimate** (a reconstruction from one view, or BlazePose's world landmarks, whose axes
are the camera's: x right, y down, z away from the camera, the OpenCV camera frame of
:mod:`vidstyle.formats.calibration`): :func:`view_to_world` gives that camera's rotation and centre,
``X_world = R @ X_cam + C`` (mm), and :func:`view_to_y_up` the rotation from the camera frame straight to
the Y-up reference frame. An estimate whose scale or distance to the camera is unknown is compared
root-relative (:func:`compare_root_relative`).

**Comparison** (:func:`compare_root_relative`): both skeletons are made root-relative (the pelvis, the
midpoint of the hips, at the origin of each frame), then optionally rotated onto the reference:
``"sequence"`` one rotation for the whole take (Kabsch, least squares over every valid keypoint of every
frame; no scale, no reflection: it removes a global frame difference such as BlazePose's camera-aligned
axes, not per-frame pose errors; BlazePose's world axes are only roughly the camera's, so the fitted
rotation is used rather than the calibrated one, and :func:`summary` reports both and the angle between
them), ``"frame"`` one rotation per frame (Procrustes without scale, the
usual PA-MPJPE), ``"none"`` as given. MPJPE is the mean Euclidean distance (mm) over the keypoints valid
in both, the root excluded (it is 0 by construction).

Nothing here is stored: the reference is computed on demand from the poses files (a few seconds for the
pose2sim take's 4 x 100 frames).
"""

from __future__ import annotations

import logging
import os
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from ..formats.calibration import Calibration, read_calibration
from ..formats.keypoints import KEYPOINTS
from ..mocap.keypoints import MIRROR, PART_LIST
from ..pose.triangulation import (
    ViewPoses,
    load_view_poses,
    reprojection_error,
    triangulate,
    triangulate_sequence,
    undistort_views,
)

log = logging.getLogger(__name__)

PELVIS = KEYPOINTS.index("pelvis")
NECK = KEYPOINTS.index("neck")
HEAD_TOP = KEYPOINTS.index("head_top")
ANKLES = (KEYPOINTS.index("left_ankle"), KEYPOINTS.index("right_ankle"))
#: a view agrees on a keypoint when its reprojection error is within this fraction of its 2D torso
OUTLIER = 0.2
#: the percentile of the lower ankle's height that is taken as the ankle level on the ground
FLOOR_PERCENTILE = 5.0
AXES = "XYZ"


@dataclass
class Reference3D:
    """Triangulated keypoints of a calibrated multi-view take (module docstring)."""

    views: ViewPoses
    """the views' poses on the shared frames (names, files, frame indices, 2D points, BlazePose world)"""
    calibration: Calibration
    positions: np.ndarray
    """(F, 15, 3) world positions, mm; NaN where not ``valid``"""
    valid: np.ndarray
    """(F, 15) bool: at least two views agree on the keypoint"""
    agree: np.ndarray
    """(V, F, 15) bool: the view's point (in the chosen left/right labelling) is used"""
    reprojection_px: np.ndarray
    """(F, 15) mean reprojection error over the agreeing views, pixels; NaN where not valid"""
    view_reprojection_px: np.ndarray
    """(V, F, 15) each view's reprojection error (its chosen labelling), pixels; NaN where the view has no
    point or there is no reference"""
    swapped: np.ndarray
    """(V, F) bool: the view's left/right labels were swapped to agree with the others"""
    up: np.ndarray
    """(3,) the world's up direction, a signed unit axis (e.g. (0, 0, 1))"""
    floor_mm: float
    """the ankle keypoints' level on the ground, mm along ``up`` (module docstring)"""
    up_tilt_deg: float
    """angle between ``up`` and the mean ankles-to-head direction of the take, degrees"""
    outlier: float = OUTLIER
    """the agreement threshold used, a fraction of the view's 2D torso"""
    min_score: float = 0.0
    """2D keypoints at or below this score were not used"""

    @property
    def frames(self) -> np.ndarray:
        """(F,) frame indices"""
        return self.views.frames

    @property
    def names(self) -> list[str]:
        """the camera name of each view"""
        return self.views.names

    @property
    def up_axis(self) -> str:
        """``"+Z"`` and the like"""
        i = int(np.argmax(np.abs(self.up)))
        return ("+" if self.up[i] > 0 else "-") + AXES[i]


def triangulated_reference(calibration: str | os.PathLike | Calibration, poses_paths: Sequence[str | os.PathLike],
                           min_score: float = 0.0, outlier: float = OUTLIER) -> Reference3D:
    """The 3D reference of ``poses_paths`` (``poses.json`` of synchronised views; a file whose name
    contains a camera's name goes to that camera, else the calibration's order) with ``calibration``
    (a path or a :class:`Calibration`; world in mm). ``min_score``: 2D keypoints with a score at or
    below it are not used; ``outlier``: agreement threshold, a fraction of the view's 2D torso."""
    calib = calibration if isinstance(calibration, Calibration) else read_calibration(calibration)
    if not outlier > 0:
        raise ValueError(f"outlier: must be positive, got {outlier}")
    views = load_view_poses(calib.cameras, poses_paths)
    cams = [calib.camera(n) for n in views.names]
    P = [c.P for c in cams]
    V, F, K = views.points.shape[:3]
    _, und = undistort_views(cams, views.points, min_score)
    X, lab = triangulate_sequence(P, und, "robust", MIRROR, (NECK, PELVIS), outlier)
    swapped = np.zeros((V, F), dtype=bool)
    for v in range(V):
        same = np.isfinite(lab[v]) & np.isfinite(und[v])
        swapped[v] = np.any(same & (np.abs(lab[v] - und[v]) > 1e-9), axis=(-1, -2))
    torso = np.linalg.norm(lab[:, :, NECK] - lab[:, :, PELVIS], axis=-1)  # (V, F), the views' own 2D torso
    torso = np.where(torso > 0, torso, np.nan)

    def errors(X):
        e = np.full((V, F, K), np.nan)
        for v in range(V):
            e[v] = reprojection_error(X.reshape(-1, 3), lab[v].reshape(-1, 2), P[v]).reshape(F, K)
        return e

    agree = np.nan_to_num(errors(X) / torso[..., None], nan=np.inf) <= outlier
    # a keypoint some seen view disagrees on: triangulated again from the agreeing views only
    seen = np.all(np.isfinite(lab), axis=-1)
    for f, k in zip(*np.nonzero((agree.sum(axis=0) >= 2) & np.any(seen & ~agree, axis=0))):
        use = np.flatnonzero(agree[:, f, k])
        X[f, k] = triangulate(lab[use, f, k], [P[v] for v in use])
    err = errors(X)
    agree = np.nan_to_num(err / torso[..., None], nan=np.inf) <= outlier
    valid = agree.sum(axis=0) >= 2
    X[~valid] = np.nan
    err[:, ~valid] = np.nan
    reproj = np.full((F, K), np.nan)
    if valid.any():
        reproj[valid] = np.nanmean(np.where(agree, err, np.nan)[:, valid], axis=0)
    where = views.files[0]
    up, tilt = detect_up(X, where)
    floor = ankle_level(X, up)
    log.info("reference of %s: %d of %d keypoints triangulated; up %s (tilt %.1f deg); ankle level %.0f mm",
             ", ".join(views.names), int(valid.sum()), valid.size, _axis_name(up), tilt, floor)
    return Reference3D(views, calib, X, valid, agree, reproj, err, swapped, up, floor, tilt, outlier, min_score)


def _axis_name(up: np.ndarray) -> str:
    i = int(np.argmax(np.abs(up)))
    return ("+" if up[i] > 0 else "-") + AXES[i]


def detect_up(positions: np.ndarray, where: str | os.PathLike = "the poses") -> tuple[np.ndarray, float]:
    """The world's up direction from (F, 15, 3) keypoint positions (NaN allowed): the signed world axis
    closest to the mean direction from the ankles' midpoint to head_top (neck where head_top is missing)
    over the frames that have both. Returns that unit axis (3,) and its angle (degrees) to the mean
    direction. :class:`InputError` (naming ``where``) when no frame has both."""
    X = np.asarray(positions, dtype=np.float64)
    top = np.where(np.isfinite(X[:, HEAD_TOP]), X[:, HEAD_TOP], X[:, NECK])
    feet = np.nanmean(X[:, list(ANKLES)], axis=1) if np.isfinite(X[:, list(ANKLES)]).any() else X[:, ANKLES[0]]
    d = top - feet
    d = d[np.all(np.isfinite(d), axis=1)]
    if not len(d):
        raise InputError(f"{where}: no frame with both the head and an ankle triangulated: cannot tell the "
                         "world's up axis")
    mean = d.mean(axis=0)
    norm = np.linalg.norm(mean)
    if not norm > 0:
        raise InputError(f"{where}: the head and ankles coincide on average: cannot tell the world's up axis")
    i = int(np.argmax(np.abs(mean)))
    up = np.zeros(3)
    up[i] = np.sign(mean[i])
    tilt = float(np.degrees(np.arccos(np.clip(abs(mean[i]) / norm, -1.0, 1.0))))
    if tilt > 30:
        log.warning("%s: the body's mean vertical is %.0f degrees from the nearest world axis %s: the world "
                    "may have no vertical axis", where, tilt, _axis_name(up))
    return up, tilt


def ankle_level(positions: np.ndarray, up: np.ndarray, percentile: float = FLOOR_PERCENTILE) -> float:
    """The ankles' height on the ground along ``up`` (mm): the ``percentile`` of the lower ankle's height
    over the frames (NaN when no ankle is known)."""
    h = np.asarray(positions, dtype=np.float64)[:, list(ANKLES)] @ np.asarray(up, dtype=np.float64)
    h = h[np.isfinite(h).any(axis=1)]
    if not len(h):
        return float("nan")
    return float(np.percentile(np.nanmin(h, axis=1), percentile))


def rotation_between(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The smallest rotation (3, 3) taking direction ``a`` to direction ``b`` (half a turn about an axis
    perpendicular to ``a`` when they are opposite)."""
    a = np.asarray(a, dtype=np.float64) / np.linalg.norm(a)
    b = np.asarray(b, dtype=np.float64) / np.linalg.norm(b)
    v = np.cross(a, b)
    c = float(a @ b)
    if c < -1 + 1e-12:
        axis = np.cross(a, np.eye(3)[int(np.argmin(np.abs(a)))])
        axis /= np.linalg.norm(axis)
        return 2 * np.outer(axis, axis) - np.eye(3)
    vx = np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])
    return np.eye(3) + vx + vx @ vx / (1 + c)


def y_up_rotation(up: np.ndarray) -> np.ndarray:
    """(3, 3) rotation from the world to the project's +Y-up frame: the smallest one taking ``up`` to +Y
    (for ``up`` = +Z: ``(x, y, z) -> (x, z, -y)``)."""
    return rotation_between(up, (0.0, 1.0, 0.0))


def reference_in_y_up(ref: Reference3D, floor_at_zero: bool = False) -> np.ndarray:
    """(F, 15, 3) the reference positions in the +Y-up frame, mm (NaN where not valid); with
    ``floor_at_zero`` the ankle level (:attr:`Reference3D.floor_mm`) is at Y = 0."""
    out = ref.positions @ y_up_rotation(ref.up).T
    if floor_at_zero:
        out[..., 1] -= ref.floor_mm
    return out


def view_to_world(calibration: str | os.PathLike | Calibration, camera: str) -> tuple[np.ndarray, np.ndarray]:
    """``(R, C)`` of ``camera`` (its name in the calibration, e.g. ``"cam01"``): a point in that camera's
    frame (OpenCV: x right, y down, z forward, mm) is at ``R @ X_cam + C`` in the world (mm). ``R`` (3, 3)
    is the camera -> world rotation (the transpose of the calibration's world -> camera ``R``), ``C``
    (3,) the camera centre, mm. :class:`InputError` for an unknown camera."""
    calib = calibration if isinstance(calibration, Calibration) else read_calibration(calibration)
    try:
        cam = calib.camera(camera)
    except KeyError:
        raise InputError(f"{calib.source or 'calibration'}: no camera {camera!r} (cameras: "
                         f"{', '.join(calib.names())})") from None
    R = np.asarray(cam.R, dtype=np.float64).T
    return R, R @ -np.asarray(cam.t, dtype=np.float64)


def view_to_y_up(ref: Reference3D, camera: str) -> np.ndarray:
    """(3, 3) rotation from ``camera``'s frame (x right, y down, z forward) to the reference's +Y-up frame
    (:func:`reference_in_y_up`): a camera-frame direction ``d`` is ``M @ d`` there."""
    R, _ = view_to_world(ref.calibration, camera)
    return y_up_rotation(ref.up) @ R


def kabsch(source: np.ndarray, target: np.ndarray) -> np.ndarray:
    """(3, 3) rotation ``R`` minimising ``sum ||R s - t||^2`` over paired rows of ``source`` and ``target``
    (N, 3) (no translation, no scale, no reflection)."""
    H = np.asarray(source, dtype=np.float64).T @ np.asarray(target, dtype=np.float64)
    U, _, Vt = np.linalg.svd(H)
    d = np.sign(np.linalg.det(Vt.T @ U.T)) or 1.0
    return Vt.T @ np.diag([1.0, 1.0, d]) @ U.T


@dataclass
class Comparison:
    """Root-relative errors of a 3D estimate against the reference (:func:`compare_root_relative`), mm."""

    mpjpe_mm: float
    """mean over every compared keypoint of every frame"""
    per_keypoint_mm: dict[str, float | None]
    per_frame_mm: np.ndarray
    """(F,) mean over the frame's compared keypoints; NaN where none"""
    n: int
    """compared keypoints (root excluded)"""
    frames: int
    """frames with at least one compared keypoint"""
    rotation: np.ndarray
    """(3, 3) the sequence rotation applied to the estimate (identity for ``"none"`` and ``"frame"``)"""


def compare_root_relative(estimate: np.ndarray, reference: np.ndarray, valid: np.ndarray | None = None,
                          align: str = "sequence", root: int = PELVIS) -> Comparison:
    """MPJPE of ``estimate`` against ``reference``, both (F, 15, 3) in the same unit (mm) and, for
    ``align="none"``, the same axes; NaN = unknown. ``valid`` (F, 15) optionally restricts the reference.
    Each frame is made relative to its ``root`` keypoint (a frame whose root is unknown in either is not
    compared); ``align``: ``"sequence"`` (one Kabsch rotation of the estimate for the whole take),
    ``"frame"`` (one per frame) or ``"none"`` (module docstring)."""
    if align not in ("sequence", "frame", "none"):
        raise ValueError(f"align: 'sequence', 'frame' or 'none', got {align!r}")
    est = np.asarray(estimate, dtype=np.float64)
    ref = np.asarray(reference, dtype=np.float64).copy()
    if est.shape != ref.shape or est.ndim != 3 or est.shape[-1] != 3:
        raise ValueError(f"estimate {est.shape} and reference {ref.shape} must both be (F, K, 3)")
    if valid is not None:
        ref[~np.asarray(valid, dtype=bool)] = np.nan
    e = est - est[:, root:root + 1]
    r = ref - ref[:, root:root + 1]
    both = np.all(np.isfinite(e), axis=-1) & np.all(np.isfinite(r), axis=-1)
    both[:, root] = False
    R = np.eye(3)
    if align == "sequence" and both.any():
        R = kabsch(e[both], r[both])
        e = e @ R.T
    elif align == "frame":
        for f in range(len(e)):
            if both[f].sum() >= 3:
                e[f] = e[f] @ kabsch(e[f, both[f]], r[f, both[f]]).T
    d = np.where(both, np.linalg.norm(np.nan_to_num(e - r), axis=-1), np.nan)
    names = KEYPOINTS if d.shape[1] == len(KEYPOINTS) else tuple(str(i) for i in range(d.shape[1]))
    per_kp = {n: (float(np.nanmean(d[:, k])) if both[:, k].any() else None) for k, n in enumerate(names)
              if k != root}
    counts = both.sum(axis=1)
    per_frame = np.where(counts > 0, np.nansum(d, axis=1) / np.maximum(counts, 1), np.nan)
    return Comparison(float(np.nanmean(d)) if both.any() else float("nan"), per_kp, per_frame,
                      int(both.sum()), int((counts > 0).sum()), R)


def bone_lengths(positions: np.ndarray) -> dict[str, np.ndarray]:
    """(F,) length of each part of :data:`vidstyle.mocap.keypoints.PART_LIST` (same unit as
    ``positions`` (F, 15, 3)), NaN where an end is unknown."""
    X = np.asarray(positions, dtype=np.float64)
    return {name: np.linalg.norm(X[:, KEYPOINTS.index(a)] - X[:, KEYPOINTS.index(b)], axis=-1)
            for name, (a, b) in PART_LIST}


def blazepose_world_mm(ref: Reference3D, view: int | str) -> np.ndarray:
    """(F, 15, 3) the BlazePose world keypoints of one view (index or camera name) in mm, camera-aligned
    axes (x right, y down, z away from the camera), hip-centred; NaN where the view has none."""
    v = ref.names.index(view) if isinstance(view, str) else int(view)
    return ref.views.world[v] * 1000.0


def summary(ref: Reference3D) -> dict:
    """The reference's figures (a JSON-ready dict): coverage, reprojection errors, bone-length
    consistency, and per view the MPJPE of that view's BlazePose world keypoints against the reference
    (root-relative; aligned by one Kabsch rotation for the take, by the camera's own rotation, and per
    frame)."""

    def f(x):
        return None if x is None or not np.isfinite(x) else round(float(x), 2)

    F, K = ref.valid.shape
    out = {
        "views": list(ref.names), "files": list(ref.views.files), "frames": int(F), "keypoints": int(K),
        "calibration": str(ref.calibration.source),
        "up_axis": ref.up_axis, "up_tilt_deg": f(ref.up_tilt_deg), "ankle_floor_mm": f(ref.floor_mm),
        "valid_keypoints": int(ref.valid.sum()), "valid_percent": f(ref.valid.mean() * 100),
        "frames_all_valid": int(ref.valid.all(axis=1).sum()),
        "valid_per_keypoint": {n: int(ref.valid[:, k].sum()) for k, n in enumerate(KEYPOINTS)},
        "views_per_valid_keypoint": f(ref.agree.sum(axis=0)[ref.valid].mean()) if ref.valid.any() else None,
        "reprojection_px": {"mean": f(np.nanmean(ref.reprojection_px)) if ref.valid.any() else None,
                            "median": f(np.nanmedian(ref.reprojection_px)) if ref.valid.any() else None},
    }
    lengths = bone_lengths(ref.positions)
    out["bones_mm"] = {name: {"mean": f(np.nanmean(x)), "std": f(np.nanstd(x)), "n": int(np.isfinite(x).sum())}
                       for name, x in lengths.items() if np.isfinite(x).any()}
    y_up = reference_in_y_up(ref)
    per_view = {}
    for v, name in enumerate(ref.names):
        has_pose = np.all(np.isfinite(ref.views.points[v, ..., :2]), axis=(-1, -2))
        used = ref.agree[v] & ref.valid
        e = ref.view_reprojection_px[v]
        block = {
            "frames_with_pose": int(has_pose.sum()),
            "frames_compared": int((has_pose & ref.valid[:, PELVIS]).sum()),
            "keypoints_with_reference": int((has_pose[:, None] & ref.valid).sum()),
            "keypoints_agreeing": int(used.sum()),
            "frames_swapped": int(ref.swapped[v].sum()),
            "reprojection_px_agreeing": f(np.nanmean(e[used])) if used.any() else None,
            "reprojection_px_all": f(np.nanmean(e[np.isfinite(e)])) if np.isfinite(e).any() else None,
        }
        world = blazepose_world_mm(ref, v)
        if np.isfinite(world).any():
            M = view_to_y_up(ref, name)
            seq = compare_root_relative(world, y_up, ref.valid, "sequence")
            cam = compare_root_relative(world @ M.T, y_up, ref.valid, "none")
            frame = compare_root_relative(world, y_up, ref.valid, "frame")
            angle = np.degrees(np.arccos(np.clip((np.trace(seq.rotation @ M.T) - 1) / 2, -1, 1)))
            block["blazepose_world_mpjpe_mm"] = {
                "sequence_kabsch": f(seq.mpjpe_mm), "camera_rotation": f(cam.mpjpe_mm),
                "per_frame_procrustes": f(frame.mpjpe_mm), "n": seq.n, "frames": seq.frames,
                "kabsch_vs_camera_rotation_deg": f(angle),
                "per_keypoint_sequence_kabsch": {k: f(x) for k, x in seq.per_keypoint_mm.items()},
            }
            wl = bone_lengths(world)
            block["blazepose_bones_mean_mm"] = {n: f(np.nanmean(x)) for n, x in wl.items() if np.isfinite(x).any()}
        per_view[name] = block
    out["per_view"] = per_view
    out["params"] = {"outlier_torso_fraction": ref.outlier, "min_score": ref.min_score, "floor_percentile": FLOOR_PERCENTILE,
                     "root": KEYPOINTS[PELVIS]}
    return out
