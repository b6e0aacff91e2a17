"""``vidstyle evaluate augmg``: retrieval error and transition error against the demo's true transitions.

Queries: every styled transition (:mod:`vidstyle.demo.transitions`) of every performance video of the
dataset, at its key frame, or at the frames of an annotations file (accepted marks only). The dataset's
performers are never library performers and the library holds no transition (:mod:`vidstyle.demo.library`), so every
query is a held-out performer and a held-out transition.

For each query and each 2D source (``gt``: the exact projection of the true pose with the video's camera;
``noisy``: the same plus Gaussian noise of ``noise`` x the 2D torso length per coordinate; ``model``:
``poses.json`` files of the pose stage, with its viewpoint class):

- **retrieval**: MPJPE (mm, over the 15 keypoints, after the motion-graph alignment: vertical rotation +
  floor translation) between the top-1 library frame and the true 3D pose; recall@1 / @10: a top-k
  candidate lies within 2 indexed frames (same clip) of the library frame closest to the true 3D pose
  (the *oracle* frame, found by brute force over the whole library after alignment);
- **transition error**: mean keypoint error (mm) over the true transition's frames of the generated
  transition with the same endpoints (the frame before the transition and the frame after it):
  ``plain`` blends straight from one endpoint into the other (the motion-graph transition),
  ``augmg`` passes through the reference point chosen by the enhanced distance among the top-k
  (:mod:`vidstyle.augmg.enhance`), using the library segment between its enhancement nodes ``w_z0 .. w_z2``
  (:func:`vidstyle.augmg.enhance.enhancement_nodes`; ``segment="fixed"``: ``w_{z-h} .. w_{z+h}`` with ``h`` =
  ``segment_scale`` x half the transition), ``augmg_top1`` through the top-1 match, ``oracle`` through the oracle frame.
"""

from __future__ import annotations

import logging
import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..augmg import defaults as D
from ..errors import InputError, ParameterError

log = logging.getLogger(__name__)

#: the dataset manifest's key for its mocap length unit (metres per BVH length unit)
UNIT_KEY = "mocap_unit_m"
#: the 2D sources of the validation (``model`` = pictorial structures)
SOURCES = ("model", "blazepose", "gt", "noisy")


def source_thresholds(sources, max_match_cost=D.MAX_MATCH_COST, max_enh_cost=D.MAX_ENH_COST,
                      min_gain=D.MIN_GAIN) -> dict:
    """Per-source acceptance thresholds ``{source: {"max_match_cost", "max_enh_cost", "min_gain_mm"}}``
    (None = no threshold) of ``sources`` from numbers / None or per-source dicts ``{source or "*": value}``
    (:func:`vidstyle.augmg.augment.source_threshold`); defaults: the validated ones."""
    from ..augmg.augment import check_thresholds, source_threshold

    check_thresholds(max_match_cost=max_match_cost, max_enh_cost=max_enh_cost, min_gain=min_gain)
    return {s: {"max_match_cost": source_threshold(max_match_cost, s), "max_enh_cost": source_threshold(max_enh_cost, s),
                "min_gain_mm": source_threshold(min_gain, s)} for s in sources}


#: the validated acceptance thresholds of every validation source (:mod:`vidstyle.augmg.defaults`)
THRESHOLDS = source_thresholds(SOURCES)


def mocap_unit_mm(manifest: dict, dataset) -> float:
    """Millimetres per mocap length unit of a dataset manifest (its ``mocap_unit_m``)."""
    unit = manifest.get(UNIT_KEY)
    if not isinstance(unit, (int, float)) or isinstance(unit, bool) or not np.isfinite(unit) or unit <= 0:
        raise InputError(f"{dataset}: {UNIT_KEY}: missing or not a positive number (the mocap's length unit in "
                         "metres; give unit_mm / --unit-mm)")
    return 1000.0 * float(unit)


