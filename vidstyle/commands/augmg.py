"""AugMG stages: ``vidstyle match-pose``, ``vidstyle augment``, ``vidstyle evaluate augmg`` and
``vidstyle demo make-library`` (the demo's mocap library that holds transition poses, not transitions)."""

from __future__ import annotations

import logging
from pathlib import Path
from typing import List, Optional

import typer

from ..augmg import defaults as D
from ..errors import InputError
from ._evaluate import evaluate_app
from ._numbers import jobs_option, number
from .demo import demo_app

log = logging.getLogger(__name__)

# the validated defaults live in the library (vidstyle.augmg.defaults, from
# pipelines/kickboxing/validation/augmg.json); the options below default to them


def _per_source_text(values: dict) -> list[str]:
    """``{"model": 0.526}`` -> ``["model=0.526"]`` (a per-source default as the repeatable option's text)."""
    return [f"{s}={v}" if s != "*" else str(v) for s, v in values.items()]


_JOBS = jobs_option(-1, help="Parallel workers for projecting and indexing (-1 = all cores).")
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
    pose_scales: Optional[str] = typer.Option(",".join(str(z) for z in D.POSE_SCALES) if D.POSE_SCALES else None, "--pose-scales", help="With --pose-model: zoom factors of multi-scale pose inference (as vidstyle pose --scales). Default: chosen on validation performers."),
    k: int = number(D.K, "--k", lo=1, hi=D.MAX_K, help="Candidate reference points per mark."),
    views: int = number(D.N_VIEWS, "--views", lo=1, hi=D.MAX_VIEWS, help="Azimuths the library is projected at."),
    edges_per_side: int = number(D.EDGES_PER_SIDE, "--edges-per-side", lo=1, hi=D.MAX_EDGES_PER_SIDE, help="Enhancement nodes on each side: departures x arrivals edges per mark."),
    enhancement_cost: float = number(D.ENHANCEMENT_COST, "--enhancement-cost", lo=0, lo_open=True, help="Edge cost as a fraction of the cheapest plain blend of that action pair (< 1: the planner prefers the enhancement)."),
    context: int = number(D.CONTEXT, "--context", lo=0, hi=D.MAX_CONTEXT, help="Match each mark together with the poses of up to this many frames either side (temporal coherence; run vidstyle pose with --context; less than the video's frame count)."),
    scores: bool = typer.Option(D.SCORES, "--scores/--no-scores", help="Weight bones by the poses' confidence scores."),
    foreshortening: bool = typer.Option(D.FORESHORTENING, "--foreshortening/--no-foreshortening", help="Also weight bones by their image length against their side-on length (a bone pointing at the camera counts less)."),
    max_match_cost: List[str] = typer.Option(_per_source_text(D.MAX_MATCH_COST), "--max-match-cost", help="Reject a reference point whose match cost exceeds this (the pair keeps its plain transitions): VALUE, or SOURCE=VALUE per pose source (model = ps, blazepose); repeatable. Default: chosen on validation performers (scripts/validate_augmg.py)."),
    anchor: str = typer.Option(D.ANCHOR, "--anchor", help="Align the enhancement segment by the library's enhancement nodes (nodes: its frames most like the departure and the arrival) or by the windows beside the reference pose (ends). Default: chosen on validation performers (as evaluate augmg)."),
    hold: float = number(D.HOLD, "--hold", lo=0, hi=1, hi_open=True, help="Fraction of an enhancement shown with the segment's full weight, about the reference pose (0: the thesis' two-half blend). Default: chosen on validation performers."),
    jobs: int = _JOBS,
) -> None:
    """Insert enhancement nodes (thesis 5.2) for the accepted transition marks: match each marked frame's
    2D pose against the projected library, pick the reference point by the enhanced distance, and add
    ENHANCEMENT edges through it for that action pair. Discarded marks / candidates are left out, so a
    rerun restores the plain transition (or takes the next candidate)."""
    from ..augmg import augment as augment_graph_file
    from .pose import parse_scales

    zooms = parse_scales(pose_scales, "--pose-scales") if pose_model is not None else None
    graph, inserted = augment_graph_file(graph_path, annotations, library, video=video, poses=poses, pose_model=pose_model,
                                         pose_scales=zooms, k=k, views=views, edges_per_side=edges_per_side,
                                         enhancement_cost=enhancement_cost, context=context, scores=scores,
                                         foreshortening=foreshortening,
                                         max_match_cost=per_source(max_match_cost, "--max-match-cost"),
                                         anchor=anchor, hold=hold, jobs=jobs)
    graph.save(out)
    log.info("wrote %s: %d reference points, %d enhancement edges", out, len(inserted),
             sum(len(i.edges) for i in inserted))


