"""Walks through a motion graph that realise a requested action sequence.

The request is a label per output frame (the sequence's actions, each for its duration, resampled to
the graph's frame rate). The walk minimises

    sum over transitions (cost / threshold + transition_penalty) + mismatch_penalty * #frames whose label
    differs from the requested one

by dynamic programming over (graph frame x output time): at each output frame the walk either plays
the next frame of the current clip or completes a transition, whose k blended frames count with the
label of the clip that dominates the blend. With transitions sorted by arrival frame, one output frame
costs a few vector operations over the component's frames and transitions, so synthesis runs far
faster than real time. Sequence file (written by ``vidstyle generate``)::

    {"classes": [...], "sequence": [{"action": "Jab", "frames": 14}, ...], "fps": 20}

(``action`` may be a class index; a plain JSON list of action names is also accepted, each then lasting
``default_seconds``.)
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..mocap import Motion
from .blend import blend_frames, blend_weight, compose, place
from .graph import MotionGraph

log = logging.getLogger(__name__)


@dataclass
class Step:
    action: str
    frames: int  # at the graph's fps


def read_sequence(path: str | Path, fps: float, default_seconds: float = 1.0) -> list[Step]:
    """Steps of a sequence file (see the module docstring), durations converted to ``fps`` frames."""
    from ..fileio import read_json

    data = read_json(path)
    return parse_sequence(data, fps, default_seconds, source=str(path))


def parse_sequence(data, fps: float, default_seconds: float = 1.0, source: str = "--sequence") -> list[Step]:
    default = max(1, int(round(default_seconds * fps)))
    if isinstance(data, list):
        items, classes, seq_fps = data, [], None
    elif isinstance(data, dict) and isinstance(data.get("sequence"), list):
        items, classes, seq_fps = data["sequence"], list(data.get("classes") or []), data.get("fps")
    else:
        raise InputError(f"{source}: expected a list of actions or an object with a 'sequence' list")
    steps = []
    for i, item in enumerate(items):
        if isinstance(item, (str, int)):
            action, n = item, None
        elif isinstance(item, dict) and "action" in item:
            action, n = item["action"], item.get("frames")
            if n is None and "seconds" in item:
                n = float(item["seconds"]) * (seq_fps or fps)
        else:
            raise InputError(f"{source}: step {i}: expected an action name or {{'action', 'frames'}}")
        if isinstance(action, int) and not isinstance(action, bool):
            if not 0 <= action < len(classes):
                raise InputError(f"{source}: step {i}: class index {action} outside 'classes'")
            action = classes[action]
        if n is None:
            frames = default
        else:
            try:
                n = float(n)
            except (TypeError, ValueError):
                raise InputError(f"{source}: step {i}: 'frames' must be a number") from None
            if n <= 0:
                raise InputError(f"{source}: step {i}: 'frames' must be positive")
            frames = max(1, int(round(n * fps / float(seq_fps)))) if seq_fps else max(1, int(round(n)))
        steps.append(Step(str(action), frames))
    if not steps:
        raise InputError(f"{source}: empty sequence")
    return steps


@dataclass
class Walk:
    """Per output frame: database frame shown (the dominant one while blending), transition index or -1."""

    frames: np.ndarray
    transition: np.ndarray
    requested: list[str]
    steps: list[Step]
    transitions_used: list[int] = field(default_factory=list)
    cost: float = 0.0


def plan_walk(
    graph: MotionGraph,
    steps: list[Step],
    mismatch_penalty: float = 5.0,
    transition_penalty: float = 0.2,
    strict: bool = True,
) -> Walk:
    """Minimum-cost walk realising ``steps`` (see the module docstring)."""
    k = int(graph.window)
    names = graph.label_names_
    scc = np.flatnonzero(graph.scc_)
    if not len(scc):
        raise InputError("--graph: the graph has no strongly connected component to walk")
    lab_scc = graph.labels_[scc]
    present = {names[i] for i in np.unique(lab_scc)}
    prev = None
    for s, step in enumerate(steps):
        if step.action not in present:
            where = "has no clips labelled" if step.action not in names else "keeps no frames (after pruning) of"
            raise InputError(
                f"--sequence: step {s} ({step.action!r}{', after ' + repr(prev) if prev else ''}): the graph {where} "
                f"{step.action!r}; it knows {sorted(present)}"
            )
        prev = step.action
    acts = sorted({st.action for st in steps})
    act_id = {a: i for i, a in enumerate(acts)}
    # label of every graph label in request space (-1: never requested)
    g2r = np.array([act_id.get(nm, -1) for nm in names])
    req = np.concatenate([np.full(st.frames, act_id[st.action]) for st in steps])
    T = len(req)

    n = len(scc)
    node_lab = g2r[lab_scc]
    mm = np.where(node_lab[None, :] == np.arange(len(acts))[:, None], 0.0, mismatch_penalty)  # (A, n)
    compact = np.full(graph.n_frames, -1)
    compact[scc] = np.arange(n)
    prev_ok = np.zeros(n, bool)
    prev_ok[1:] = (scc[1:] == scc[:-1] + 1) & (graph.frame_clip_[scc[1:]] == graph.frame_clip_[np.maximum(scc[1:] - 1, 0)])

    use = np.flatnonzero(graph.trans_in_scc_)
    dep = compact[graph.trans_from_[use] - 1]
    arr = compact[graph.trans_to_[use]]
    order = np.argsort(arr, kind="stable")
    use, dep, arr = use[order], dep[order], arr[order]
    thr = graph.threshold_ or 1.0
    tcost = graph.trans_cost_[use] / thr + transition_penalty
    # labels of the k blend frames: the departing clip's while alpha >= 1/2, then the arriving clip's
    p = np.arange(k)
    from_side = blend_weight(p, k) >= 0.5
    fa = graph.trans_from_[use][:, None] + p[None, :]
    fb = graph.trans_to_[use][:, None] - (k - 1) + p[None, :]
    blend_lab = g2r[np.where(from_side[None, :], graph.labels_[fa], graph.labels_[fb])]  # (E, k)
    blend_mm_const = mismatch_penalty * (blend_lab[:, :, None] != np.arange(len(acts))[None, None, :]).sum(1)  # (E, A)
    uarr, first, gid = np.unique(arr, return_index=True, return_inverse=True)
    arr_pos = np.full(n, -1)
    arr_pos[uarr] = np.arange(len(uarr))

    hist = np.full((k + 1, n), np.inf)
    bp = np.full((T, len(uarr)), -1, dtype=np.int32)
    V = mm[req[0]].copy()
    hist[0] = V
    change = np.zeros(T + 1, int)
    change[1:T] = np.diff(req) != 0
    cum_change = np.cumsum(change)
    for t in range(1, T):
        Vn = np.full(n, np.inf)
        Vn[1:] = V[:-1]
        Vn[~prev_ok] = np.inf
        Vn += mm[req[t]]
        if t >= k and len(use):
            Vk = hist[(t - k) % (k + 1)]
            if cum_change[t] == cum_change[t - k + 1]:
                bmm = blend_mm_const[:, req[t]]
            else:
                bmm = mismatch_penalty * (blend_lab != req[t - k + 1 : t + 1][None, :]).sum(1)
            cand = Vk[dep]
            cand += tcost
            cand += bmm
            best = np.minimum.reduceat(cand, first)
            better = best < Vn[uarr]
            if better.any():
                # index of the best transition within each arrival group
                hit = np.flatnonzero(cand == best[gid])
                ids = np.full(len(uarr), -1, dtype=np.int64)
                ids[gid[hit]] = hit  # last hit per group wins; all have the same cost
                sel = np.flatnonzero(better)
                bp[t, sel] = ids[sel]
                Vn[uarr[sel]] = best[sel]
        V = Vn
        hist[t % (k + 1)] = V
    end = int(np.argmin(V))
    if not np.isfinite(V[end]):
        raise InputError("--sequence: no walk of the requested length exists in the graph")
    frames = np.empty(T, np.int64)
    trans = np.full(T, -1, np.int64)
    used = []
    t, i = T - 1, end
    while t >= 0:
        e = bp[t, arr_pos[i]] if arr_pos[i] >= 0 else -1
        if e >= 0 and t >= k:
            ge = int(use[e])
            used.append(ge)
            fa_e, fb_e = graph.trans_from_[ge] + p, graph.trans_to_[ge] - (k - 1) + p
            lo = t - k + 1
            frames[lo : t + 1] = np.where(from_side, fa_e, fb_e)
            trans[lo : t + 1] = ge
            t, i = lo - 1, int(dep[e])
        else:
            frames[t] = scc[i]
            t, i = t - 1, i - 1
    used.reverse()
    requested = [acts[r] for r in req]
    walk = Walk(frames, trans, requested, steps, used, float(V[end]))
    _check_steps(graph, walk, strict)
    return walk


def _check_steps(graph: MotionGraph, walk: Walk, strict: bool) -> None:
    names = graph.label_names_
    got = [names[x] for x in graph.labels_[walk.frames]]
    start = 0
    for s, step in enumerate(walk.steps):
        seg = got[start : start + step.frames]
        hit = sum(g == step.action for g in seg)
        if hit == 0 and strict:
            prev = walk.steps[s - 1].action if s else None
            raise InputError(
                f"--sequence: step {s} ({step.action!r}, {step.frames} frames{', after ' + repr(prev) if prev else ''}): "
                f"the graph cannot reach {step.action!r} {'from ' + repr(prev) + ' ' if prev else ''}within the requested "
                "duration (no transition path; add clips, raise the threshold or lengthen the step)"
            )
        if hit < 0.5 * len(seg):
            log.warning("step %d (%s): only %d of %d frames carry the label", s, step.action, hit, len(seg))
        start += step.frames


def render_walk(graph: MotionGraph, walk: Walk) -> Motion:
    """The output motion of a walk: clip frames placed by the accumulated alignments, transitions blended.

    The first frame is turned to face +Z with its root above the origin.
    """
    k = int(graph.window)
    T = len(walk.frames)
    rot = np.empty((T, graph.skeleton_.n_joints, 4))
    root = np.empty((T, 3))
    first = graph.motion(walk.frames[:1])
    ang = first.facing_angles()[0]
    theta = -ang
    c, s = np.cos(theta), np.sin(theta)
    r0 = graph.root_positions_[walk.frames[0]]
    off = -np.array([c * r0[0] + s * r0[2], -s * r0[0] + c * r0[2]])
    t = 0
    while t < T:
        e = walk.transition[t]
        if e < 0:
            t1 = t
            while t1 < T and walk.transition[t1] < 0 and (t1 == t or walk.frames[t1] == walk.frames[t1 - 1] + 1):
                t1 += 1
            f = walk.frames[t:t1]
            rot[t:t1], root[t:t1] = place(graph.rotations_[f], graph.root_positions_[f], theta, off)
            t = t1
            continue
        n = min(k, T - t)
        fa = graph.trans_from_[e] + np.arange(k)
        fb = graph.trans_to_[e] - (k - 1) + np.arange(k)
        ra, pa = place(graph.rotations_[fa], graph.root_positions_[fa], theta, off)
        theta, off = compose(theta, off, float(graph.trans_theta_[e]), np.array([graph.trans_x0_[e], graph.trans_z0_[e]]))
        rb, pb = place(graph.rotations_[fb], graph.root_positions_[fb], theta, off)
        br, bp = blend_frames(ra, pa, rb, pb, k)
        rot[t : t + n], root[t : t + n] = br[:n], bp[:n]
        t += n
    return Motion(graph.skeleton_, rot, None, graph.fps, root_positions=root)


def walk_labels(graph: MotionGraph, walk: Walk, bvh_name: str) -> dict:
    """The ``<out>.labels.json`` document of a walk."""
    names = graph.label_names_
    clip_of = graph.frame_clip_[walk.frames]
    starts = np.asarray(graph.clips_["start"])
    events, t = [], 0
    for st in walk.steps:
        events.append({"label": st.action, "start": t, "end": t + st.frames})
        t += st.frames
    return {
        "bvh": bvh_name,
        "fps": graph.fps,
        "classes": sorted(set(walk.requested)),
        "labels": walk.requested,
        "source_labels": [names[x] for x in graph.labels_[walk.frames]],
        "source_clip": [graph.clips_["names"][c] for c in clip_of],
        "source_frame": (walk.frames - starts[clip_of]).tolist(),
        "graph_frame": walk.frames.tolist(),
        "transition": walk.transition.tolist(),
        "transitions_used": walk.transitions_used,
        "events": events,
        "cost": walk.cost,
    }
