"""Static pinhole camera placed relative to a performer's facing direction (numpy only: importable
without OpenCV).

Conventions (OpenCV): camera coordinates have +x to the right of the image, +y down, +z forward (the
viewing direction); ``x_cam = R @ x_world + t``; pixel ``(u, v) = (K @ x_cam)[:2] / z`` with ``u`` the
column and ``v`` the row, integer values at pixel centres (``cx = (W - 1) / 2``). The world is +Y up
and a performer at facing angle 0 looks along +Z (the BVH convention of :mod:`vidstyle.mocap`).

Views are azimuths relative to the performer's facing direction: 0 = in front of the performer, looking
at them (``"front"``), +90 = at the performer's left side (``"left"``), -90 = at their right side
(``"right"``), 180 = behind. Elevation raises the camera above the look-at point (degrees, positive =
looking down).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

VIEWS = {"front": 0.0, "left": 90.0, "right": -90.0, "back": 180.0}
DEFAULT_VFOV_DEG = 40.0
UP = np.array([0.0, 1.0, 0.0])


def parse_view(view: str | float | int) -> float:
    """``"front" | "left" | "right" | "back"`` or a number (degrees, also as a string) -> azimuth in degrees."""
    if isinstance(view, (int, float, np.integer, np.floating)):
        az = float(view)
    else:
        key = str(view).strip().lower()
        if key in VIEWS:
            az = VIEWS[key]
        else:
            try:
                az = float(key)
            except ValueError:
                raise ValueError(
                    f"view must be front, left, right, back or an azimuth in degrees, got {view!r}"
                ) from None
    if not math.isfinite(az):
        raise ValueError(f"view azimuth must be finite, got {view!r}")
    return az


def intrinsics(size: tuple[int, int], vfov_deg: float = DEFAULT_VFOV_DEG) -> np.ndarray:
    """(3, 3) pinhole K for an image ``size = (W, H)`` with vertical field of view ``vfov_deg``."""
    W, H = size
    f = (H / 2.0) / math.tan(math.radians(vfov_deg) / 2.0)
    return np.array([[f, 0.0, (W - 1) / 2.0], [0.0, f, (H - 1) / 2.0], [0.0, 0.0, 1.0]])


def look_at_rotation(eye: np.ndarray, target: np.ndarray) -> np.ndarray:
    """World-to-camera rotation for a camera at ``eye`` looking at ``target`` with +Y up in the image."""
    fwd = np.asarray(target, float) - np.asarray(eye, float)
    fwd /= np.linalg.norm(fwd)
    right = np.cross(fwd, UP)
    n = np.linalg.norm(right)
    if n < 1e-8:
        raise ValueError("camera looks straight up or down; the image's up direction is undefined")
    right /= n
    down = np.cross(fwd, right)
    return np.stack([right, down, fwd])


def circular_median(angles: np.ndarray) -> float:
    """Median of angles (radians) around their circular mean; robust to wrap-around."""
    angles = np.asarray(angles, dtype=np.float64)
    if angles.size == 0:
        return 0.0
    mean = math.atan2(np.sin(angles).mean(), np.cos(angles).mean())
    rel = np.angle(np.exp(1j * (angles - mean)))
    return float(mean + np.median(rel))


@dataclass
class Camera:
    """Static pinhole camera. ``x_cam = R @ x_world + t``; see the module docstring for conventions.

    Attributes: ``K`` (3, 3), ``R`` (3, 3), ``t`` (3,), ``azimuth_deg`` (relative to the performer's
    facing), ``elevation_deg``, ``size`` (W, H) in pixels, ``facing_deg`` (the performer's facing angle
    the azimuth is relative to, about +Y, 0 = +Z).
    """

    K: np.ndarray
    R: np.ndarray
    t: np.ndarray
    azimuth_deg: float = 0.0
    elevation_deg: float = 0.0
    size: tuple[int, int] = (160, 120)
    facing_deg: float = 0.0
    extra: dict = field(default_factory=dict, repr=False)

    def __post_init__(self) -> None:
        self.K = np.asarray(self.K, dtype=np.float64).reshape(3, 3)
        self.R = np.asarray(self.R, dtype=np.float64).reshape(3, 3)
        self.t = np.asarray(self.t, dtype=np.float64).reshape(3)
        W, H = (int(v) for v in self.size)
        if W < 2 or H < 2:
            raise ValueError(f"image size must be at least 2x2, got {W}x{H}")
        self.size = (W, H)

    # ------------------------------------------------------------------ geometry
    @property
    def width(self) -> int:
        return self.size[0]

    @property
    def height(self) -> int:
        return self.size[1]

    @property
    def focal(self) -> float:
        return float(self.K[1, 1])

    @property
    def center(self) -> np.ndarray:
        """Camera position in world coordinates."""
        return -self.R.T @ self.t

    def to_camera(self, points: np.ndarray) -> np.ndarray:
        """World points (..., 3) -> camera coordinates (..., 3)."""
        return np.asarray(points, dtype=np.float64) @ self.R.T + self.t

    def project(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """World points (..., 3) -> pixel coordinates (..., 2) (x = column, y = row) and depth (...)."""
        cam = self.to_camera(points)
        z = cam[..., 2]
        with np.errstate(divide="ignore", invalid="ignore"):
            uvw = cam @ self.K.T
            uv = uvw[..., :2] / z[..., None]
        return uv, z

    # ------------------------------------------------------------------ constructors
    @classmethod
    def for_view(
        cls,
        motion,
        view: str | float = "front",
        elevation_deg: float = 10.0,
        distance: float | None = None,
        size: tuple[int, int] = (160, 120),
        vfov_deg: float = DEFAULT_VFOV_DEG,
        margin: float = 0.08,
        positions: np.ndarray | None = None,
    ) -> Camera:
        """Static camera looking at the clip's centre from ``view`` (see :func:`parse_view`), relative
        to the performer's median facing angle over the clip.

        ``distance`` (world units, from the look-at point) ``None`` places the camera just far enough
        that every joint of every frame, padded by the body's thickness, lies inside the image with a
        ``margin`` (fraction of the image) to spare. ``positions`` (F, N, 3) may be passed to avoid
        recomputing forward kinematics (default: all joints and End Sites).
        """
        from ..mocap import end_site_positions, forward_kinematics
        from .body import skeleton_height

        az = parse_view(view)
        el = float(elevation_deg)
        if not math.isfinite(el) or abs(el) >= 89.0:
            raise ValueError(f"elevation must be between -89 and 89 degrees, got {elevation_deg}")
        W, H = (int(v) for v in size)
        if W < 2 or H < 2:
            raise ValueError(f"image size must be at least 2x2, got {W}x{H}")
        if motion.n_frames == 0:
            raise ValueError("cannot place a camera for a motion with no frames")
        if positions is None:
            pos, mats = forward_kinematics(motion)
            _, ends = end_site_positions(motion, mats, pos)  # head top, finger tips, toes
            pos = np.concatenate([pos, ends], axis=1)
        else:
            pos = np.asarray(positions, float)
        pts = pos.reshape(-1, 3)
        pts = pts[np.all(np.isfinite(pts), axis=1)]
        if len(pts) == 0:
            raise ValueError("motion has no finite joint positions")
        facing = circular_median(motion.facing_angles())
        lo, hi = pts.min(axis=0), pts.max(axis=0)
        target = (lo + hi) / 2.0
        height = skeleton_height(motion.skeleton)
        pad = 0.09 * height  # thickness of the body around the joints (head, torso)

        ang = facing + math.radians(az)
        horiz = np.array([math.sin(ang), 0.0, math.cos(ang)])
        back = math.cos(math.radians(el)) * horiz + math.sin(math.radians(el)) * UP  # target -> camera
        R = look_at_rotation(target + back, target)
        K = intrinsics((W, H), vfov_deg)
        if distance is None:
            # camera at target + d * back: camera coordinates are R (p - target) + (0, 0, d)
            rel = (pts - target) @ R.T
            kx = (W / 2.0) / K[0, 0] * (1.0 - 2 * margin)
            ky = (H / 2.0) / K[1, 1] * (1.0 - 2 * margin)
            need_x = (np.abs(rel[:, 0]) + pad) / kx - rel[:, 2] + pad
            need_y = (np.abs(rel[:, 1]) + pad) / ky - rel[:, 2] + pad
            near = -rel[:, 2] + 2 * pad
            d = float(max(need_x.max(), need_y.max(), near.max(), 1e-6))
        else:
            d = float(distance)
            if not (math.isfinite(d) and d > 0):
                raise ValueError(f"distance must be positive, got {distance}")
        eye = target + d * back
        return cls(K, R, -R @ eye, az, el, (W, H), math.degrees(facing), {"target": target, "distance": d})
