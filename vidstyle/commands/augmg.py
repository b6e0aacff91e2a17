"""AugMG stages: ``vidstyle match-pose``, ``vidstyle augment``, ``vidstyle evaluate augmg`` and
``vidstyle demo make-library`` (the demo's mocap library that holds transition poses, not transitions)."""

from __future__ import annotations

import logging
from pathlib import Path
from typing import List, Optional

import typer

from ..errors import InputError
from ._evaluate import evaluate_app
from .demo import demo_app

log = logging.getLogger(__name__)

# Defaults chosen on the validation performers (scripts/validate_augmg.py, recorded in
# pipelines/kickboxing/validation/augmg.json): never on the test performers.
SEGMENT = "adaptive"
CONTEXT = 2
SCORES = True
FORESHORTENING = True
PLACE = "drift"
ANCHOR = "nodes"
HOLD = 0.2
MAX_MATCH_COST = ["model=0.526", "blazepose=0.431"]
MAX_ENH_COST = ["model=4.408"]
MIN_GAIN = ["model=74.315", "gt=123.566", "noisy=95.722"]
#: zoom factors of the pose stage's multi-scale inference (``vidstyle pose --scales``); None: one scale
POSE_SCALES: list[float] | None = None

_JOBS = typer.Option(1, "--jobs", "-j", help="Parallel workers for projecting and indexing (-1 = all cores).")
_SCHEDULER = typer.Option(None, "--scheduler", help="Dask scheduler address (tcp://host:port) instead of local workers.")


def register(app: typer.Typer) -> None:
    app.command("match-pose")(match_pose)
    app.command("augment")(augment)


