"""A library clip filmed by the reconstruction's camera model: the known answer the reconstruct tests
compare with (tests/test_reconstruct.py, tests/test_reconstruct_footlock.py)."""

from __future__ import annotations

import math

import numpy as np

W, H, FPS = 320, 240, 20.0


def filmed(clip_path, yaw: float, place: np.ndarray, elevation: float = 10.0, cam_height: float = 20.0,
           focal: float | None = None):
    """A library clip turned by ``yaw``, moved to ``place`` (floor) and filmed at 20 fps by the
    reconstruction's camera model (``focal``: its focal length in pixels, default the default lens):
    (true world keypoints (T, 15, 3), 2D (T, 15, 2), azimuth (T,))."""
    from vidstyle.augmg.keypoints import KP
    from vidstyle.augmg.projection import facing_of_keypoints, relative_azimuth
    from vidstyle.mocap import read_bvh
    from vidstyle.mocap.keypoints import keypoint_positions
    from vidstyle.mocap.motion import Motion
    from vidstyle.mocap.placement import yaw_quat
    from vidstyle.mocap.quat import qmul
    from vidstyle.reconstruct.camera import default_intrinsics, intrinsics_for_focal, project
    from vidstyle.reconstruct.core import camera_rotation

    m = read_bvh(clip_path)
    step = int(round(m.fps / FPS))
    q = m.rotations[::step].copy()
    q[:, 0] = qmul(yaw_quat(np.full(len(q), yaw)), q[:, 0])
    c, s = math.cos(yaw), math.sin(yaw)
    r = m.root_positions[::step]
    root = np.column_stack([c * r[:, 0] + s * r[:, 2], r[:, 1], -s * r[:, 0] + c * r[:, 2]])
    root[:, [0, 2]] += place - root[0, [0, 2]]
    pts = keypoint_positions(Motion(m.skeleton, q, fps=FPS, root_positions=root))
    cam = np.array([0.0, cam_height, 0.0])
    K = default_intrinsics(W, H) if focal is None else intrinsics_for_focal(W, H, focal)
    uv = project((pts - cam) @ camera_rotation(elevation).T, K)
    az = relative_azimuth(cam, pts[:, KP["pelvis"]], facing_of_keypoints(pts))
    return pts, uv, az
