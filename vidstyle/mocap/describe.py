"""What ``vidstyle mocap info`` and ``vidstyle mocap convert`` do, as library calls: a BVH motion's
summary, and a motion cut, resampled, mirrored or facing-normalised."""

from __future__ import annotations

import os

import numpy as np

from ..errors import InputError, ParameterError
from .keypoints import KeypointMappingError, keypoint_joints
from .kinematics import end_site_positions, forward_kinematics
from .motion import Motion
from .retarget import leg_length


def describe(motion: Motion, file: str | os.PathLike | None = None) -> dict:
    """Joints, frames, fps, duration, bounding box (joints and End Sites, all frames), channels, End
    Sites, leg length, and where the 15 body keypoints sit on the skeleton (``keypoints`` None and
    ``keypoint_error`` set when they cannot be mapped). ``file`` is reported as given."""
    pos, mats = forward_kinematics(motion)
    pos = np.concatenate([pos, end_site_positions(motion, mats, pos)[1]], axis=1)
    lo = pos.reshape(-1, 3).min(axis=0) if motion.n_frames else np.zeros(3)
    hi = pos.reshape(-1, 3).max(axis=0) if motion.n_frames else np.zeros(3)
    try:
        mapping = keypoint_joints(motion.skeleton)
        keypoints = {k: {"joint": m.joint_name, "index": m.joint, "end_site": m.end_site, "how": m.how}
                     for k, m in mapping.items()}
        keypoint_error = None
    except KeypointMappingError as e:
        keypoints, keypoint_error = None, str(e)
    return {
        "file": None if file is None else str(file),
        "joints": motion.n_joints,
        "joint_names": motion.skeleton.names,
        "frames": motion.n_frames,
        "fps": motion.fps,
        "duration_s": motion.duration,
        "bbox_min": lo.round(4).tolist(),
        "bbox_max": hi.round(4).tolist(),
        "channels": int(sum(len(c) for c in motion.skeleton.channels)),
        "end_sites": len(motion.skeleton.end_sites),
        "leg_length": round(leg_length(motion.skeleton), 6),
        "keypoints": keypoints,
        "keypoint_error": keypoint_error,
    }


def edit(
    motion: Motion,
    *,
    start: int | None = None,
    stop: int | None = None,
    fps: float | None = None,
    mirror: bool = False,
    normalize_facing: bool = False,
    source: str | os.PathLike | None = None,
) -> Motion:
    """Frames ``start:stop`` (0-based, stop exclusive), resampled to ``fps`` (slerp), mirrored (left and
    right swapped) and rotated about the vertical so frame 0 faces +Z with the root over the origin, in
    that order. ``source`` names the motion in errors."""
    if fps is not None and not fps > 0:
        raise ParameterError("fps", f"must be positive, got {fps}")
    name = "motion" if source is None else str(source)
    if start is not None or stop is not None:
        n = motion.n_frames
        motion = motion[start:stop]
        if motion.n_frames == 0:
            raise InputError(f"{name}: --start/--stop select no frames (file has {n})")
    if fps is not None:
        motion = motion.resample(fps)
    if mirror:
        try:
            motion = motion.mirror()
        except ValueError as e:
            raise InputError(f"{name}: cannot mirror: {e}") from None
    if normalize_facing and motion.n_frames:
        motion = motion.normalize_facing()
    return motion


def convert(
    src: str | os.PathLike,
    dst: str | os.PathLike,
    *,
    start: int | None = None,
    stop: int | None = None,
    fps: float | None = None,
    mirror: bool = False,
    normalize_facing: bool = False,
) -> Motion:
    """Read the BVH ``src``, :func:`edit` it and write the BVH ``dst`` (atomically); returns the written
    motion. ``fps`` is checked before ``src`` is read."""
    from .bvh import read_bvh, write_bvh

    if fps is not None and not fps > 0:
        raise ParameterError("fps", f"must be positive, got {fps}")
    motion = edit(read_bvh(src), start=start, stop=stop, fps=fps, mirror=mirror, normalize_facing=normalize_facing,
                  source=src)
    write_bvh(motion, dst)
    return motion