def augment(
    graph_path: Path = typer.Option(..., "--graph", "-g", help="Plain motion graph (from build-graph)."),
    annotations: Path = typer.Option(..., "--annotations", "-a", help="Annotations file with transition marks (vidstyle annotate)."),
    library: List[Path] = typer.Option(..., "--library", "-l", help="Library BVH clips or directories to find reference points in (repeatable)."),
    out: Path = typer.Option(..., "--out", "-o", help="Augmented graph file to write."),
    video: Optional[Path] = typer.Option(None, "--video", "-V", help="Use only the marks of this video (default: every annotated video)."),
    poses: List[Path] = typer.Option([], "--poses", "-p", help="poses.json of the marked frames (from vidstyle pose; repeatable, one per video)."),
    pose_model: Optional[Path] = typer.Option(None, "--pose-model", help="Pose model: estimate the marked frames' poses here (needs --video)."),
    pose_scales: Optional[str] = typer.Option(",".join(str(z) for z in POSE_SCALES) if POSE_SCALES else None, "--pose-scales", help="With --pose-model: zoom factors of multi-scale pose inference (as vidstyle pose --scales). Default: chosen on validation performers."),
    k: int = typer.Option(10, "--k", help="Candidate reference points per mark."),
    views: int = typer.Option(12, "--views", help="Azimuths the library is projected at."),
    edges_per_side: int = typer.Option(3, "--edges-per-side", help="Enhancement nodes on each side: departures x arrivals edges per mark."),
    enhancement_cost: float = typer.Option(0.5, "--enhancement-cost", help="Edge cost as a fraction of the cheapest plain blend of that action pair (< 1: the planner prefers the enhancement)."),
    context: int = typer.Option(CONTEXT, "--context", help="Match each mark together with the poses of up to this many frames either side (temporal coherence; run vidstyle pose with --context)."),
    scores: bool = typer.Option(SCORES, "--scores/--no-scores", help="Weight bones by the poses' confidence scores."),
    foreshortening: bool = typer.Option(FORESHORTENING, "--foreshortening/--no-foreshortening", help="Also weight bones by their image length against their side-on length (a bone pointing at the camera counts less)."),
    max_match_cost: List[str] = typer.Option(MAX_MATCH_COST, "--max-match-cost", help="Reject a reference point whose match cost exceeds this (the pair keeps its plain transitions): VALUE, or SOURCE=VALUE per pose source (model = ps, blazepose); repeatable. Default: chosen on validation performers (scripts/validate_augmg.py)."),
    anchor: str = typer.Option(ANCHOR, "--anchor", help="Align the enhancement segment by the library's enhancement nodes (nodes: its frames most like the departure and the arrival) or by the windows beside the reference pose (ends). Default: chosen on validation performers (as evaluate augmg)."),
    hold: float = typer.Option(HOLD, "--hold", help="Fraction of an enhancement shown with the segment's full weight, about the reference pose (0: the thesis' two-half blend). Default: chosen on validation performers."),
    jobs: int = _JOBS,
) -> None:
    """Insert enhancement nodes (thesis 5.2) for the accepted transition marks: match each marked frame's
    2D pose against the projected library, pick the reference point by the enhanced distance, and add
    ENHANCEMENT edges through it for that action pair. Discarded marks / candidates are left out, so a
    rerun restores the plain transition (or takes the next candidate)."""
    from ..augmg.annotations_io import read_marks
    from ..augmg.augment import augment_graph
    from ..augmg.poses_io import read_frame_poses
    from ..motiongraph import MotionGraph

    _check_placement(anchor=anchor, hold=hold)
    marks = read_marks(annotations)
    if video is not None:
        from ..formats.annotations import file_sha256, read_annotations

        if not video.is_file():
            raise InputError(f"--video: {video}: no such file")
        ann = read_annotations(annotations)
        va = next((v for v in ann.videos if Path(v.path).stem == video.stem), None)
        if va is not None and va.sha256 != file_sha256(video):
            raise InputError(f"{annotations}: {video} is not the annotated video (its sha256 differs)")
        marks = [m for m in marks if m["video"] == video.stem]
        if not marks:
            raise InputError(f"{annotations}: no transition marks for {video.name}")
    by_video: dict = {}
    if pose_model is not None:
        if video is None:
            raise InputError("--pose-model: give --video (the poses of its marked frames are estimated)")
        from .pose import parse_scales

        zooms = parse_scales(pose_scales, "--pose-scales")
        by_video[video.stem] = _estimate_poses(pose_model, video, sorted({m["frame"] + d for m in marks
                                                                           for d in range(-context, context + 1)
                                                                           if m["frame"] + d >= 0}), zooms)
    source = "model" if pose_model is not None else None
    for p in poses:
        from ..formats.poses import read_poses

        source = source or ("model" if read_poses(p).backend == "ps" else str(read_poses(p).backend))
        vid, frames = read_frame_poses(p)
        by_video.setdefault(Path(vid).stem, {}).update({f.frame: f for f in frames})
    if not by_video and any(m["status"] == "accepted" for m in marks):
        raise InputError("give --poses (poses.json of the marked frames) or --pose-model with --video")
    graph = MotionGraph.load(graph_path)
    if context < 0:
        raise InputError(f"--context: must be at least 0, got {context}")
    limit = per_source(max_match_cost, "--max-match-cost")
    fps = next((m["fps"] for m in marks), 20.0)
    inserted = augment_graph(graph, marks, by_video, library, k=k, n_views=views, edges_per_side=edges_per_side,
                             enhancement_cost=enhancement_cost, context=context, use_scores=scores,
                             foreshortening=foreshortening, anchor=anchor, hold=hold,
                             max_match_cost=limit.get(source, limit.get("*")), video_fps=fps, jobs=jobs)
    graph.save(out)
    log.info("wrote %s: %d reference points, %d enhancement edges", out, len(inserted),
             sum(len(i.edges) for i in inserted))


def _check_placement(place: str | None = None, anchor: str | None = None, hold: float | None = None) -> None:
    """The placement options' check (:func:`vidstyle.augmg.enhance.check_placement`) as a one-line CLI error."""
    from ..augmg.enhance import check_placement

    try:
        check_placement(place, anchor, hold)
    except ValueError as e:
        raise InputError(f"--{e}") from None


def per_source(values: list[str], option: str) -> dict:
    """``["1.2", "model=1.3", "blazepose=-"]`` -> ``{"*": 1.2, "model": 1.3, "blazepose": None}`` (a
    threshold for every source, per source; ``-`` = none)."""
    out: dict = {}
    for v in values:
        name, _, num = v.rpartition("=")
        try:
            out[name or "*"] = None if num.strip() == "-" else float(num)
        except ValueError:
            raise InputError(f"{option}: {v!r} is not VALUE or SOURCE=VALUE") from None
    return out


