"""The 15-keypoint, 10-part body model of the 2D pose stage, and where its keypoints sit on a skeleton.

Keypoints (left = the performer's left), in this order everywhere (poses.json, models, metrics):
``head_top, neck, pelvis, left_shoulder, right_shoulder, left_elbow, right_elbow, left_wrist,
right_wrist, left_hip, right_hip, left_knee, right_knee, left_ankle, right_ankle``.

Parts (:data:`PARTS`) are keypoint pairs; the torso is the root of the tree model used by pictorial
structures and every other part has a parent (:data:`PART_PARENTS`).

On the CMU skeleton (and the demo performers, which share its layout) the keypoints are the joints
``Head`` (its End Site: head_top), ``Neck``, ``Hips``, ``LeftArm``, ``LeftForeArm``, ``LeftHand``,
``LeftUpLeg``, ``LeftLeg``, ``LeftFoot`` and their right counterparts. Other skeletons are mapped

1. by name: the side marker (``Left``/``Right``, ``L``/``R``, ``l_``/``r_``, ``_L``/``.L``...) is
   removed, names are lower-cased without namespace (``mixamorig:``) or separators, and the rest is
   matched against the usual vocabularies (CMU/Mixamo ``LeftArm``/``LeftForeArm``, Unity/VRM
   ``LeftUpperArm``/``LeftLowerArm``, H-Anim ``l_shoulder``/``l_elbow``, Biped ``L Thigh``/``L Calf``,
   ``HeadTop_End``...), each candidate checked against the hierarchy (an elbow below its shoulder);
2. by topology, for the keypoints names did not find: in the rest pose (+Y up, facing +Z, so the
   performer's left is +X) the two lowest leaf chains are the legs and the two most lateral remaining
   ones the arms; along an arm the wrist is the first joint that branches (into fingers) and the
   shoulder and elbow the two distinct joints before it; along a leg (or an arm without fingers) the
   two consecutive longest bones are upper and lower limb (hip, knee, ankle); pelvis is the legs' common ancestor, neck the joint just above the
   arms' common ancestor on the way to the head, head_top the End Site (or leaf) of the head chain.
   Twist joints in the middle of a limb defeat this rule; such skeletons need names.

>>> from vidstyle.mocap import read_bvh                                    # doctest: +SKIP
>>> pts = keypoint_positions(read_bvh("01_01.bvh"))                      # (F, 15, 3)  # doctest: +SKIP
"""

from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np

from ..formats.keypoints import KEYPOINTS
from .kinematics import forward_kinematics
from .motion import Motion
from .skeleton import Skeleton

KEYPOINT_INDEX = {k: i for i, k in enumerate(KEYPOINTS)}

# (part name, (proximal keypoint, distal keypoint)); the torso (root) goes neck -> pelvis.
PART_LIST: tuple[tuple[str, tuple[str, str]], ...] = (
    ("torso", ("neck", "pelvis")),
    ("head", ("neck", "head_top")),
    ("left_upper_arm", ("left_shoulder", "left_elbow")),
    ("right_upper_arm", ("right_shoulder", "right_elbow")),
    ("left_forearm", ("left_elbow", "left_wrist")),
    ("right_forearm", ("right_elbow", "right_wrist")),
    ("left_upper_leg", ("left_hip", "left_knee")),
    ("right_upper_leg", ("right_hip", "right_knee")),
    ("left_lower_leg", ("left_knee", "left_ankle")),
    ("right_lower_leg", ("right_knee", "right_ankle")),
)
PARTS: dict[str, tuple[str, str]] = dict(PART_LIST)
"""Part name -> (proximal keypoint, distal keypoint), torso first (the tree root)."""
PART_NAMES: tuple[str, ...] = tuple(PARTS)
PART_PARENTS: dict[str, str | None] = {
    "torso": None,
    "head": "torso",
    "left_upper_arm": "torso",
    "right_upper_arm": "torso",
    "left_forearm": "left_upper_arm",
    "right_forearm": "right_upper_arm",
    "left_upper_leg": "torso",
    "right_upper_leg": "torso",
    "left_lower_leg": "left_upper_leg",
    "right_lower_leg": "right_upper_leg",
}
"""Tree of the pictorial-structures model: part -> parent part (``None`` for the torso root)."""
PART_KEYPOINTS = np.array([[KEYPOINT_INDEX[a], KEYPOINT_INDEX[b]] for a, b in PARTS.values()], dtype=np.int64)
"""(10, 2) keypoint indices of each part's (proximal, distal) ends, in :data:`PART_NAMES` order."""
PART_PARENT_INDEX = np.array([-1 if PART_PARENTS[p] is None else PART_NAMES.index(PART_PARENTS[p])
                              for p in PART_NAMES], dtype=np.int64)
