"""A small kickboxing rig: a handful of intuitive pose channels -> joint rotations on the CMU skeleton.

A pose is a vector of named channels (:data:`CHANNELS`):

- pelvis: world position offset ``px, py, pz`` (in statures H; ``py`` relative to the stance height)
  and ``yaw, pitch, roll`` in degrees (``R = Ry(yaw) Rx(pitch) Rz(roll)``; yaw > 0 turns the character
  to its left, pitch > 0 leans forward, roll > 0 lifts its left hip);
- chest relative to pelvis ``cyaw, cpitch, croll`` (spread over LowerBack, Spine, Spine1) and an extra
  head pitch ``hpitch`` (the head also turns back against the body yaw so the eyes stay on the
  opponent, who stands along +Z);
- wrist targets ``lh*``/``rh*`` relative to each shoulder in the chest frame, in arm lengths, and elbow
  pole directions ``le*``/``re*`` (chest frame);
- ankle targets ``lf*``/``rf*`` in the world, in statures (``lfy`` is the ankle height; a foot whose
  ankle target is at the flat-foot ankle height is planted), foot yaw/pitch in degrees (pitch > 0 =
  toes down), and knee pole directions ``lk*``/``rk*`` (world).

Limbs are solved by analytic two-bone IK. The chain frames are built from the bone direction and the
hinge plane, so the middle joint bends about one fixed local axis and never flips as long as the pole
is not parallel to the limb. Planted feet land exactly on their targets: the pelvis height is capped
(smoothly, with a soft minimum) at what the legs can reach, which puts the feet on the floor and stops
planted-foot skid without a separate clean-up pass.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from ..mocap import Motion, Skeleton
from ..mocap.quat import continuous_quaternions
from .skeleton import Body, build_skeleton

CHANNELS: tuple[str, ...] = (
    "px", "py", "pz", "yaw", "pitch", "roll",
    "cyaw", "cpitch", "croll", "hpitch",
    "lhx", "lhy", "lhz", "lex", "ley", "lez",
    "rhx", "rhy", "rhz", "rex", "rey", "rez",
    "lfx", "lfy", "lfz", "lfyaw", "lfpitch", "lkx", "lky", "lkz",
    "rfx", "rfy", "rfz", "rfyaw", "rfpitch", "rkx", "rky", "rkz",
)
CH = {c: i for i, c in enumerate(CHANNELS)}

STANCE_HEIGHT = 0.515
"""Pelvis height (statures) of the fighting stance before the reach cap; knees slightly bent."""

ARM_REACH = 0.995  # fraction of the arm length IK may use (a locked elbow has no defined pole)
LEG_REACH = 0.985
PLANTED_TOL = 0.004  # statures: an ankle target this close to the floor height counts as planted
SOFT_CAP = 0.006  # statures: softness of the pelvis-height cap


def _rot_x(deg: np.ndarray) -> np.ndarray:
    return Rotation.from_rotvec(np.deg2rad(deg)[:, None] * [1.0, 0.0, 0.0]).as_matrix()


def _rot_y(deg: np.ndarray) -> np.ndarray:
    return Rotation.from_rotvec(np.deg2rad(deg)[:, None] * [0.0, 1.0, 0.0]).as_matrix()


def _rot_z(deg: np.ndarray) -> np.ndarray:
    return Rotation.from_rotvec(np.deg2rad(deg)[:, None] * [0.0, 0.0, 1.0]).as_matrix()


def _unit(v: np.ndarray) -> np.ndarray:
    n = np.linalg.norm(v, axis=-1, keepdims=True)
    return v / np.maximum(n, 1e-12)


def _frame(direction: np.ndarray, hinge: np.ndarray, rest_dir: np.ndarray, rest_pole: np.ndarray) -> np.ndarray:
    """(F, 3, 3) rotation taking ``rest_dir`` to ``direction`` and ``rest_dir x rest_pole`` to the
    unit ``hinge`` axis (perpendicular to ``direction``)."""
    new = np.stack([direction, np.cross(hinge, direction), hinge], axis=-1)
    rest = np.stack([rest_dir, rest_pole, np.cross(rest_dir, rest_pole)], axis=-1)
    return new @ rest.T


def two_bone_ik(start: np.ndarray, target: np.ndarray, l1: float, l2: float, pole: np.ndarray,
                rest_dir: np.ndarray, rest_pole: np.ndarray, reach: float) -> tuple[np.ndarray, np.ndarray]:
    """Global rotations (F, 3, 3) of the upper and lower bone of a limb rooted at ``start`` reaching for
    ``target``; the middle joint bends towards ``pole``. Targets beyond ``reach * (l1 + l2)`` are
    approached along the same line."""
    v = target - start
    dist = np.linalg.norm(v, axis=-1)
    u = v / np.maximum(dist, 1e-9)[:, None]
    # a soft limit: the limb decelerates into full extension instead of locking in one frame
    d = np.maximum(_soft_min(dist, reach * (l1 + l2), 0.03 * (l1 + l2)), abs(l1 - l2) + 1e-6)
    q = _unit(pole - np.sum(pole * u, axis=-1, keepdims=True) * u)
    cos_a = np.clip((l1 * l1 + d * d - l2 * l2) / (2 * l1 * d), -1.0, 1.0)
    sin_a = np.sqrt(1.0 - cos_a * cos_a)
    a1 = cos_a[:, None] * u + sin_a[:, None] * q
    mid = start + l1 * a1
    a2 = _unit(start + d[:, None] * u - mid)
    # Both bones share the hinge axis u x q. Building each frame from it (rather than from q made
    # perpendicular to each bone) keeps the twist right when the lower bone folds back past 90 degrees.
    hinge = _unit(np.cross(u, q))
    return _frame(a1, hinge, rest_dir, rest_pole), _frame(a2, hinge, rest_dir, rest_pole)


def _fk_partial(sk: Skeleton, local: np.ndarray, root_pos: np.ndarray, upto: int) -> tuple[np.ndarray, np.ndarray]:
    """Global rotations and positions of joints ``0..upto-1`` (file order makes that a prefix)."""
    F = local.shape[0]
    glob = np.empty((F, upto, 3, 3))
    pos = np.empty((F, upto, 3))
    for j in range(upto):
        p = sk.parents[j]
        if p < 0:
            glob[:, j] = local[:, j]
            pos[:, j] = root_pos
        else:
            glob[:, j] = glob[:, p] @ local[:, j]
            pos[:, j] = pos[:, p] + glob[:, p] @ sk.offsets[j]
    return glob, pos


def _soft_min(a: np.ndarray, cap: np.ndarray, k: float) -> np.ndarray:
    """A smooth ``min(a, cap)`` that never exceeds ``cap`` (so a reach limit always holds)."""
    return cap - k * np.logaddexp(0.0, (cap - a) / k)


def planted_mask(channels: np.ndarray, body: Body) -> np.ndarray:
    """(F, 2) bool: left/right ankle target on the floor (flat-foot ankle height)."""
    floor = body.ankle_height / body.H
    return np.stack([channels[:, CH["lfy"]] <= floor + PLANTED_TOL,
                     channels[:, CH["rfy"]] <= floor + PLANTED_TOL], axis=1)


def solve_motion(channels: np.ndarray, body: Body, fps: float, skeleton: Skeleton | None = None) -> Motion:
    """Channels ``(F, len(CHANNELS))`` -> :class:`Motion` on ``build_skeleton(body)``."""
    sk = skeleton or build_skeleton(body)
    idx = {n: i for i, n in enumerate(sk.names)}
    c = {name: channels[:, i] for name, i in CH.items()}
    F = channels.shape[0]
    H = body.H
    J = sk.n_joints
    local = np.broadcast_to(np.eye(3), (F, J, 3, 3)).copy()

    pelvis = _rot_y(c["yaw"]) @ _rot_x(c["pitch"]) @ _rot_z(c["roll"])
    local[:, idx["Hips"]] = pelvis
    spine = _rot_y(c["cyaw"] / 3) @ _rot_x(c["cpitch"] / 3) @ _rot_z(c["croll"] / 3)
    for name in ("LowerBack", "Spine", "Spine1"):
        local[:, idx[name]] = spine
    # the head turns back against the body yaw and leans so the eyes stay level on the opponent
    body_yaw = c["yaw"] + c["cyaw"]
    local[:, idx["Neck1"]] = _rot_y(-0.45 * body_yaw) @ _rot_x(-0.4 * (c["pitch"] + c["cpitch"]))
    local[:, idx["Head"]] = _rot_y(-0.4 * body_yaw) @ _rot_x(c["hpitch"] - 0.3 * (c["pitch"] + c["cpitch"])) \
        @ _rot_z(-0.6 * (c["roll"] + c["croll"]))

    # ---- pelvis position, capped so planted feet stay reachable
    root = np.stack([c["px"] * H, (STANCE_HEIGHT + c["py"]) * H, c["pz"] * H], axis=1)
    ankles = {s: np.stack([c[f"{s}fx"], c[f"{s}fy"], c[f"{s}fz"]], axis=1) * H for s in "lr"}
    plant = planted_mask(channels, body)
    lmax = LEG_REACH * body.leg_length
    cap = np.full(F, np.inf)
    for k, (s, side) in enumerate((("l", "Left"), ("r", "Right"))):
        hip_off = pelvis @ sk.offsets[idx[f"{side}UpLeg"]]  # hip joint relative to the root
        dxz = (root[:, [0, 2]] + hip_off[:, [0, 2]]) - ankles[s][:, [0, 2]]
        reach_y = np.sqrt(np.maximum(lmax**2 - np.sum(dxz**2, axis=1), 0.0))
        cap_s = ankles[s][:, 1] + reach_y - hip_off[:, 1]
        cap = np.where(plant[:, k], np.minimum(cap, cap_s), cap)
    finite = np.isfinite(cap)
    root[finite, 1] = _soft_min(root[finite, 1], cap[finite], SOFT_CAP * H)

    n_torso = idx["Head"] + 1  # Hips .. Head: legs come first in file order but are identity here
    glob, pos = _fk_partial(sk, local, root, n_torso)
    chest = glob[:, idx["Spine1"]]

    # ---- legs
    down, fwd = np.array([0.0, -1.0, 0.0]), np.array([0.0, 0.0, 1.0])
    for s, side in (("l", "Left"), ("r", "Right")):
        hip = pos[:, idx[f"{side}UpLeg"]]
        pole = np.stack([c[f"{s}kx"], c[f"{s}ky"], c[f"{s}kz"]], axis=1)
        g_thigh, g_shank = two_bone_ik(hip, ankles[s], body.thigh, body.shank, pole, down, fwd, LEG_REACH)
        g_foot = _rot_y(c[f"{s}fyaw"]) @ _rot_x(c[f"{s}fpitch"])
        g_hipjoint = pelvis  # LHipJoint/RHipJoint carry no rotation
        local[:, idx[f"{side}UpLeg"]] = np.swapaxes(g_hipjoint, 1, 2) @ g_thigh
        local[:, idx[f"{side}Leg"]] = np.swapaxes(g_thigh, 1, 2) @ g_shank
        local[:, idx[f"{side}Foot"]] = np.swapaxes(g_shank, 1, 2) @ g_foot

    # ---- arms (clavicles carry no rotation, so the upper arm's parent frame is the chest)
    for s, side, rest_dir in (("l", "Left", np.array([1.0, 0.0, 0.0])), ("r", "Right", np.array([-1.0, 0.0, 0.0]))):
        shoulder = pos[:, idx["Spine1"]] + chest @ sk.offsets[idx[f"{side}Arm"]]
        rel = np.stack([c[f"{s}hx"], c[f"{s}hy"], c[f"{s}hz"]], axis=1) * body.arm_length
        target = shoulder + np.einsum("fij,fj->fi", chest, rel)
        pole = np.einsum("fij,fj->fi", chest, np.stack([c[f"{s}ex"], c[f"{s}ey"], c[f"{s}ez"]], axis=1))
        g_upper, g_fore = two_bone_ik(shoulder, target, body.upper_arm, body.forearm, pole,
                                      rest_dir, np.array([0.0, 0.0, -1.0]), ARM_REACH)
        local[:, idx[f"{side}Arm"]] = np.swapaxes(chest, 1, 2) @ g_upper
        local[:, idx[f"{side}ForeArm"]] = np.swapaxes(g_upper, 1, 2) @ g_fore

    quats = Rotation.from_matrix(local.reshape(-1, 3, 3)).as_quat().reshape(F, J, 4)
    quats = continuous_quaternions(quats)
    return Motion(sk, quats, None, fps, root_positions=root)