def _estimate_poses(model: Path, video: Path, frames: list[int], scales: list[float] | None = None) -> dict:
    """Poses of ``frames`` of ``video`` by the pose stage (pictorial structures, ``model``; ``scales``:
    multi-scale inference)."""
    from ..augmg.poses_io import FramePose
    from ..pose.run import estimate_video

    doc = estimate_video(video, backend="ps", model_path=model, frames=frames, jobs=1, scales=scales)
    return {f.frame: FramePose(int(f.frame), str(f.viewpoint), f.xy.copy(), f.scores.copy()) for f in doc.frames}


@demo_app.command("make-library")
def make_library_cmd(
    out: Path = typer.Option(..., "--out", "-o", help="Output directory (created; must be empty or absent)."),
    seed: int = typer.Option(0, "--seed", help="Seed of the library performers (disjoint from every dataset performer)."),
    performers: int = typer.Option(3, "--performers", help="Library performers."),
    action_seconds: float = typer.Option(6.0, "--action-seconds", help="Length of each single-action clip."),
    cmu: Optional[Path] = typer.Option(None, "--cmu", help="Also add CMU BVH clips from this directory (retargeted)."),
    cmu_clips: int = typer.Option(-1, "--cmu-clips", help="How many CMU clips (sorted by name) to add; -1 = all."),
    overwrite: bool = typer.Option(False, "--overwrite", help="Replace a non-empty --out once the new library is complete."),
    jobs: int = typer.Option(-1, "--jobs", "-j", help="Parallel workers (-1 = all cores)."),
    scheduler: str = _SCHEDULER,
) -> None:
    """Write the AugMG mocap library: every action per library performer, plus dodge / stance-switch /
    stop clips that hold the demo's transition poses in another context (never a performer's
    transition itself). Layout: DIR/library.json, DIR/clips/<name>.bvh (+ .labels.json)."""
    from ..augmg.library import LibraryParams, make_library

    params = LibraryParams(seed=seed, performers=performers, action_seconds=action_seconds,
                           cmu_clips=cmu_clips if cmu is not None else 0)
    path = make_library(out, params, cmu_dir=cmu, overwrite=overwrite, jobs=jobs, scheduler=scheduler)
    log.info("library manifest %s", path)


def match_pose(
    poses: Path = typer.Argument(..., help="poses.json of the annotated frames (from vidstyle pose)."),
    library: List[Path] = typer.Option(..., "--library", "-l", help="Library BVH clips or directories (repeatable)."),
    out: Path = typer.Option(..., "--out", "-o", help="matches.json to write."),
    k: int = typer.Option(10, "--k", help="Candidates per frame."),
    views: int = typer.Option(12, "--views", help="Azimuths the library is projected at (360 / views apart)."),
    elevation: float = typer.Option(10.0, "--elevation", help="Camera elevation of the projection (degrees)."),
    stride: int = typer.Option(3, "--stride", help="Index every N-th library frame."),
    coherence: bool = typer.Option(False, "--coherence/--no-coherence", help="Re-rank candidates of consecutive frames by temporal coherence (Tautges' lazy neighbourhood graph)."),
    fps: float = typer.Option(20.0, "--fps", help="Video rate of the poses' frame numbers (for --coherence)."),
    jobs: int = _JOBS,
    scheduler: str = _SCHEDULER,
) -> None:
    """Match each frame's 2D pose against the library projected at the frame's viewpoint (relative to
    the character's facing; joint-angle features, kd-tree kNN); write the top-k library frames per
    frame as {"clip", "time", "cost"}."""
    import numpy as np

    from ..augmg.index import PoseIndex, coherent_ranking, library_clips
    from ..augmg.poses_io import read_frame_poses
    from ..formats.matches import Candidate, FrameMatches, Matches, write_matches
    from ..render.camera import parse_view

    if k < 1:
        raise InputError(f"--k: must be at least 1, got {k}")
    if views < 1 or stride < 1:
        raise InputError("--views and --stride must be at least 1")
    video, frames = read_frame_poses(poses)
    if not frames:
        raise InputError(f"{poses}: no frames to match")
    clips = library_clips(library)
    index = PoseIndex(n_views=views, elevation_deg=elevation, stride=stride, jobs=jobs, scheduler=scheduler).fit(clips)
    ids, costs, azs = [], [], []
    for f in frames:
        try:
            az = parse_view(f.viewpoint)
        except ValueError as e:
            raise InputError(f"{poses}: frame {f.frame}: {e}") from None
        from ..augmg.evaluate import _query_views

        # a named viewpoint is a class (front / left / right): search its neighbouring azimuths too
        spread = 0 if _is_number(f.viewpoint) else 1
        i, c = _query_views(index, f.points, az, k, spread)
        ids.append(i[0])
        costs.append(c[0])
        azs.append(az)
    kk = min(len(x) for x in ids)
    I, C = np.stack([x[:kk] for x in ids]), np.stack([x[:kk] for x in costs])
    if coherence:
        I, C = coherent_ranking(index, I, C, np.array([f.frame for f in frames]), fps)
    times = index.time_of(I)
    out_frames = [FrameMatches(f.frame, float(az), [Candidate(index.paths_[int(index.clip_[j])], float(t), float(c))
                                                    for j, t, c in zip(I[q], times[q], C[q])])
                  for q, (f, az) in enumerate(zip(frames, azs))]
    write_matches(out, Matches(str(poses), video, index.paths_, {**index.get_params(), "k": k, "coherence": coherence},
                               out_frames))
    log.info("wrote %s: %d frames x %d candidates over %d library frames", out, len(frames), kk, index.n_frames)