def check_evaluate_params(segment: str = D.SEGMENT, segment_scale: float = D.SEGMENT_SCALE, place: str = D.PLACE,
                          anchor: str = D.ANCHOR, hold: float = D.HOLD, enh_window: int = D.ENH_WINDOW,
                          context: int = D.CONTEXT, k: int = D.K, views: int = D.N_VIEWS,
                          noise: float = D.NOISE) -> None:
    """:class:`~vidstyle.errors.ParameterError` naming the first bad parameter of :func:`evaluate` /
    :func:`evaluate_augmg` (checked before any file is read)."""
    from ..augmg.enhance import check_placement

    if segment not in ("fixed", "nodes", "adaptive"):
        raise ParameterError("segment", f"fixed, nodes or adaptive, got {segment!r}")
    check_placement(place, anchor, hold)
    if not 0 <= context <= D.MAX_CONTEXT:
        raise ParameterError("context", f"must be in 0..{D.MAX_CONTEXT}, got {context}")
    if enh_window < 1:
        raise ParameterError("enh_window", f"must be at least 1, got {enh_window}")
    if not 0 < segment_scale <= 1:
        raise ParameterError("segment_scale", f"must be in (0, 1], got {segment_scale}")
    if not 1 <= k <= D.MAX_K:
        raise ParameterError("k", f"must be in 1..{D.MAX_K}, got {k}")
    if not 1 <= views <= D.MAX_VIEWS:
        raise ParameterError("views", f"must be in 1..{D.MAX_VIEWS}, got {views}")
    if not (np.isfinite(noise) and noise >= 0):
        raise ParameterError("noise", f"must be a finite number >= 0, got {noise}")


@dataclass
class Query:
    video: str  # manifest id
    performer: str
    take_bvh: Path
    truth: Path
    view: str
    azimuth: float
    frame: int  # video frame
    ratio: int  # mocap frames per video frame
    transition: dict  # styled transition, video frames
    annotation: dict | None = None


