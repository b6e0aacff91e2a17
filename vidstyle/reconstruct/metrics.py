"""Error metrics of a reconstructed 3D motion against the truth (issue 29), and foot contacts.

Inputs are keypoint positions ``pred`` and ``true``, each (F, 15, 3) in the order of
:data:`vidstyle.formats.keypoints.KEYPOINTS`, in millimetres (the figures are then in mm; any other
unit gives figures in that unit), with the world's up axis ``up`` (default 1: +Y up; the floor is a
plane of constant up-coordinate). A frame is *valid* when all 15 keypoints of both ``pred`` and
``true`` are finite; every metric uses the valid frames only and :func:`summarise` reports how many
were excluded.

Horizontal coordinates: for up axis ``k`` the floor plane has coordinates ``(a, b) = (k+1, k+2) mod 3``
(with Y up: ``(Z, X)``). A *yaw* ``theta`` is a right-handed rotation about +up, i.e. the 2D rotation
``(a, b) -> (a cos theta - b sin theta, a sin theta + b cos theta)`` (with Y up it turns +Z towards +X,
increasing the facing angle ``atan2(x, z)`` of :mod:`vidstyle.augmg.projection` by ``theta``).

Metrics (all means are over valid frames and all 15 keypoints unless said otherwise):

- **MPJPE** (:func:`mpjpe`): mean Euclidean keypoint error after :func:`align_sequence`, the one yaw and
  one floor-plane translation (the up coordinate is left alone by default: a reconstruction must get
  its height above the floor right) that minimise the summed squared error over all valid frames and
  keypoints (closed form: 2D Kabsch on the horizontal components, no reflection).
- **Root-relative MPJPE** (:func:`mpjpe_root_relative`): every frame of both motions has its root
  (pelvis) subtracted, then one yaw per sequence about the (now common) root minimises the summed
  squared error; the mean includes the root itself (error 0), as Human3.6M's protocol 1 does.
- **PA-MPJPE** (:func:`pa_mpjpe`): per frame, the similarity transform (rotation without reflection,
  uniform scale, translation; Umeyama 1991) of ``pred`` that minimises the squared error to ``true``.
- **Acceleration error** (:func:`acceleration_error`): with the second difference
  ``a[t] = x[t-1] - 2 x[t] + x[t+1]`` (units/frame^2) of the sequence-aligned ``pred`` and of ``true``,
  the mean of ``||a_pred[t] - a_true[t]||`` over keypoints and the triplets ``t-1, t, t+1`` of three
  valid frames (a triplet touching an invalid frame is skipped).
- **Foot skate** (:func:`foot_skate`): the *slide* of a foot (ankle keypoint) from frame ``t`` to
  ``t+1`` is its horizontal displacement; foot skate is the mean slide (units/frame) over the
  (foot, t) pairs where the foot is *planted* in both frames. Planted by default means "within
  ``height_tol`` of the sequence's floor" (height only: a sliding foot is fast, so a speed criterion
  would hide exactly what is measured); alternatively the caller passes contact flags, e.g. the
  truth's :func:`foot_contacts`, so that the prediction is scored where the performer's foot was down.
- **Library bound** (:func:`library_bound`): per frame, the PA-MPJPE of the library frame nearest the
  truth after that alignment, the floor of what one library pose per frame can reach.
- **Floor** of a sequence: the ``floor_percentile`` (default 5) percentile of the up-coordinate of both
  ankles over the valid frames (the ankle keypoint sits above the sole, so this is the height of a
  planted ankle, not of the ground).
- **Leg length** (:func:`leg_length`): median over valid frames and both sides of
  ``|hip - knee| + |knee - ankle|``. Default tolerances are fractions of it, so contacts work in any
  unit: height tolerance 0.1 leg lengths (~ 85 mm for an adult), speed tolerance 0.5 leg lengths/s
  (~ 0.4 m/s, well below a swinging foot's 2-4 m/s during walking).
- **Foot contacts** (:func:`foot_contacts`): a foot is in contact in frame ``t`` when its height above
  the floor is at most ``height_tol`` and its horizontal speed (central difference over the valid
  neighbouring frames, one-sided at the ends and next to invalid frames, times ``fps``) is below
  ``speed_tol``. Invalid frames (any keypoint not finite) have no contact.
"""

