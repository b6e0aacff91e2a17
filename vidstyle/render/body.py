"""A volumetric body for any skeleton: tapered capsules (sphere-swept segments) per bone.

The body is derived from the joint hierarchy alone:

- every bone (parent joint -> child joint, or joint -> End Site) longer than ``1.5 %`` of the figure's
  height becomes a capsule; zero-length bones (CMU's ``LHipJoint``, ``Neck``, ``LeftFingerBase`` ...) and
  tiny ones are skipped, so chains of degenerate joints merge naturally;
- each hand and foot is one capsule from the wrist / ankle to the farthest point of its subtree (CMU's
  finger, thumb and toe bones are merged into it; a skeleton without hand joints gets a short hand
  continuing the forearm);
- each bone is classified from the names of its two joints (``upperarm``, ``thigh``, ``torso`` ...) and
  gets radii relative to the figure's height (thick torso and thighs, thin forearms) and a clothing
  region (shirt, trousers, skin, shoes, gloves);
- the torso gets a volume: capsules hip -> shoulder on each side, across the hips and across the
  shoulders, around the spine bones (they replace the pelvis and clavicle bones);
- the head is a capsule along the head bone, with hair on the top and back.

A capsule's two end points are fixed linear combinations of "key points" (joints and End Sites), so
all capsule end points of all frames are one matrix product: ``ends = W @ keypoints``.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np

from ..mocap.skeleton import Skeleton, mirror_name

# clothing regions (material ids); Appearance.palette() returns colours in this order
SKIN, HAIR, SHIRT, TROUSERS, SHOES, GLOVES, SLEEVE, LEG = range(8)
N_MATERIALS = 8

# radii at the (start, end) of a bone, as fractions of the figure's height
RADII = {
    "torso": (0.068, 0.074),
    "upperchest": (0.068, 0.036),  # chest -> neck base: tapers so it does not cover the chin
    "pelvis": (0.062, 0.058),
    "neck": (0.036, 0.033),
    "clavicle": (0.034, 0.030),
    "upperarm": (0.034, 0.028),
    "forearm": (0.028, 0.022),
    "hand": (0.024, 0.020),
    "thigh": (0.056, 0.038),
    "shin": (0.038, 0.028),
    "foot": (0.028, 0.022),
    "toe": (0.024, 0.019),
    "other": (0.028, 0.024),
}
TORSO_KINDS = ("torso", "upperchest", "pelvis", "clavicle")  # one body volume
MIN_BONE = 0.015  # bones shorter than this fraction of the height are skipped
HEAD_RADIUS = 0.05  # x height
HEAD_HEIGHT = 0.135  # chin to crown, x height


def _has(name: str, *words: str) -> bool:
    n = name.lower()
    return any(w in n for w in words)


def classify_bone(parent: str, child: str | None) -> str:
    """Body part of the bone from joint ``parent`` to ``child`` (``None`` for an End Site).

    Works for CMU/Mixamo-style names (the bone is named after the joint that moves it: ``LeftArm`` ->
    upper arm, ``LeftForeArm`` -> forearm, ``LeftUpLeg`` -> thigh, ``LeftLeg`` -> shin) and for
    joint-centred names (``lshoulder`` -> ``lelbow`` is an upper arm).
    """
    c = child or ""
    # joint-centred names: the child says where the bone ends
    if _has(c, "elbow"):
        return "upperarm"
    if _has(c, "wrist"):
        return "forearm"
    if _has(c, "knee"):
        return "thigh"
    if _has(c, "ankle"):
        return "shin"
    p = parent
    if _has(p, "thumb"):
        return "thumb"
    if _has(p, "hand", "finger", "wrist", "index", "palm", "pinky", "middle", "ring"):
        return "hand"
    if _has(p, "forearm", "lowerarm", "elbow", "fore_arm", "lower_arm"):
        return "forearm"
    if _has(p, "clavicle", "collar"):
        return "clavicle"
    if _has(p, "shoulder"):
        # CMU/Mixamo "LeftShoulder" is the clavicle; "lshoulder" -> "lelbow" was caught above
        return "upperarm" if _has(c, "forearm", "elbow") else "clavicle"
    if _has(p, "uparm", "upperarm", "upper_arm", "humerus", "arm"):
        return "upperarm"
    if _has(p, "toe"):
        return "toe"
    if _has(p, "foot", "ankle", "heel"):
        return "foot" if not _has(c, "site") else "toe"
    if _has(p, "upleg", "thigh", "upperleg", "upper_leg", "femur"):
        return "thigh"
    if _has(p, "hipjoint", "pelvis"):
        return "pelvis"
    if _has(p, "knee", "shin", "calf", "lowerleg", "lower_leg", "leg", "tibia"):
        return "shin"
    if _has(p, "head", "skull"):
        return "head"
    if _has(p, "neck"):
        return "neck"
    if _has(p, "hip", "root", "spine", "back", "chest", "torso", "abdomen", "waist", "thorax"):
        if _has(c, "upleg", "thigh", "hipjoint", "leg") or _has(c, "hip") and mirror_name(c) != c:
            return "pelvis"
        if _has(c, "neck", "head"):
            return "neck" if _has(p, "neck") else "upperchest"
        if _has(c, "shoulder", "clavicle", "collar"):
            return "clavicle"
        return "torso"
    return "other"


def side_of(name: str) -> str | None:
    """``"L"``, ``"R"`` or ``None`` from a joint name."""
    if mirror_name(name) == name:
        return None
    n = name
    if re.search(r"(^left|left$|^l_|_l$|^L(?=[A-Z_]))", n, flags=0) or n.lower().startswith("left"):
        return "L"
    return "R"


def rest_positions(skeleton: Skeleton) -> np.ndarray:
    """(J, 3) joint positions of the rest pose (offsets only)."""
    pos = np.zeros((skeleton.n_joints, 3))
    for j, p in enumerate(skeleton.parents):
        pos[j] = skeleton.offsets[j] + (pos[p] if p >= 0 else 0.0)
    return pos


def skeleton_height(skeleton: Skeleton) -> float:
    """Height of the figure in its rest pose (End Sites included); falls back to the largest extent
    when the rest pose is not upright, and to 1.0 for a skeleton without extent."""
    pos = rest_positions(skeleton)
    ends = np.array([pos[j] + off for j, off in skeleton.end_sites.items()]).reshape(-1, 3)
    pts = np.concatenate([pos, ends])
    ext = pts.max(axis=0) - pts.min(axis=0)
    h = float(ext[1])
    if h < 0.5 * float(ext.max()):
        h = float(ext.max())
    if not h > 0:
        # no extent: sum of bone lengths as a last resort
        h = float(np.linalg.norm(skeleton.offsets, axis=1).sum()) or 1.0
    return h


@dataclass
class BodyModel:
    """Capsules of a skeleton. ``C`` capsules, ``P = J + E`` key points (joints, then End Sites).

    Attributes
    ----------
    weights : (2C, P) end points of capsule c are rows 2c, 2c+1 of ``weights @ keypoints``.
    radii : (C, 2) world radius at each end.
    material : (C, 2) clothing region at each end; ``split`` (C,) the fraction along the capsule where
        it changes from the first to the second (1.0 = one material).
    owner : (C,) joint index that moves the capsule (its part id in masks).
    kind : list of C body-part names (``"thigh"``, ``"head"`` ...).
    is_head : (C,) bool (head capsules get hair on the top and back).
    end_site_owner : (E,) joint index of each End Site key point.
    height : figure height in world units.
    """

    weights: np.ndarray
    radii: np.ndarray
    material: np.ndarray
    split: np.ndarray
    owner: np.ndarray
    kind: list[str]
    is_head: np.ndarray
    end_site_owner: np.ndarray
    end_site_offsets: np.ndarray
    height: float
    n_joints: int

    @property
    def n_capsules(self) -> int:
        return len(self.kind)

    def keypoints(self, positions: np.ndarray, matrices: np.ndarray) -> np.ndarray:
        """(F, P, 3) joints followed by End Sites, from forward kinematics output."""
        if len(self.end_site_owner) == 0:
            return positions
        owners = self.end_site_owner
        ends = positions[:, owners] + np.einsum("feij,ej->fei", matrices[:, owners], self.end_site_offsets)
        return np.concatenate([positions, ends], axis=1)

    def capsule_ends(self, keypoints: np.ndarray) -> np.ndarray:
        """(F, C, 2, 3) capsule end points."""
        F = keypoints.shape[0]
        ends = np.einsum("cp,fpd->fcd", self.weights, keypoints)
        return ends.reshape(F, self.n_capsules, 2, 3)


def build_body(skeleton: Skeleton, appearance=None) -> BodyModel:
    """The capsule body of ``skeleton``; ``appearance`` supplies build (thickness), sleeve and leg
    lengths (see :class:`vidstyle.render.appearance.Appearance`)."""
    build = getattr(appearance, "build", 1.0)
    long_sleeves = getattr(appearance, "sleeves", "short") == "long"
    shorts = getattr(appearance, "shorts", False)
    gloves = getattr(appearance, "gloves", None) is not None
    barefoot = getattr(appearance, "shoes", 0) is None

    names = skeleton.names
    J = skeleton.n_joints
    H = skeleton_height(skeleton)
    rest = rest_positions(skeleton)
    es_owner = np.array(sorted(skeleton.end_sites), dtype=np.int64)
    es_off = np.array([skeleton.end_sites[j] for j in es_owner]).reshape(-1, 3)
    P = J + len(es_owner)
    rest_kp = np.concatenate([rest, rest[es_owner] + es_off]) if len(es_owner) else rest

    bones: list[tuple[int, int, str]] = []  # (start key point, end key point, kind)
    for j in range(J):
        p = int(skeleton.parents[j])
        if p >= 0:
            bones.append((p, j, classify_bone(names[p], names[j])))
    for e, j in enumerate(es_owner):
        bones.append((int(j), J + e, classify_bone(names[j], names[j] + "Site")))

    def owner_of(a: int) -> int:
        return a if a < J else int(es_owner[a - J])

    # head: the first joint classified as head (by name), else the highest leaf of the rest pose
    head_joint = next((j for j in range(J) if _has(names[j], "head", "skull") and not _has(names[j], "end")), None)
    if head_joint is None:
        leaves = [j for j in range(J) if not skeleton.children(j)]
        if leaves:
            cand = max(leaves, key=lambda j: rest[j, 1])
            if rest[cand, 1] > rest[:, 1].mean() + 0.2 * H:
                head_joint = cand

    rows_a: list[np.ndarray] = []
    rows_b: list[np.ndarray] = []
    radii, mats, splits, owners, kinds, heads = [], [], [], [], [], []

    def point(k: int) -> np.ndarray:
        v = np.zeros(P)
        v[k] = 1.0
        return v

    def add(wa, wb, ra, rb, ma, mb, split, owner, kind, head=False):
        rows_a.append(wa)
        rows_b.append(wb)
        radii.append((ra * H * build, rb * H * build))
        mats.append((ma, mb))
        splits.append(split)
        owners.append(owner)
        kinds.append(kind)
        heads.append(head)

    # waist height for trousers/shirt on the torso: 30 % of the way from hips to shoulders (rest pose)
    hips = [a for a, b, k in bones if k == "thigh"]
    shoulders = [a for a, b, k in bones if k == "upperarm"]
    y_hip = rest[hips, 1].mean() if hips else rest[0, 1]
    y_sh = rest[shoulders, 1].mean() if shoulders else y_hip + 0.3 * H
    y_waist = y_hip + 0.3 * (y_sh - y_hip)

    def torso_split(a_pt: np.ndarray, b_pt: np.ndarray) -> tuple[int, int, float]:
        ya, yb = a_pt[1], b_pt[1]
        lo_mat, hi_mat = TROUSERS, SHIRT
        if max(ya, yb) <= y_waist:
            return lo_mat, lo_mat, 1.0
        if min(ya, yb) >= y_waist:
            return hi_mat, hi_mat, 1.0
        s = (y_waist - ya) / (yb - ya)
        return (lo_mat, hi_mat, s) if ya < yb else (hi_mat, lo_mat, s)

    material_of = {
        "neck": (SKIN, SKIN),
        "clavicle": (SHIRT, SHIRT),
        "upperarm": (SHIRT, SLEEVE) if not long_sleeves else (SHIRT, SHIRT),
        "forearm": (SHIRT, SHIRT) if long_sleeves else (SKIN, SKIN),
        "hand": (GLOVES, GLOVES) if gloves else (SKIN, SKIN),
        "thigh": (TROUSERS, LEG) if shorts else (TROUSERS, TROUSERS),
        "shin": (SKIN, SKIN) if shorts else (TROUSERS, TROUSERS),
        "foot": (SKIN, SKIN) if barefoot else (SHOES, SHOES),
        "toe": (SKIN, SKIN) if barefoot else (SHOES, SHOES),
        "other": (SHIRT, SHIRT),
    }

    def by_side(joints: list[int]) -> dict[str, int]:
        out: dict[str, int] = {}
        for j in joints:
            s = side_of(names[j]) or ("L" if rest[j, 0] > rest[0, 0] else "R")
            out.setdefault(s, j)
        return out

    # hands and feet: one capsule each, from the wrist / ankle to the farthest key point of its subtree
    # (CMU's FingerBase, HandIndex1, Thumb and ToeBase bones are tiny or zero-length)
    parent_kp = np.concatenate([skeleton.parents, es_owner]) if len(es_owner) else skeleton.parents.copy()

    def subtree(root: int) -> list[int]:
        out = []
        for k in range(P):
            q = int(parent_kp[k]) if k != root else -1
            while q >= 0 and q != root:
                q = int(skeleton.parents[q])
            if q == root and k != root:
                out.append(k)
        return out

    extremity: dict[int, tuple[str, list[int]]] = {}
    for _a, b, kind in bones:
        if b < J and kind in ("forearm", "shin"):
            extremity[b] = ("hand" if kind == "forearm" else "foot", subtree(b))
    merged = set()
    for root, (_, sub) in extremity.items():
        merged.add(root)
        merged.update(k for k in sub if k < J)

    have_hip_cross = len(by_side(hips)) == 2
    have_shoulder_cross = len(by_side(shoulders)) == 2
    for a, b, kind in bones:
        length = float(np.linalg.norm(rest_kp[b] - rest_kp[a]))
        if kind in ("head", "thumb") or a in merged:
            continue
        if (kind == "pelvis" and have_hip_cross) or (kind == "clavicle" and have_shoulder_cross):
            continue  # inside the torso volume built below
        if length < MIN_BONE * H:
            continue
        ra, rb = RADII[kind]
        if kind in TORSO_KINDS:
            ma, mb, s = torso_split(rest_kp[a], rest_kp[b])
        else:
            ma, mb = material_of[kind]
            s = 1.0 if ma == mb else 0.5
            if kind == "upperarm" and not long_sleeves:
                s, mb = 0.55, SKIN
            if kind == "thigh" and shorts:
                s, mb = 0.6, SKIN
        add(point(a), point(b), ra, rb, ma, mb, s, owner_of(a), kind)

    for root, (kind, sub) in extremity.items():
        cands = [k for k in sub if not _has(names[owner_of(k)], "thumb")]
        ra, rb = RADII[kind]
        ma, mb = material_of[kind]
        if kind == "hand" and gloves:
            ra, rb = ra * 1.5, rb * 1.5
        far = max(cands, key=lambda k: np.linalg.norm(rest_kp[k] - rest[root]), default=None)
        reach = np.linalg.norm(rest_kp[far] - rest[root]) if far is not None else 0.0
        if far is not None and reach >= MIN_BONE * H:
            add(point(root), point(far), ra, rb, ma, mb, 1.0, root, kind)
        elif kind == "hand":
            # no hand bones: a short hand continuing the forearm
            elbow = int(skeleton.parents[root])
            L = float(np.linalg.norm(rest[root] - rest[elbow]))
            if L > 1e-6 * H:
                tip = point(root) + (0.07 * H / L) * (point(root) - point(elbow))
                add(point(root), tip, ra, rb, ma, mb, 1.0, root, kind)

    # torso volume: hip -> shoulder on each side, across hips and shoulders
    hip_side, sh_side = by_side(hips), by_side(shoulders)
    root_owner = next((owner_of(a) for a, b, k in bones if k in ("torso", "pelvis")), 0)
    chest_owner = next((owner_of(a) for a, b, k in bones if k == "clavicle"), root_owner)
    for s in ("L", "R"):
        if s in hip_side and s in sh_side:
            h, sh = hip_side[s], sh_side[s]
            ma, mb, sp = torso_split(rest[h], rest[sh])
            # pull the side line slightly inwards so shoulders are not wider than the arms
            wa = point(h)
            wb = point(sh)
            if "L" in sh_side and "R" in sh_side:
                other = sh_side["R" if s == "L" else "L"]
                wb = 0.88 * point(sh) + 0.12 * point(other)
            add(wa, wb, 0.052, 0.040, ma, mb, sp, root_owner, "torso")
    if len(hip_side) == 2:
        add(point(hip_side["L"]), point(hip_side["R"]), 0.055, 0.055, TROUSERS, TROUSERS, 1.0, root_owner, "pelvis")
    if len(sh_side) == 2:
        # across the shoulders, slightly inwards and down (sloping shoulders)
        wl = 0.88 * point(sh_side["L"]) + 0.12 * point(sh_side["R"])
        wr = 0.88 * point(sh_side["R"]) + 0.12 * point(sh_side["L"])
        if len(hip_side) == 2:
            wl = 0.9 * wl + 0.1 * point(hip_side["L"])
            wr = 0.9 * wr + 0.1 * point(hip_side["R"])
        add(wl, wr, 0.040, 0.040, SHIRT, SHIRT, 1.0, chest_owner, "torso")

    # head capsule along the head direction
    if head_joint is not None:
        tip = None
        es = [J + e for e, j in enumerate(es_owner) if j == head_joint]
        kids = skeleton.children(head_joint)
        if es:
            tip = es[0]
        elif kids:
            tip = kids[0]
        base = point(head_joint)
        r = HEAD_RADIUS
        L_tip = float(np.linalg.norm(rest_kp[tip] - rest[head_joint])) if tip is not None else 0.0
        if L_tip >= 0.03 * H:
            # the tip (End Site / child) is the top of the head: sphere-swept from the chin to the crown
            u = (point(tip) - base) / L_tip
            wb = point(tip) - (r * H) * u
            wa = point(tip) - ((HEAD_HEIGHT - r) * H) * u
        else:
            par = int(skeleton.parents[head_joint])
            L_par = float(np.linalg.norm(rest[head_joint] - rest[par])) if par >= 0 else 0.0
            if L_par > 1e-6 * H:
                # no usable tip: the head joint is the base of the skull, the head continues the neck
                u = (base - point(par)) / L_par
                wa = base + ((r - 0.01) * H) * u
                wb = base + ((HEAD_HEIGHT - 0.01 - r) * H) * u
            else:
                wa = wb = base
        add(wa, wb, r, r, SKIN, HAIR, 0.7, head_joint, "head", head=True)

    if not kinds:
        raise ValueError("skeleton has no bones long enough to draw")
    weights = np.empty((2 * len(kinds), P))
    weights[0::2] = np.array(rows_a)
    weights[1::2] = np.array(rows_b)
    return BodyModel(
        weights=weights,
        radii=np.array(radii, dtype=np.float64),
        material=np.array(mats, dtype=np.int64),
        split=np.array(splits, dtype=np.float64),
        owner=np.array(owners, dtype=np.int64),
        kind=kinds,
        is_head=np.array(heads, dtype=bool),
        end_site_owner=es_owner,
        end_site_offsets=es_off,
        height=H,
        n_joints=J,
    )
