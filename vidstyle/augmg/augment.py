"""``vidstyle augment``: enhancement nodes from annotated transition frames, inserted into a motion graph.

For every *accepted* transition mark (video frame, from-action ``A``, to-action ``B``) of an annotations
file:

1. the frame's 2D pose (``poses.json`` of the pose stage) is matched against the library projected at its
   viewpoint (:class:`.index.PoseIndex`): the top-k candidate reference points, minus the candidates the
   annotator discarded;
2. each candidate ``w_z`` is scored by the enhanced distance (:func:`.enhance.enhanced_distance`, thesis
   eq. 16) against the graph: departures ``a_i`` are the last frames of the graph's ``A`` runs, arrivals
   ``b_j`` the first frames of its ``B`` runs (both within the walkable component), each allowed to move
   ``max_x`` / ``max_y`` frames (the responsiveness terms); the best candidate is the **reference point**;
3. the library segment ``w_{z-k+1}..w_{z+k-1}`` (``k`` = the graph's window, resampled to the graph's
   rate and put on the graph's skeleton) is stored with :meth:`MotionGraph.add_segment`, and
   ``ENHANCEMENT`` edges ``a_i -> b_j`` through it are added for the ``edges_per_side`` best departures
   and arrivals (the **enhancement nodes**), with cost ``enhancement_cost`` x the cheapest plain ``A -> B``
   blend cost so that the planner prefers them for that pair; then the graph is re-pruned.

A discarded mark adds nothing, so the pair keeps its plain transitions; a discarded candidate is skipped,
so the next candidate becomes the reference point. ``augment`` always starts from the plain graph, so a
rerun with changed decisions gives exactly the graph those decisions describe.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np

from ..errors import InputError

log = logging.getLogger(__name__)


@dataclass
class Insertion:
    """What one accepted mark added: the reference point and the enhancement edges."""

    video: str
    frame: int
    from_action: str
    to_action: str
    clip: str
    time: float
    cost: float
    segment: int
    edges: list[tuple[int, int]]


def _runs(labels: np.ndarray, clip: np.ndarray, code: int) -> tuple[np.ndarray, np.ndarray]:
    """(last frames, first frames) of the maximal runs of label ``code`` inside one clip."""
    on = labels == code
    prev = np.concatenate([[False], on[:-1] & (clip[1:] == clip[:-1])])
    nxt = np.concatenate([on[1:] & (clip[1:] == clip[:-1]), [False]])
    return np.flatnonzero(on & ~nxt), np.flatnonzero(on & ~prev)


def augment_graph(graph, marks: list[dict], poses: dict, library_paths, k: int = 10, n_views: int = 12,
                  elevation_deg: float = 10.0, max_x: int = 10, max_y: int = 10, lam: float = 0.5,
                  edges_per_side: int = 3, enhancement_cost: float = 0.5, context: int = 2,
                  use_scores: bool = False, max_match_cost: float | None = None, video_fps: float = 20.0,
                  jobs: int = 1, foreshortening: bool = False, anchor: str = "ends", hold: float = 0.0,
                  max_span_s: float = 1.0) -> list[Insertion]:
    """Add enhancement segments and edges to ``graph`` in place (module docstring).

    ``marks``: :func:`.annotations_io.read_marks` items; ``poses``: video stem -> {frame: FramePose}.
    The marked frame is matched together with the poses of up to ``context`` frames either side that
    ``poses`` holds (:func:`.index.window_query`, at ``video_fps``; ``use_scores``: confidence-weighted
    bones); a reference point whose match cost exceeds ``max_match_cost`` is rejected and the pair keeps
    its plain transitions (the robust AugMG of ``vidstyle evaluate augmg``, thresholds from
    ``scripts/validate_augmg.py``).

    ``anchor="nodes"``: the stored segment also reaches the library clip's enhancement nodes around
    ``w_z`` (:func:`.enhance.enhancement_nodes` against the best departure and arrival windows, within
    ``max_span_s`` seconds, as ``vidstyle evaluate augmg``'s 60 frames at 60 fps), and the enhancement
    edges align those instead of the windows beside ``w_z`` (:class:`~vidstyle.motiongraph.graph.Segment`
    ``anchors``); ``hold``: the segment's hold (the same options as ``vidstyle evaluate augmg
    --anchor/--hold``). The graph places the segment from the departure only, and the arrival follows
    it (a walk goes wherever the segment leads), like ``evaluate augmg --place first``.
    """
    from .enhance import check_placement

    check_placement(anchor=anchor, hold=hold)
    from ..mocap import read_bvh
    from ..mocap.retarget import retarget
    from ..motiongraph.graph import EdgeKind
    from ..render.camera import parse_view
    from .enhance import enhanced_distance, enhancement_nodes
    from .index import PoseIndex, library_clips, window_query
    from .keypoints import keypoint_positions

    accepted = [m for m in marks if m["status"] == "accepted"]
    if not accepted:
        log.info("no accepted transition marks: the graph keeps its plain transitions")
        return []
    clips = library_clips(library_paths)
    index = PoseIndex(n_views=n_views, elevation_deg=elevation_deg, jobs=jobs).fit(clips)
    gk = int(graph.window)
    gpts = keypoint_positions(graph.motion())
    names = list(graph.label_names_)
    out: list[Insertion] = []
    motions: dict[int, object] = {}
    for m in accepted:
        a_name, b_name = m["from"], m["to"]
        if a_name not in names or b_name not in names:
            log.warning("%s frame %d: the graph has no %r or %r frames; mark skipped", m["video"], m["frame"],
                        a_name, b_name)
            continue
        fp = poses.get(m["video"], {}).get(m["frame"])
        if fp is None:
            raise InputError(f"poses: no pose for {m['video']} frame {m['frame']} (run vidstyle pose with --frames)")
        az = parse_view(fp.viewpoint) if fp.viewpoint != "unknown" else 0.0
        spread = index.n_views // 2 if fp.viewpoint == "unknown" else 1
        near = [(d, poses[m["video"]][m["frame"] + d]) for d in range(-context, context + 1)
                if m["frame"] + d in poses[m["video"]]]
        ids, match = window_query(index, np.stack([f.points for _, f in near]),
                                  np.array([d for d, _ in near]) / float(video_fps), az, k, spread,
                                  np.stack([f.scores for _, f in near]) if use_scores else None,
                                  foreshortening=foreshortening)
        discarded = {(c["clip"], round(c["time"], 3)) for c in m.get("candidates", []) if c["status"] == "discarded"}
        keep = [r for r, i in enumerate(ids)
                if (index.paths_[int(index.clip_[i])], round(float(index.time_of(np.array([i]))[0]), 3)) not in discarded]
        cands = [int(ids[r]) for r in keep]
        cand_cost = {int(ids[r]): float(match[r]) for r in keep}
        ends_a, _ = _runs(graph.labels_, graph.frame_clip_, names.index(a_name))
        _, starts_b = _runs(graph.labels_, graph.frame_clip_, names.index(b_name))
        ends_a = ends_a[graph.scc_[ends_a]]
        starts_b = starts_b[graph.scc_[starts_b]]
        if len(ends_a) == 0 or len(starts_b) == 0:
            log.warning("%s frame %d: no walkable %s run end or %s run start", m["video"], m["frame"], a_name, b_name)
            continue
        best = None
        for cand in cands:
            c = int(index.clip_[cand])
            if c not in motions:
                lm = read_bvh(clips[c].path).resample(graph.fps)
                motions[c] = (lm, keypoint_positions(lm))
            lm, lpts = motions[c]
            z = int(round(index.time_of(np.array([cand]))[0] * graph.fps))
            # h = 0: the edge blends A's last k frames with w_{z-k+1}..w_z and w_z.. with B's first k
            d_in, d_out, xs, ys = [], [], [], []
            for i in ends_a:
                e = enhanced_distance(gpts, int(i), lpts, z, gpts, int(i), 0, k=gk, max_x=max_x, max_y=0,
                                      lam=lam, fps=graph.fps)
                d_in.append(np.inf if e is None else e.into)
                xs.append(0 if e is None else e.x)
            for j in starts_b:
                e = enhanced_distance(gpts, int(j), lpts, z, gpts, int(j), 0, k=gk, max_x=0, max_y=max_y,
                                      lam=lam, fps=graph.fps)
                d_out.append(np.inf if e is None else e.out)
                ys.append(0 if e is None else e.y)
            d_in, d_out = np.array(d_in), np.array(d_out)
            total = d_in.min() + d_out.min()
            if np.isfinite(total) and (best is None or total < best[0]):
                best = (total, cand, c, z, d_in, d_out, np.array(xs), np.array(ys))
        if best is None:
            log.warning("%s frame %d: no candidate fits the graph's windows; plain transition kept", m["video"], m["frame"])
            continue
        total, cand, c, z, d_in, d_out, xs, ys = best
        if max_match_cost is not None and cand_cost[cand] > max_match_cost:
            log.info("%s frame %d (%s -> %s): reference point rejected (match cost %.3f > %.3f); plain transition "
                     "kept", m["video"], m["frame"], a_name, b_name, cand_cost[cand], max_match_cost)
            continue
        lm, lpts = motions[c]
        lo, hi, anchors = z - gk + 1, z + gk, None
        if anchor == "nodes":
            # the clip's own look-alikes of the best departure / arrival windows (h = 0 as above)
            i_best, j_best = int(ends_a[int(np.argmin(d_in))]), int(starts_b[int(np.argmin(d_out))])
            nodes = enhancement_nodes(gpts, i_best, lpts, z, gpts, j_best, k=gk,
                                      max_span=max(1, int(round(max_span_s * graph.fps))))
            if nodes is not None:
                z0, z2, _ = nodes
                lo, hi = min(lo, z0 - gk + 1), max(hi, z2 + gk)
                anchors = (z0 - lo, z2 - lo)
        seg_motion, _ = retarget(lm[lo:hi], graph.skeleton_, clips[c].path)
        t = float(z / graph.fps)
        seg = graph.add_segment(seg_motion.rotations, seg_motion.root_positions, centre=z - lo,
                                source=f"{clips[c].path}@{t:.3f}s", label=f"{a_name}->{b_name}", anchors=anchors,
                                hold=hold)
        # departures: the run end i of A (minus the best x of the window) -> the edge leaves at src = i - x
        # the edge blends src+1..src+k (A's frames ending x before the run end) and dst-k+1..dst (B's
        # frames starting y after the run start)
        oa, ob = np.argsort(d_in)[:edges_per_side], np.argsort(d_out)[:edges_per_side]
        src = ends_a[oa] - xs[oa] - gk
        dst = starts_b[ob] + ys[ob] + gk - 1
        pairs = [(int(s), int(d)) for s in src for d in dst if s >= 0 and d < graph.n_frames]
        plain = graph.edges(EdgeKind.BLEND)
        ab = plain[(graph.labels_[graph.edge_src_[plain]] == names.index(a_name))
                   & (graph.labels_[graph.edge_dst_[plain]] == names.index(b_name))]
        ref_cost = float(graph.edge_cost_[ab].min()) if len(ab) else float(graph.threshold_)
        ok = []
        for s, d in pairs:
            try:
                graph.add_edges(s, d, EdgeKind.ENHANCEMENT, cost=enhancement_cost * ref_cost, segment=seg)
                ok.append((s, d))
            except ValueError as exc:  # windows crossing a clip end: that node pair cannot carry the edge
                log.debug("enhancement edge %d -> %d skipped: %s", s, d, exc)
        out.append(Insertion(m["video"], int(m["frame"]), a_name, b_name, clips[c].path, t, float(total), seg, ok))
        log.info("%s frame %d (%s -> %s): reference point %s @ %.2f s, %d enhancement edges", m["video"], m["frame"],
                 a_name, b_name, clips[c].path, t, len(ok))
    graph.prune()
    return out