from __future__ import annotations

import math

import numpy as np

from ..formats.keypoints import KEYPOINTS

_KP = {k: i for i, k in enumerate(KEYPOINTS)}
PELVIS = _KP["pelvis"]
#: left and right ankle keypoint indices, the columns of :func:`foot_contacts`
ANKLES = (_KP["left_ankle"], _KP["right_ankle"])
_LEGS = ((_KP["left_hip"], _KP["left_knee"], _KP["left_ankle"]),
         (_KP["right_hip"], _KP["right_knee"], _KP["right_ankle"]))

DEFAULT_FLOOR_PERCENTILE = 5.0
#: default contact tolerances, in leg lengths and leg lengths per second
DEFAULT_HEIGHT_TOL_LEGS = 0.1
DEFAULT_SPEED_TOL_LEGS = 0.5


def _points(points: np.ndarray, name: str = "points") -> np.ndarray:
    p = np.asarray(points, dtype=np.float64)
    if p.ndim != 3 or p.shape[1:] != (len(KEYPOINTS), 3):
        raise ValueError(f"{name} must be an (F, {len(KEYPOINTS)}, 3) array, got shape {p.shape}")
    return p


def _pair(pred: np.ndarray, true: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    p, t = _points(pred, "pred"), _points(true, "true")
    if p.shape != t.shape:
        raise ValueError(f"pred and true must have one shape, got {p.shape} and {t.shape}")
    return p, t


def _check_up(up: int) -> int:
    if up not in (0, 1, 2):
        raise ValueError(f"up must be an axis 0, 1 or 2, got {up!r}")
    return int(up)


def _horizontal_axes(up: int) -> tuple[int, int]:
    return (up + 1) % 3, (up + 2) % 3


def valid_frames(pred: np.ndarray, true: np.ndarray | None = None) -> np.ndarray:
    """(F,) bool: the frames where every keypoint of ``pred`` (and of ``true``, if given) is finite."""
    if true is None:
        return np.isfinite(_points(pred, "pred")).all(axis=(1, 2))
    p, t = _pair(pred, true)
    return np.isfinite(p).all(axis=(1, 2)) & np.isfinite(t).all(axis=(1, 2))


def rotate_yaw(points: np.ndarray, yaw: float, up: int = 1) -> np.ndarray:
    """``points`` (..., 3) rotated by ``yaw`` (radians, right-handed about +up; see the module text)
    about the origin."""
    up = _check_up(up)
    a, b = _horizontal_axes(up)
    p = np.asarray(points, dtype=np.float64)
    out = p.copy()
    c, s = math.cos(yaw), math.sin(yaw)
    out[..., a] = c * p[..., a] - s * p[..., b]
    out[..., b] = s * p[..., a] + c * p[..., b]
    return out


def _yaw_kabsch(p: np.ndarray, q: np.ndarray, a: int, b: int) -> float:
    """The yaw minimising sum ||R p - q||^2 over the rows of p, q (N, 3), horizontal components only."""
    cos_term = np.sum(p[:, a] * q[:, a] + p[:, b] * q[:, b])
    sin_term = np.sum(p[:, a] * q[:, b] - p[:, b] * q[:, a])
    if cos_term == 0.0 and sin_term == 0.0:
        return 0.0
    return float(math.atan2(sin_term, cos_term))


def align_sequence(pred: np.ndarray, true: np.ndarray, up: int = 1,
                   vertical: bool = False) -> tuple[np.ndarray, float, np.ndarray]:
    """The yaw and translation of ``pred`` that best match ``true`` over the whole sequence.

    Minimises ``sum ||R(yaw) p + d - q||^2`` over the valid frames' keypoints, where ``d`` (3,) has a
    zero up component unless ``vertical`` (then the up offset is fitted too: the mean up difference).
    Returns ``(aligned, yaw, d)``: ``aligned`` (F, 15, 3) is ``R(yaw) pred + d`` for every frame (invalid
    frames stay as they were transformed, NaN included), ``yaw`` radians, ``d`` (3,) in input units.
    With no valid frame: ``pred`` unchanged, yaw 0, ``d`` zero.
    """
    p, t = _pair(pred, true)
    up = _check_up(up)
    a, b = _horizontal_axes(up)
    ok = valid_frames(p, t)
    if not ok.any():
        return p.copy(), 0.0, np.zeros(3)
    P = p[ok].reshape(-1, 3)
    Q = t[ok].reshape(-1, 3)
    cp, cq = P.mean(axis=0), Q.mean(axis=0)
    yaw = _yaw_kabsch(P - cp, Q - cq, a, b)
    d = cq - rotate_yaw(cp, yaw, up)
    if not vertical:
        d[up] = 0.0
    return rotate_yaw(p, yaw, up) + d, yaw, d


def _mean_error(p: np.ndarray, t: np.ndarray, ok: np.ndarray) -> float:
    if not ok.any():
        return math.nan
    return float(np.linalg.norm(p[ok] - t[ok], axis=-1).mean())


def mpjpe(pred: np.ndarray, true: np.ndarray, up: int = 1, vertical: bool = False) -> float:
    """Mean per-keypoint position error (input units) after :func:`align_sequence`; NaN when no frame is
    valid."""
    p, t = _pair(pred, true)
    aligned, _, _ = align_sequence(p, t, up, vertical)
    return _mean_error(aligned, t, valid_frames(p, t))


def mpjpe_root_relative(pred: np.ndarray, true: np.ndarray, root: int = PELVIS, up: int = 1) -> float:
    """Mean per-keypoint error (input units) with each frame's ``root`` keypoint (default pelvis)
    subtracted from both motions and one per-sequence yaw about the root (fitted over the valid frames);
    the mean includes the root keypoint. NaN when no frame is valid."""
    p, t = _pair(pred, true)
    up = _check_up(up)
    if not 0 <= root < len(KEYPOINTS):
        raise ValueError(f"root must be a keypoint index in [0, {len(KEYPOINTS)}), got {root}")
    ok = valid_frames(p, t)
    if not ok.any():
        return math.nan
    pr = p[ok] - p[ok][:, root:root + 1]
    tr = t[ok] - t[ok][:, root:root + 1]
    a, b = _horizontal_axes(up)
    yaw = _yaw_kabsch(pr.reshape(-1, 3), tr.reshape(-1, 3), a, b)
    return float(np.linalg.norm(rotate_yaw(pr, yaw, up) - tr, axis=-1).mean())


def procrustes_align(pred: np.ndarray, true: np.ndarray) -> np.ndarray:
    """(F, N, 3) ``pred`` mapped per frame by the similarity transform ``s R x + d`` (R a rotation,
    det +1; s >= 0; Umeyama 1991) that minimises the squared distance to ``true`` (F, N, 3). Frames
    with a non-finite value in either come back all NaN."""
    p = np.asarray(pred, dtype=np.float64)
    t = np.asarray(true, dtype=np.float64)
    if p.ndim != 3 or p.shape[-1] != 3 or p.shape != t.shape:
        raise ValueError(f"pred and true must be (F, N, 3) arrays of one shape, got {p.shape} and {t.shape}")
    out = np.full_like(p, np.nan)
    ok = np.isfinite(p).all(axis=(1, 2)) & np.isfinite(t).all(axis=(1, 2))
    if not ok.any():
        return out
    P, T = p[ok], t[ok]
    mp, mt = P.mean(axis=1, keepdims=True), T.mean(axis=1, keepdims=True)
    Pc, Tc = P - mp, T - mt
    cov = np.einsum("fni,fnj->fij", Tc, Pc) / P.shape[1]  # (F, 3, 3): sum q p^T / N
    U, S, Vt = np.linalg.svd(cov)
    sign = np.sign(np.linalg.det(U @ Vt))
    sign[sign == 0] = 1.0
    D = np.ones((len(P), 3))
    D[:, 2] = sign
    R = U @ (D[:, :, None] * Vt)  # U diag(D) Vt
    var_p = (Pc ** 2).sum(axis=(1, 2)) / P.shape[1]
    s = np.where(var_p > 0, (S * D).sum(axis=1) / np.where(var_p > 0, var_p, 1.0), 0.0)
    out[ok] = s[:, None, None] * np.einsum("fij,fnj->fni", R, Pc) + mt
    return out


def pa_mpjpe(pred: np.ndarray, true: np.ndarray) -> float:
    """Mean per-keypoint error (input units) after the per-frame similarity alignment of
    :func:`procrustes_align`; NaN when no frame is valid."""
    p, t = _pair(pred, true)
    ok = valid_frames(p, t)
    return _mean_error(procrustes_align(p, t), t, ok)


def library_bound(library: np.ndarray, true: np.ndarray, chunk: int = 8192) -> np.ndarray:
    """(F,) per frame of ``true`` (F, N, 3), the smallest PA-MPJPE (:func:`pa_mpjpe`'s per-frame
    similarity alignment, ``true``'s units) any frame of ``library`` (L, N, 3; any unit, any facing)
    reaches: what a method that outputs one library pose per frame could reach at best, so how much of a
    reconstruction's error the library's coverage alone explains. NaN for a frame of ``true`` with a
    non-finite value; library frames with one are never chosen. Brute force, ``chunk`` library frames
    at a time (L x F similarity fits)."""
    lib = np.asarray(library, dtype=np.float64)
    t = np.asarray(true, dtype=np.float64)
    if lib.ndim != 3 or t.ndim != 3 or lib.shape[1:] != t.shape[1:] or t.shape[-1] != 3:
        raise ValueError(f"library (L, N, 3) and true (F, N, 3) must share N, got {lib.shape} and {t.shape}")
    if chunk < 1:
        raise ValueError(f"chunk must be >= 1, got {chunk}")
    lib = lib[np.isfinite(lib).all(axis=(1, 2))]
    out = np.full(len(t), np.nan)
    if not len(lib):
        return out
    for f in np.flatnonzero(np.isfinite(t).all(axis=(1, 2))):
        best = np.inf
        for a in range(0, len(lib), chunk):
            part = lib[a:a + chunk]
            target = np.broadcast_to(t[f], part.shape)
            err = np.linalg.norm(procrustes_align(part, target) - target, axis=-1).mean(axis=1)
            best = min(best, float(err.min()))
        out[f] = best
    return out


def _second_differences(points: np.ndarray) -> np.ndarray:
    return points[:-2] - 2.0 * points[1:-1] + points[2:]


def acceleration_triplets(pred: np.ndarray, true: np.ndarray) -> np.ndarray:
    """(max(F-2, 0),) bool: triplet ``t`` (frames t, t+1, t+2) is used by :func:`acceleration_error`."""
    ok = valid_frames(pred, true)
    if len(ok) < 3:
        return np.zeros(0, dtype=bool)
    return ok[:-2] & ok[1:-1] & ok[2:]


def acceleration_error(pred: np.ndarray, true: np.ndarray, up: int = 1) -> float:
    """Mean ``||second difference of aligned pred - second difference of true||`` (input units per
    frame^2) over keypoints and valid frame triplets; ``pred`` is first :func:`align_sequence`-aligned
    (its yaw rotates the accelerations; the translation cancels). NaN with no valid triplet."""
    p, t = _pair(pred, true)
    trip = acceleration_triplets(p, t)
    if not trip.any():
        return math.nan
    aligned, _, _ = align_sequence(p, t, up)
    err = _second_differences(aligned)[trip] - _second_differences(t)[trip]
    return float(np.linalg.norm(err, axis=-1).mean())


def leg_length(points: np.ndarray) -> float:
    """Median over valid frames and both legs of ``|hip - knee| + |knee - ankle|`` (input units); NaN
    when no frame is valid."""
    p = _points(points)
    ok = valid_frames(p)
    if not ok.any():
        return math.nan
    q = p[ok]
    lengths = [np.linalg.norm(q[:, h] - q[:, k], axis=-1) + np.linalg.norm(q[:, k] - q[:, a], axis=-1)
               for h, k, a in _LEGS]
    return float(np.median(np.concatenate(lengths)))


def floor_height(points: np.ndarray, up: int = 1, floor_percentile: float = DEFAULT_FLOOR_PERCENTILE) -> float:
    """The sequence's floor (see the module text): a low percentile of both ankles' up-coordinate over
    the valid frames; NaN when no frame is valid."""
    p = _points(points)
    up = _check_up(up)
    if not 0.0 <= floor_percentile <= 100.0:
        raise ValueError(f"floor_percentile must be in [0, 100], got {floor_percentile}")
    ok = valid_frames(p)
    if not ok.any():
        return math.nan
    return float(np.percentile(p[ok][:, list(ANKLES), up], floor_percentile))


def _tolerance(value: float | None, default_legs: float, points: np.ndarray, name: str) -> float:
    if value is None:
        return default_legs * leg_length(points)
    value = float(value)
    if not value >= 0.0:
        raise ValueError(f"{name} must be a non-negative number, got {value}")
    return value


def near_floor(points: np.ndarray, up: int = 1, height_tol: float | None = None,
               floor_percentile: float = DEFAULT_FLOOR_PERCENTILE) -> np.ndarray:
    """(F, 2) bool, left and right ankle: the frame is valid and the ankle's height above
    :func:`floor_height` is at most ``height_tol`` (input units; default 0.1 :func:`leg_length`)."""
    p = _points(points)
    up = _check_up(up)
    ok = valid_frames(p)
    out = np.zeros((len(p), 2), dtype=bool)
    if not ok.any():
        return out
    tol = _tolerance(height_tol, DEFAULT_HEIGHT_TOL_LEGS, p, "height_tol")
    floor = floor_height(p, up, floor_percentile)
    h = p[:, list(ANKLES), up] - floor
    with np.errstate(invalid="ignore"):
        out[ok] = h[ok] <= tol
    return out


def horizontal_speed(points: np.ndarray, fps: float, up: int = 1) -> np.ndarray:
    """(F, 2) horizontal speed of the left and right ankle (input units per second): central difference
    between the valid neighbouring frames, one-sided where only one neighbour is valid; NaN for an
    invalid frame or one with no valid neighbour."""
    p = _points(points)
    up = _check_up(up)
    fps = float(fps)
    if not (math.isfinite(fps) and fps > 0):
        raise ValueError(f"fps must be a positive number, got {fps}")
    a, b = _horizontal_axes(up)
    ok = valid_frames(p)
    h = p[:, list(ANKLES)][:, :, [a, b]]  # (F, 2, 2)
    F = len(p)
    speed = np.full((F, 2), np.nan)
    if F < 2:
        return speed
    prev_ok = np.zeros(F, dtype=bool)
    prev_ok[1:] = ok[:-1]
    next_ok = np.zeros(F, dtype=bool)
    next_ok[:-1] = ok[1:]
    lo = np.where(prev_ok, np.arange(F) - 1, np.arange(F))
    hi = np.where(next_ok, np.arange(F) + 1, np.arange(F))
    use = ok & (hi > lo)
    disp = h[hi[use]] - h[lo[use]]
    speed[use] = np.linalg.norm(disp, axis=-1) / (hi[use] - lo[use])[:, None] * fps
    return speed


def foot_contacts(points: np.ndarray, fps: float, up: int = 1, height_tol: float | None = None,
                  speed_tol: float | None = None,
                  floor_percentile: float = DEFAULT_FLOOR_PERCENTILE) -> np.ndarray:
    """(F, 2) bool, left and right ankle: in contact with the floor (see the module text): near the floor
    (:func:`near_floor`; ``height_tol`` in input units, default 0.1 leg lengths) and horizontal speed
    (:func:`horizontal_speed`) below ``speed_tol`` (input units per second, default 0.5 leg lengths per
    second). ``points`` (F, 15, 3) in any unit, ``fps`` frames per second."""
    p = _points(points)
    speed = horizontal_speed(p, fps, up)
    low = near_floor(p, up, height_tol, floor_percentile)
    if not low.any():
        return low
    tol = _tolerance(speed_tol, DEFAULT_SPEED_TOL_LEGS, p, "speed_tol")
    with np.errstate(invalid="ignore"):
        return low & (speed < tol)


def foot_slides(points: np.ndarray, contacts: np.ndarray | None = None, up: int = 1,
                height_tol: float | None = None,
                floor_percentile: float = DEFAULT_FLOOR_PERCENTILE) -> np.ndarray:
    """(F-1, 2) horizontal displacement (input units) of the left and right ankle from frame ``t`` to
    ``t+1`` where the foot is planted in both frames, NaN elsewhere. Planted: ``contacts`` (F, 2) bool if
    given, else :func:`near_floor` with ``height_tol``; invalid frames are never planted."""
    p = _points(points)
    up = _check_up(up)
    F = len(p)
    if contacts is None:
        planted = near_floor(p, up, height_tol, floor_percentile)
    else:
        planted = np.asarray(contacts)
        if planted.shape != (F, 2):
            raise ValueError(f"contacts must be an ({F}, 2) bool array, got shape {planted.shape}")
        planted = planted.astype(bool) & valid_frames(p)[:, None]
    if F < 2:
        return np.zeros((0, 2))
    a, b = _horizontal_axes(up)
    h = p[:, list(ANKLES)][:, :, [a, b]]
    slide = np.linalg.norm(h[1:] - h[:-1], axis=-1)
    return np.where(planted[1:] & planted[:-1], slide, np.nan)


def foot_skate(points: np.ndarray, contacts: np.ndarray | None = None, up: int = 1,
               height_tol: float | None = None,
               floor_percentile: float = DEFAULT_FLOOR_PERCENTILE) -> float:
    """Mean slide per frame (input units/frame) of planted feet over the counted (foot, frame pair)s of
    :func:`foot_slides` (same arguments); NaN when no foot is planted in two consecutive frames."""
    s = foot_slides(points, contacts, up, height_tol, floor_percentile)
    n = np.isfinite(s)
    return float(s[n].mean()) if n.any() else math.nan


def _num(x: float) -> float | None:
    return float(x) if math.isfinite(x) else None


def summarise(pred: np.ndarray, true: np.ndarray, fps: float, up: int = 1) -> dict:
    """Every figure of the module for ``pred`` against ``true`` (F, 15, 3) in mm at ``fps``, as a dict
    of JSON-serialisable numbers (an undefined figure, e.g. with no valid frame, is ``None``):

    ``frames``, ``valid_frames``, ``excluded_frames`` (frames with a non-finite value in either);
    ``mpjpe_mm``, ``mpjpe_root_relative_mm``, ``pa_mpjpe_mm``; ``yaw_deg`` and ``translation_mm`` [3]
    of :func:`align_sequence`; ``acceleration_error_mm_per_frame2`` over ``acceleration_triplets``;
    foot skate in mm/frame of the prediction with its own height-based planting
    (``foot_skate_mm_per_frame``, over ``foot_skate_pairs`` (foot, frame pair)s), of the prediction
    where the truth's :func:`foot_contacts` say a foot is down (``foot_skate_true_contacts_mm_per_frame``
    over ``foot_skate_true_contacts_pairs``), and of the truth itself with its own contacts
    (``true_foot_skate_mm_per_frame``, the floor of what the truth's contact labels allow). Frames not
    valid in both are treated as missing in both.
    """
    p, t = _pair(pred, true)
    ok = valid_frames(p, t)
    p = np.where(ok[:, None, None], p, np.nan)
    t = np.where(ok[:, None, None], t, np.nan)
    aligned, yaw, d = align_sequence(p, t, up)
    trip = acceleration_triplets(p, t)
    true_contacts = foot_contacts(t, fps, up)
    own = foot_slides(p, None, up)
    at_true = foot_slides(p, true_contacts, up)
    true_own = foot_slides(t, true_contacts, up)

    def mean(s: np.ndarray) -> float | None:
        n = np.isfinite(s)
        return float(s[n].mean()) if n.any() else None

    return {
        "frames": len(p),
        "valid_frames": int(ok.sum()),
        "excluded_frames": int((~ok).sum()),
        "mpjpe_mm": _num(_mean_error(aligned, t, ok)),
        "mpjpe_root_relative_mm": _num(mpjpe_root_relative(p, t, up=up)),
        "pa_mpjpe_mm": _num(pa_mpjpe(p, t)),
        "yaw_deg": float(math.degrees(yaw)),
        "translation_mm": [float(x) for x in d],
        "acceleration_error_mm_per_frame2": _num(acceleration_error(p, t, up)),
        "acceleration_triplets": int(trip.sum()),
        "foot_skate_mm_per_frame": mean(own),
        "foot_skate_pairs": int(np.isfinite(own).sum()),
        "foot_skate_true_contacts_mm_per_frame": mean(at_true),
        "foot_skate_true_contacts_pairs": int(np.isfinite(at_true).sum()),
        "true_foot_skate_mm_per_frame": mean(true_own),
    }