def per_source(values: list[str], option: str) -> dict:
    """``["1.2", "model=1.3", "blazepose=-"]`` -> ``{"*": 1.2, "model": 1.3, "blazepose": None}`` (a
    threshold for every source, per source; ``-`` = none): the repeatable SOURCE=VALUE options' text as
    the library's per-source thresholds."""
    out: dict = {}
    for v in values:
        name, _, num = v.rpartition("=")
        try:
            out[name or "*"] = None if num.strip() == "-" else float(num)
        except ValueError:
            raise InputError(f"{option}: {v!r} is not VALUE or SOURCE=VALUE") from None
    return out


@demo_app.command("make-library")
def make_library_cmd(
    out: Path = typer.Option(..., "--out", "-o", help="Output directory (created; must be empty or absent)."),
    seed: int = typer.Option(0, "--seed", help="Seed of the library performers (disjoint from every dataset performer)."),
    performers: int = number(3, "--performers", lo=1, hi=100, help="Library performers."),
    action_seconds: float = number(6.0, "--action-seconds", lo=0, lo_open=True, hi=600, help="Length of each single-action clip."),
    cmu: Optional[Path] = typer.Option(None, "--cmu", help="Also add CMU BVH clips from this directory (retargeted)."),
    cmu_clips: int = number(-1, "--cmu-clips", lo=-1, help="How many CMU clips (sorted by name) to add; -1 = all."),
    overwrite: bool = typer.Option(False, "--overwrite", help="Replace a non-empty --out once the new library is complete."),
    jobs: int = jobs_option(-1, help="Parallel workers (-1 = all cores)."),
    scheduler: str = _SCHEDULER,
) -> None:
    """Write the AugMG mocap library: every action per library performer, plus dodge / stance-switch /
    stop clips that hold the demo's transition poses in another context (never a performer's
    transition itself). Layout: DIR/library.json, DIR/clips/<name>.bvh (+ .labels.json)."""
    from ..demo.library import LibraryParams, make_library

    params = LibraryParams(seed=seed, performers=performers, action_seconds=action_seconds,
                           cmu_clips=cmu_clips if cmu is not None else 0)
    path = make_library(out, params, cmu_dir=cmu, overwrite=overwrite, jobs=jobs, scheduler=scheduler)
    log.info("library manifest %s", path)


def match_pose(
    poses: Path = typer.Argument(..., help="poses.json of the annotated frames (from vidstyle pose)."),
    library: List[Path] = typer.Option(..., "--library", "-l", help="Library BVH clips or directories (repeatable)."),
    out: Path = typer.Option(..., "--out", "-o", help="matches.json to write."),
    k: int = number(D.K, "--k", lo=1, hi=D.MAX_K, help="Candidates per frame."),
    views: int = number(D.N_VIEWS, "--views", lo=1, hi=D.MAX_VIEWS, help="Azimuths the library is projected at (360 / views apart)."),
    elevation: float = number(D.ELEVATION_DEG, "--elevation", lo=-89, hi=89, help="Camera elevation of the projection (degrees)."),
    stride: int = number(D.STRIDE, "--stride", lo=1, hi=D.MAX_STRIDE, help="Index every N-th library frame."),
    coherence: bool = typer.Option(False, "--coherence/--no-coherence", help="Re-rank candidates of consecutive frames by temporal coherence (Tautges' lazy neighbourhood graph)."),
    fps: float = number(D.VIDEO_FPS, "--fps", lo=0, lo_open=True, hi=1000, help="Video rate of the poses' frame numbers (for --coherence)."),
    jobs: int = _JOBS,
    scheduler: str = _SCHEDULER,
) -> None:
    """Match each frame's 2D pose against the library projected at the frame's viewpoint (relative to
    the character's facing; joint-angle features, kd-tree kNN); write the top-k library frames per
    frame as {"clip", "time", "cost"}."""
    from ..augmg import match_poses
    from ..formats.matches import write_matches

    matches = match_poses(poses, library, k=k, views=views, elevation=elevation, stride=stride, coherence=coherence,
                          fps=fps, jobs=jobs, scheduler=scheduler)
    write_matches(out, matches)
    log.info("wrote %s", out)


