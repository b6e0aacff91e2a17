"""The blended pose bent toward the observed keypoints (Tautges 2012, section 3.5, in a local linear model).

The blend of a frame's neighbours (:mod:`.core`, step 3) averages what the library holds; nothing in it
looks at the frame's keypoints again. Tautges minimises, per frame, a control term (the pose against the
sensors) plus a prior (the pose against its weighted neighbours), not in the full pose space but in a
local linear model spanned by the neighbours (his weighted PCA; Chai and Hodgins). Here:

- the pose of frame ``t`` is ``q(a) = exp(sum_i a_i d_i) q_b`` per joint, with ``q_b`` the blended local
  rotation and ``d_i = log(q_i q_b^-1)`` the rotation vector from the blend to neighbour ``i`` (so ``a = 0``
  is the blend and ``a = e_i`` neighbour ``i``'s own joint rotations, every joint moving together);
- the control residual is the frame's 15 keypoints, facing-normalised and projected orthographically at
  the frame's azimuth and elevation (as the index projects the library), against the observed keypoints
  after the confidence-weighted scale and translation that fit them best, each keypoint weighted by the
  square root of its confidence, all divided by the observed pose's weighted spread (unit-free);
- the prior residual is ``sqrt(prior) * a`` (the pose stays near the blend of the coherent neighbours;
  ``prior`` large: the blend itself).

The sum of squares is minimised by Levenberg-Marquardt steps from ``a = 0``, all frames at once: the
Jacobian by forward differences (one forward kinematics of every frame per coefficient), a step kept for
a frame only where it lowers that frame's cost. Frames without a pose keep the blend.
"""

from __future__ import annotations

import numpy as np


def _residuals(skeleton, q: np.ndarray, obs_xy: np.ndarray, obs_w: np.ndarray, R: np.ndarray) -> np.ndarray:
    """(T, 30) control residuals of local rotations ``q`` (T, J, 4) (module docstring)."""
    from ..augmg.projection import facing_normalised, facing_of_keypoints
    from ..mocap.keypoints import keypoint_positions
    from ..mocap.motion import Motion
    from .core import similarity_fit

    T = len(q)
    pts = keypoint_positions(Motion(skeleton, q, root_positions=np.zeros((T, 3))))
    norm = facing_normalised(pts, facing_of_keypoints(pts))
    model = np.einsum("tij,tkj->tki", R, norm)[..., :2]
    r, do = similarity_fit(model, obs_xy, obs_w)
    w = obs_w
    spread = np.sqrt(np.maximum((w * (do * do).sum(-1)).sum(-1), 1e-12))
    return (np.sqrt(w)[..., None] * r).reshape(T, -1) / spread[:, None]


def refine_poses(skeleton, q_blend: np.ndarray, q_neighbours: np.ndarray, active: np.ndarray, obs_xy: np.ndarray,
                 obs_w: np.ndarray, azimuth_deg: np.ndarray, elevation_deg: float, prior: float = 1.0,
                 iterations: int = 5, step: float = 1e-3, damping: float = 1e-3) -> np.ndarray:
    """(T, J, 4) local rotations: ``q_blend`` (T, J, 4) moved within the span of ``q_neighbours``
    (T, I, J, 4; ``active`` (T, I) which of them exist) toward the observed keypoints ``obs_xy`` (T, 15, 2)
    with confidences ``obs_w`` (T, 15) at ``azimuth_deg`` (T,) and ``elevation_deg`` (module docstring).
    Frames whose weights are all zero keep the blend."""
    from scipy.spatial.transform import Rotation

    from ..mocap.quat import compose
    from .core import view_rotations

    q_blend = np.asarray(q_blend, dtype=np.float64)
    T, J, _ = q_blend.shape
    I = q_neighbours.shape[1]
    if q_neighbours.shape != (T, I, J, 4) or active.shape != (T, I):
        raise ValueError(f"neighbours (T, I, J, 4) and active (T, I) must match the blend's {q_blend.shape}")
    obs_xy = np.where(np.isfinite(obs_xy), obs_xy, 0.0)
    obs_w = np.where(np.all(np.isfinite(obs_xy), -1), np.clip(obs_w, 0, None), 0.0)
    frames = obs_w.sum(-1) > 0
    if not frames.any() or I == 0:
        return q_blend.copy()
    rb = Rotation.from_quat(q_blend.reshape(-1, 4))
    rn = Rotation.from_quat(np.asarray(q_neighbours, dtype=np.float64).reshape(-1, 4))
    rb_rep = Rotation.from_quat(np.repeat(q_blend[:, None], I, axis=1).reshape(-1, 4))
    d = (rn * rb_rep.inv()).as_rotvec().reshape(T, I, J, 3)
    d = np.where(active[:, :, None, None], d, 0.0)
    R = view_rotations(azimuth_deg, elevation_deg)
    qb = rb.as_quat()

    def pose(a: np.ndarray) -> np.ndarray:
        delta = Rotation.from_rotvec(np.einsum("ti,tijk->tjk", a, d).reshape(-1, 3))
        return compose(delta.as_quat(), qb).reshape(T, J, 4)  # (delta * rb).as_quat(), to the bit

    sp = np.sqrt(max(float(prior), 0.0))

    def cost_and_res(a):
        r = _residuals(skeleton, pose(a), obs_xy, obs_w, R)
        full = np.concatenate([r, sp * a], axis=1)
        return (full * full).sum(1), full

    a = np.zeros((T, I))
    cost, res = cost_and_res(a)
    for _ in range(int(iterations)):
        jac = np.empty(res.shape + (I,))
        for i in range(I):
            b = a.copy()
            b[:, i] += step
            _, r2 = cost_and_res(b)
            jac[:, :, i] = (r2 - res) / step
        jt = np.transpose(jac, (0, 2, 1))
        A = jt @ jac + damping * np.eye(I)[None]
        g = np.einsum("tik,tk->ti", jt, res)
        delta = -np.linalg.solve(A, g[..., None])[..., 0]
        delta = np.where(active & frames[:, None], delta, 0.0)
        c2, r2 = cost_and_res(a + delta)
        better = c2 < cost
        a = np.where(better[:, None], a + delta, a)
        cost = np.where(better, c2, cost)
        res = np.where(better[:, None], r2, res)
        if not better.any():
            break
    return pose(a)