MIRROR = np.array([KEYPOINT_INDEX[k.replace("left_", "#").replace("right_", "left_").replace("#", "right_")]
                   for k in KEYPOINTS], dtype=np.int64)
"""(15,) index of each keypoint's left/right counterpart (itself for head_top, neck, pelvis)."""

CMU_NAMES: dict[str, str] = {
    "head_top": "Head", "neck": "Neck", "pelvis": "Hips",
    "left_shoulder": "LeftArm", "right_shoulder": "RightArm",
    "left_elbow": "LeftForeArm", "right_elbow": "RightForeArm",
    "left_wrist": "LeftHand", "right_wrist": "RightHand",
    "left_hip": "LeftUpLeg", "right_hip": "RightUpLeg",
    "left_knee": "LeftLeg", "right_knee": "RightLeg",
    "left_ankle": "LeftFoot", "right_ankle": "RightFoot",
}
"""The CMU joint of each keypoint (head_top is the End Site of ``Head``)."""


@dataclass(frozen=True)
class KeypointJoint:
    """Where a keypoint sits: joint ``joint`` (index, name ``joint_name``) or, with ``end_site``, the
    End Site of that joint. ``how`` is ``"name"`` or ``"topology"``."""

    keypoint: str
    joint: int
    joint_name: str
    end_site: bool = False
    how: str = "name"


class KeypointMappingError(ValueError):
    """A skeleton's joints cannot be matched to every keypoint."""


# ---------------------------------------------------------------- names
def split_side(name: str) -> tuple[str | None, str]:
    """``"mixamorig:LeftForeArm"`` -> ``("left", "forearm")``; ``"l_elbow"`` -> ``("left", "elbow")``;
    ``"Bip01 L Thigh"`` -> ``("left", "thigh")``; ``"Neck1"`` -> ``(None, "neck1")``. Namespaces
    (``a:b``, ``a|b``), ``Bip01``-style prefixes and separators are dropped."""
    base = re.split(r"[:|]", name)[-1].strip()
    tokens = [t for t in re.split(r"[ _.\-]+", base) if t and not re.fullmatch(r"bip\d*", t.lower())]
    side = None
    words = {"l": "left", "left": "left", "r": "right", "right": "right"}
    for i in (0, len(tokens) - 1, 1):  # "l_elbow", "Hand_L", "Bip01 L Thigh"
        if len(tokens) > 1 and i < len(tokens) and tokens[i].lower() in words:
            side = words[tokens[i].lower()]
            del tokens[i]
            break
    base = "".join(tokens)
    if side is None:
        for word, rx in (("left", r"^(Left|left|L)(?=[A-Z0-9])"), ("right", r"^(Right|right|R)(?=[A-Z0-9])"),
                         ("left", r"(?<=[a-z0-9])(Left|L)$"), ("right", r"(?<=[a-z0-9])(Right|R)$")):
            if re.search(rx, base):
                side, base = word, re.sub(rx, "", base, count=1)
                break
    return side, base.lower()


# candidates per body landmark, most specific first; each is a normalised, side-free joint name
_LIMB_NAMES = {
    "shoulder": ("upperarm", "arm", "humerus", "shoulder"),
    "elbow": ("forearm", "lowerarm", "elbow", "radius"),
    "wrist": ("wrist", "hand"),
    "hip": ("upleg", "upperleg", "thigh", "femur", "hip"),
    "knee": ("lowerleg", "knee", "shin", "calf", "tibia", "leg"),
    "ankle": ("ankle", "foot"),
}
_CENTRAL_NAMES = {
    "pelvis": ("hips", "pelvis", "hip", "root"),
    "neck": ("neck", "neck1", "neck01", "neck0"),
    "head": ("head",),
    "head_top": ("headtopend", "headtop", "headend", "headsite", "headnub", "topofhead"),
}


def _ancestors(parents: np.ndarray, j: int) -> list[int]:
    out = []
    while parents[j] >= 0:
        j = int(parents[j])
        out.append(j)
    return out


