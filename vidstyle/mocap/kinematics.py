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


def _levels(parents: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
    """Joints grouped by depth (roots first): ``[(joints, their parents), ...]``, file order within a level."""
    depth = np.zeros(len(parents), dtype=np.int64)
    for j, p in enumerate(parents):  # parents[j] < j: a parent's depth is known before its children's
        if p >= 0:
            depth[j] = depth[p] + 1
    return [(idx, parents[idx]) for idx in (np.flatnonzero(depth == d) for d in range(int(depth.max(initial=-1)) + 1))]


def forward_kinematics(motion: Motion, return_matrices: bool = True) -> tuple[np.ndarray, np.ndarray | None]:
    """Global joint positions ``(F, J, 3)`` and global rotation matrices ``(F, J, 3, 3)``.

    With ``return_matrices=False`` the second item is ``None`` (and the rotations of joints without
    children, which no position needs, are not composed).

    The work runs one depth level of the hierarchy at a time (all joints of a level at once) on
    component-major arrays (``(3, 3, J, F)`` matrices, ``(3, J, F)`` positions: every operand contiguous),
    with the arithmetic of the per-joint ``glob[p] @ local[j]`` and ``x_p + glob[p] @ t_j`` written out:
    each entry ``(a0 * b0 + a1 * b1) + a2 * b2``, the order numpy's matmul and einsum sum in, so the
    results are those of the matrix products.
    """
    q = motion.rotations
    F, J = q.shape[:2]
    parents = motion.skeleton.parents
    x, y, z, w = np.ascontiguousarray(q.transpose(2, 1, 0))  # (J, F) each
    # quat_to_matrix's entries, the same operations in the same order
    xx, yy, zz = x * x, y * y, z * z
    xy, xz, yz = x * y, x * z, y * z
    wx, wy, wz = w * x, w * y, w * z
    local = np.empty((3, 3, J, F))
    local[0, 0] = 1 - 2 * (yy + zz)
    local[0, 1] = 2 * (xy - wz)
    local[0, 2] = 2 * (xz + wy)
    local[1, 0] = 2 * (xy + wz)
    local[1, 1] = 1 - 2 * (xx + zz)
    local[1, 2] = 2 * (yz - wx)
    local[2, 0] = 2 * (xz - wy)
    local[2, 1] = 2 * (yz + wx)
    local[2, 2] = 1 - 2 * (xx + yy)
    trans = np.ascontiguousarray(motion.translations.transpose(2, 1, 0))  # (3, J, F)
    has_child = np.zeros(J, dtype=bool)
    has_child[parents[parents >= 0]] = True
    glob = np.empty((3, 3, J, F))
    pos = np.empty((3, J, F))
    for d, (idx, pidx) in enumerate(_levels(parents)):
        if d == 0:  # roots
            glob[:, :, idx] = local[:, :, idx]
            pos[:, idx] = trans[:, idx]
            continue
        gp = glob[:, :, pidx]  # (3, 3, n, F): the parents' global rotations
        t = trans[:, idx]
        pos[:, idx] = pos[:, pidx] + ((gp[:, 0] * t[0] + gp[:, 1] * t[1]) + gp[:, 2] * t[2])
        if not return_matrices:  # a joint's rotation is needed only by its children
            keep = has_child[idx]
            if not keep.any():
                continue
            if not keep.all():
                idx, gp = idx[keep], gp[:, :, keep]
        lc = local[:, :, idx]
        glob[:, :, idx] = (gp[:, 0, None] * lc[None, 0] + gp[:, 1, None] * lc[None, 1]) + gp[:, 2, None] * lc[None, 2]
    positions = np.ascontiguousarray(pos.transpose(2, 1, 0))
    if not return_matrices:
        return positions, None
    return positions, np.ascontiguousarray(glob.transpose(3, 2, 0, 1))


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
