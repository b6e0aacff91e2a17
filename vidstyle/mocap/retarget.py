"""Retargeting clips of one joint layout onto a reference skeleton.

Clips from several sources share a joint layout (the same joint names, after dropping a namespace prefix
such as ``mixamorig:``, and the same parents) but not bone lengths or length units (CMU's ~5.64 cm units,
metres, centimetres). :func:`retarget` puts such a clip on the reference skeleton: local joint
rotations are kept as they are, the rest offsets become the reference's, and the root translation is
scaled by ``leg_length(reference) / leg_length(clip)`` so steps and jumps keep their size relative to
the body. Clips with another joint layout cannot be retargeted this way; they map onto the named body
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
    """Length of the bone chain from the root down to the lowest point of the rest pose (a joint or End
    Site; a foot): the sum of the bone lengths along it. 0 when the skeleton is a single point."""
    pos, ends = rest_positions(skeleton)
    pts = [(pos[j, 1], j, None) for j in range(skeleton.n_joints)] + [(e[1], j, e) for j, e in ends.items()]
    ys = np.array([p[0] for p in pts])
    # the first of the (near-)lowest points, with a tolerance relative to the body's extent, so the same
    # point is chosen whatever the unit (float rounding must not flip a tie between a toe and its End Site)
    tol = 1e-6 * max(float(ys.max() - ys.min()), 1e-300)
    _, j, end = next(p for p in pts if p[0] <= ys.min() + tol)
    total = float(np.linalg.norm(end - pos[j])) if end is not None else 0.0
    while skeleton.parents[j] >= 0:
        total += float(np.linalg.norm(skeleton.offsets[j]))
        j = int(skeleton.parents[j])
    return total


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