def _is_number(s: str) -> bool:
    try:
        float(s)
        return True
    except ValueError:
        return False


@evaluate_app.command("augmg")
def evaluate_augmg_cmd(
    dataset: Path = typer.Option(..., "--dataset", "-d", help="Demo dataset directory (performances with styled transitions)."),
    library: Path = typer.Option(..., "--library", "-l", help="Library directory (vidstyle demo make-library)."),
    out: Path = typer.Option(Path("metrics/augmg.json"), "--out", "-o", help="Metrics JSON."),
    annotations: Optional[Path] = typer.Option(None, "--annotations", "-a", help="Query the accepted marks of this annotations file instead of every transition's key frame."),
    poses_dir: List[Path] = typer.Option([], "--poses-dir", help="Directory of poses.json files (<video id>.poses.json) of the pose stage: adds an estimated 2D source named by its backend ('model' for ps, 'blazepose'); repeatable."),
    noise: float = typer.Option(0.05, "--noise", help="2D noise sigma of the 'noisy' source, as a fraction of the torso length."),
    k: int = typer.Option(10, "--k", help="Candidates per query (the reference point is chosen among them)."),
    views: int = typer.Option(12, "--views", help="Azimuths the library is projected at."),
    segment: str = typer.Option(SEGMENT, "--segment", help="Library segment through the reference point: fixed (w_z-h..w_z+h, h = --segment-scale x half the transition), nodes (between the enhancement nodes w_z0..w_z2) or adaptive (each side's length chosen by the enhanced distance)."),
    segment_scale: float = typer.Option(1.0, "--segment-scale", help="Library half-segment around the reference point, as a fraction of the transition's half-length (time-warped to it)."),
    place: str = typer.Option(PLACE, "--place", help="Placement of the library segment on the performer: first (aligned onto the departing pose), both (the mean of that and the alignment onto the arriving pose) or drift (moving from one to the other over the segment)."),
    anchor: str = typer.Option(ANCHOR, "--anchor", help="Library poses aligned for --place: ends (the segment's first and last frames) or nodes (the clip's enhancement nodes: its frames most like the departure and the arrival)."),
    hold: float = typer.Option(HOLD, "--hold", help="Fraction of the transition, centred on the reference pose, that follows the library segment with full weight (0: the thesis' two-half blend)."),
    enh_window: int = typer.Option(9, "--enh-window", help="Window (frames) of the enhanced distance."),
    context: int = typer.Option(CONTEXT, "--context", help="Match the marked frame together with this many video frames either side (temporal coherence; estimated sources use the neighbours their poses hold)."),
    scores: bool = typer.Option(SCORES, "--scores/--no-scores", help="Weight bones by the estimated pose's confidence scores."),
    foreshortening: bool = typer.Option(FORESHORTENING, "--foreshortening/--no-foreshortening", help="Also weight bones by their image length against their side-on length (a bone pointing at the camera counts less)."),
    max_match_cost: List[str] = typer.Option(MAX_MATCH_COST, "--max-match-cost", help="Accept an enhancement only when its match cost is at most this, else keep the plain transition: VALUE or SOURCE=VALUE (- = none); repeatable. Default: chosen per source on validation performers (scripts/validate_augmg.py)."),
    max_enh_cost: List[str] = typer.Option(MAX_ENH_COST, "--max-enh-cost", help="... and its enhanced distance (CMU length units) at most this: VALUE or SOURCE=VALUE; repeatable; default from validation."),
    min_gain: List[str] = typer.Option(MIN_GAIN, "--min-gain", help="... and the reference pose at least this far (mm) from the plain transition's middle frame: VALUE or SOURCE=VALUE; repeatable; default from validation."),
    seed: int = typer.Option(0, "--seed", help="Seed of the 2D noise."),
    headline: Optional[Path] = typer.Option(None, "--headline", help="Also merge augmg.* keys into this headline JSON."),
    transitions: Optional[Path] = typer.Option(None, "--transitions", help="Also write the headline source's poses and plain / AugMG / true transitions of every query (transitions.json, for the report's animations)."),
    jobs: int = _JOBS,
) -> None:
    """Retrieval MPJPE / recall@1/@10 and transition error (AugMG vs plain motion graph against the
    performer's true transition, same endpoints), per 2D source: gt, noisy (and model)."""
    from rich.console import Console
    from rich.table import Table

    from ..augmg.evaluate import evaluate_augmg
    from ..fileio import write_json

    if segment not in ("fixed", "nodes", "adaptive"):
        raise InputError(f"--segment: fixed, nodes or adaptive, got {segment!r}")
    _check_placement(place, anchor, hold)
    if context < 0:
        raise InputError(f"--context: must be at least 0, got {context}")
    if enh_window < 1:
        raise InputError(f"--enh-window: must be at least 1, got {enh_window}")
    if not 0 < segment_scale <= 1:
        raise InputError(f"--segment-scale: must be in (0, 1], got {segment_scale}")
    marks = _read_marks(annotations) if annotations else None
    poses: dict = {}
    for d in poses_dir:
        name, doc = _read_poses_dir(d)
        if name in poses:
            raise InputError(f"--poses-dir: {d}: a second directory of {name} poses")
        poses[name] = doc
    sources = [*poses, "gt", "noisy"]
    metrics = evaluate_augmg(dataset, library, sources=tuple(sources), poses=poses, annotations=marks, noise=noise,
                             k=k, n_views=views, segment=segment, segment_scale=segment_scale, enh_window=enh_window,
                             place=place, anchor=anchor, hold=hold,
                             context=context, use_scores=scores, foreshortening=foreshortening, thresholds=_thresholds(sources, max_match_cost,
                                                                                        max_enh_cost, min_gain),
                             animate=next((x for x in ("model", "blazepose") if x in poses), "gt"), seed=seed, jobs=jobs)
    animations_source = next((x for x in ("model", "blazepose") if x in poses), "gt")
    # the headline is the thesis' own estimated pose (pictorial structures, 'model') when given,
    # fixed in advance (not the better of the estimated sources)
    head = next((x for x in ("model", "blazepose", "gt") if x in metrics["by_source"]), "gt")
    main = metrics["by_source"][head]
    metrics["headline"] = {
        "augmg.retrieval_mpjpe": main["retrieval_mpjpe_mm"],
        "augmg.transition_error_plain": main["transition_plain_mm"],
        "augmg.transition_error_augmg": main["transition_augmg_mm"],
        "augmg.source": head,
    }
    for src, r in metrics["by_source"].items():
        if src != head:
            metrics["headline"][f"augmg.{src}.retrieval_mpjpe"] = r["retrieval_mpjpe_mm"]
            metrics["headline"][f"augmg.{src}.transition_error_augmg"] = r["transition_augmg_mm"]
    from ..formats.metrics import AUGMG, write_metrics

    if transitions is not None:
        from ..augmg.evaluate import transitions_document
        from ..formats.augmg_transitions import write_augmg_transitions
        from ..formats.dataset import read_dataset

        man = read_dataset(dataset)
        step = max(1, int(man.extra["mocap_fps"] // man.fps))
        write_augmg_transitions(transitions, transitions_document(metrics, animations_source, float(man.fps), step))
        log.info("wrote %s", transitions)
    metrics.pop("animations", None)
    metrics = {"seed": seed, **metrics}
    write_metrics(out, metrics, kind=AUGMG)
    if headline is not None:
        from ..fileio import read_json

        doc = read_json(headline) if headline.is_file() else {}
        doc.update({k2: v for k2, v in metrics["headline"].items()})
        write_json(headline, doc)
    table = Table(title=f"AugMG: {metrics['params']['queries']} held-out transitions, "
                        f"{metrics['params']['library_frames']} library frames")
    for col in ("2D source", "queries", "MPJPE top-1 mm", "MPJPE ref mm", "oracle mm", "R@1", "R@10",
                "plain mm", "AugMG mm", "accepted", "enhanced mm", "oracle mm ", "reduction", "95 % interval"):
        table.add_column(col)
    for src, r in metrics["by_source"].items():
        table.add_row(src, str(r["queries"]), f"{r['retrieval_mpjpe_mm']:.1f}", f"{r['reference_mpjpe_mm']:.1f}",
                      f"{r['oracle_mpjpe_mm']:.1f}", f"{r['recall_at_1']:.2f}", f"{r['recall_at_10']:.2f}",
                      f"{r['transition_plain_mm']:.1f}", f"{r['transition_augmg_mm']:.1f}",
                      f"{r['accepted']:.2f}", f"{r['transition_enhanced_mm']:.1f}", f"{r['transition_oracle_mm']:.1f}",
                      f"{100 * r['transition_reduction']:.0f} %",
                      "-" if not r.get("transition_reduction_ci95") else
                      "{:.0f} .. {:.0f} %".format(*(100 * x for x in r["transition_reduction_ci95"])))
    kinds = Table(title="AugMG transition error by kind (mm)")
    for col in ("2D source", "kind", "queries", "plain mm", "AugMG mm", "accepted", "enhanced mm", "oracle mm"):
        kinds.add_column(col)
    for src, r in metrics["by_source"].items():
        for kind, x in r["by_kind"].items():
            kinds.add_row(src, kind, str(x["queries"]), f"{x['plain_mm']:.1f}", f"{x['augmg_mm']:.1f}",
                          f"{x['accepted']:.2f}", f"{x['enhanced_mm']:.1f}", f"{x['oracle_mm']:.1f}")
    console = Console(width=160)
    console.print(table)
    console.print(kinds)
    log.info("wrote %s", out)


def _thresholds(sources, match: list[str], enh: list[str], gain: list[str]) -> dict:
    """Per-source acceptance thresholds of evaluate augmg from the repeatable SOURCE=VALUE options."""
    m, e, g = per_source(match, "--max-match-cost"), per_source(enh, "--max-enh-cost"), per_source(gain, "--min-gain")
    return {s: {"max_match_cost": m.get(s, m.get("*")), "max_enh_cost": e.get(s, e.get("*")),
                "min_gain_mm": g.get(s, g.get("*"))} for s in sources}


def _read_marks(path: Path) -> list[dict]:
    """Transition marks of an annotations file as {"video", "frame", "from", "to", "status"}."""
    from ..augmg.annotations_io import read_marks

    return read_marks(path)


def _read_poses_dir(d: Path) -> tuple[str, dict]:
    """(source name, video id -> {frame: (points, viewpoint_deg, view spread, scores)}) of a directory of
    poses.json files; the source is named by the backend ('model' for pictorial structures)."""
    from ..formats.poses import read_poses
    from ..render.camera import parse_view

    files = sorted(d.glob("*.poses.json"))
    if not files:
        raise InputError(f"--poses-dir: no *.poses.json in {d}")
    out: dict = {}
    backends = set()
    for f in files:
        doc = read_poses(f)
        backends.add(str(doc.backend))
        vid = f.name[: -len(".poses.json")]
        out[vid] = {int(fp.frame): (fp.xy.copy(), parse_view(fp.viewpoint), 0 if _is_number(fp.viewpoint) else 1,
                                    fp.scores.copy()) for fp in doc.frames}
    if len(backends) != 1:
        raise InputError(f"--poses-dir: {d} mixes pose backends {sorted(backends)}")
    backend = backends.pop()
    return ("model" if backend == "ps" else backend), out
