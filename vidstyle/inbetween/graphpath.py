"""Baseline: the motion graph's own shortest path between the library frames nearest the two keys.

The frames of the graph's walkable component nearest the start and end key (pose feature distance,
:func:`~.poses.pose_features`) are joined by Dijkstra's shortest path over the graph's edge table (a
playback edge costs 1 frame; a blend edge its ``k`` frames plus ``transition_penalty`` frames per threshold
unit of its edge cost). The walk is rendered by the motion graph itself
(:func:`vidstyle.motiongraph.render_walk`, without foot locking), time-warped to the requested number of
frames (slerp / linear resampling), placed at the start key and pinned to both keys (:func:`~.poses.pin`).
"""

from __future__ import annotations

from itertools import pairwise

import numpy as np

from ..errors import InputError
from ..mocap import Motion
from ..mocap.retarget import leg_length
from ..motiongraph.graph import EdgeKind
from ..motiongraph.synthesis import Walk, edge_frames, render_walk
from . import defaults as D
from .poses import Keypose, pin, placement_onto, pose_features


class GraphInbetweener:
    """Shortest-path in-betweening on a fitted :class:`~vidstyle.motiongraph.MotionGraph` (``fit(graph)``)."""

    def __init__(self, transition_penalty: float = D.GRAPH_TRANSITION_PENALTY, height_weight: float = D.HEIGHT_WEIGHT):
        self.transition_penalty = transition_penalty
        self.height_weight = height_weight

    def get_params(self, deep: bool = True) -> dict:
        return {"transition_penalty": self.transition_penalty, "height_weight": self.height_weight}

    def fit(self, graph, y=None) -> GraphInbetweener:
        from scipy.sparse import csr_matrix

        if not graph.scc_.any():
            raise InputError("graph: the graph has no strongly connected component to walk")
        self.graph_ = graph
        self.leg_ = float(leg_length(graph.skeleton_))
        self.nodes_ = np.flatnonzero(graph.scc_)
        self.features_ = pose_features(graph.rotations_[self.nodes_], graph.root_positions_[self.nodes_], self.leg_,
                                       self.height_weight)
        use = np.flatnonzero(graph.edge_in_scc_ & np.isin(graph.edge_kind_, [EdgeKind.PLAYBACK, EdgeKind.BLEND]))
        k = int(graph.window)
        thr = graph.threshold_ or 1.0
        kind = graph.edge_kind_[use]
        w = np.where(kind == EdgeKind.PLAYBACK, 1.0, k + self.transition_penalty * graph.edge_cost_[use] / thr)
        src, dst = graph.edge_src_[use], graph.edge_dst_[use]
        order = np.lexsort((w, dst, src))  # the cheapest edge of each (src, dst) pair first
        src, dst, w, use = src[order], dst[order], w[order], use[order]
        first = np.ones(len(src), bool)
        first[1:] = (src[1:] != src[:-1]) | (dst[1:] != dst[:-1])
        self.edge_ids_ = {}
        for s, d, e in zip(src[first], dst[first], use[first]):
            self.edge_ids_[(int(s), int(d))] = int(e)
        N = graph.n_frames
        self.matrix_ = csr_matrix((w[first], (src[first], dst[first])), shape=(N, N))
        return self

    def nearest(self, key: Keypose) -> int:
        f = pose_features(key.rotations[None], key.root[None], self.leg_, self.height_weight)[0]
        return int(self.nodes_[np.argmin(np.sum((self.features_ - f) ** 2, axis=1))])

    def walk(self, a: int, b: int) -> Walk:
        from scipy.sparse.csgraph import dijkstra

        g = self.graph_
        _dist, pred = dijkstra(self.matrix_, indices=a, return_predecessors=True)
        if b != a and pred[b] < 0:
            raise InputError("graph: no path between the frames nearest the two keyframes")
        nodes = [b]
        while nodes[-1] != a:
            nodes.append(int(pred[nodes[-1]]))
        nodes.reverse()
        frames, trans = [a], [-1]
        for s, d in pairwise(nodes):
            e = self.edge_ids_[(s, d)]
            if g.edge_kind_[e] == EdgeKind.PLAYBACK:
                frames.append(d)
                trans.append(-1)
            else:
                f = edge_frames(g, np.array([e]))[0]
                frames.extend(int(x) for x in f)
                trans.extend([e] * len(f))
        used = [e for i, e in enumerate(trans) if e >= 0 and (i == 0 or trans[i - 1] != e)]
        return Walk(np.array(frames, np.int64), np.array(trans, np.int64), [], [], used)

    def inbetween(self, start: Keypose, end: Keypose, n_frames: int, free_end: bool = False) -> tuple[np.ndarray, np.ndarray]:
        """As :meth:`vidstyle.inbetween.MarkovInbetweener.inbetween`."""
        g = self.graph_
        walk = self.walk(self.nearest(start), self.nearest(end))
        m = render_walk(g, walk, foot_lock=False)
        if m.n_frames >= 2 and n_frames >= 2:  # time-warp the walk onto n_frames frames
            m = Motion(m.skeleton, m.rotations, m.translations, fps=m.n_frames - 1).resample(n_frames - 1)
        idx = np.minimum(np.arange(n_frames), m.n_frames - 1)
        rot, root = m.rotations[idx], m.root_positions[idx]
        here = placement_onto(rot[0, 0], root[0], start.rotations[0], start.root)
        rot, root = here.apply_frames(rot, root)
        if free_end:
            end = end.placed(placement_onto(end.rotations[0], end.root, rot[-1, 0], root[-1]))
        return pin(rot, root, start, end)