def _by_name(sk: Skeleton) -> dict[str, KeypointJoint]:
    names = sk.names
    parsed = [split_side(n) for n in names]
    found: dict[str, KeypointJoint] = {}

    def first(side, cands, below=None):
        for c in cands:
            for j, (s, base) in enumerate(parsed):
                if s == side and base == c and (below is None or below in _ancestors(sk.parents, j)):
                    return j
        return None

    for side in ("left", "right"):
        chain = {}
        for a, b, c in (("shoulder", "elbow", "wrist"), ("hip", "knee", "ankle")):
            jb = first(side, _LIMB_NAMES[b])
            ja = None
            jc = None
            if jb is not None:
                ja = first(side, _LIMB_NAMES[a])
                if ja is not None and ja not in _ancestors(sk.parents, jb):
                    # e.g. "shoulder" naming the clavicle: take the candidate that is above the elbow
                    ja = next((j for cand in _LIMB_NAMES[a] for j, (s, base) in enumerate(parsed)
                               if s == side and base == cand and j in _ancestors(sk.parents, jb)), None)
                jc = first(side, _LIMB_NAMES[c], below=jb)
            chain.update({a: ja, b: jb, c: jc})
        for part, j in chain.items():
            if j is not None:
                found[f"{side}_{part}"] = KeypointJoint(f"{side}_{part}", j, names[j])
    for key in ("pelvis", "neck"):
        j = first(None, _CENTRAL_NAMES[key])
        if j is not None:
            found[key] = KeypointJoint(key, j, names[j])
    j = first(None, _CENTRAL_NAMES["head_top"])
    if j is not None:
        found["head_top"] = KeypointJoint("head_top", j, names[j])
    else:
        j = first(None, _CENTRAL_NAMES["head"])
        if j is not None and j in sk.end_sites:
            found["head_top"] = KeypointJoint("head_top", j, names[j], end_site=True)
    return found


# ---------------------------------------------------------------- topology
def _rest_positions(sk: Skeleton) -> np.ndarray:
    pos = np.zeros((sk.n_joints, 3))
    for j, p in enumerate(sk.parents):
        pos[j] = sk.offsets[j] if p < 0 else pos[p] + sk.offsets[j]
    return pos


def _path(parents: np.ndarray, j: int) -> list[int]:
    return list(reversed([j] + _ancestors(parents, j)))


def _limb_triplet(chain: list[int], pos: np.ndarray, children=None) -> tuple[int, int, int]:
    """Joints (a, b, c) along ``chain`` (root to leaf): with ``children`` (an arm) the wrist ``c`` is
    the first joint that branches into fingers, ``a`` and ``b`` the two distinct joints before it;
    otherwise (or if nothing branches) the two consecutive longest bones."""
    distinct = [chain[0]]
    for j in chain[1:]:
        if np.linalg.norm(pos[j] - pos[distinct[-1]]) > 1e-9:
            distinct.append(j)
    if children is not None:
        branch = next((j for j in chain if len(children(j)) >= 2), None)
        if branch is not None:
            before = [j for j in distinct[: distinct.index(branch) if branch in distinct else len(distinct)]
                      if chain.index(j) < chain.index(branch)]
            if len(before) >= 2:
                return before[-2], before[-1], branch
    if len(distinct) < 3:
        raise KeypointMappingError("a limb chain has fewer than three distinct joints")
    seg = np.linalg.norm(np.diff(pos[distinct], axis=0), axis=1)
    i = int(np.argmax(seg[:-1] + seg[1:]))
    return distinct[i], distinct[i + 1], distinct[i + 2]


def _lca(parents: np.ndarray, a: int, b: int) -> int:
    pa = set([a] + _ancestors(parents, a))
    for j in [b] + _ancestors(parents, b):
        if j in pa:
            return j
    raise KeypointMappingError("limbs belong to different roots")


