"""Foot locking at transition seams: planted feet stay put, a two-bone IK bends the legs to match.

Blending two aligned clips interpolates the root and every joint rotation, so a foot that is planted in
both clips still slides by the residual misalignment of the two windows (the seams of an unlocked walk
skid about 3x more than the original clips). Here:

1. **Contacts** come from the *source* frames the walk shows (height + speed of the ankle in its own
   clip, which is what the animator captured), not from the output, where the skid to be removed would
   hide them.
2. Every contact run of an ankle that overlaps a seam (a transition blend) is **locked**: its horizontal
   position stays where the run began (the height follows the output, so heel roll is kept). After the
   run the correction fades out with the C^1 blend weight over ``ease`` frames, so the swing starts
   without a pop.
3. A **two-bone IK** (hip, knee, ankle) reaches each target: the knee's interior angle by the law of
   cosines, then a shortest-arc hip rotation onto the target; the ankle keeps its global orientation (the
   sole stays as it was). Only the leg's rotations change; the root path is untouched.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from ..mocap import Motion, Skeleton
from ..mocap.kinematics import forward_kinematics
from .blend import blend_weight


def leg_chains(skeleton: Skeleton) -> list[tuple[int, int, int]]:
    """(hip, knee, ankle) joint triples: an ankle is a joint named ``*foot*`` or ``*ankle*`` (not a
    toe) whose parent and grandparent exist."""
    out = []
    for j, name in enumerate(skeleton.names):
        low = name.lower()
        if ("foot" in low or "ankle" in low) and "toe" not in low:
            knee = int(skeleton.parents[j])
            hip = int(skeleton.parents[knee]) if knee >= 0 else -1
            if hip >= 0:
                out.append((hip, knee, j))
    return out


def source_contacts(graph, frames: np.ndarray, ankles: list[int], leg: float,
                    height_tol: float = 0.12, speed_tol: float = 0.6) -> np.ndarray:
    """(T, F) bool: ankle f of database frame ``frames[t]`` is planted in its clip: within
    ``height_tol * leg`` of the lowest ankle height of these frames and moving horizontally slower than
    ``speed_tol * leg`` per second (central difference inside the clip)."""
    clip = graph.frame_clip_
    N = graph.n_frames
    prv = np.where((frames > 0) & (clip[np.maximum(frames - 1, 0)] == clip[frames]), frames - 1, frames)
    nxt = np.where((frames < N - 1) & (clip[np.minimum(frames + 1, N - 1)] == clip[frames]), frames + 1, frames)
    T = len(frames)
    pos = forward_kinematics(graph.motion(np.concatenate([prv, frames, nxt])), return_matrices=False)[0][:, ankles]
    p_prev, p, p_next = pos[:T], pos[T : 2 * T], pos[2 * T :]
    dt = np.maximum(nxt - prv, 1)[:, None] / graph.fps
    speed = np.linalg.norm((p_next - p_prev)[..., [0, 2]], axis=-1) / dt
    floor = np.percentile(p[..., 1], 2)
    return (p[..., 1] < floor + height_tol * leg) & (speed < speed_tol * leg)


def _runs(mask: np.ndarray) -> list[tuple[int, int]]:
    d = np.diff(np.concatenate([[0], mask.astype(np.int8), [0]]))
    return list(zip(np.flatnonzero(d == 1), np.flatnonzero(d == -1)))


def _axis_angle(axis: np.ndarray, angle: np.ndarray) -> np.ndarray:
    n = np.linalg.norm(axis, axis=-1, keepdims=True)
    axis = np.where(n > 1e-12, axis / np.maximum(n, 1e-12), np.array([1.0, 0.0, 0.0]))
    return Rotation.from_rotvec(axis * angle[:, None]).as_matrix()


def two_bone_ik(hip: np.ndarray, knee: np.ndarray, ankle: np.ndarray, target: np.ndarray,
                pole: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Global rotations (Q_hip, Q_knee) (F, 3, 3) that move the ankle of the chain onto ``target``
    (as near as the leg reaches): the lower leg turns by ``Q_knee`` about the knee, then the whole leg by
    ``Q_hip`` about the hip. ``pole`` is the knee hinge axis used when the leg is straight."""
    l1 = np.linalg.norm(knee - hip, axis=-1)
    l2 = np.linalg.norm(ankle - knee, axis=-1)
    u, v = hip - knee, ankle - knee
    cur = np.arccos(np.clip(np.sum(u * v, -1) / np.maximum(l1 * l2, 1e-12), -1, 1))
    d = np.clip(np.linalg.norm(target - hip, axis=-1), np.abs(l1 - l2) + 1e-6, (l1 + l2) * 0.9999)
    new = np.arccos(np.clip((l1**2 + l2**2 - d**2) / np.maximum(2 * l1 * l2, 1e-12), -1, 1))
    axis = np.cross(u, v)
    straight = np.linalg.norm(axis, axis=-1) < 1e-6 * np.maximum(l1 * l2, 1e-12)
    axis[straight] = pole[straight]
    # rotating v about u x v by +delta opens the knee's interior angle by delta
    Qk = _axis_angle(axis, new - cur)
    a1 = knee + np.einsum("fij,fj->fi", Qk, v)
    x, y = a1 - hip, target - hip
    x /= np.maximum(np.linalg.norm(x, axis=-1, keepdims=True), 1e-12)
    y /= np.maximum(np.linalg.norm(y, axis=-1, keepdims=True), 1e-12)
    Qh = _axis_angle(np.cross(x, y), np.arctan2(np.linalg.norm(np.cross(x, y), axis=-1), np.sum(x * y, -1)))
    return Qh, Qk


