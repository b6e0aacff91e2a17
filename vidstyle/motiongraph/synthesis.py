"""Walks through a motion graph that realise a requested action sequence.

The request is a label per output frame (the sequence's actions, each for its duration, resampled to
the graph's frame rate). The walk minimises

    sum over transitions (cost / threshold + transition_penalty) + mismatch_penalty * #frames whose label
    differs from the requested one

by dynamic programming over (graph frame x output time): at each output frame the walk either plays
the next frame of the current clip or completes a transition, whose k blended frames count with the
label of the clip that dominates the blend. The DP is exact and blocked by k (see :class:`_Planner`):
the transition step of k output frames is one cache-friendly gather-and-minimum over the transitions,
so planning runs >100x real time on a 10k-frame, 54k-transition graph. Sequence file: what ``vidstyle generate --format json`` writes, as-is::

    {"kind": "vidstyle.sequence", "fps": 20.0,
     "events": [{"action": "Jab", "duration_frames": 14, "start_frame": 0}, ...]}

(durations in frames at the sequence's ``fps``; ``start_frame`` is ignored, steps are played back to
back). Also accepted: ``{"classes": [...], "sequence": [{"action": "Jab" | <class index>, "frames": 14
| "seconds": 0.7}, ...], "fps": 20}`` and a plain JSON list of action names, each lasting
``default_seconds``.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field
from itertools import pairwise
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
    from ..formats import read_json_document
    from ..formats.sequence import parse_sequence as parse_generated

    data = read_json_document(path)
    if isinstance(data, dict) and "kind" in data:  # vidstyle generate --format json: its owner validates it
        seq = parse_generated(data, path)
        data = {"fps": seq.fps, "events": [e.to_dict() for e in seq.events]}
    return parse_sequence(data, fps, default_seconds, source=str(path))


def parse_sequence(data, fps: float, default_seconds: float = 1.0, source: str = "--sequence") -> list[Step]:
    default = max(1, int(round(default_seconds * fps)))
    if isinstance(data, list):
        items, classes, seq_fps = data, [], None
    elif isinstance(data, dict) and isinstance(data.get("sequence"), list):
        items, classes, seq_fps = data["sequence"], list(data.get("classes") or []), data.get("fps")
    elif isinstance(data, dict) and isinstance(data.get("events"), list):  # vidstyle generate --format json
        items, classes, seq_fps = data["events"], list(data.get("classes") or []), data.get("fps")
    else:
        raise InputError(f"{source}: expected a list of actions or an object with a 'sequence' or 'events' list")
    if seq_fps is not None:
        try:
            seq_fps = float(seq_fps)
        except (TypeError, ValueError):
            raise InputError(f"{source}: 'fps' must be a number, got {seq_fps!r}") from None
        if not seq_fps > 0:
            raise InputError(f"{source}: 'fps' must be positive, got {seq_fps}")
    steps = []
    for i, item in enumerate(items):
        if isinstance(item, (str, int)):
            action, n = item, None
        elif isinstance(item, dict) and "action" in item:
            action = item["action"]
            n = item.get("frames", item.get("duration_frames"))
            if n is None and "seconds" in item:
                n = float(item["seconds"]) * (seq_fps or fps)
        else:
            raise InputError(f"{source}: step {i}: expected an action name or {{'action', 'frames' | 'duration_frames'}}")
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
            frames = max(1, int(round(n * fps / seq_fps))) if seq_fps else max(1, int(round(n)))
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
    foot_lock: dict = field(default_factory=dict)  # filled by render_walk
    planner: dict = field(default_factory=dict)  # parameters of plan_walk


def _cap_in_degree(graph: MotionGraph, use: np.ndarray, cap: int) -> np.ndarray:
    """The approximation of ``plan_walk(max_in_degree=cap)``: of the transitions ``use`` arriving at one
    frame from frames of one label, keep the ``cap`` cheapest. Per label, so every label change the exact
    graph offers at a frame stays possible; what is lost is the choice among similar departures, whose
    effect on the walk cost is measured against the exact DP (see the closing note of issue 6)."""
    if cap < 1:
        raise InputError(f"--max-in-degree: must be at least 1, got {cap}")
    arr = graph.trans_to_[use]
    lab = graph.labels_[graph.trans_from_[use]]
    cost = graph.trans_cost_[use]
    order = np.lexsort((cost, lab, arr))
    key = arr[order] * (int(lab.max()) + 1) + lab[order]
    first = np.flatnonzero(np.concatenate([[True], key[1:] != key[:-1]]))
    rank = np.arange(len(order)) - np.repeat(first, np.diff(np.concatenate([first, [len(order)]])))
    return np.sort(use[order[rank < cap]])


class _Planner:
    """The dynamic programme of :func:`plan_walk`, blocked by the window ``k``.

    ``V_t[i]``: least cost of an output prefix of ``t + 1`` frames ending at component frame ``i``::

        V_t[i] = min( V_{t-1}[i-1] + mm_t[i]                 (play on; i-1 -> i inside one clip)
                      min_{e: arr_e = i} V_{t-k}[dep_e] + c_e(t) )   (a k-frame transition ends at t)

    A transition read ``V`` from k frames earlier, so the transition minima of the k frames of one block
    ``[b k, b k + k)`` depend only on the previous block: they are computed together, as one gather of
    (E, k) values and a per-arrival-group minimum over rows laid out by rank within the group (groups
    sorted by in-degree, so row ``r`` is a prefix: ``max in-degree`` vectorised minimum calls per block
    instead of a segmented reduction per frame, which dominated). Only the cheap playback recursion is
    sequential per frame. This is the exact DP (no pruning); back-pointers are not stored but recovered
    by re-evaluating the few candidates of each frame on the optimal path from the stored ``V`` blocks
    (checkpointed and recomputed when the history would exceed ``max_history_bytes``).
    """

    CHUNK = 16384  # transitions per cache-resident chunk of the transition step (measured: 2x on 227k transitions)

    def __init__(self, graph: MotionGraph, acts: list[str], mismatch_penalty: float, transition_penalty: float,
                 max_in_degree: int | None = None):
        k = self.k = int(graph.window)
        names = graph.label_names_
        self.scc = scc = np.flatnonzero(graph.scc_)
        n = self.n = len(scc)
        act_id = {a: i for i, a in enumerate(acts)}
        g2r = np.array([act_id.get(nm, -1) for nm in names])
        node_lab = g2r[graph.labels_[scc]]
        A = len(acts)
        self.mismatch = float(mismatch_penalty)
        self.mm = np.where(node_lab[None, :] == np.arange(A)[:, None], 0.0, self.mismatch)  # (A, n)
        compact = np.full(graph.n_frames, -1)
        compact[scc] = np.arange(n)
        prev_ok = np.zeros(n, bool)
        prev_ok[1:] = (scc[1:] == scc[:-1] + 1) & (graph.frame_clip_[scc[1:]] == graph.frame_clip_[scc[:-1]])
        self.prev_ok = prev_ok
        self.no_prev = np.flatnonzero(~prev_ok)

        use = np.flatnonzero(graph.trans_in_scc_)
        self.dropped = 0
        if max_in_degree is not None and len(use):
            use = _cap_in_degree(graph, use, int(max_in_degree))
            self.dropped = int(graph.trans_in_scc_.sum() - len(use))
        arr = compact[graph.trans_to_[use]]
        p = np.arange(k)
        self.from_side = from_side = blend_weight(p, k) >= 0.5
        # row layout: arrival groups by in-degree (descending); row r holds the r-th transition of every
        # group with more than r transitions, so it is a prefix of the group order. Every per-transition
        # array below is in this order.
        self.E = E = len(use)
        self.row_counts = np.zeros(1, np.int64)
        if E:
            uarr, gid, deg = np.unique(arr, return_inverse=True, return_counts=True)
            gorder = np.argsort(-deg, kind="stable")
            grank = np.empty_like(gorder)
            grank[gorder] = np.arange(len(gorder))
            g = grank[gid]  # group of each transition in sorted order
            order = np.argsort(g, kind="stable")
            rank = np.empty(E, np.int64)
            starts = np.searchsorted(g[order], np.arange(len(uarr)))
            rank[order] = np.arange(E) - starts[g[order]]
            rows = np.lexsort((g, rank))  # transitions by (rank, group)
            use, arr = use[rows], arr[rows]
            self.row_counts = np.bincount(rank, minlength=int(rank.max()) + 1)
            self.row_off = np.concatenate([[0], np.cumsum(self.row_counts)])
            chunks = [0]
            for r in range(1, len(self.row_counts)):
                if self.row_off[r + 1] - self.row_off[chunks[-1]] > self.CHUNK:
                    chunks.append(r)
            self.chunks = chunks + [len(self.row_counts)]
            self.group_node = uarr[gorder]
        dep = compact[graph.trans_from_[use] - 1]
        thr = graph.threshold_ or 1.0
        tcost = graph.trans_cost_[use] / thr + transition_penalty
        # labels of the k blend frames: the departing clip's while alpha >= 1/2, then the arriving clip's
        fa = graph.trans_from_[use][:, None] + p[None, :]
        fb = graph.trans_to_[use][:, None] - (k - 1) + p[None, :]
        blend_lab = g2r[np.where(from_side[None, :], graph.labels_[fa], graph.labels_[fb])]  # (E, k)
        # cum[a, q, e]: blend frames p < q of transition e whose label is not a; a window whose requested
        # labels are constant over [q0, q1) costs cum[a, q1] - cum[a, q0] mismatches there
        cum = np.zeros((A, k + 1, E), np.int32)
        for a in range(A):
            for q in range(k):
                np.add(cum[a, q], blend_lab[:, q] != a, out=cum[a, q + 1])
        self.use, self.dep, self.arr, self.tcost, self.cum = use, dep, arr, tcost, cum
        self.const_cost = tcost[None, :] + self.mismatch * cum[:, k, :]  # (A, E): constant request
        # per node: its incoming transitions (for the back-tracking)
        by_arr = np.argsort(arr, kind="stable")
        self.in_ptr = np.searchsorted(arr[by_arr], np.arange(n + 1))
        self.in_e = by_arr

    # ----------------------------------------------------------------------------------- costs
    def _window_counts(self, win: np.ndarray, cum: np.ndarray) -> np.ndarray:
        """Mismatched blend frames of every transition (columns of ``cum``) against requested ``win``."""
        cuts = np.flatnonzero(np.diff(win)) + 1
        bounds = np.concatenate([[0], cuts, [len(win)]])
        cnt = np.zeros(cum.shape[-1], np.int32)
        for q0, q1 in pairwise(bounds):
            a = win[q0]
            if q0 == 0 and q1 == len(win):
                cnt += cum[a, q1]
            else:
                cnt += cum[a, q1]
                cnt -= cum[a, q0]
        return cnt

    def _cost(self, win: np.ndarray, e) -> np.ndarray:
        """Cost of transitions ``e`` (index or slice into the row-ordered arrays) whose blend covers the
        requested labels ``win``: ``tcost + mismatch * count``, the same arithmetic wherever it is used,
        so back-tracking reproduces the forward values exactly."""
        if (win == win[0]).all():
            return self.const_cost[win[0], e]
        return self.mismatch * self._window_counts(win, self.cum[:, :, e]) + self.tcost[e]

    def transition_cost(self, e: np.ndarray, req: np.ndarray, t: int) -> np.ndarray:
        """Cost of transitions ``e`` ending at output frame t."""
        return self._cost(req[t - self.k + 1 : t + 1], e)

    # ----------------------------------------------------------------------------------- forward
    def first_block(self, req: np.ndarray) -> np.ndarray:
        k = self.k
        B = np.empty((k, self.n))
        B[0] = self.mm[req[0]]
        for c in range(1, k):
            self._play(B[c - 1], B[c], req[c])
        return B

    def _play(self, V: np.ndarray, out: np.ndarray, r: int) -> None:
        out[0] = np.inf
        np.add(V[:-1], self.mm[r][1:], out=out[1:])
        out[self.no_prev] = np.inf

    def block(self, prev: np.ndarray, req: np.ndarray, b: int) -> np.ndarray:
        """V of output frames ``b k .. b k + k - 1`` from those of the previous block (``prev`` (k, n));
        ``req`` is padded to whole blocks."""
        k = self.k
        t0 = b * k
        B = np.empty((k, self.n))
        best = None
        if self.E:
            Vp = np.ascontiguousarray(prev.T)  # (n, k): V_{t-k}[i] for the k frames of this block
            span = req[t0 - k + 1 : t0 + k]
            if (span == span[0]).all():
                const = self.const_cost[span[0]][:, None]
                wins = None
            else:  # a step boundary inside some window: the columns' windows differ
                wins = [req[t0 + c - k + 1 : t0 + c + 1] for c in range(k)]
            # rows in chunks of <= CHUNK transitions, so each chunk's (rows, k) candidates stay in cache
            # while they are gathered, costed and reduced (one (E, k) matrix would stream through memory
            # three times; one row at a time costs Python overhead on graphs with hundreds of rows)
            best = None
            for r0, r1 in zip(self.chunks[:-1], self.chunks[1:]):
                o0, o1 = self.row_off[r0], self.row_off[r1]
                M = np.take(Vp, self.dep[o0:o1], axis=0)
                if wins is None:
                    M += const[o0:o1]
                else:
                    for c, win in enumerate(wins):
                        M[:, c] += self._cost(win, slice(o0, o1))
                for r in range(r0, r1):
                    m = self.row_counts[r]
                    o = self.row_off[r] - o0
                    if best is None:
                        best = M[:m].copy()
                    else:
                        np.minimum(best[:m], M[o : o + m], out=best[:m])
        V = prev[k - 1]
        for c in range(k):
            out = B[c]
            self._play(V, out, req[t0 + c])
            if best is not None:
                cur = out[self.group_node]
                np.minimum(cur, best[:, c], out=cur)
                out[self.group_node] = cur
            V = out
        return B


def plan_walk(
    graph: MotionGraph,
    steps: list[Step],
    mismatch_penalty: float = 5.0,
    transition_penalty: float = 0.2,
    strict: bool = True,
    max_history_bytes: int = 256 << 20,
    max_in_degree: int | None = None,
) -> Walk:
    """Minimum-cost walk realising ``steps`` (see the module docstring and :class:`_Planner`).

    Exact by default. ``max_in_degree`` trades optimality for speed on graphs with many transitions per
    frame: only the cheapest ``max_in_degree`` transitions into each frame from each label are walked
    (:func:`_cap_in_degree`); the walk is then optimal for that subgraph.

    ``max_history_bytes`` bounds the stored DP values; longer requests keep one block in
    ``ceil(history / max_history_bytes)`` and recompute the others while back-tracking (same result).
    """
    k = int(graph.window)
    names = graph.label_names_
    if not graph.scc_.any():
        raise InputError("--graph: the graph has no strongly connected component to walk")
    lab_scc = graph.labels_[graph.scc_]
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
    req = np.concatenate([np.full(st.frames, act_id[st.action]) for st in steps])
    T = len(req)
    P = _Planner(graph, acts, mismatch_penalty, transition_penalty, max_in_degree)
    n = P.n
    nb = -(-T // k)
    reqp = np.concatenate([req, np.full(nb * k - T, req[-1])])  # padded frames never reach frame T-1

    # forward: keep every block, or every `stride`-th as a checkpoint
    stride = max(1, -(-(nb * k * n * 8) // max_history_bytes))
    kept: dict[int, np.ndarray] = {}
    B = P.first_block(reqp)
    kept[0] = B
    for b in range(1, nb):
        B = P.block(B, reqp, b)
        if b % stride == 0 or b == nb - 1:
            kept[b] = B
    last = kept[nb - 1][(T - 1) % k]
    end = int(np.argmin(last))
    if not np.isfinite(last[end]):
        raise InputError("--sequence: no walk of the requested length exists in the graph")
    cost = float(last[end])

    def values(b: int) -> np.ndarray:
        """V of block b (recomputed from the checkpoint before it when not kept)."""
        if b not in kept:
            c = (b // stride) * stride
            Bc = kept[c]
            for bb in range(c + 1, b + 1):
                Bc = P.block(Bc, reqp, bb)
                kept[bb] = Bc
        return kept[b]

    def V(t: int) -> np.ndarray:
        return values(t // k)[t % k]

    # back-track: at (t, i) take the predecessor whose value is least (that is the one the forward pass
    # kept: the same candidates, the same arithmetic)
    frames = np.empty(T, np.int64)
    trans = np.full(T, -1, np.int64)
    used = []
    p = np.arange(k)
    t, i = T - 1, end
    while t >= 0:
        if stride > 1:  # drop recomputed blocks behind us
            for b in [b for b in kept if b > t // k + 1 and b % stride and b != nb - 1]:
                del kept[b]
        best_play = np.inf
        if t > 0 and P.prev_ok[i]:
            best_play = V(t - 1)[i - 1] + P.mm[req[t], i]
        best_e, best_tr = -1, np.inf
        if t >= k and P.E:
            es = P.in_e[P.in_ptr[i] : P.in_ptr[i + 1]]
            if len(es):
                cand = V(t - k)[P.dep[es]] + P.transition_cost(es, req, t)
                j = int(np.argmin(cand))
                best_e, best_tr = int(es[j]), float(cand[j])
        if t == 0:
            frames[0] = P.scc[i]
            break
        if best_e >= 0 and best_tr < best_play:
            ge = int(P.use[best_e])
            used.append(ge)
            fa_e, fb_e = graph.trans_from_[ge] + p, graph.trans_to_[ge] - (k - 1) + p
            lo = t - k + 1
            frames[lo : t + 1] = np.where(P.from_side, fa_e, fb_e)
            trans[lo : t + 1] = ge
            t, i = lo - 1, int(P.dep[best_e])
        else:
            if not np.isfinite(best_play):
                raise RuntimeError("motion graph back-tracking lost the optimal path")  # a bug, not bad input
            frames[t] = P.scc[i]
            t, i = t - 1, i - 1
    used.reverse()
    requested = [acts[r] for r in req]
    walk = Walk(frames, trans, requested, steps, used, cost)
    walk.planner = {"mismatch_penalty": mismatch_penalty, "transition_penalty": transition_penalty,
                    "max_in_degree": max_in_degree, "exact": max_in_degree is None,
                    "transitions_walked": int(P.E), "transitions_dropped": P.dropped}
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
            # generated sequences have steps of a fraction of a second; a k-frame blend plus the approach
            # inside the clip may not fit, which is a fidelity loss, not an error (unless strict)
            log.warning("step %d (%s, %d frames): only %d frames carry the label", s, step.action, len(seg), hit)
        start += step.frames


def render_walk(graph: MotionGraph, walk: Walk, foot_lock: bool = True, ease: int | None = None) -> Motion:
    """The output motion of a walk: clip frames placed by the accumulated alignments, transitions blended,
    and (``foot_lock``) feet that are planted in the source clips held still across the seams by a
    two-bone leg IK (:mod:`.footlock`; ``ease`` frames to release a lock, default ``window // 2 + 1``).

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
    motion = Motion(graph.skeleton_, rot, None, graph.fps, root_positions=root)
    if not foot_lock:
        walk.foot_lock = {"enabled": False}
        return motion
    from .footlock import leg_chains, lock_feet, source_contacts
    from .graph import rest_height

    chains = leg_chains(graph.skeleton_)
    if not chains:
        walk.foot_lock = {"enabled": False, "reason": "no hip-knee-ankle chains in the skeleton"}
        return motion
    contacts = source_contacts(graph, walk.frames, [c[2] for c in chains], rest_height(graph.skeleton_))
    motion, info = lock_feet(motion, contacts, walk.transition >= 0, chains, ease or k // 2 + 1)
    walk.foot_lock = {"enabled": True, **info}
    return motion


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
        "foot_lock": walk.foot_lock,
        "planner": walk.planner,
    }
