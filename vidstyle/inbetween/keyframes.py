"""Keyframe-to-keyframe synthesis of a whole keyframes file (what ``vidstyle synthesize --keyframes`` runs).

>>> from vidstyle.motiongraph import MotionGraph                                      # doctest: +SKIP
>>> motion = synthesize_keyframes(MotionGraph.load("graph.npz"), "keys.json", "markov")  # doctest: +SKIP

Every keyframe's pose is read from its clip (retargeted onto the graph's skeleton like library clips),
placed at output frame ``round((time - first time) * fps)`` at the graph's frame rate, and each consecutive
pair in-betweened by the chosen method (:data:`METHODS`). The first keyframe keeps its clip's heading and
floor position; each later one keeps its pose (joint rotations, root height) and takes the heading and
floor position the motion arrives at (``slerp``: those of the keyframe before it, so the character turns
and travels only as the library motion does).
"""

from __future__ import annotations

import os
import time as _time
from dataclasses import dataclass, field

import numpy as np

from ..errors import InputError
from ..formats.keyframes import Keyframes, read_keyframes
from ..mocap import Motion, read_bvh
from ..mocap.retarget import retarget
from . import defaults as D
from .graphpath import GraphInbetweener
from .markov import MarkovInbetweener
from .poses import Keypose, placement_onto, slerp_inbetween

METHODS = D.METHODS


@dataclass
class KeyframeSynthesis:
    motion: Motion
    key_frames: list[int]  # output frame of each keyframe
    method: str
    seconds: float
    info: dict = field(default_factory=dict)


def load_keyposes(keys: Keyframes, graph) -> list[Keypose]:
    """The pose of every keyframe on the graph's skeleton (with the frame one graph step before it)."""
    cache: dict[str, Motion] = {}
    poses = []
    for i, k in enumerate(keys.keyframes):
        path = keys.clip_path(k)
        if str(path) not in cache:
            m = read_bvh(path)
            m, _scale = retarget(m, graph.skeleton_, f"{keys.path or 'keyframes'}: keyframes[{i}].clip {path}")
            cache[str(path)] = m
        m = cache[str(path)]
        if k.frame >= m.n_frames:
            raise InputError(f"{keys.path or 'keyframes'}: keyframes[{i}].frame: {k.frame} is past the last frame "
                             f"({m.n_frames - 1}) of {path}")
        step = max(1, round(m.fps / float(graph.fps)))
        p = max(k.frame - step, 0)
        prev = Keypose(m.rotations[p].copy(), m.root_positions[p].copy())
        poses.append(Keypose(m.rotations[k.frame].copy(), m.root_positions[k.frame].copy(), prev))
    return poses


def make_inbetweener(method: str, graph, random_state: int = D.RANDOM_STATE):
    """The fitted in-betweener of ``method`` on ``graph`` (``None`` for slerp, which needs no library)."""
    if method == "markov":
        return MarkovInbetweener(random_state=random_state).fit(graph)
    if method == "graph":
        return GraphInbetweener().fit(graph)
    if method == "slerp":
        return None
    raise InputError(f"method: {method!r} is not one of {', '.join(METHODS)}")


def inbetween_pair(model, start: Keypose, end: Keypose, n_frames: int, free_end: bool) -> tuple[np.ndarray, np.ndarray]:
    """One in-between with a fitted ``model`` (or slerp when ``None``)."""
    if model is None:
        if free_end:
            end = end.placed(placement_onto(end.rotations[0], end.root, start.rotations[0], start.root))
        return slerp_inbetween(start, end, n_frames)
    return model.inbetween(start, end, n_frames, free_end=free_end)


def synthesize_keyframes(graph, keyframes: str | os.PathLike | Keyframes, method: str = D.METHOD,
                         random_state: int = D.RANDOM_STATE) -> KeyframeSynthesis:
    """Motion through every keyframe of ``keyframes`` (a file or a parsed :class:`Keyframes`)."""
    if method not in METHODS:
        raise InputError(f"method: {method!r} is not one of {', '.join(METHODS)}")
    keys = keyframes if isinstance(keyframes, Keyframes) else read_keyframes(keyframes)
    fps = float(graph.fps)
    t0 = keys.keyframes[0].time
    at = [round((k.time - t0) * fps) for k in keys.keyframes]
    for i in range(1, len(at)):
        if at[i] <= at[i - 1]:
            raise InputError(f"{keys.path or 'keyframes'}: keyframes[{i}].time: {keys.keyframes[i].time:g} s is less "
                             f"than one frame at {fps:g} fps after keyframes[{i - 1}]")
    poses = load_keyposes(keys, graph)
    start_clock = _time.perf_counter()
    model = make_inbetweener(method, graph, random_state)
    rots, roots = [poses[0].rotations[None]], [poses[0].root[None]]
    here = poses[0]
    for i in range(1, len(poses)):
        rot, root = inbetween_pair(model, here, poses[i], at[i] - at[i - 1] + 1, free_end=True)
        rots.append(rot[1:])
        roots.append(root[1:])
        here = Keypose(rot[-1], root[-1], Keypose(rot[-2], root[-2]))
    motion = Motion(graph.skeleton_, np.concatenate(rots), None, fps, root_positions=np.concatenate(roots))
    return KeyframeSynthesis(motion, at, method, _time.perf_counter() - start_clock)
