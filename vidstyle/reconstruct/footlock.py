"""Planted feet held in place by two-bone inverse kinematics of the legs: :func:`pin_feet`.

Moving the root (:meth:`.core.Reconstructor._lock_feet`) can hold one planted foot, not two whose
blended stance changes under them; this moves the legs instead. Per foot (the legs are the chains
``hip -> knee -> ankle`` of :func:`vidstyle.mocap.keypoints.keypoint_joints`: on the CMU layout
``LeftUpLeg``, ``LeftLeg``, ``LeftFoot`` and the right ones; joints between them are carried along
unchanged) and per maximal run ``s..e`` of frames where ``contacts`` says it is planted:

1. **Target**: the ankle's world position at frame ``s`` horizontally (X, Z), and the median of its
   height (Y) over ``s..e`` (with ``floor``: at least ``floor``). Every frame of the run aims the
   ankle at that one point (the blend windows around it: step 3).
2. **Two-bone IK** per frame (hip ``H``, knee ``K``, ankle ``A`` from forward kinematics; thigh length
   ``a = |K - H|``, shin length ``b = |A - K|``; target ``P``, ``d = |P - H|`` clamped to
   ``[|a - b| + eps, a + b - eps]`` with ``eps = EXTENSION_EPS * (a + b)``, so an unreachable target is
   met by the leg at full extension less ``eps``, pointing at it):

   a. the knee turns about its current bend axis ``n = (H - K) x (A - K)`` (normalised; where the leg
      is straight, the mean bend axis of the well-bent frames in the knee's own frame, else any axis
      across the shin) by ``theta1 - theta0``: ``theta0`` the current inner knee angle, ``theta1`` the
      one at which ``|A - H| = d`` (law of cosines);
   b. the hip turns by the least rotation taking the new ``A - H`` onto ``P - H``;
   c. the hip turns about ``P - H`` until the knee lies in the plane of ``H``, ``P`` and the current
      knee ``K`` (the pole), on ``K``'s side.

   With ``D`` the hip's world rotation (b then c) and ``R`` the knee's (a), the new local rotations are
   ``hip = G(parent of hip)^-1 D G(hip)``, ``knee = G(parent of knee)^-1 R G(knee)`` and
   ``ankle = (D R G(parent of ankle))^-1 G(ankle)`` (``G`` the world rotations before the IK): bone
   lengths stay (only rotations change), and the foot keeps its world orientation, so the toes do not
   swing. Nothing else changes.
3. **Blend**: over ``blend_frames`` frames before and after a run, the pinned local rotations of the
   three joints are slerped with the unpinned ones at weight ``1 - k / (blend_frames + 1)`` at ``k``
   frames from the run (1 inside it). There the IK target moves with the unpinned ankle ``A(t)``,
   offset as at the run's boundary: ``target + A(t) - A(e)`` after a run ending at ``e``,
   ``target + A(t) - A(s)`` before one starting at ``s``; so the correction the run needed is faded
   out (in) while the foot lifts off (lands), instead of the lifting foot being pulled back to where
   it stood. A frame in the windows of two runs (a gap shorter than two windows) aims at the mean of
   the two, weighted by the two weights, at the larger weight. Frames outside every run and window are
   returned bit for bit.
4. **Leash** (with ``max_offset``): a target farther than ``max_offset`` from the unpinned ankle
   ``A(t)`` is moved onto the sphere of that radius about ``A(t)``, towards the target: the IK never
   moves an ankle further than that (a wrong contact or root path is not turned into a contorted
   leg; the foot then trails the pose at that distance and slides by what exceeds it).

Everything is vectorised over frames (scipy :class:`~scipy.spatial.transform.Rotation`); the Python
loops are over the two feet and a leg's three joints only (10^4 frames: under a second).
"""

from __future__ import annotations

import math

import numpy as np
from scipy.spatial.transform import Rotation

