"""The CMU 31-joint skeleton layout, with offsets built from a performer's body proportions.

Joint names, hierarchy, channel layout (root: 3 positions + ZYX, others ZYX) and End Sites are those
of the CMU BVH conversions (e.g. ``shared/data/mocap/cmu/01_01.bvh``), so every consumer of CMU data
reads demo motions unchanged. Units are CMU units too (:data:`UNIT_M` metres per unit), so demo and
CMU motions share a scale in the motion graph.

Unlike the CMU files, whose legs splay 20 degrees outwards in the rest pose (an artefact of the ASF
conversion), the rest pose here is a clean T-pose: legs straight down, arms horizontal along +-X,
facing +Z, +Y up. That keeps every joint's rest frame aligned with the world, which is what lets
:mod:`vidstyle.demo.rig` aim bones with simple frames.

Segment lengths follow the classic anthropometric fractions of stature (Drillis & Contini 1966, as
tabulated by Winter, *Biomechanics and Motor Control of Human Movement*): thigh 0.245 H, shank
0.246 H, upper arm 0.186 H, forearm 0.146 H, shoulder width 0.259 H, ankle height 0.039 H.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from ..mocap import Skeleton

UNIT_M = 0.0564
"""Metres per CMU length unit (the CMU BVH conversions use about 5.64 cm per unit)."""

# (name, parent name) in CMU file order.
CMU_HIERARCHY: tuple[tuple[str, str | None], ...] = (
    ("Hips", None),
    ("LHipJoint", "Hips"),
    ("LeftUpLeg", "LHipJoint"),
    ("LeftLeg", "LeftUpLeg"),
    ("LeftFoot", "LeftLeg"),
    ("LeftToeBase", "LeftFoot"),
    ("RHipJoint", "Hips"),
    ("RightUpLeg", "RHipJoint"),
    ("RightLeg", "RightUpLeg"),
    ("RightFoot", "RightLeg"),
    ("RightToeBase", "RightFoot"),
    ("LowerBack", "Hips"),
    ("Spine", "LowerBack"),
    ("Spine1", "Spine"),
    ("Neck", "Spine1"),
    ("Neck1", "Neck"),
    ("Head", "Neck1"),
    ("LeftShoulder", "Spine1"),
    ("LeftArm", "LeftShoulder"),
    ("LeftForeArm", "LeftArm"),
    ("LeftHand", "LeftForeArm"),
    ("LeftFingerBase", "LeftHand"),
    ("LeftHandIndex1", "LeftFingerBase"),
    ("LThumb", "LeftHand"),
    ("RightShoulder", "Spine1"),
    ("RightArm", "RightShoulder"),
    ("RightForeArm", "RightArm"),
    ("RightHand", "RightForeArm"),
    ("RightFingerBase", "RightHand"),
    ("RightHandIndex1", "RightFingerBase"),
    ("RThumb", "RightHand"),
)
JOINT_NAMES: tuple[str, ...] = tuple(n for n, _ in CMU_HIERARCHY)
ROOT_CHANNELS = ("Xposition", "Yposition", "Zposition", "Zrotation", "Yrotation", "Xrotation")
JOINT_CHANNELS = ("Zrotation", "Yrotation", "Xrotation")


@dataclass(frozen=True)
class Body:
    """Body proportions of a performer. Lengths scale with ``height_m``; the ratios scale segments."""

    height_m: float = 1.75
    leg_ratio: float = 1.0  # thigh and shank
    arm_ratio: float = 1.0  # upper arm, forearm, hand
    shoulder_ratio: float = 1.0  # shoulder width
    hip_ratio: float = 1.0  # hip width
    torso_ratio: float = 1.0  # pelvis-to-neck

    def to_dict(self) -> dict:
        return {k: round(float(v), 6) for k, v in asdict(self).items()}

    @classmethod
    def random(cls, rng: np.random.Generator) -> Body:
        return cls(
            height_m=float(rng.uniform(1.60, 1.92)),
            leg_ratio=float(rng.uniform(0.95, 1.05)),
            arm_ratio=float(rng.uniform(0.95, 1.06)),
            shoulder_ratio=float(rng.uniform(0.90, 1.12)),
            hip_ratio=float(rng.uniform(0.90, 1.12)),
            torso_ratio=float(rng.uniform(0.95, 1.05)),
        )

    # ---- segment lengths in CMU units
    @property
    def H(self) -> float:
        """Stature in CMU units."""
        return self.height_m / UNIT_M

    @property
    def thigh(self) -> float:
        return 0.245 * self.H * self.leg_ratio

    @property
    def shank(self) -> float:
        return 0.246 * self.H * self.leg_ratio

    @property
    def ankle_height(self) -> float:
        """Height of the ankle joint above the floor when the foot is flat."""
        return 0.039 * self.H

    @property
    def upper_arm(self) -> float:
        return 0.186 * self.H * self.arm_ratio

    @property
    def forearm(self) -> float:
        return 0.146 * self.H * self.arm_ratio

    @property
    def arm_length(self) -> float:
        """Shoulder to wrist."""
        return self.upper_arm + self.forearm

    @property
    def leg_length(self) -> float:
        """Hip to ankle."""
        return self.thigh + self.shank


def build_skeleton(body: Body | None = None) -> Skeleton:
    """The CMU-layout skeleton of ``body`` in its T-pose rest (see the module docstring)."""
    b = body or Body()
    H = b.H
    hip_half = 0.05 * H * b.hip_ratio  # hip joint centres are about 0.1 H apart
    shoulder_half = 0.115 * H * b.shoulder_ratio  # shoulder joint centres, inside the 0.259 H width
    toe_drop = b.ankle_height - 0.012 * H  # toe joint centre sits 0.012 H above the floor
    spine = 0.09 * H * b.torso_ratio
    off = {
        "Hips": (0.0, 0.0, 0.0),
        "LHipJoint": (0.0, 0.0, 0.0),
        "LeftUpLeg": (hip_half, -0.03 * H, 0.0),
        "LeftLeg": (0.0, -b.thigh, 0.0),
        "LeftFoot": (0.0, -b.shank, 0.0),
        "LeftToeBase": (0.0, -toe_drop, 0.11 * H),
        "LowerBack": (0.0, 0.0, 0.0),
        "Spine": (0.0, spine, -0.01 * H),
        "Spine1": (0.0, spine, 0.005 * H),
        "Neck": (0.0, 0.0, 0.0),
        "Neck1": (0.0, 0.10 * H * b.torso_ratio, 0.005 * H),
        "Head": (0.0, 0.055 * H, 0.0),
        "LeftShoulder": (0.0, 0.0, 0.0),
        "LeftArm": (shoulder_half, 0.085 * H * b.torso_ratio, 0.0),
        "LeftForeArm": (b.upper_arm, 0.0, 0.0),
        "LeftHand": (b.forearm, 0.0, 0.0),
        "LeftFingerBase": (0.0, 0.0, 0.0),
        "LeftHandIndex1": (0.05 * H * b.arm_ratio, 0.0, 0.0),
        "LThumb": (0.0, 0.0, 0.0),
    }
    for name in list(off):
        right = _mirror(name)
        if right != name:
            x, y, z = off[name]
            off[right] = (-x, y, z)
    ends = {
        "LeftToeBase": (0.0, 0.0, 0.045 * H),
        "Head": (0.0, 0.105 * H, 0.01 * H),
        "LeftHandIndex1": (0.04 * H * b.arm_ratio, 0.0, 0.0),
        "LThumb": (0.025 * H, 0.0, 0.025 * H),
    }
    for name in list(ends):
        right = _mirror(name)
        if right != name:
            x, y, z = ends[name]
            ends[right] = (-x, y, z)
    index = {n: i for i, n in enumerate(JOINT_NAMES)}
    parents = np.array([-1 if p is None else index[p] for _, p in CMU_HIERARCHY])
    offsets = np.array([off[n] for n in JOINT_NAMES], dtype=np.float64)
    channels = [ROOT_CHANNELS if p is None else JOINT_CHANNELS for _, p in CMU_HIERARCHY]
    end_sites = {index[n]: np.array(v) for n, v in ends.items()}
    return Skeleton(list(JOINT_NAMES), parents, offsets, channels, end_sites)


def _mirror(name: str) -> str:
    if name.startswith("Left"):
        return "Right" + name[4:]
    if name in ("LHipJoint", "LThumb"):
        return "R" + name[1:]
    return name