def _by_topology(sk: Skeleton) -> dict[str, KeypointJoint]:
    pos = _rest_positions(sk)
    par = sk.parents
    leaves = [j for j in range(sk.n_joints) if not sk.children(j)]
    tip = {j: pos[j] + sk.end_sites.get(j, np.zeros(3)) for j in leaves}
    roots = np.flatnonzero(par < 0)
    if len(roots) != 1 or len(leaves) < 5:
        raise KeypointMappingError("topology: need one root and at least five leaf chains (head, 2 arms, 2 legs)")

    by_low = sorted(leaves, key=lambda j: tip[j][1])
    # legs: lowest leaf on each side (+X = left)
    left_legs = [j for j in by_low if tip[j][0] > 1e-9]
    right_legs = [j for j in by_low if tip[j][0] < -1e-9]
    if not left_legs or not right_legs:
        raise KeypointMappingError("topology: no leaf chains on both sides of the body (legs)")
    leg_l, leg_r = left_legs[0], right_legs[0]
    leg_chain_joints = set(_path(par, leg_l)) | set(_path(par, leg_r))
    pelvis = _lca(par, leg_l, leg_r)
    rest = [j for j in leaves if not (set(_path(par, j)) & (leg_chain_joints - set(_path(par, pelvis))))]
    if len(rest) < 3:
        raise KeypointMappingError("topology: fewer than three upper-body leaf chains (head, arms)")
    arm_l = max(rest, key=lambda j: tip[j][0])
    arm_r = min(rest, key=lambda j: tip[j][0])
    if tip[arm_l][0] <= 0 or tip[arm_r][0] >= 0:
        raise KeypointMappingError("topology: no arm chains reaching out on both sides")
    arm_joints = set(_path(par, arm_l)) | set(_path(par, arm_r))
    chest = _lca(par, arm_l, arm_r)
    heads = [j for j in rest if chest in _path(par, j) and not (set(_path(par, j)) & (arm_joints - set(_path(par, chest))))]
    if not heads:
        raise KeypointMappingError("topology: no head chain above the arms")
    head_leaf = max(heads, key=lambda j: tip[j][1])
    head_path = _path(par, head_leaf)
    k = head_path.index(chest)
    if k + 1 >= len(head_path):
        raise KeypointMappingError("topology: the head chain has no joint above the arms' branch point")
    neck = head_path[k + 1]
    out = {
        "pelvis": pelvis, "neck": neck,
    }
    for side, leg, arm in (("left", leg_l, arm_l), ("right", leg_r, arm_r)):
        lp = _path(par, leg)
        h, kn, an = _limb_triplet(lp[lp.index(pelvis) + 1:], pos)
        ap = _path(par, arm)
        s, e, w = _limb_triplet(ap[ap.index(chest) + 1:], pos, sk.children)
        out.update({f"{side}_hip": h, f"{side}_knee": kn, f"{side}_ankle": an,
                    f"{side}_shoulder": s, f"{side}_elbow": e, f"{side}_wrist": w})
    res = {k: KeypointJoint(k, int(j), sk.names[int(j)], how="topology") for k, j in out.items()}
    res["head_top"] = KeypointJoint("head_top", head_leaf, sk.names[head_leaf],
                                    end_site=head_leaf in sk.end_sites, how="topology")
    return res


def keypoint_joints(skeleton: Skeleton) -> dict[str, KeypointJoint]:
    """Map every keypoint (``KEYPOINTS`` order) to a joint of ``skeleton`` (or a joint's End Site).

    Names first, topology for what names did not find (see the module docstring). Raises
    :class:`KeypointMappingError` naming the keypoints that could not be placed.
    """
    sk = skeleton
    if all(n in sk.names for n in CMU_NAMES.values()) and sk.index("Head") in sk.end_sites:
        return {k: KeypointJoint(k, sk.index(n), n, end_site=(k == "head_top")) for k, n in CMU_NAMES.items()}
    found = _by_name(sk)
    missing = [k for k in KEYPOINTS if k not in found]
    if missing:
        try:
            topo = _by_topology(sk)
        except KeypointMappingError as exc:
            raise KeypointMappingError(
                f"skeleton ({sk.n_joints} joints, root {sk.names[0]!r}): no joint for keypoint(s) "
                f"{', '.join(missing)} by name, and the topology fallback failed: {exc}") from None
        for k in missing:
            found[k] = topo[k]
    return {k: found[k] for k in KEYPOINTS}


def keypoint_positions(motion: Motion, mapping: dict[str, KeypointJoint] | None = None,
                       positions: np.ndarray | None = None, matrices: np.ndarray | None = None) -> np.ndarray:
    """(F, 15, 3) world positions of the keypoints of ``motion`` (``KEYPOINTS`` order).

    ``mapping`` defaults to :func:`keypoint_joints` of the motion's skeleton; ``positions`` /
    ``matrices`` (from :func:`forward_kinematics`) may be passed to avoid recomputing them.
    """
    sk = motion.skeleton
    mapping = mapping or keypoint_joints(sk)
    if positions is None or matrices is None:
        positions, matrices = forward_kinematics(motion)
    out = np.empty((positions.shape[0], len(KEYPOINTS), 3))
    for i, k in enumerate(KEYPOINTS):
        m = mapping[k]
        out[:, i] = positions[:, m.joint]
        if m.end_site:
            out[:, i] += np.einsum("fij,j->fi", matrices[:, m.joint], sk.end_sites[m.joint])
    return out
