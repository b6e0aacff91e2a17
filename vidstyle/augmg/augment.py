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
import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import InputError, ParameterError
from . import defaults as D

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


def augment_graph(graph, marks: list[dict], poses: dict, library_paths, k: int = D.K, n_views: int = D.N_VIEWS,
                  elevation_deg: float = D.ELEVATION_DEG, max_x: int = 10, max_y: int = 10, lam: float = 0.5,
                  edges_per_side: int = D.EDGES_PER_SIDE, enhancement_cost: float = D.ENHANCEMENT_COST,
                  context: int = D.CONTEXT, use_scores: bool = D.SCORES, max_match_cost: float | None = None,
                  video_fps: float = D.VIDEO_FPS, jobs: int = 1, foreshortening: bool = D.FORESHORTENING,
                  anchor: str = D.ANCHOR, hold: float = D.HOLD, max_span_s: float = 1.0) -> list[Insertion]:
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
    edges align those instead of the windows beside ``w_z`` (:class:`~vidstyle.motiongraph.graph.EnhancementSegment`
    ``anchors``); ``hold``: the segment's hold (the same options as ``vidstyle evaluate augmg
    --anchor/--hold``). The graph places the segment from the departure only, and the arrival follows
    it (a walk goes wherever the segment leads), like ``evaluate augmg --place first``.

    Defaults: the validated ones (:mod:`.defaults`); ``max_match_cost`` is one source's threshold
    (:func:`augment` picks it from :data:`.defaults.MAX_MATCH_COST` by the poses' source).
    """
    check_augment_params(k=k, n_views=n_views, edges_per_side=edges_per_side, context=context, anchor=anchor,
                         hold=hold, max_match_cost=max_match_cost, enhancement_cost=enhancement_cost)
    from ..mocap import read_bvh
    from ..mocap.retarget import retarget
    from ..motiongraph.graph import EdgeKind
    from ..render.camera import parse_view
    from .enhance import enhanced_sides, enhancement_nodes
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
            # h = 0: the edge blends A's last k frames with w_{z-k+1}..w_z and w_z.. with B's first k; every
            # run end and start at once (enhanced_sides: enhanced_distance per i and per j, batched)
            d_in, xs, d_out, ys = enhanced_sides(gpts, ends_a, lpts, z, gpts, starts_b, 0, k=gk, max_x=max_x,
                                                 max_y=max_y, lam=lam, fps=graph.fps)
            total = d_in.min() + d_out.min()
            if np.isfinite(total) and (best is None or total < best[0]):
                best = (total, cand, c, z, d_in, d_out, xs, ys)
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


def check_augment_params(k: int = D.K, n_views: int = D.N_VIEWS, edges_per_side: int = D.EDGES_PER_SIDE,
                         context: int = D.CONTEXT, anchor: str = D.ANCHOR, hold: float = D.HOLD,
                         max_match_cost=None, enhancement_cost: float = D.ENHANCEMENT_COST) -> None:
    """:class:`~vidstyle.errors.ParameterError` naming the first bad parameter of :func:`augment_graph` /
    :func:`augment` (``max_match_cost``: a number, None, or per source ``{source or "*": number or None}``)."""
    from .enhance import check_placement

    check_placement(anchor=anchor, hold=hold)
    for name, value, low, high in (("k", k, 1, D.MAX_K), ("views", n_views, 1, D.MAX_VIEWS),
                                   ("edges_per_side", edges_per_side, 1, D.MAX_EDGES_PER_SIDE),
                                   ("context", context, 0, D.MAX_CONTEXT)):
        if not low <= value <= high:
            raise ParameterError(name, f"must be in {low}..{high}, got {value}")
    if not (np.isfinite(enhancement_cost) and enhancement_cost > 0):
        raise ParameterError("enhancement_cost", f"must be a finite number > 0, got {enhancement_cost}")
    check_thresholds(max_match_cost=max_match_cost)


def check_thresholds(**thresholds) -> None:
    """:class:`~vidstyle.errors.ParameterError` unless every threshold is None (none) or a finite number;
    a value may also be a dict ``{source or "*": number or None}`` (per 2D source)."""
    for name, value in thresholds.items():
        for source, v in (value.items() if isinstance(value, dict) else [(None, value)]):
            if v is None:
                continue
            try:
                ok = bool(np.isfinite(float(v)))
            except (TypeError, ValueError):
                ok = False
            if not ok:
                where = "" if source is None else f"{source}="
                raise ParameterError(name, f"{where}{v!r}: must be a finite number (or None for no threshold)")


def source_threshold(values, source: str | None):
    """The threshold of ``source`` from a number / None (every source) or a per-source dict
    ``{source or "*": number or None}`` (``"*"``: every source not named; a source not named and no
    ``"*"``: None, no threshold)."""
    if not isinstance(values, dict):
        return values
    return values.get(source, values.get("*"))


def augment(graph, annotations: str | os.PathLike, library: Sequence[str | os.PathLike],
            video: str | os.PathLike | None = None, poses: Sequence[str | os.PathLike] = (),
            pose_model: str | os.PathLike | None = None, pose_scales: list[float] | None = D.POSE_SCALES,
            k: int = D.K, views: int = D.N_VIEWS, edges_per_side: int = D.EDGES_PER_SIDE,
            enhancement_cost: float = D.ENHANCEMENT_COST, context: int = D.CONTEXT, scores: bool = D.SCORES,
            foreshortening: bool = D.FORESHORTENING, max_match_cost=D.MAX_MATCH_COST, anchor: str = D.ANCHOR,
            hold: float = D.HOLD, jobs: int = 1) -> tuple[object, list[Insertion]]:
    """``vidstyle augment`` as a library call: insert enhancement nodes for the accepted transition marks
    of ``annotations`` into ``graph`` (a :class:`~vidstyle.motiongraph.MotionGraph`, changed in place, or
    the path of a plain graph file, loaded after the checks) and return (the graph, what was inserted);
    save the graph with its ``save``.

    The marked frames' poses come from ``poses`` (poses.json files of the pose stage, one per video) or
    are estimated with ``pose_model`` (pictorial structures, at ``pose_scales``; needs ``video``, whose
    marks alone are used when given). ``max_match_cost``: a number, None or per pose source
    (``{"model": .., "blazepose": .., "*": ..}``; the source is the poses' backend, ``model`` for
    pictorial structures). Other parameters: :func:`augment_graph`; defaults: :mod:`.defaults` (the
    CLI's). Every parameter is checked before any file is read."""
    from ..formats.annotations import file_sha256, read_annotations
    from ..formats.poses import read_poses
    from ..motiongraph import MotionGraph
    from .annotations_io import read_marks
    from .poses_io import read_frame_poses

    check_augment_params(k=k, n_views=views, edges_per_side=edges_per_side, context=context, anchor=anchor,
                         hold=hold, max_match_cost=max_match_cost, enhancement_cost=enhancement_cost)
    if pose_model is not None and video is None:
        raise ParameterError("pose_model", "give video too (the poses of its marked frames are estimated)")
    marks = read_marks(annotations)
    if video is not None:
        video = Path(video)
        if not video.is_file():
            raise ParameterError("video", f"{video}: no such file")
        ann = read_annotations(annotations)
        va = next((v for v in ann.videos if Path(v.path).stem == video.stem), None)
        if va is not None and va.sha256 != file_sha256(video):
            raise InputError(f"{annotations}: {video} is not the annotated video (its sha256 differs)")
        marks = [m for m in marks if m["video"] == video.stem]
        if not marks:
            raise InputError(f"{annotations}: no transition marks for {video.name}")
        if va is not None and context >= va.frames:
            raise ParameterError("context", f"must be less than the video's {va.frames} frames, got {context}")
    by_video: dict = {}
    if pose_model is not None:
        frames = sorted({m["frame"] + d for m in marks for d in range(-context, context + 1) if m["frame"] + d >= 0})
        by_video[video.stem] = estimate_mark_poses(pose_model, video, frames, pose_scales)
    source = "model" if pose_model is not None else None
    for p in poses:
        source = source or ("model" if read_poses(p).backend == "ps" else str(read_poses(p).backend))
        vid, frames = read_frame_poses(p)
        by_video.setdefault(Path(vid).stem, {}).update({f.frame: f for f in frames})
    if not by_video and any(m["status"] == "accepted" for m in marks):
        raise ParameterError("poses", "give poses.json files of the marked frames, or pose_model with video")
    unposed = sorted({m["video"] for m in marks if m["status"] == "accepted" and m["video"] not in by_video})
    if unposed:  # poses of some videos only: augment with those (a pipeline poses the videos it names)
        log.warning("the transition marks of %s are left out: no poses of %s were given (run vidstyle pose "
                    "VIDEO --annotations %s and pass its poses.json with --poses to use them)",
                    ", ".join(unposed), "it" if len(unposed) == 1 else "them", annotations)
        marks = [m for m in marks if m["video"] not in unposed]
    if not isinstance(graph, MotionGraph):
        graph = MotionGraph.load(graph)
    fps = next((m["fps"] for m in marks), D.VIDEO_FPS)
    return graph, augment_graph(graph, marks, by_video, library, k=k, n_views=views, edges_per_side=edges_per_side,
                                enhancement_cost=enhancement_cost, context=context, use_scores=scores,
                                foreshortening=foreshortening, anchor=anchor, hold=hold,
                                max_match_cost=source_threshold(max_match_cost, source), video_fps=fps, jobs=jobs)


def estimate_mark_poses(model: str | os.PathLike, video: str | os.PathLike, frames: list[int],
                        scales: list[float] | None = None) -> dict:
    """{frame: :class:`.poses_io.FramePose`} of ``frames`` of ``video`` by the pose stage (pictorial
    structures ``model``; ``scales``: multi-scale inference)."""
    from ..pose.run import estimate_video
    from .poses_io import FramePose

    doc = estimate_video(Path(video), backend="ps", model_path=Path(model), frames=frames, jobs=1, scales=scales)
    return {f.frame: FramePose(int(f.frame), str(f.viewpoint), f.xy.copy(), f.scores.copy()) for f in doc.frames}
