"""Walks through a motion graph that realise a requested action sequence.

The request is a label per output frame (the sequence's actions, each for its duration, resampled to
the graph's frame rate). The walk minimises

    sum over the non-playback edges it takes (edge_cost_ / threshold_ + transition_penalty)
    + mismatch_penalty * #output frames whose label differs from the requested one

by dynamic programming over (graph frame x output time) on the graph's edge table (:mod:`.graph`): at
each output frame the walk either plays the next frame of the current clip (a PLAYBACK edge) or completes
a BLEND (k output frames, labelled by the clip that dominates the blend) or an ENHANCEMENT (2k output
frames through its segment, the first k labelled as the departing frames, the last k as the arriving
ones). Every edge's own ``edge_cost_`` is what it is charged, so an enhancement edge cheaper than the
plain blends between two actions is taken when the request asks for that pair, and a removed edge is
simply not there. The DP is exact and blocked by k (see :class:`_Planner`): the edge step of k output
frames is one cache-friendly gather-and-minimum over the edges, so planning runs >100x real time on a
10k-frame, 54k-transition graph (``scripts/bench_graph_edges.py`` compares it with the planner it replaced). Sequence file: what ``vidstyle generate --format json`` writes, as-is::

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
from .blend import blend_frames, blend_weight
from .graph import EdgeKind, MotionGraph

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


def parse_sequence(data, fps: float, default_seconds: float = 1.0, source: str = "sequence") -> list[Step]:
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
    """The approximation of ``plan_walk(max_in_degree=cap)``: of the edges ``use`` arriving at one frame
    from frames of one label, keep the ``cap`` cheapest. Per label, so every label change the exact graph
    offers at a frame stays possible; what is lost is the choice among similar departures, whose effect
    on the walk cost is measured against the exact DP (see the closing note of issue 6)."""
    if cap < 1:
        raise InputError(f"max_in_degree: must be at least 1, got {cap}")
    if not len(use):
        return use
    arr = graph.edge_dst_[use]
    lab = graph.labels_[graph.edge_src_[use]]
    cost = graph.edge_cost_[use]
    order = np.lexsort((cost, lab, arr))
    key = arr[order] * (int(lab.max()) + 1) + lab[order]
    first = np.flatnonzero(np.concatenate([[True], key[1:] != key[:-1]]))
    rank = np.arange(len(order)) - np.repeat(first, np.diff(np.concatenate([first, [len(order)]])))
    return np.sort(use[order[rank < cap]])


def edge_frames(graph: MotionGraph, edges: np.ndarray) -> np.ndarray:
    """(E, d) graph frames that stand for the output frames of ``edges`` (all of one kind; d = k for
    BLEND, 2k for ENHANCEMENT): the dominant frame of a blend, and for an enhancement the departing frames
    then the arriving ones (see :mod:`.graph`). Their labels are the labels the planner charges."""
    k = int(graph.window)
    p = np.arange(k)
    src, dst = graph.edge_src_[edges][:, None], graph.edge_dst_[edges][:, None]
    kinds = set(graph.edge_kind_[edges].tolist())
    if len(kinds) > 1:
        raise ValueError("edge_frames: edges of one kind at a time")
    if kinds == {EdgeKind.ENHANCEMENT}:
        return np.concatenate([src + 1 + p, dst - k + 1 + p], axis=1)
    from_side = blend_weight(p, k) >= 0.5
    return np.where(from_side[None, :], src + 1 + p, dst - k + 1 + p)


class _EdgeSet:
    """The walkable edges of one duration ``d = lag * k`` (BLEND: lag 1, ENHANCEMENT: lag 2), laid out for
    the blocked minimum of :class:`_Planner`."""

    CHUNK = 16384  # edges per cache-resident chunk of the transition step (measured: 2x on 227k transitions)

    def __init__(self, graph: MotionGraph, use: np.ndarray, lag: int, compact: np.ndarray, g2r: np.ndarray, A: int,
                 mismatch: float, transition_penalty: float):
        k = int(graph.window)
        self.lag, self.d = lag, lag * k
        arr = compact[graph.edge_dst_[use]]
        # row layout: arrival groups by in-degree (descending); row r holds the r-th edge of every group
        # with more than r edges, so it is a prefix of the group order. Every per-edge array below is in
        # this order.
        self.E = E = len(use)
        uarr, gid, deg = np.unique(arr, return_inverse=True, return_counts=True)
        gorder = np.argsort(-deg, kind="stable")
        grank = np.empty_like(gorder)
        grank[gorder] = np.arange(len(gorder))
        g = grank[gid]  # group of each edge in sorted order
        order = np.argsort(g, kind="stable")
        rank = np.empty(E, np.int64)
        starts = np.searchsorted(g[order], np.arange(len(uarr)))
        rank[order] = np.arange(E) - starts[g[order]]
        rows = np.lexsort((g, rank))  # edges by (rank, group)
        use, arr = use[rows], arr[rows]
        self.row_counts = np.bincount(rank, minlength=int(rank.max()) + 1)
        self.row_off = np.concatenate([[0], np.cumsum(self.row_counts)])
        chunks = [0]
        for r in range(1, len(self.row_counts)):
            if self.row_off[r + 1] - self.row_off[chunks[-1]] > self.CHUNK:
                chunks.append(r)
        self.chunks = chunks + [len(self.row_counts)]
        self.group_node = uarr[gorder]
        self.use, self.arr = use, arr
        self.dep = compact[graph.edge_src_[use]]
        thr = graph.threshold_ or 1.0
        self.tcost = graph.edge_cost_[use] / thr + transition_penalty
        self.frames = edge_frames(graph, use)  # (E, d)
        lab = g2r[graph.labels_[self.frames]]
        # cum[a, q, e]: output frames p < q of edge e whose label is not a; a window whose requested labels
        # are constant over [q0, q1) costs cum[a, q1] - cum[a, q0] mismatches there
        cum = np.zeros((A, self.d + 1, E), np.int32)
        for a in range(A):
            for q in range(self.d):
                np.add(cum[a, q], lab[:, q] != a, out=cum[a, q + 1])
        self.cum = cum
        self.mismatch = mismatch
        self.const_cost = self.tcost[None, :] + mismatch * cum[:, self.d, :]  # (A, E): constant request
        by_arr = np.argsort(arr, kind="stable")
        self.in_ptr = np.searchsorted(arr[by_arr], np.arange(len(compact) + 1))
        self.in_e = by_arr

    def _window_counts(self, win: np.ndarray, cum: np.ndarray) -> np.ndarray:
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

    def cost(self, win: np.ndarray, e) -> np.ndarray:
        """Cost of edges ``e`` (index or slice into the row-ordered arrays) whose output frames meet the
        requested labels ``win`` (length d): ``tcost + mismatch * count``, the same arithmetic wherever it
        is used, so back-tracking reproduces the forward values exactly."""
        if (win == win[0]).all():
            return self.const_cost[win[0], e]
        return self.mismatch * self._window_counts(win, self.cum[:, :, e]) + self.tcost[e]

    def best(self, Vp: np.ndarray, req: np.ndarray, t0: int, k: int) -> np.ndarray:
        """(groups, k): per arrival group, the least ``V_{t-d}[dep] + cost`` for the k frames
        ``t = t0 .. t0+k-1``; ``Vp`` (n, k) holds ``V_{t-d}``."""
        d = self.d
        span = req[t0 - d + 1 : t0 + k]
        if (span == span[0]).all():
            const = self.const_cost[span[0]][:, None]
            wins = None
        else:  # a step boundary inside some window: the columns' windows differ
            const = None
            wins = [req[t0 + c - d + 1 : t0 + c + 1] for c in range(k)]
        # rows in chunks of <= CHUNK edges, so each chunk's (rows, k) candidates stay in cache while they are
        # gathered, costed and reduced
        best = None
        for r0, r1 in zip(self.chunks[:-1], self.chunks[1:]):
            o0, o1 = self.row_off[r0], self.row_off[r1]
            M = np.take(Vp, self.dep[o0:o1], axis=0)
            if wins is None:
                M += const[o0:o1]
            else:
                for c, win in enumerate(wins):
                    M[:, c] += self.cost(win, slice(o0, o1))
            for r in range(r0, r1):
                m = self.row_counts[r]
                o = self.row_off[r] - o0
                if best is None:
                    best = M[:m].copy()
                else:
                    np.minimum(best[:m], M[o : o + m], out=best[:m])
        return best


class _Planner:
    """The dynamic programme of :func:`plan_walk`, blocked by the window ``k``.

    ``V_t[i]``: least cost of an output prefix of ``t + 1`` frames ending at component frame ``i``::

        V_t[i] = min( V_{t-1}[i-1] + mm_t[i]                       (PLAYBACK edge i-1 -> i)
                      min_{e: dst_e = i} V_{t-d_e}[src_e] + c_e(t) )  (a BLEND (d = k) or ENHANCEMENT
                                                                      (d = 2k) edge ends at t)

    An edge of ``d = lag k`` frames reads ``V`` from ``lag`` blocks earlier, so the edge minima of the k
    frames of one block ``[b k, b k + k)`` depend only on earlier blocks: they are computed together, as
    one gather of (E, k) values and a per-arrival-group minimum over rows laid out by rank within the
    group (:class:`_EdgeSet`). Only the cheap playback recursion is sequential per frame. This is the
    exact DP (no pruning); back-pointers are not stored but recovered by re-evaluating the few candidates
    of each frame on the optimal path from the stored ``V`` blocks (checkpointed and recomputed when the
    history would exceed ``max_history_bytes``).
    """

    def __init__(self, graph: MotionGraph, acts: list[str], mismatch_penalty: float, transition_penalty: float,
                 max_in_degree: int | None = None):
        self.k = int(graph.window)
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
        play = graph.edges(EdgeKind.PLAYBACK, in_scc=True)
        prev_ok = np.zeros(n, bool)
        prev_ok[compact[graph.edge_dst_[play]]] = True  # dst = src + 1, both kept: compact neighbours
        self.prev_ok = prev_ok
        self.no_prev = np.flatnonzero(~prev_ok)
        self.dropped = 0
        self.sets: list[_EdgeSet] = []
        for kind, lag in ((EdgeKind.BLEND, 1), (EdgeKind.ENHANCEMENT, 2)):
            use = graph.edges(kind, in_scc=True)
            if max_in_degree is not None:
                capped = _cap_in_degree(graph, use, int(max_in_degree))
                self.dropped += len(use) - len(capped)
                use = capped
            if len(use):
                self.sets.append(_EdgeSet(graph, use, lag, compact, g2r, A, self.mismatch, transition_penalty))
        self.E = sum(s.E for s in self.sets)
        self.lag = max([s.lag for s in self.sets], default=1)

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

    def block(self, history: list[np.ndarray], req: np.ndarray, b: int) -> np.ndarray:
        """V of output frames ``b k .. b k + k - 1`` from the previous blocks (``history[-m]`` is block
        ``b - m``, each (k, n)); ``req`` is padded to whole blocks."""
        k = self.k
        t0 = b * k
        B = np.empty((k, self.n))
        bests = []
        for s in self.sets:
            if b - s.lag < 0:
                continue
            Vp = np.ascontiguousarray(history[-s.lag].T)  # (n, k): V_{t-d}[i] for the k frames of this block
            bests.append((s, s.best(Vp, req, t0, k)))
        V = history[-1][k - 1]
        for c in range(k):
            out = B[c]
            self._play(V, out, req[t0 + c])
            for s, best in bests:
                cur = out[s.group_node]
                np.minimum(cur, best[:, c], out=cur)
                out[s.group_node] = cur
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

    Exact by default. Every walkable edge (``edge_in_scc_``) of the graph's edge table is a candidate,
    charged ``edge_cost_ / threshold_ + transition_penalty``. ``max_in_degree`` trades optimality for
    speed on graphs with many transitions per frame: only the cheapest ``max_in_degree`` edges of each
    kind into each frame from each label are walked (:func:`_cap_in_degree`); the walk is then optimal
    for that subgraph.

    ``max_history_bytes`` bounds the stored DP values; longer requests keep a few blocks in
    ``ceil(history / max_history_bytes)`` and recompute the others while back-tracking (same result).
    """
    k = int(graph.window)
    names = graph.label_names_
    if not graph.scc_.any():
        raise InputError("graph: the graph has no strongly connected component to walk")
    lab_scc = graph.labels_[graph.scc_]
    present = {names[i] for i in np.unique(lab_scc)}
    missing: dict[str, list[int]] = {}
    for s, step in enumerate(steps):
        if step.action not in present:
            missing.setdefault(step.action, []).append(s)
    if missing:  # every action the graph cannot perform at once, before any planning
        absent = [a for a in missing if a not in names]
        pruned = [a for a in missing if a in names]
        said = "; ".join(f"{a!r} (step{'s' if len(v) > 1 else ''} {', '.join(map(str, v[:8]))}"
                         f"{', ...' if len(v) > 8 else ''})" for a, v in missing.items())
        why = []
        if absent:
            why.append(f"the library it was built from has no frames labelled {', '.join(map(repr, absent))} "
                       "(label library clips with them: build-graph --labels with a CSV file,label[,start,end], "
                       "and --require-classes to check before the build)")
        if pruned:
            why.append(f"{', '.join(map(repr, pruned))} frames are not connected to the rest of the graph and were "
                       "pruned (rebuild with a higher --quantile or --threshold, or add clips that move into them)")
        first = min(v[0] for v in missing.values())
        prev = f", after {steps[first - 1].action!r}" if first else ""
        raise InputError(
            f"steps: step {first} ({steps[first].action!r}{prev}): the graph cannot perform {said}: "
            f"{'; '.join(why)}. It can perform {', '.join(sorted(present - {'unlabelled'})) or 'nothing labelled'}"
        )
    acts = sorted({st.action for st in steps})
    act_id = {a: i for i, a in enumerate(acts)}
    req = np.concatenate([np.full(st.frames, act_id[st.action]) for st in steps])
    T = len(req)
    P = _Planner(graph, acts, mismatch_penalty, transition_penalty, max_in_degree)
    n, M = P.n, P.lag
    nb = -(-T // k)
    reqp = np.concatenate([req, np.full(nb * k - T, req[-1])])  # padded frames never reach frame T-1

    # forward: keep every block, or the M blocks ending at every `stride`-th block as a checkpoint
    stride = max(1, -(-(nb * k * n * 8) // max_history_bytes))

    def checkpoint_member(b: int) -> bool:
        return b == nb - 1 or any((b + j) % stride == 0 for j in range(M))

    kept: dict[int, np.ndarray] = {}
    history = [P.first_block(reqp)]
    kept[0] = history[0]
    for b in range(1, nb):
        B = P.block(history, reqp, b)
        history = (history + [B])[-M:]
        if checkpoint_member(b):
            kept[b] = B
    last = kept[nb - 1][(T - 1) % k]
    end = int(np.argmin(last))
    if not np.isfinite(last[end]):
        raise InputError("steps: no walk of the requested length exists in the graph")
    cost = float(last[end])

    def values(b: int) -> np.ndarray:
        """V of block b (recomputed from the checkpoint before it when not kept)."""
        if b not in kept:
            c = (b // stride) * stride
            hist = [kept[x] for x in range(max(c - M + 1, 0), c + 1)]
            for bb in range(c + 1, b + 1):
                Bc = P.block(hist, reqp, bb)
                kept[bb] = Bc
                hist = (hist + [Bc])[-M:]
        return kept[b]

    def V(t: int) -> np.ndarray:
        return values(t // k)[t % k]

    # back-track: at (t, i) take the predecessor whose value is least (that is one the forward pass kept:
    # the same candidates, the same arithmetic)
    frames = np.empty(T, np.int64)
    trans = np.full(T, -1, np.int64)
    used = []
    t, i = T - 1, end
    while t >= 0:
        if stride > 1:  # drop recomputed blocks behind us
            for b in [b for b in kept if b > t // k + 1 and not checkpoint_member(b)]:
                del kept[b]
        if t == 0:
            frames[0] = P.scc[i]
            break
        best, choice = np.inf, None
        if P.prev_ok[i]:
            best = V(t - 1)[i - 1] + P.mm[req[t], i]
        for s in P.sets:
            if t < s.d:
                continue
            es = s.in_e[s.in_ptr[i] : s.in_ptr[i + 1]]
            if len(es):
                cand = V(t - s.d)[s.dep[es]] + s.cost(req[t - s.d + 1 : t + 1], es)
                j = int(np.argmin(cand))
                if cand[j] < best:
                    best, choice = float(cand[j]), (s, int(es[j]))
        if not np.isfinite(best):
            raise RuntimeError("motion graph back-tracking lost the optimal path")  # a bug, not bad input
        if choice is None:
            frames[t] = P.scc[i]
            t, i = t - 1, i - 1
        else:
            s, e = choice
            ge = int(s.use[e])
            used.append(ge)
            lo = t - s.d + 1
            frames[lo : t + 1] = s.frames[e]
            trans[lo : t + 1] = ge
            t, i = lo - 1, int(s.dep[e])
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
    start, short = 0, 0
    for s, step in enumerate(walk.steps):
        seg = got[start : start + step.frames]
        hit = sum(g == step.action for g in seg)
        if hit == 0 and strict:
            prev = walk.steps[s - 1].action if s else None
            raise InputError(
                f"steps: step {s} ({step.action!r}, {step.frames} frames{', after ' + repr(prev) if prev else ''}): "
                f"the graph cannot reach {step.action!r} {'from ' + repr(prev) + ' ' if prev else ''}within the requested "
                "duration (no transition path; add clips, raise the threshold or lengthen the step)"
            )
        if hit < 0.5 * len(seg):
            # generated sequences have steps of a fraction of a second; a k-frame blend plus the approach
            # inside the clip may not fit, which is a fidelity loss, not an error (unless strict)
            prev = walk.steps[s - 1].action if s else None
            log.warning(
                "step %d (%r, %d frames = %.2f s%s): the motion shows %r in only %d of them; the graph has no "
                "path that reaches %r frames in time%s, so the step is spent in a transition or in the previous "
                "action. Longer steps (synthesize --seconds, or durations in the sequence), library clips that "
                "move %sinto %r, or a graph built with a higher --quantile help; --strict makes a step with none "
                "an error", s, step.action, len(seg), len(seg) / float(graph.fps),
                f", after {prev!r}" if prev else "", step.action, hit, step.action,
                f" from {prev!r}" if prev else "", f"from {prev!r} " if prev else "", step.action)
            short += 1
        start += step.frames
    if short:
        log.warning("%d of %d steps are mostly not shown as asked (the warnings above)", short, len(walk.steps))


def render_walk(graph: MotionGraph, walk: Walk, foot_lock: bool = True, ease: int | None = None) -> Motion:
    """The output motion of a walk: clip frames placed by the accumulated alignments, edges realised by
    kind (BLEND: one k-frame blend; ENHANCEMENT: the two-half blend through its segment, see
    :mod:`.graph`), and (``foot_lock``) feet that are planted in the source clips held still across the
    seams by a two-bone leg IK (:mod:`.footlock`; ``ease`` frames to release a lock, default
    ``window // 2 + 1``).

    The first frame is turned to face +Z with its root above the origin.
    """
    from ..mocap.placement import Placement

    k = int(graph.window)
    T = len(walk.frames)
    rot = np.empty((T, graph.skeleton_.n_joints, 4))
    root = np.empty((T, 3))
    first = graph.motion(walk.frames[:1])
    here = Placement.facing(float(first.facing_angles()[0]), graph.root_positions_[walk.frames[0]])
    p = np.arange(k)
    t = 0
    while t < T:
        e = walk.transition[t]
        if e < 0:
            t1 = t
            while t1 < T and walk.transition[t1] < 0 and (t1 == t or walk.frames[t1] == walk.frames[t1 - 1] + 1):
                t1 += 1
            f = walk.frames[t:t1]
            rot[t:t1], root[t:t1] = here.apply_frames(graph.rotations_[f], graph.root_positions_[f])
            t = t1
            continue
        kind = graph.edge_kind_[e]
        src, dst = int(graph.edge_src_[e]), int(graph.edge_dst_[e])
        fa, fb = src + 1 + p, dst - k + 1 + p
        ra, pa = here.apply_frames(graph.rotations_[fa], graph.root_positions_[fa])
        if kind == EdgeKind.ENHANCEMENT:
            S = graph.segments_[int(graph.edge_segment_[e])]
            at_w = here.then(Placement.from_array(graph.edge_align_segment_[e]))
            w1 = S.centre - k + 1 + p
            w2 = np.minimum(S.centre + 1 + p, S.n_frames - 1)  # w_{z+k} has weight 0 when absent
            rw1, pw1 = at_w.apply_frames(S.rotations[w1], S.root_positions[w1])
            rw2, pw2 = at_w.apply_frames(S.rotations[w2], S.root_positions[w2])
            here = here.then(Placement.from_array(graph.edge_align_[e]))
            rb, pb = here.apply_frames(graph.rotations_[fb], graph.root_positions_[fb])
            held = min(k - 1, int(round(S.hold * k)))  # each half shows W alone over `held` frames
            rot[t : t + k], root[t : t + k] = blend_frames(ra, pa, rw1, pw1, k, ramp=k - held)
            rot[t + k : t + 2 * k], root[t + k : t + 2 * k] = blend_frames(rw2, pw2, rb, pb, k, ramp=k - held, start=held)
            t += 2 * k
        else:
            here = here.then(Placement.from_array(graph.edge_align_[e]))
            rb, pb = here.apply_frames(graph.rotations_[fb], graph.root_positions_[fb])
            rot[t : t + k], root[t : t + k] = blend_frames(ra, pa, rb, pb, k)
            t += k
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
        "transition_kinds": [EdgeKind(int(graph.edge_kind_[e])).name for e in walk.transitions_used],
        "transition_segments": [int(graph.edge_segment_[e]) for e in walk.transitions_used],
        "events": events,
        "cost": walk.cost,
        "foot_lock": walk.foot_lock,
        "planner": walk.planner,
    }