def dataset_queries(dataset: Path, annotations=None) -> tuple[dict, list[Query]]:
    """The manifest and one query per styled transition x performance video (or per accepted mark of
    ``annotations``: a list of ``{"video", "frame", "from", "to", "status"}``)."""
    from ..formats.dataset import read_dataset
    from ..formats.labels import read_labels

    manifest_path = dataset / "dataset.json" if dataset.is_dir() else dataset
    if not manifest_path.is_file():
        raise InputError(f"{manifest_path}: no demo dataset manifest")
    ds = read_dataset(manifest_path)
    root = ds.root
    manifest = {**ds.extra, "fps": ds.fps}
    for key in ("mocap_fps", "params", "size"):
        if key not in manifest:
            raise InputError(f"{manifest_path}: {key}: missing (not a demo dataset rendered by vidstyle demo make-dataset)")
    ratio = int(manifest["mocap_fps"] // manifest["fps"])
    marks: dict[str, list[dict]] = {}
    for a in annotations or []:
        if a.get("status", "accepted") == "accepted":
            marks.setdefault(a["video"], []).append(a)
    out = []
    for v in ds.videos:
        if v.kind != "performance":
            continue
        if v.bvh is None or v.truth is None:
            raise InputError(f"{manifest_path}: video {v.id}: needs 'bvh' and 'truth' (the demo's mocap and render truth)")
        styled = read_labels(ds.labels_path(v)).extra.get("styled_transitions", [])
        base = dict(video=v.id, performer=v.performer, take_bvh=root / v.bvh, truth=root / v.truth,
                    view=v.view, azimuth=float(v.azimuth_deg or 0.0), ratio=ratio)
        if annotations is None:
            out += [Query(**base, frame=int(t["key"]), transition=t) for t in styled]
            continue
        for a in marks.get(v.id, []):
            t = next((t for t in styled if t["start"] <= a["frame"] < t["end"]), None)
            if t is None:
                log.warning("%s frame %d: no styled transition there; skipped", v.id, a["frame"])
                continue
            out.append(Query(**base, frame=int(a["frame"]), transition=t, annotation=a))
    return manifest, out


class _Library:
    """The indexed library plus lazily loaded clip motions."""

    def __init__(self, library: Path, n_views: int, elevation: float, jobs: int) -> None:
        from ..augmg.index import PoseIndex, library_clips

        clips_dir = library / "clips" if (library / "clips").is_dir() else library
        self.clips = library_clips([clips_dir])
        self.index = PoseIndex(n_views=n_views, elevation_deg=elevation, jobs=jobs).fit(self.clips)
        self._motions: dict[int, object] = {}
        # every indexed frame's 3D keypoints, for the oracle
        self.points = np.concatenate([c.points[::self.index.stride] for c in self.clips])

    def motion(self, clip: int):
        from ..mocap import read_bvh

        if clip not in self._motions:
            self._motions[clip] = read_bvh(self.clips[clip].path)
        return self._motions[clip]


def aligned_mpjpe(true: np.ndarray, cand: np.ndarray) -> np.ndarray:
    """MPJPE (length units) of candidate poses (N, 15, 3) against ``true`` (15, 3) after aligning each
    candidate (vertical rotation + floor translation, :func:`vidstyle.augmg.enhance.window_distance`'s alignment)."""
    from ..motiongraph.distance import align_windows
    from ..augmg.enhance import KEYPOINT_WEIGHTS

    p = np.broadcast_to(true[None, None], (len(cand), 1) + true.shape)
    q = cand[:, None]
    _, th, x0, z0 = align_windows(p, q, KEYPOINT_WEIGHTS)
    c, s = np.cos(th), np.sin(th)
    x = c[:, None] * cand[..., 0] + s[:, None] * cand[..., 2] + x0[:, None]
    z = -s[:, None] * cand[..., 0] + c[:, None] * cand[..., 2] + z0[:, None]
    moved = np.stack([x, cand[..., 1], z], axis=-1)
    return np.linalg.norm(moved - true[None], axis=-1).mean(axis=1)


def _query_2d(q: Query, pts3d: np.ndarray, cam, source: str, rng, noise: float, poses: dict | None,
              context: int = 0):
    """The 2D evidence of query ``q``: (offsets (D,) in video frames, (D, 15, 2) image keypoints, (D, 15)
    scores or None, viewpoint (degrees relative to facing), view spread), for the marked frame and the
    frames up to ``context`` either side (an estimated source only has the frames its poses hold; the
    marked frame must be among them); None when the source has no pose of the marked frame."""
    from ..augmg.keypoints import KP
    from ..augmg.projection import facing_of_keypoints, relative_azimuth

    offsets = np.arange(-context, context + 1)
    if source not in ("gt", "noisy"):
        doc = (poses or {}).get(source, {}).get(q.video)
        if doc is None or q.frame not in doc:
            return None
        have = [int(d) for d in offsets if q.frame + d in doc]
        uv = np.stack([doc[q.frame + d][0] for d in have])
        sc = np.stack([doc[q.frame + d][3] for d in have])
        _, az, spread, _ = doc[q.frame]
        return np.array(have), uv, sc, az, spread
    fs = np.clip((q.frame + offsets) * q.ratio, 0, len(pts3d) - 1)
    uv = np.stack([cam.project(pts3d[f])[0] for f in fs])
    f = q.frame * q.ratio
    az = float(relative_azimuth(cam.center, pts3d[f:f + 1, KP["pelvis"]], facing_of_keypoints(pts3d[f:f + 1]))[0])
    if source == "noisy":
        torso = np.linalg.norm(uv[:, KP["neck"]] - uv[:, KP["pelvis"]], axis=-1)
        uv = uv + rng.normal(0.0, 1.0, uv.shape) * (noise * torso)[:, None, None]
    return offsets, uv, None, az, 0


def _camera(q: Query, motion, manifest: dict):
    from ..render.camera import Camera

    if q.truth.is_file():
        from ..render import load_truth

        t = load_truth(q.truth)
        return Camera(t["K"], t["R"], t["t"], float(t["azimuth_deg"]), float(t["elevation_deg"]),
                      tuple(int(x) for x in t["size"]), float(t["facing_deg"]))
    return Camera.for_view(motion, view=q.azimuth, elevation_deg=float(manifest["params"]["elevation_deg"]),
                           size=tuple(manifest["size"]))


def evaluate_augmg(dataset: Path, library: Path, sources=("gt", "noisy"), poses: dict | None = None,
                   annotations=None, noise: float = D.NOISE, k: int = D.K, n_views: int = D.N_VIEWS,
                   enh_window: int = D.ENH_WINDOW, place: str = D.PLACE, segment: str = D.SEGMENT,
                   segment_scale: float = D.SEGMENT_SCALE, max_span: int = 60, context: int = D.CONTEXT,
                   use_scores: bool = D.SCORES, foreshortening: bool = D.FORESHORTENING,
                   max_match_cost: float = np.inf, max_enh_cost: float = np.inf, min_gain_mm: float = -np.inf,
                   thresholds: dict | None = THRESHOLDS, videos=None, animate: str | None = None, seed: int = 0,
                   jobs: int = 1, anchor: str = D.ANCHOR, hold: float = D.HOLD, unit_mm: float | None = None) -> dict:
    """Metrics dict (module docstring); ``poses``: source name -> video id -> {frame: ((15, 2) points,
    viewpoint_deg, spread, (15,) scores)}; ``videos``: only these video ids (default: all);
    ``animate``: keep the poses and transitions of that source's queries under ``"animations"``
    (:func:`transitions_document`).

    Robustness (thesis 5.2.5: a bad enhancement node is discarded and the plain transition kept):
    ``context`` > 0 matches the marked frame together with ``context`` video frames either side
    (:func:`vidstyle.augmg.index.window_query`, temporal coherence); ``use_scores`` weights bones by the pose's
    confidence scores; an enhancement is *accepted* only when its match cost is at most
    ``max_match_cost`` and its enhanced distance at most ``max_enh_cost``, else the plain transition is
    kept (``transition_augmg_mm`` is then the plain error; ``transition_enhanced_mm`` is always the
    enhanced one), and its gain is at least ``min_gain_mm`` (:func:`accept`; ``thresholds``: per source). Defaults come from ``scripts/validate_augmg.py`` on validation performers, never on
    the test performers.

    Placement of the library segment on the performer (:func:`vidstyle.augmg.enhance.place_segment`): ``place`` =
    ``first`` aligns onto the departure only, ``both`` averages that with the alignment onto the
    arrival, ``drift`` moves from one to the other over the segment; ``anchor`` = ``ends`` aligns the
    segment's own first and last frames, ``nodes`` the clip's enhancement nodes ``w_z0`` / ``w_z2``
    (:func:`vidstyle.augmg.enhance.enhancement_nodes`, the library frames that look like the departure and the
    arrival). ``hold``: the fraction of the transition, centred on the reference pose, during which
    the segment is followed with full weight (:func:`vidstyle.augmg.enhance.two_half_transition`; 0: the thesis'
    two-half blend, which reaches ``w_z`` at one frame only).

    Defaults: the validated ones (:mod:`vidstyle.augmg.defaults`; ``thresholds``: :data:`THRESHOLDS`,
    per source; None = no thresholds). Errors are reported in millimetres: ``unit_mm`` millimetres per
    mocap length unit, by default the dataset manifest's ``mocap_unit_m`` (:data:`UNIT_KEY`)."""
    check_evaluate_params(segment=segment, segment_scale=segment_scale, place=place, anchor=anchor, hold=hold,
                          enh_window=enh_window, context=context, k=k, views=n_views, noise=noise)
    from ..logutil import progress
    from ..mocap import Motion, read_bvh
    from ..mocap.retarget import leg_length
    from ..augmg.enhance import (
        adaptive_halves,
        enhanced_distance,
        enhancement_nodes,
        place_segment,
        plain_transition,
        two_half_transition,
    )
    from ..augmg.index import window_query
    from ..augmg.keypoints import keypoint_positions

    manifest, queries = dataset_queries(Path(dataset), annotations)
    mm_per_unit = mocap_unit_mm(manifest, dataset) if unit_mm is None else float(unit_mm)
    if videos is not None:
        queries = [q for q in queries if q.video in set(videos)]
    if not queries:
        raise InputError(f"{dataset}: no styled transitions in any performance video to evaluate")
    lib = _Library(Path(library), n_views, float(manifest["params"]["elevation_deg"]), jobs)
    idx_all = lib.index
    rng = np.random.default_rng(np.random.SeedSequence([seed, 14]))
    takes: dict[Path, tuple] = {}
    rows: list[dict] = []
    animations: list[dict] = []
    for q in progress(queries, "augmg queries"):
        if q.take_bvh not in takes:
            m = read_bvh(q.take_bvh)
            takes[q.take_bvh] = (m, keypoint_positions(m))
        motion, pts3d = takes[q.take_bvh]
        cam = _camera(q, motion, manifest)
        f = q.frame * q.ratio
        s, e = q.transition["start"] * q.ratio, q.transition["end"] * q.ratio
        true = pts3d[f]
        err_lib = aligned_mpjpe(true, lib.points)
        oracle = int(np.argmin(err_lib))
        scale = leg_length(motion.skeleton) / leg_length(lib.motion(0).skeleton)
        L = e - s
        h = max(1, int(round(segment_scale * (L // 2))))  # segment="fixed": library half-segment
        halves = sorted({max(1, int(round(fr * (L // 2)))) for fr in (0.25, 0.5, 0.75, 1.0)})
        truth_seg = pts3d[s:e]

        def choose(cand: int):
            """(lo, hi, enhanced cost) of the library segment through candidate ``cand``."""
            c, z = int(idx_all.clip_[cand]), int(idx_all.frame_[cand])
            w = lib.clips[c].points
            if segment == "adaptive":
                got = adaptive_halves(pts3d, s - 1, w, z, pts3d, e, halves, k=enh_window)
                if got is not None:
                    h1, h2, cost = got
                    return z - h1, z + h2, cost
            ec = enhanced_distance(pts3d, s - 1, w, z, pts3d, e, h, k=enh_window)
            cost = np.inf if ec is None else ec.cost
            if segment == "nodes":
                nodes = enhancement_nodes(pts3d, s - 1, w, z, pts3d, e, k=enh_window, max_span=max_span)
                if nodes is not None:
                    return nodes[0], nodes[1], cost
            n = len(w)
            return max(0, z - h), min(n - 1, z + h), cost

        def transition_error(cand: int | None, keep: bool = False):
            if cand is None:
                rot, root = plain_transition(motion.rotations[s - 1], motion.root_positions[s - 1],
                                             motion.rotations[e], motion.root_positions[e], L)
            else:
                c, z = int(idx_all.clip_[cand]), int(idx_all.frame_[cand])
                lm = lib.motion(c)
                lo, hi, _ = choose(cand)
                lo, hi = max(0, lo), min(lm.n_frames - 1, hi)
                seg = lm[lo:hi + 1]
                seg_pts = lib.clips[c].points[lo:hi + 1]
                align, at = None, None
                if anchor == "nodes":  # align the library's own look-alikes of the endpoints, not the cut ends
                    nodes = enhancement_nodes(pts3d, s - 1, lib.clips[c].points, z, pts3d, e, k=enh_window,
                                              max_span=max_span)
                    if nodes is not None:
                        align = (lib.clips[c].points[nodes[0]], lib.clips[c].points[nodes[1]])
                        at = (nodes[0] - lo, nodes[1] - lo)
                srot, sroot = place_segment(seg, seg_pts, pts3d[s - 1], scale, pts3d[e] if place != "first" else None,
                                           drift=place == "drift", align_points=align, align_frames=at)
                rot, root = two_half_transition(motion.rotations[s - 1], motion.root_positions[s - 1], srot, sroot,
                                                motion.rotations[e], motion.root_positions[e], L, centre=z - lo,
                                                hold=hold)
            gen = keypoint_positions(Motion(motion.skeleton, rot, None, motion.fps, root_positions=root))
            err = float(np.linalg.norm(gen - truth_seg, axis=-1).mean() * mm_per_unit)
            return (err, gen) if keep else err

        plain, plain_pts = transition_error(None, keep=True)
        oracle_err = transition_error(oracle)
        plain_mid = plain_pts[L // 2]
        for source in sources:
            got = _query_2d(q, pts3d, cam, source, rng, noise, poses, context)
            if got is None:
                continue
            offs, uv, sc, az, spread = got
            top, costs = window_query(idx_all, uv, offs / float(manifest["fps"]), az, k, spread,
                                      sc if use_scores else None, foreshortening=foreshortening)
            same = idx_all.clip_[top] == idx_all.clip_[oracle]
            near = same & (np.abs(idx_all.frame_[top] - idx_all.frame_[oracle]) <= 2 * idx_all.stride)
            # reference point: the enhanced distance over the top-k candidates
            best, best_cost, best_rank = top[0], np.inf, 0
            for rank, cand in enumerate(top):
                ec = choose(int(cand))[2]
                if ec < best_cost:
                    best, best_cost, best_rank = cand, ec, rank
            enhanced, enhanced_pts = transition_error(int(best), keep=True)
            rows.append({
                "video": q.video, "performer": q.performer, "view": q.view, "frame": q.frame, "source": source,
                "kind": q.transition["kind"], "from": q.transition["from"], "to": q.transition["to"],
                "viewpoint_deg": round(az, 2), "context_frames": int(len(offs)),
                "top1_clip": Path(lib.clips[int(idx_all.clip_[top[0]])].path).stem,
                "reference_clip": Path(lib.clips[int(idx_all.clip_[best])].path).stem,
                "reference_time_s": float(idx_all.time_of(np.array([best]))[0]),
                "top1_mpjpe_mm": float(err_lib[top[0]] * mm_per_unit),
                "reference_mpjpe_mm": float(err_lib[best] * mm_per_unit),
                "oracle_mpjpe_mm": float(err_lib[oracle] * mm_per_unit),
                "recall_at_1": bool(near[0]), "recall_at_10": bool(near[:10].any()),
                "match_cost": float(costs[best_rank]), "enhanced_cost": _finite(best_cost),
                "gain_mm": float(aligned_mpjpe(plain_mid, lib.points[int(best):int(best) + 1] * scale)[0] * mm_per_unit),
                "transition_plain_mm": plain, "transition_enhanced_mm": enhanced,
                "transition_augmg_top1_mm": transition_error(int(top[0])), "transition_oracle_mm": oracle_err,
            })
            if source == animate:
                from ..augmg.projection import facing_normalised, facing_of_keypoints, project

                lp = lib.points[int(best):int(best) + 1]
                lib2d = project(facing_normalised(lp, facing_of_keypoints(lp)), az,
                                float(manifest["params"]["elevation_deg"]))[0]
                centre = int(np.flatnonzero(offs == 0)[0])
                animations.append({"row": len(rows) - 1, "pose2d": uv[centre], "library2d": lib2d,
                                   "truth": truth_seg, "plain": plain_pts, "enhanced": enhanced_pts})
    params = dict(dataset=str(dataset), library=str(library), library_frames=idx_all.n_frames,
                  library_clips=len(lib.clips), k=k, n_views=n_views, noise=noise, seed=seed,
                  enh_window=enh_window, place=place, anchor=anchor, hold=hold, segment=segment,
                  segment_scale=segment_scale,
                  max_span=max_span, context=context, use_scores=use_scores, foreshortening=foreshortening,
                  max_match_cost=_finite(max_match_cost), max_enh_cost=_finite(max_enh_cost),
                  min_gain_mm=_finite(min_gain_mm), thresholds=thresholds,
                  sources=list(sources), index=idx_all.get_params(), queries=len(queries),
                  annotations=annotations is not None)
    out = summarise(accept(rows, _finite(max_match_cost), _finite(max_enh_cost), _finite(min_gain_mm), thresholds),
                    params)
    if animate is not None:
        out["animations"] = animations  # not part of the metrics document: :func:`transitions_document`
    return out


def transitions_document(metrics: dict, source: str, fps: float, step: int):
    """The report's animation data (:mod:`vidstyle.formats.augmg_transitions`) of an
    :func:`evaluate_augmg` result made with ``animate=source``; transitions subsampled every ``step``
    mocap frames (to ``fps``)."""
    from ..formats.augmg_transitions import AugmgTransitions, TransitionEntry

    entries = []
    for a in metrics.get("animations", []):
        r = metrics["rows"][a["row"]]
        aug = a["enhanced"] if r["accepted"] else a["plain"]
        entries.append(TransitionEntry(
            r["video"], int(r["frame"]), r["from"], r["to"], r["kind"], bool(r["accepted"]), r["match_cost"],
            r["enhanced_cost"], r["reference_clip"], r["reference_time_s"], r["viewpoint_deg"], a["pose2d"],
            a["library2d"], a["truth"][::step], a["plain"][::step], aug[::step], r["transition_plain_mm"],
            r["transition_augmg_mm"]))
    return AugmgTransitions(source, fps, entries)


def _finite(x: float):
    """A threshold for JSON: None for no threshold (infinity)."""
    return None if not np.isfinite(x) else float(x)


def accept(rows: list[dict], max_match_cost: float | None = None, max_enh_cost: float | None = None,
           min_gain_mm: float | None = None, thresholds: dict | None = None) -> list[dict]:
    """Rows with ``accepted`` and ``transition_augmg_mm``: the enhanced transition's error when the
    enhancement is accepted, else the plain one (the plain transition is kept). Accepted: the match
    cost is at most ``max_match_cost``, the enhanced distance at most ``max_enh_cost`` and the *gain*
    (how far the reference pose lies from the plain transition's middle frame, mm: an enhancement
    that the plain blend already passes near adds only risk) at least ``min_gain_mm``; None = no
    threshold. ``thresholds``: per source ``{"max_match_cost", "max_enh_cost", "min_gain_mm"}``
    overriding those for that source's rows."""
    base = {"max_match_cost": max_match_cost, "max_enh_cost": max_enh_cost, "min_gain_mm": min_gain_mm}
    out = []
    for r in rows:
        t = {**base, **((thresholds or {}).get(r["source"], {}) if "source" in r else {})}
        mm = np.inf if t["max_match_cost"] is None else t["max_match_cost"]
        me = np.inf if t["max_enh_cost"] is None else t["max_enh_cost"]
        mg = -np.inf if t["min_gain_mm"] is None else t["min_gain_mm"]
        ok = bool(r["match_cost"] <= mm and r["enhanced_cost"] is not None and r["enhanced_cost"] <= me
                  and r.get("gain_mm", np.inf) >= mg)
        out.append({**r, "accepted": ok,
                    "transition_augmg_mm": r["transition_enhanced_mm"] if ok else r["transition_plain_mm"]})
    return out


def reduction_interval(plain, augmg, seed: int = 0, reps: int = 2000, level: float = 0.95) -> list[float] | None:
    """Percentile bootstrap interval of the transition-error reduction ``1 - mean(augmg) / mean(plain)``
    over queries resampled with replacement (paired: a query keeps both its errors); None for fewer
    than two queries. With a few held-out marks the reduction is uncertain, and this says by how much."""
    p, a = np.asarray(plain, dtype=np.float64), np.asarray(augmg, dtype=np.float64)
    if len(p) < 2:
        return None
    rng = np.random.default_rng(np.random.SeedSequence([seed, 1414]))
    idx = rng.integers(0, len(p), size=(reps, len(p)))
    red = 1.0 - a[idx].mean(axis=1) / p[idx].mean(axis=1)
    lo, hi = np.quantile(red, [(1 - level) / 2, (1 + level) / 2])
    return [float(lo), float(hi)]


def summarise(rows: list[dict], params: dict) -> dict:
    out: dict = {"params": params, "by_source": {}, "rows": rows}
    for source in params["sources"]:
        r = [x for x in rows if x["source"] == source]
        if not r:
            continue

        def mean(key: str) -> float:
            return float(np.mean([x[key] for x in r]))

        plain, aug = mean("transition_plain_mm"), mean("transition_augmg_mm")
        out["by_source"][source] = {
            "queries": len(r),
            "retrieval_mpjpe_mm": mean("top1_mpjpe_mm"), "reference_mpjpe_mm": mean("reference_mpjpe_mm"),
            "oracle_mpjpe_mm": mean("oracle_mpjpe_mm"),
            "recall_at_1": mean("recall_at_1"), "recall_at_10": mean("recall_at_10"),
            "transition_plain_mm": plain, "transition_augmg_mm": aug,
            "transition_augmg_top1_mm": mean("transition_augmg_top1_mm"),
            "transition_enhanced_mm": mean("transition_enhanced_mm"),
            "accepted": mean("accepted"),
            "transition_oracle_mm": mean("transition_oracle_mm"),
            "transition_reduction": float(1.0 - aug / plain) if plain > 0 else 0.0,
            "transition_reduction_ci95": reduction_interval([x["transition_plain_mm"] for x in r],
                                                            [x["transition_augmg_mm"] for x in r],
                                                            seed=int(params.get("seed", 0) or 0)),
            "by_kind": {kind: {"queries": len(rk), "plain_mm": float(np.mean([x["transition_plain_mm"] for x in rk])),
                               "augmg_mm": float(np.mean([x["transition_augmg_mm"] for x in rk])),
                               "enhanced_mm": float(np.mean([x["transition_enhanced_mm"] for x in rk])),
                               "oracle_mm": float(np.mean([x["transition_oracle_mm"] for x in rk])),
                               "accepted": float(np.mean([x["accepted"] for x in rk]))}
                        for kind in sorted({x["kind"] for x in r}) for rk in [[x for x in r if x["kind"] == kind]]},
        }
    return out


def read_poses_dir(d: str | os.PathLike) -> tuple[str, dict]:
    """(source name, video id -> {frame: (points, viewpoint_deg, view spread, scores)}) of a directory of
    poses.json files (``<video id>.poses.json``), as :func:`evaluate_augmg`'s ``poses`` takes them; the
    source is named by the backend (``model`` for pictorial structures)."""
    from ..augmg.match import view_spread
    from ..augmg.poses_io import viewpoint_of
    from ..formats.poses import read_poses
    from ..render.camera import parse_view

    d = Path(d)
    files = sorted(d.glob("*.poses.json"))
    if not files:
        raise ParameterError("poses_dir", f"no *.poses.json in {d}")
    out: dict = {}
    backends = set()
    for f in files:
        doc = read_poses(f)
        backends.add(str(doc.backend))
        vid = f.name[: -len(".poses.json")]
        out[vid] = {int(fp.frame): (fp.xy.copy(), parse_view(viewpoint_of(fp)), view_spread(viewpoint_of(fp)),
                                    fp.scores.copy()) for fp in doc.frames if fp.found}
    if len(backends) != 1:
        raise ParameterError("poses_dir", f"{d} mixes pose backends {sorted(backends)}")
    backend = backends.pop()
    return ("model" if backend == "ps" else backend), out


def headline(metrics: dict) -> dict:
    """The ``augmg.*`` headline keys of an :func:`evaluate_augmg` result: the thesis' own estimated pose
    (pictorial structures, ``model``) when evaluated, else BlazePose, else ``gt`` (fixed in advance, not
    the better of the estimated sources), plus every other source's retrieval and AugMG errors."""
    head = next((x for x in ("model", "blazepose", "gt") if x in metrics["by_source"]), "gt")
    main = metrics["by_source"][head]
    out = {
        "augmg.retrieval_mpjpe": main["retrieval_mpjpe_mm"],
        "augmg.transition_error_plain": main["transition_plain_mm"],
        "augmg.transition_error_augmg": main["transition_augmg_mm"],
        "augmg.source": head,
    }
    for src, r in metrics["by_source"].items():
        if src != head:
            out[f"augmg.{src}.retrieval_mpjpe"] = r["retrieval_mpjpe_mm"]
            out[f"augmg.{src}.transition_error_augmg"] = r["transition_augmg_mm"]
    return out


def evaluate(dataset: str | os.PathLike, library: str | os.PathLike, annotations: str | os.PathLike | None = None,
             poses_dir: Sequence[str | os.PathLike] = (), noise: float = D.NOISE, k: int = D.K,
             views: int = D.N_VIEWS, segment: str = D.SEGMENT, segment_scale: float = D.SEGMENT_SCALE,
             place: str = D.PLACE, anchor: str = D.ANCHOR, hold: float = D.HOLD, enh_window: int = D.ENH_WINDOW,
             context: int = D.CONTEXT, scores: bool = D.SCORES, foreshortening: bool = D.FORESHORTENING,
             max_match_cost=D.MAX_MATCH_COST, max_enh_cost=D.MAX_ENH_COST, min_gain=D.MIN_GAIN, seed: int = 0,
             unit_mm: float | None = None, transitions: bool = False, jobs: int = 1):
    """``vidstyle evaluate augmg`` as a library call: (the metrics document, the report's transitions
    document or None).

    Sources: one per ``poses_dir`` (:func:`read_poses_dir`, named by its backend), then ``gt`` and
    ``noisy``; queries: every styled transition's key frame, or the accepted marks of ``annotations``.
    The metrics are :func:`evaluate_augmg`'s with ``"seed"`` first and the ``"headline"`` keys
    (:func:`headline`); with ``transitions`` the animations of the headline's estimated source (``gt``
    without one) as :class:`vidstyle.formats.augmg_transitions.AugmgTransitions`. Thresholds: numbers,
    None or per source ``{source or "*": value}`` (:func:`source_thresholds`). Defaults: the validated
    ones (:mod:`vidstyle.augmg.defaults`), the CLI's; every parameter is checked before any file is read."""
    from ..augmg.annotations_io import read_marks

    check_evaluate_params(segment=segment, segment_scale=segment_scale, place=place, anchor=anchor, hold=hold,
                          enh_window=enh_window, context=context, k=k, views=views, noise=noise)
    from ..augmg.augment import check_thresholds

    check_thresholds(max_match_cost=max_match_cost, max_enh_cost=max_enh_cost, min_gain=min_gain)
    dataset, library = Path(dataset), Path(library)
    marks = read_marks(annotations) if annotations else None
    poses: dict = {}
    for d in poses_dir:
        name, doc = read_poses_dir(d)
        if name in poses:
            raise ParameterError("poses_dir", f"{d}: a second directory of {name} poses")
        poses[name] = doc
    sources = [*poses, "gt", "noisy"]
    animations_source = next((x for x in ("model", "blazepose") if x in poses), "gt")
    metrics = evaluate_augmg(dataset, library, sources=tuple(sources), poses=poses, annotations=marks, noise=noise,
                             k=k, n_views=views, segment=segment, segment_scale=segment_scale, enh_window=enh_window,
                             place=place, anchor=anchor, hold=hold, context=context, use_scores=scores,
                             foreshortening=foreshortening,
                             thresholds=source_thresholds(sources, max_match_cost, max_enh_cost, min_gain),
                             animate=animations_source, seed=seed, jobs=jobs, unit_mm=unit_mm)
    metrics["headline"] = headline(metrics)
    doc = None
    if transitions:
        from ..formats.dataset import read_dataset

        man = read_dataset(dataset)
        step = max(1, int(man.extra["mocap_fps"] // man.fps))
        doc = transitions_document(metrics, animations_source, float(man.fps), step)
    metrics.pop("animations", None)
    return {"seed": seed, **metrics}, doc
