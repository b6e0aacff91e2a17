"""Forward kinematics, vectorised over frames.

For joint j with parent p: ``R_j = R_p * r_j`` and ``x_j = x_p + R_p t_j``, where ``r_j`` and ``t_j`` are
the local rotation and translation (see :mod:`vidstyle.mocap.motion`). Joints are in file order, so one
pass over joints (each a batched operation over all frames) suffices.
"""

from __future__ import annotations

import numpy as np

from .motion import Motion


def quat_to_matrix(q: np.ndarray) -> np.ndarray:
    """(..., 4) unit quaternions (x, y, z, w) -> (..., 3, 3) rotation matrices."""
    x, y, z, w = np.moveaxis(q, -1, 0)
    xx, yy, zz = x * x, y * y, z * z
    xy, xz, yz = x * y, x * z, y * z
    wx, wy, wz = w * x, w * y, w * z
    m = np.empty(q.shape[:-1] + (3, 3))
    m[..., 0, 0] = 1 - 2 * (yy + zz)
    m[..., 0, 1] = 2 * (xy - wz)
    m[..., 0, 2] = 2 * (xz + wy)
    m[..., 1, 0] = 2 * (xy + wz)
    m[..., 1, 1] = 1 - 2 * (xx + zz)
    m[..., 1, 2] = 2 * (yz - wx)
    m[..., 2, 0] = 2 * (xz - wy)
    m[..., 2, 1] = 2 * (yz + wx)
    m[..., 2, 2] = 1 - 2 * (xx + yy)
    return m


def forward_kinematics(motion: Motion, return_matrices: bool = True) -> tuple[np.ndarray, np.ndarray | None]:
    """Global joint positions ``(F, J, 3)`` and global rotation matrices ``(F, J, 3, 3)``.

    With ``return_matrices=False`` the second item is ``None`` (the matrices are still computed
    internally, as the positions need them).
    """
    local = quat_to_matrix(motion.rotations)  # (F, J, 3, 3)
    trans = motion.translations
    parents = motion.skeleton.parents
    F, J = local.shape[:2]
    glob = np.empty_like(local)
    pos = np.empty((F, J, 3))
    for j in range(J):
        p = parents[j]
        if p < 0:
            glob[:, j] = local[:, j]
            pos[:, j] = trans[:, j]
        else:
            glob[:, j] = glob[:, p] @ local[:, j]
            pos[:, j] = pos[:, p] + np.einsum("fij,fj->fi", glob[:, p], trans[:, j])
    return pos, (glob if return_matrices else None)


def global_positions(motion: Motion) -> np.ndarray:
    """(F, J, 3) global joint positions, joints in file order."""
    return forward_kinematics(motion, return_matrices=False)[0]


def end_site_positions(motion: Motion, matrices: np.ndarray | None = None,
                       positions: np.ndarray | None = None) -> tuple[list[int], np.ndarray]:
    """Global positions of End Sites: (joint indices that own one, (F, E, 3) positions)."""
    if matrices is None or positions is None:
        positions, matrices = forward_kinematics(motion)
    owners = sorted(motion.skeleton.end_sites)
    if not owners:
        return [], np.zeros((motion.n_frames, 0, 3))
    offs = np.stack([motion.skeleton.end_sites[j] for j in owners])  # (E, 3)
    ends = positions[:, owners] + np.einsum("feij,ej->fei", matrices[:, owners], offs)
    return owners, ends
