"""Forward kinematics.

For joint j with parent p: ``R_j = R_p * r_j`` and ``x_j = x_p + R_p t_j``, where ``r_j`` and ``t_j`` are
the local rotation and translation (see :mod:`vidstyle.mocap.motion`). Joints are in file order
(``parents[j] < j``), so one pass over the joints suffices.

:func:`forward_kinematics` runs a compiled loop (numba, :func:`vidstyle.compiled.compile_kernel`) frame by
frame and joint by joint; :func:`forward_kinematics_numpy`, vectorised over frames one depth level of the
hierarchy at a time, is its reference: the two give the same bits (the same float64 operations in the same
order, no fused multiply-add). The compiled loop matters because the callers are many small calls (a style
fit's or a reconstruction's thousands of candidate poses), where numpy's per-operation overhead dominated.
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
    children, which no position needs, are not composed). The compiled :func:`_fk_loop`; without numba
    :func:`forward_kinematics_numpy` (the same bits).
    """
    kernel = _fk_kernel()
    if kernel is None:  # pragma: no cover - numba is a dependency
        return forward_kinematics_numpy(motion, return_matrices)
    q = np.ascontiguousarray(motion.rotations, dtype=np.float64)
    trans = np.ascontiguousarray(motion.translations, dtype=np.float64)
    F, J = q.shape[:2]
    parents = np.ascontiguousarray(motion.skeleton.parents, dtype=np.int64)
    if return_matrices:
        need = np.ones(J, dtype=np.bool_)
        glob = np.empty((F, J, 3, 3))
    else:  # roots and joints with children: the rotations some position needs
        need = parents < 0
        need[parents[parents >= 0]] = True
        glob = np.empty((1, J, 3, 3))  # one frame's, reused
    pos = np.empty((F, J, 3))
    kernel(q, trans, parents, need, pos, glob)
    return pos, (glob if return_matrices else None)


def _fk_loop(q, trans, parents, need, pos, glob):
    # compiled by numba: forward_kinematics_numpy frame by frame, joint by joint, the same float64 operations
    # in the same order: quat_to_matrix's entries, x_p + ((G_p[:, 0] t0 + G_p[:, 1] t1) + G_p[:, 2] t2) and
    # G_p L entry by entry as ((a0 b0 + a1 b1) + a2 b2). glob holds every frame's rotations (F, J, 3, 3),
    # or one frame's (1, J, 3, 3) reused when only positions are wanted; need[j]: compose joint j's rotation
    F, J = q.shape[0], q.shape[1]
    every = glob.shape[0] == F
    L = np.empty((3, 3))
    for f in range(F):
        g = f if every else 0
        for j in range(J):
            p = parents[j]
            if p < 0:
                for a in range(3):
                    pos[f, j, a] = trans[f, j, a]
            else:
                t0, t1, t2 = trans[f, j, 0], trans[f, j, 1], trans[f, j, 2]
                for a in range(3):
                    pos[f, j, a] = pos[f, p, a] + ((glob[g, p, a, 0] * t0 + glob[g, p, a, 1] * t1) + glob[g, p, a, 2] * t2)
            if not need[j]:
                continue
            x, y, z, w = q[f, j, 0], q[f, j, 1], q[f, j, 2], q[f, j, 3]
            xx, yy, zz = x * x, y * y, z * z
            xy, xz, yz = x * y, x * z, y * z
            wx, wy, wz = w * x, w * y, w * z
            L[0, 0] = 1 - 2 * (yy + zz)
            L[0, 1] = 2 * (xy - wz)
            L[0, 2] = 2 * (xz + wy)
            L[1, 0] = 2 * (xy + wz)
            L[1, 1] = 1 - 2 * (xx + zz)
            L[1, 2] = 2 * (yz - wx)
            L[2, 0] = 2 * (xz - wy)
            L[2, 1] = 2 * (yz + wx)
            L[2, 2] = 1 - 2 * (xx + yy)
            if p < 0:
                for a in range(3):
                    for b in range(3):
                        glob[g, j, a, b] = L[a, b]
            else:
                for a in range(3):
                    for b in range(3):
                        glob[g, j, a, b] = (glob[g, p, a, 0] * L[0, b] + glob[g, p, a, 1] * L[1, b]) + glob[g, p, a, 2] * L[2, b]


_KERNEL: list = []


def _fk_kernel():
    """:func:`_fk_loop` compiled (:func:`vidstyle.compiled.compile_kernel`), or None without numba."""
    if not _KERNEL:
        from ..compiled import compile_kernel

        _KERNEL.append(compile_kernel(_fk_loop))
    return _KERNEL[0]


def forward_kinematics_numpy(motion: Motion, return_matrices: bool = True) -> tuple[np.ndarray, np.ndarray | None]:
    """:func:`forward_kinematics` in numpy (its reference and its fallback without numba).

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
