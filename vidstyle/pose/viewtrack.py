"""The performer's viewpoint through a video, not frame by frame.

The pictorial structures classify each frame's viewpoint alone (front, left, back, right). On a small or
unfamiliar figure the classifier confuses front with back in runs of a few frames (a walker coming
towards the camera read as walking away), and the pose solved with the back model then has the
performer's left and right swapped: a 3D reconstruction from it turns the body inside out. A person
cannot turn half round between two frames: from the front the camera reaches the back only through a
side. :func:`track_views` finds the most probable sequence of views (Viterbi) on the ring
front - left - back - right, each frame's cost ``-log`` of its classifier score, a step to a neighbouring
view ``step_cost``, at most one step per frame (across a gap of ``g`` frames, ``g`` steps) and, with
``dwell``, at least that many frames between two steps (a half turn takes at least ``2 dwell`` frames:
a real turn is slower than the classifier's flicker). A frame whose
view the tracking turns by 180 degrees gets its left and right keypoints exchanged (the same image
positions, named as the other view names them); a quarter turn takes the new view and keeps its
keypoints as the classified view's model solved them (they are not solved again with the new view's).

The step cost and the dwell are chosen together on validation renders by
``scripts/validate_view_tracking.py`` (``validation/view_tracking.json``):
:data:`vidstyle.reconstruct.defaults.VIEW_STEP_COST` and ``VIEW_DWELL_S`` are the reconstruction's defaults.
"""

from __future__ import annotations

import copy
import math

import numpy as np

from ..formats.poses import Poses

#: the views in ring order (a quarter turn apart)
RING = ("front", "left", "back", "right")
#: score given to a view the classifier left out or scored 0 (keeps ``-log`` finite)
FLOOR = 1e-6


def trackable(poses: Poses) -> list[int]:
    """Indices into ``poses.frames`` of the frames with a pose, a score for every view of :data:`RING` and
    no azimuth of their own (a backend that measures the azimuth, BlazePose from its 3D landmarks, is not
    tracked: its view follows that angle)."""
    return [i for i, f in enumerate(poses.frames)
            if f.found and f.azimuth is None and f.viewpoint in RING and all(v in f.viewpoint_scores for v in RING)]


def viterbi_views(costs: np.ndarray, gaps: np.ndarray, step_cost: float, dwell: int = 1) -> np.ndarray:
    """The least-cost state sequence (T,) over the ring of :data:`RING` (``costs`` (T, 4) per frame and
    state; ``gaps`` (T - 1,) frames between consecutive rows, >= 1): a move of ``d`` ring steps (0-2)
    costs ``d * step_cost`` and is allowed when ``d`` <= the gap and at least ``d * dwell`` frames have
    passed since the previous move (``dwell`` >= 1 frames per quarter turn; the first move is free of
    it). Ties go to the lower state index."""
    costs = np.asarray(costs, dtype=np.float64)
    T = len(costs)
    m = int(dwell)
    if m < 1:
        raise ValueError(f"dwell must be an integer >= 1, got {dwell!r}")
    if T == 0:
        return np.zeros(0, dtype=np.int64)
    K = 2 * m + 1  # frames since the last move, 0..2m (2m: at least that many), per view
    views = np.repeat(np.arange(4), K)
    since = np.tile(np.arange(K), 4)
    ring = np.minimum((views[:, None] - views[None, :]) % 4, (views[None, :] - views[:, None]) % 4)
    acc = np.full(4 * K, np.inf)
    acc[since == K - 1] = costs[0]  # no move yet: free to move at once
    back = np.zeros((T, 4 * K), dtype=np.int64)
    for t in range(1, T):
        g = int(gaps[t - 1])
        elapsed = np.minimum(since + g, K - 1)[:, None]  # (from, 1)
        stay = (ring == 0) & (since[None, :] == elapsed)
        move = (ring > 0) & (ring <= g) & (since[:, None] + g >= ring * m) & (since[None, :] == 0)
        trans = np.where(stay, 0.0, np.where(move, ring * float(step_cost), np.inf))
        total = acc[:, None] + trans  # (from, to)
        back[t] = np.argmin(total, axis=0)
        acc = total[back[t], np.arange(4 * K)] + np.repeat(costs[t], K)
    states = np.zeros(T, dtype=np.int64)
    states[-1] = int(np.argmin(acc))
    for t in range(T - 1, 0, -1):
        states[t - 1] = back[t, states[t]]
    return states // K


def track_views(poses: Poses, step_cost: float, dwell: int = 1) -> Poses:
    """A copy of ``poses`` with the viewpoints tracked through the video (module docstring); ``dwell``:
    at least that many frames between two quarter turns (:func:`viterbi_views`); ``step_cost`` 0 or
    fewer than two trackable frames: an unchanged copy. Frames without view scores (other
    backends, frames without a pose) are left as they are and do not break the chain."""
    from ..mocap.keypoints import MIRROR

    if not (math.isfinite(step_cost) and step_cost >= 0):
        raise ValueError(f"step_cost must be a finite number >= 0, got {step_cost}")
    if isinstance(dwell, bool) or int(dwell) != dwell or dwell < 1:
        raise ValueError(f"dwell must be an integer >= 1, got {dwell!r}")
    out = copy.deepcopy(poses)
    rows = sorted(trackable(out), key=lambda i: out.frames[i].frame)
    if step_cost == 0 or len(rows) < 2:
        return out
    frames = [out.frames[i] for i in rows]
    costs = np.array([[-math.log(max(float(f.viewpoint_scores[v]), FLOOR)) for v in RING] for f in frames])
    gaps = np.maximum(np.diff([f.frame for f in frames]), 1)
    states = viterbi_views(costs, gaps, step_cost, dwell)
    for f, s in zip(frames, states):
        new = RING[int(s)]
        if (RING.index(new) - RING.index(f.viewpoint)) % 4 == 2:  # half a turn: left and right exchange names
            f.points = f.points[MIRROR]
        f.viewpoint = new
    return out