def lock_feet(motion: Motion, contacts: np.ndarray, seam: np.ndarray, chains: list[tuple[int, int, int]],
              ease: int = 6) -> tuple[Motion, dict]:
    """``motion`` with the ankles of ``chains`` held still during every contact run (``contacts`` (T, F))
    that overlaps a ``seam`` frame. Returns the motion and a summary (runs locked, frames touched)."""
    T = motion.n_frames
    if not chains or T < 2:
        return motion, {"runs_locked": 0, "frames_adjusted": 0}
    pos, glob = forward_kinematics(motion)
    rot = motion.rotations.copy()
    parents = motion.skeleton.parents
    w_out = blend_weight(np.arange(ease), ease)  # 1 -> 0, C^1
    runs_locked, touched = 0, np.zeros(T, bool)
    for f, (h, kn, a) in enumerate(chains):
        orig = pos[:, a]
        target = orig.copy()
        active = np.zeros(T, bool)
        for s, e in _runs(contacts[:, f]):
            if not seam[s:e].any():
                continue
            runs_locked += 1
            target[s:e, [0, 2]] = orig[s, [0, 2]]
            active[s:e] = True
            off = orig[s, [0, 2]] - orig[e - 1, [0, 2]]
            m = min(ease, T - e)
            if m > 0 and not active[e : e + m].any():
                target[e : e + m, [0, 2]] += off[None, :] * w_out[:m, None]
                active[e : e + m] = True
        idx = np.flatnonzero(active & (np.linalg.norm(target - orig, axis=-1) > 1e-9))
        if not len(idx):
            continue
        touched[idx] = True
        pole = glob[idx, kn][:, :, 0]  # knee's local x axis: the hinge of a typical BVH leg
        Qh, Qk = two_bone_ik(pos[idx, h], pos[idx, kn], pos[idx, a], target[idx], pole)
        Gh = Qh @ glob[idx, h]
        Gk = Qh @ Qk @ glob[idx, kn]
        ph = parents[h]
        Gp = glob[idx, ph] if ph >= 0 else np.broadcast_to(np.eye(3), Gh.shape)
        local_h = np.swapaxes(Gp, -1, -2) @ Gh
        local_k = np.swapaxes(Gh, -1, -2) @ Gk
        local_a = np.swapaxes(Gk, -1, -2) @ glob[idx, a]  # the foot keeps its global orientation
        for j, m in ((h, local_h), (kn, local_k), (a, local_a)):
            q = Rotation.from_matrix(m).as_quat()
            q *= np.where(np.sum(q * rot[idx, j], -1) < 0, -1.0, 1.0)[:, None]  # same hemisphere as before
            rot[idx, j] = q
        # the other leg's chain reads glob of its own joints only, so sequential legs do not interact
    out = Motion(motion.skeleton, rot, None, motion.fps, root_positions=motion.root_positions)
    return out, {"runs_locked": runs_locked, "frames_adjusted": int(touched.sum())}