#: an unreachable target is met by the leg stretched to (1 - EXTENSION_EPS) of its length
EXTENSION_EPS = 1e-6
#: the knee's bend axis is taken from the pose where the sine of its inner angle exceeds this
STRAIGHT_SIN = 1e-6
SIDES = ("left", "right")


def _path_up(parents: np.ndarray, j: int) -> list[int]:
    out = []
    while j >= 0:
        out.append(int(j))
        j = int(parents[j])
    return out


def leg_chains(skeleton) -> list[tuple[int, int, int]]:
    """``[(hip, knee, ankle)]`` joint indices of the left and right leg (:func:`keypoint_joints`);
    ValueError when a leg is not such a chain or the legs share a joint."""
    from ..mocap.keypoints import keypoint_joints

    kj = keypoint_joints(skeleton)
    parents = np.asarray(skeleton.parents)
    chains = []
    for side in SIDES:
        m = [kj[f"{side}_{n}"] for n in ("hip", "knee", "ankle")]
        if any(x.end_site for x in m):
            raise ValueError(f"the {side} leg's keypoints are not all joints")
        hip, knee, ankle = (x.joint for x in m)
        if hip not in _path_up(parents, knee)[1:] or knee not in _path_up(parents, ankle)[1:]:
            raise ValueError(f"the {side} leg's joints {skeleton.names[hip]}, {skeleton.names[knee]}, "
                             f"{skeleton.names[ankle]} are not a chain from the hip down")
        chains.append((int(hip), int(knee), int(ankle)))
    if chains[0][0] in _path_up(parents, chains[1][0]) or chains[1][0] in _path_up(parents, chains[0][0]):
        raise ValueError("one leg's hip is inside the other leg")
    return chains