@evaluate_app.command("augmg")
def evaluate_augmg_cmd(
    dataset: Path = typer.Option(..., "--dataset", "-d", help="Demo dataset directory (performances with styled transitions)."),
    library: Path = typer.Option(..., "--library", "-l", help="Library directory (vidstyle demo make-library)."),
    out: Path = typer.Option(Path("metrics/augmg.json"), "--out", "-o", help="Metrics JSON."),
    annotations: Optional[Path] = typer.Option(None, "--annotations", "-a", help="Query the accepted marks of this annotations file instead of every transition's key frame."),
    poses_dir: List[Path] = typer.Option([], "--poses-dir", help="Directory of poses.json files (<video id>.poses.json) of the pose stage: adds an estimated 2D source named by its backend ('model' for ps, 'blazepose'); repeatable."),
    noise: float = number(D.NOISE, "--noise", lo=0, hi=10, help="2D noise sigma of the 'noisy' source, as a fraction of the torso length."),
    k: int = number(D.K, "--k", lo=1, hi=D.MAX_K, help="Candidates per query (the reference point is chosen among them)."),
    views: int = number(D.N_VIEWS, "--views", lo=1, hi=D.MAX_VIEWS, help="Azimuths the library is projected at."),
    segment: str = typer.Option(D.SEGMENT, "--segment", help="Library segment through the reference point: fixed (w_z-h..w_z+h, h = --segment-scale x half the transition), nodes (between the enhancement nodes w_z0..w_z2) or adaptive (each side's length chosen by the enhanced distance)."),
    segment_scale: float = number(D.SEGMENT_SCALE, "--segment-scale", lo=0, lo_open=True, hi=1, help="Library half-segment around the reference point, as a fraction of the transition's half-length (time-warped to it)."),
    place: str = typer.Option(D.PLACE, "--place", help="Placement of the library segment on the performer: first (aligned onto the departing pose), both (the mean of that and the alignment onto the arriving pose) or drift (moving from one to the other over the segment)."),
    anchor: str = typer.Option(D.ANCHOR, "--anchor", help="Library poses aligned for --place: ends (the segment's first and last frames) or nodes (the clip's enhancement nodes: its frames most like the departure and the arrival)."),
    hold: float = number(D.HOLD, "--hold", lo=0, hi=1, hi_open=True, help="Fraction of the transition, centred on the reference pose, that follows the library segment with full weight (0: the thesis' two-half blend)."),
    enh_window: int = number(D.ENH_WINDOW, "--enh-window", lo=1, hi=1000, help="Window (frames) of the enhanced distance."),
    context: int = number(D.CONTEXT, "--context", lo=0, hi=D.MAX_CONTEXT, help="Match the marked frame together with this many video frames either side (temporal coherence; estimated sources use the neighbours their poses hold; less than the videos' frame count)."),
    scores: bool = typer.Option(D.SCORES, "--scores/--no-scores", help="Weight bones by the estimated pose's confidence scores."),
    foreshortening: bool = typer.Option(D.FORESHORTENING, "--foreshortening/--no-foreshortening", help="Also weight bones by their image length against their side-on length (a bone pointing at the camera counts less)."),
    max_match_cost: List[str] = typer.Option(_per_source_text(D.MAX_MATCH_COST), "--max-match-cost", help="Accept an enhancement only when its match cost is at most this, else keep the plain transition: VALUE or SOURCE=VALUE (- = none); repeatable. Default: chosen per source on validation performers (scripts/validate_augmg.py)."),
    max_enh_cost: List[str] = typer.Option(_per_source_text(D.MAX_ENH_COST), "--max-enh-cost", help="... and its enhanced distance (CMU length units) at most this: VALUE or SOURCE=VALUE; repeatable; default from validation."),
    min_gain: List[str] = typer.Option(_per_source_text(D.MIN_GAIN), "--min-gain", help="... and the reference pose at least this far (mm) from the plain transition's middle frame: VALUE or SOURCE=VALUE; repeatable; default from validation."),
    seed: int = typer.Option(0, "--seed", help="Seed of the 2D noise."),
    unit_mm: Optional[float] = number(None, "--unit-mm", integer=False, lo=0, lo_open=True, help="Millimetres per mocap length unit (default: the dataset manifest's mocap_unit_m)."),
    headline: Optional[Path] = typer.Option(None, "--headline", help="Also merge augmg.* keys into this headline JSON."),
    transitions: Optional[Path] = typer.Option(None, "--transitions", help="Also write the headline source's poses and plain / AugMG / true transitions of every query (transitions.json, for the report's animations)."),
    jobs: int = _JOBS,
) -> None:
    """Retrieval MPJPE / recall@1/@10 and transition error (AugMG vs plain motion graph against the
    performer's true transition, same endpoints), per 2D source: gt, noisy (and model)."""
    from rich.console import Console
    from rich.table import Table

    from ..evaluation.augmg import evaluate
    from ..formats.augmg_transitions import write_augmg_transitions
    from ..formats.metrics import AUGMG, write_metrics

    thresholds = dict(max_match_cost=per_source(max_match_cost, "--max-match-cost"),
                      max_enh_cost=per_source(max_enh_cost, "--max-enh-cost"),
                      min_gain=per_source(min_gain, "--min-gain"))
    metrics, doc = evaluate(dataset, library, annotations=annotations, poses_dir=poses_dir, noise=noise, k=k,
                            views=views, segment=segment, segment_scale=segment_scale, place=place, anchor=anchor,
                            hold=hold, enh_window=enh_window, context=context, scores=scores,
                            foreshortening=foreshortening, **thresholds, seed=seed, unit_mm=unit_mm,
                            transitions=transitions is not None, jobs=jobs)
    if transitions is not None:
        write_augmg_transitions(transitions, doc)
        log.info("wrote %s", transitions)
    write_metrics(out, metrics, kind=AUGMG)
    if headline is not None:
        from ._evaluate import merge_headline

        merge_headline(headline, metrics["headline"])
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

