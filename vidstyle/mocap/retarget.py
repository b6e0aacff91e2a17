"""Retargeting clips of one joint layout onto a reference skeleton.

Clips from several sources share a joint layout (the same joint names, after dropping a namespace prefix
such as ``mixamorig:``, and the same parents) but not bone lengths or length units (CMU's ~5.64 cm units,
metres, centimetres). :func:`retarget` puts such a clip on the reference skeleton: local joint
rotations are kept as they are, the rest offsets become the reference's, and the root translation is
scaled by ``leg_length(reference) / leg_length(clip)`` (hip height above the soles in the rest pose)
so the feet stay on the floor and steps and jumps keep their size relative to the body. Clips with another joint layout cannot be retargeted this way; they map onto the named body
keypoints instead (:mod:`vidstyle.mocap.keypoints`).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ..errors import InputError
from .motion import Motion
from .skeleton import Skeleton


def _plain(name: str) -> str:
    return name.rsplit(":", 1)[-1]


def same_layout(a: Skeleton, b: Skeleton) -> bool:
    """Same joints (names without a namespace prefix) with the same parents, in the same order."""
    return [_plain(n) for n in a.names] == [_plain(n) for n in b.names] and np.array_equal(a.parents, b.parents)


def rest_positions(skeleton: Skeleton) -> tuple[np.ndarray, dict[int, np.ndarray]]:
    """(J, 3) joint positions of the rest pose (root at its offset) and End Site positions by joint."""
    pos = np.zeros((skeleton.n_joints, 3))
    for j, p in enumerate(skeleton.parents):
        pos[j] = skeleton.offsets[j] + (pos[p] if p >= 0 else 0.0)
    return pos, {j: pos[j] + off for j, off in skeleton.end_sites.items()}


def leg_length(skeleton: Skeleton) -> float:
    """Leg length in the rest pose: the height of the root above the lowest joint or End Site (a sole),
    i.e. hip height when standing. This is the ratio that keeps retargeted feet on the floor: a root
    path scaled by it puts the new, shorter or longer legs' soles where the old ones were. 0 for a
    skeleton without anything below its root."""
    pos, ends = rest_positions(skeleton)
    ys = np.concatenate([pos[:, 1], [e[1] for e in ends.values()]]) if ends else pos[:, 1]
    return float(max(pos[0, 1] - ys.min(), 0.0))


def stature(skeleton: Skeleton) -> float:
    """Standing height in the rest pose: from the lowest to the highest joint or End Site (a sole to the top
    of the head for an upright rest pose, as a person's height is measured), in the skeleton's length unit."""
    pos, ends = rest_positions(skeleton)
    ys = np.concatenate([pos[:, 1], [e[1] for e in ends.values()]]) if ends else pos[:, 1]
    return float(ys.max() - ys.min())


def retarget(motion: Motion, reference: Skeleton, source: str = "motion") -> tuple[Motion, float]:
    """``motion`` on ``reference`` (same joint layout): rotations kept, offsets the reference's, root
    translation scaled by the leg-length ratio. Returns the motion and the scale. Raises
    :class:`~vidstyle.errors.InputError` naming ``source`` when the layouts differ."""
    if not same_layout(motion.skeleton, reference):
        a, b = motion.skeleton, reference
        diff = next((i for i, (x, y) in enumerate(zip(a.names, b.names)) if _plain(x) != _plain(y)), min(a.n_joints, b.n_joints))
        raise InputError(
            f"{source}: joint layout differs from the reference skeleton ({a.n_joints} vs {b.n_joints} joints; "
            f"first difference at joint {diff}); only clips of one joint layout can be combined in a motion graph "
            "(see `vidstyle mocap info` for its keypoint mapping)"
        )
    h, h_ref = leg_length(motion.skeleton), leg_length(reference)
    scale = h_ref / h if h > 1e-12 and h_ref > 1e-12 else 1.0
    if motion.skeleton is reference or (np.allclose(motion.skeleton.offsets, reference.offsets) and scale == 1.0):
        return Motion(reference, motion.rotations, motion.translations, motion.fps), 1.0
    trans = np.broadcast_to(reference.offsets, motion.translations.shape).copy()
    # animated offsets (position channels on non-root joints) scale like the root
    animated = reference.has_position_channels() & (reference.parents >= 0)
    trans[:, animated] = motion.translations[:, animated] * scale
    return Motion(reference, motion.rotations, trans, motion.fps, root_positions=motion.root_positions * scale), scale


def retarget_clips(motions: Sequence[Motion], reference: Skeleton, sources: Sequence[str] | None = None) -> list[tuple[Motion, float]]:
    """:func:`retarget` of every motion (``sources`` name them in errors)."""
    sources = list(sources) if sources is not None else [f"clip {i}" for i in range(len(motions))]
    return [retarget(m, reference, s) for m, s in zip(motions, sources)]


def rescale(motion: Motion, factor: float) -> Motion:
    """The same motion in another length unit: offsets, End Sites and every translation times
    ``factor`` (e.g. 0.0564 turns CMU's units into metres); rotations unchanged."""
    sk = motion.skeleton
    skeleton = Skeleton(list(sk.names), sk.parents.copy(), sk.offsets * factor, list(sk.channels),
                        {j: v * factor for j, v in sk.end_sites.items()})
    return Motion(skeleton, motion.rotations.copy(), motion.translations * factor, motion.fps)


def library_keypoints(motion: Motion, reference: Skeleton | None = None) -> np.ndarray:
    """(F, 15, 3) body keypoints of a clip of any joint layout (:func:`vidstyle.mocap.keypoints.keypoint_positions`,
    joints found by name or topology), scaled by ``leg_length(reference) / leg_length(clip)`` so clips of
    other units and body sizes are comparable with ``reference``'s (its own scale when ``None``).
    Raises :class:`~vidstyle.errors.InputError` when the skeleton has no joint for some keypoint."""
    from .keypoints import KeypointMappingError, keypoint_positions

    try:
        pts = keypoint_positions(motion)
    except KeypointMappingError as e:
        raise InputError(f"motion: cannot place the body keypoints ({e})") from None
    if reference is None:
        return pts
    h, h_ref = leg_length(motion.skeleton), leg_length(reference)
    return pts * (h_ref / h if h > 1e-12 and h_ref > 1e-12 else 1.0)


def retarget_rest_corrected(motion: Motion, target: Skeleton) -> Motion:
    """``motion`` on skeleton ``target`` of the same hierarchy but another *rest pose*: every bone keeps
    its global direction (the rest-pose difference of each non-branching joint's bone is absorbed into
    that joint's rotation), and the root path is scaled by the leg-length ratio. Unlike
    :func:`retarget`, which keeps local rotations (right when the rest poses
    agree), this is needed for CMU clips on the library's clean T-pose: CMU's rest legs splay 20 degrees,
    and copied rotations would turn the knees inwards."""
    from scipy.spatial.transform import Rotation

    from .kinematics import forward_kinematics

    src = motion.skeleton
    if not src.same_hierarchy(target):
        raise InputError("retarget: the clip's skeleton does not have the library skeleton's joints")
    J = src.n_joints
    # rest correction C_j: a rotation taking the target's rest direction of j's (first) child bone onto
    # the source's; global target rotation G'_j = G_j C_j keeps every bone's world direction.
    corr = np.tile(np.array([0.0, 0.0, 0.0, 1.0]), (J, 1))
    for j in range(J):
        kids = src.children(j)
        if len(kids) != 1:  # a branching joint (hips, chest, hand) keeps its rotation
            continue
        a = np.asarray(src.offsets[kids[0]], float)
        b = np.asarray(target.offsets[kids[0]], float)
        if np.linalg.norm(a) < 1e-9 or np.linalg.norm(b) < 1e-9:
            continue
        r, _ = Rotation.align_vectors([a], [b])
        corr[j] = r.as_quat()
    _, mats = forward_kinematics(motion)  # (F, J, 3, 3) global rotations
    C = Rotation.from_quat(corr).as_matrix()
    G = mats @ C[None]
    local = np.empty_like(G)
    for j in range(J):
        p = src.parents[j]
        local[:, j] = G[:, j] if p < 0 else np.swapaxes(G[:, p], 1, 2) @ G[:, j]
    q = Rotation.from_matrix(local.reshape(-1, 3, 3)).as_quat().reshape(-1, J, 4)
    from .quat import continuous_quaternions

    scale = leg_length(target) / max(leg_length(src), 1e-9)
    return Motion(target, continuous_quaternions(q), None, motion.fps, root_positions=motion.root_positions * scale)