def _runs(planted: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Start and end (inclusive) frames of the maximal runs of True."""
    p = np.concatenate([[False], planted, [False]]).astype(np.int8)
    d = np.diff(p)
    return np.flatnonzero(d == 1), np.flatnonzero(d == -1) - 1


def bridge_gaps(planted: np.ndarray, max_gap: int) -> np.ndarray:
    """``planted`` (T,) or (T, feet) bool with every run of False of at most ``max_gap`` frames that has
    True on both sides (a lift between two planted runs, not the start or end of the take) set True."""
    p = np.asarray(planted, dtype=bool)
    if isinstance(max_gap, bool) or int(max_gap) != max_gap or max_gap < 0:
        raise ValueError(f"max_gap must be an integer >= 0, got {max_gap!r}")
    if p.ndim == 2:
        return np.stack([bridge_gaps(p[:, f], max_gap) for f in range(p.shape[1])], axis=1) if p.shape[1] else p.copy()
    if p.ndim != 1:
        raise ValueError(f"planted must be (T,) or (T, feet), got shape {p.shape}")
    out = p.copy()
    starts, ends = _runs(~p)
    for s, e in zip(starts.tolist(), ends.tolist()):
        if s > 0 and e < len(p) - 1 and e - s + 1 <= max_gap:
            out[s:e + 1] = True
    return out


def _run_medians(x: np.ndarray, starts: np.ndarray, ends: np.ndarray) -> np.ndarray:
    """np.median of ``x[s:e+1]`` for every run, at once (runs are disjoint and sorted)."""
    n = ends - starts + 1
    run_of = np.repeat(np.arange(len(starts)), n)
    frames = np.arange(int(n.sum())) - np.repeat(np.cumsum(n) - n - starts, n)  # s..e of every run
    vals = x[frames]
    order = np.lexsort((vals, run_of))
    v = vals[order]
    off = np.concatenate([[0], np.cumsum(n)[:-1]])
    return 0.5 * (v[off + (n - 1) // 2] + v[off + n // 2])


def _schedule(planted: np.ndarray, ankle: np.ndarray, targets: np.ndarray, starts: np.ndarray,
              ends: np.ndarray, blend_frames: int, creep: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Per frame the IK weight (T,) and target (T, 3) of one foot whose unpinned ankle is at ``ankle``
    (T, 3) (module docstring, step 3); with ``creep`` (T, 3) a run's target moves by ``creep[t] -
    creep[start]`` inside it, and the window after it starts from where the target ended."""
    T = len(planted)
    t = np.arange(T)
    if len(starts) == 0:
        return np.zeros(T), np.zeros((T, 3))
    B = int(blend_frames)
    last = len(starts) - 1
    prev = np.searchsorted(ends, t, side="right") - 1  # the last run ending at or before t
    nxt = np.searchsorted(starts, t, side="left")  # the first run starting at or after t
    pi, ni = np.maximum(prev, 0), np.minimum(nxt, last)
    w1 = np.where(prev >= 0, np.clip(1.0 - (t - ends[pi]) / (B + 1), 0.0, 1.0), 0.0)
    w2 = np.where(nxt <= last, np.clip(1.0 - (starts[ni] - t) / (B + 1), 0.0, 1.0), 0.0)
    ends_at = targets if creep is None else targets + creep[ends] - creep[starts]  # the target at a run's end
    # in a window the target moves with the foot, offset as at the run's end / start
    P1 = ends_at[pi] + ankle - ankle[ends[pi]]
    P2 = targets[ni] + ankle - ankle[starts[ni]]
    tot = np.maximum(w1 + w2, 1e-300)[:, None]
    inside = planted.astype(bool)
    run = np.maximum(np.searchsorted(starts, t, side="right") - 1, 0)
    held = targets[run] if creep is None else targets[run] + creep - creep[starts[run]]
    w = np.where(inside, 1.0, np.maximum(w1, w2))
    P = np.where(inside[:, None], held, (w1[:, None] * P1 + w2[:, None] * P2) / tot)
    return w, P


def _unit(v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    n = np.linalg.norm(v, axis=-1, keepdims=True)
    return v / np.where(n > 0, n, 1.0), n[..., 0]


def _between(u: np.ndarray, v: np.ndarray) -> Rotation:
    """The least rotations taking directions ``u`` onto ``v`` (N, 3) (opposite: a half turn about any
    axis across them)."""
    u, _ = _unit(u)
    v, _ = _unit(v)
    c = np.cross(u, v)
    s = np.linalg.norm(c, axis=-1)
    ang = np.arctan2(s, np.sum(u * v, axis=-1))
    axis = c / np.where(s > 0, s, 1.0)[:, None]
    flat = s <= 1e-12 * np.maximum(1.0, np.abs(np.sum(u * v, axis=-1)))
    if flat.any():  # parallel or opposite: any axis across u
        alt = np.cross(u[flat], np.array([1.0, 0.0, 0.0]))
        small = np.linalg.norm(alt, axis=-1) < 1e-6
        alt[small] = np.cross(u[flat][small], np.array([0.0, 0.0, 1.0]))
        axis[flat] = _unit(alt)[0]
    return Rotation.from_rotvec(axis * ang[:, None])


def _leg_ik(pos: np.ndarray, glob: Rotation, parent_of: dict, chain: tuple[int, int, int], frames: np.ndarray,
            P: np.ndarray) -> tuple[Rotation, Rotation, Rotation]:
    """New local rotations (hip, knee, ankle) over ``frames`` putting the ankle at ``P`` (step 2).
    ``pos`` (T, J, 3) and ``glob`` (a function of (frames, joint) -> Rotation) from forward kinematics."""
    hip, knee, ankle = chain
    H, K, A = pos[frames, hip], pos[frames, knee], pos[frames, ankle]
    G_knee = glob(frames, knee)
    h, s = H - K, A - K
    a, b = np.linalg.norm(h, axis=-1), np.linalg.norm(s, axis=-1)
    cr = np.cross(h, s)
    sin_ab = np.linalg.norm(cr, axis=-1)
    theta0 = np.arctan2(sin_ab, np.sum(h * s, axis=-1))
    bent = sin_ab > STRAIGHT_SIN * a * b
    n = cr / np.where(bent, sin_ab, 1.0)[:, None]
    if not bent.all():  # straight leg: the bend axis of the bent frames, in the knee's frame
        if bent.any():
            local = G_knee[bent].inv().apply(n[bent]).mean(axis=0)
        else:
            local = np.array([1.0, 0.0, 0.0])
        alt = G_knee[~bent].apply(np.broadcast_to(local, (int((~bent).sum()), 3)))
        sd = _unit(s[~bent])[0]
        alt = alt - np.sum(alt * sd, axis=-1, keepdims=True) * sd
        alt, an = _unit(alt)
        if np.any(an < 1e-9):
            fb = np.cross(sd, np.array([1.0, 0.0, 0.0]))
            fb2 = np.cross(sd, np.array([0.0, 0.0, 1.0]))
            fb = np.where(np.linalg.norm(fb, axis=-1, keepdims=True) > 1e-6, fb, fb2)
            alt = np.where((an < 1e-9)[:, None], _unit(fb)[0], alt)
        n[~bent] = alt
    reach = P - H
    u, dist = _unit(reach)
    eps = EXTENSION_EPS * (a + b)
    d = np.clip(dist, np.abs(a - b) + eps, a + b - eps)
    cos1 = (a * a + b * b - d * d) / np.maximum(2.0 * a * b, 1e-300)
    theta1 = np.arccos(np.clip(cos1, -1.0, 1.0))
    R = Rotation.from_rotvec(n * (theta1 - theta0)[:, None])  # (a) the knee, about the knee
    w1 = K + R.apply(s) - H
    nowhere = dist <= 0  # target at the hip: keep the leg's direction
    u = np.where(nowhere[:, None], _unit(w1)[0], u)
    Da = _between(w1, u)  # (b)
    k2 = Da.apply(K - H)
    k2p = k2 - np.sum(k2 * u, axis=-1, keepdims=True) * u
    pole = (K - H) - np.sum((K - H) * u, axis=-1, keepdims=True) * u
    tw = np.arctan2(np.sum(u * np.cross(k2p, pole), axis=-1), np.sum(k2p * pole, axis=-1))
    lk = np.linalg.norm(k2p, axis=-1) * np.linalg.norm(pole, axis=-1)
    tw = np.where(lk > 1e-12 * a * a, tw, 0.0)
    D = Rotation.from_rotvec(u * tw[:, None]) * Da  # (c) then the world rotation of the hip
    ph, pk, pa = parent_of[hip], parent_of[knee], parent_of[ankle]
    G_ph = glob(frames, ph) if ph >= 0 else Rotation.identity(len(frames))
    new_hip = G_ph.inv() * D * glob(frames, hip)
    new_knee = glob(frames, pk).inv() * R * G_knee
    new_ankle = (D * R * glob(frames, pa)).inv() * glob(frames, ankle)
    return new_hip, new_knee, new_ankle


def pin_feet(motion, contacts: np.ndarray, blend_frames: int = 3, floor: float | None = None,
             max_offset: float | None = None, height: float | None = None, creep: np.ndarray | None = None):
    """A new :class:`~vidstyle.mocap.motion.Motion` whose planted ankles stay where they were planted
    (module docstring); ``motion`` is not modified.

    ``contacts`` (T, 2) bool (or 0 / 1): left / right foot planted per frame; ``blend_frames`` >= 0
    frames of blending either side of a run; ``floor`` the lowest target ankle height (None: no limit);
    ``max_offset`` the leash (step 4; None: none), in the motion's length units; ``height`` (None: the
    run's median, step 1) the target ankle height of every run instead (the planted ankle height of a
    generated motion: :mod:`vidstyle.actionmodel`); ``creep`` (None: none) a (T, 3) path by which a planted
    ankle's target moves inside its run: at frame ``t`` of a run that began at ``s``, the target plus
    ``creep[t] - creep[s]`` (the reconstruction's relaxed root drift), and the blend window after the run
    starts from where the target ended. ValueError on a
    ``contacts`` of the wrong shape or values, a bad ``blend_frames``, ``floor`` or ``max_offset``, or a
    skeleton without two leg chains (:func:`leg_chains`).
    """
    from ..mocap.kinematics import forward_kinematics
    from ..mocap.motion import Motion

    T = motion.n_frames
    contacts = np.asarray(contacts)
    if contacts.shape != (T, 2):
        raise ValueError(f"contacts must be ({T}, 2) (frames, left/right), got {contacts.shape}")
    if contacts.dtype != bool:
        if not np.all(np.isin(contacts, (0, 1))):
            raise ValueError("contacts must be booleans (or 0 / 1)")
        contacts = contacts.astype(bool)
    if isinstance(blend_frames, bool) or int(blend_frames) != blend_frames or blend_frames < 0:
        raise ValueError(f"blend_frames must be an integer >= 0, got {blend_frames!r}")
    if floor is not None and not math.isfinite(float(floor)):
        raise ValueError(f"floor must be a finite number or None, got {floor!r}")
    if height is not None and not math.isfinite(float(height)):
        raise ValueError(f"height must be a finite number or None, got {height!r}")
    if max_offset is not None and not (float(max_offset) >= 0 and math.isfinite(float(max_offset))):
        raise ValueError(f"max_offset must be a finite number >= 0 or None, got {max_offset!r}")
    if creep is not None:
        creep = np.asarray(creep, dtype=np.float64)
        if creep.shape != (T, 3) or not np.all(np.isfinite(creep)):
            raise ValueError(f"creep must be a finite ({T}, 3) array, got shape {creep.shape}")
    rotations = motion.rotations.copy()
    out = Motion(motion.skeleton, rotations, motion.translations.copy(), motion.fps)
    out.rotations = rotations  # the constructor renormalises; untouched frames stay bit for bit
    if T == 0 or not contacts.any():
        return out
    chains = leg_chains(motion.skeleton)
    pos, mats = forward_kinematics(motion)
    parents = motion.skeleton.parents
    parent_of = {j: int(parents[j]) for c in chains for j in c}

    def glob(frames: np.ndarray, j: int) -> Rotation:
        return Rotation.from_matrix(mats[frames, j])

    for f, chain in enumerate(chains):
        planted = contacts[:, f]
        if not planted.any():
            continue
        ankle = chain[2]
        starts, ends = _runs(planted)
        targets = pos[starts, ankle].copy()
        targets[:, 1] = _run_medians(pos[:, ankle, 1], starts, ends) if height is None else float(height)
        if floor is not None:
            targets[:, 1] = np.maximum(targets[:, 1], float(floor))
        w, P = _schedule(planted, pos[:, ankle], targets, starts, ends, blend_frames, creep)
        if max_offset is not None:  # the leash: at most max_offset from where the pose puts the ankle
            off = P - pos[:, ankle]
            n = np.linalg.norm(off, axis=-1, keepdims=True)
            P = np.where(n > max_offset, pos[:, ankle] + off * (float(max_offset) / np.maximum(n, 1e-300)), P)
        frames = np.flatnonzero(w > 0)
        pinned = _leg_ik(pos, glob, parent_of, chain, frames, P[frames])
        wf = w[frames]
        partial = wf < 1.0
        for j, new in zip(chain, pinned):
            old_q = motion.rotations[frames, j]
            q = new.as_quat()
            if partial.any():
                r0 = Rotation.from_quat(old_q[partial])
                step = (r0.inv() * new[partial]).as_rotvec() * wf[partial, None]
                q[partial] = (r0 * Rotation.from_rotvec(step)).as_quat()
            q = np.where(np.sum(q * old_q, axis=-1, keepdims=True) < 0, -q, q)  # the input's hemisphere
            rotations[frames, j] = q
    return out
