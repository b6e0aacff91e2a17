"""Library frames projected to 2D at a viewpoint relative to the character's facing, and the
joint-angle features compared with a video frame's 2D pose (thesis 5.2.3.1).

Viewpoint: azimuth ``az`` (degrees, the renderer's convention: 0 = in front of the character, +90 =
at its left side) and elevation ``el`` (degrees, positive = looking down), both relative to the
character's facing *in that frame*; the projection is orthographic with the renderer's camera axes
(x = image column to the right, y = image row downwards), so a perspective video frame and the
projected library agree on every bone's image direction up to the (small) perspective distortion.

Features (thesis: "the angle information between the connecting joints ... avoids the issues of
scaling and length of limbs"): for every bone of :data:`.keypoints.BONES`, the image direction as the
unit vector (cos a, sin a) of its angle a. Squared distance between two such vectors is
``2 - 2 cos(a - a')``, a monotone function of the angle difference that a kd-tree can index.
"""

from __future__ import annotations

import math

import numpy as np

from .keypoints import BONE_INDEX, KP

N_FEATURES = 2 * len(BONE_INDEX)


def view_rotation(azimuth_deg: float, elevation_deg: float) -> np.ndarray:
    """(3, 3) world-to-camera rotation of a camera at ``azimuth_deg`` / ``elevation_deg`` relative to a
    character facing +Z (rows: image right, image down, viewing direction)."""
    from ..render.camera import look_at_rotation

    a, e = math.radians(azimuth_deg), math.radians(elevation_deg)
    back = np.array([math.cos(e) * math.sin(a), math.sin(e), math.cos(e) * math.cos(a)])
    return look_at_rotation(back, np.zeros(3))


def facing_normalised(points: np.ndarray, facing: np.ndarray) -> np.ndarray:
    """(F, K, 3) points rotated about +Y by ``-facing`` (radians, per frame) around the pelvis, so every
    frame's character faces +Z with its pelvis above the origin."""
    c, s = np.cos(facing), np.sin(facing)
    rel = points - points[:, KP["pelvis"]][:, None, :] * np.array([1.0, 0.0, 1.0])
    x = c[:, None] * rel[..., 0] - s[:, None] * rel[..., 2]
    z = s[:, None] * rel[..., 0] + c[:, None] * rel[..., 2]
    return np.stack([x, rel[..., 1], z], axis=-1)


def facing_of_keypoints(points: np.ndarray) -> np.ndarray:
    """(F,) facing angle (radians about +Y, 0 = +Z) from the hips and shoulders, as
    :func:`vidstyle.mocap.motion.facing_directions` does for a skeleton."""
    across = (points[:, KP["left_hip"]] - points[:, KP["right_hip"]]
              + points[:, KP["left_shoulder"]] - points[:, KP["right_shoulder"]])
    fwd = np.cross(across, [0.0, 1.0, 0.0])
    return np.arctan2(fwd[:, 0], fwd[:, 2])


def project(points_normalised: np.ndarray, azimuth_deg: float, elevation_deg: float) -> np.ndarray:
    """(F, K, 2) orthographic image coordinates (column, row directions) of facing-normalised points."""
    return (points_normalised @ view_rotation(azimuth_deg, elevation_deg).T)[..., :2]


def angle_features(points2d: np.ndarray) -> np.ndarray:
    """(F, 2B) float32 bone-direction features of 2D keypoints (F, 15, 2) (column, row). A bone of
    zero length (both ends on one pixel) gets the zero vector, which is equally far from every
    direction.

    The neck is taken as the midpoint of the shoulders and the pelvis as the midpoint of the hips, for
    the library and for every query alike: pose estimators place "the neck" and "the pelvis"
    differently (BlazePose has neither and uses those midpoints; the mocap keypoints sit above the
    shoulder and hip lines: on the validation frames 0.5 torso lengths of systematic neck error and a
    30-degree bias of the pelvis-hip bones), while shoulders and hips mean the same to all of them."""
    points2d = np.array(points2d, dtype=np.float64, copy=True)
    points2d[:, KP["neck"]] = 0.5 * (points2d[:, KP["left_shoulder"]] + points2d[:, KP["right_shoulder"]])
    points2d[:, KP["pelvis"]] = 0.5 * (points2d[:, KP["left_hip"]] + points2d[:, KP["right_hip"]])
    v = points2d[:, BONE_INDEX[:, 1]] - points2d[:, BONE_INDEX[:, 0]]
    n = np.linalg.norm(v, axis=-1, keepdims=True)
    u = np.where(n > 1e-9, v / np.maximum(n, 1e-12), 0.0)
    return u.reshape(len(points2d), -1).astype(np.float32)


def relative_azimuth(camera_center: np.ndarray, pelvis: np.ndarray, facing: np.ndarray) -> np.ndarray:
    """Azimuth (degrees, in (-180, 180]) of a camera at ``camera_center`` seen from the character's pelvis
    (F, 3) relative to its facing (F,) radians."""
    d = np.asarray(camera_center, float)[None, :] - pelvis
    ang = np.arctan2(d[:, 0], d[:, 2]) - facing
    return np.degrees(np.angle(np.exp(1j * ang)))
