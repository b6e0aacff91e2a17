"""``vidstyle build-graph``, ``vidstyle synthesize`` and ``vidstyle evaluate motion``: motion graphs."""

from __future__ import annotations

import logging
import time
from contextlib import contextmanager
from pathlib import Path
from typing import List, Optional

import numpy as np
import typer

from ..errors import InputError
from ._evaluate import evaluate_app

log = logging.getLogger(__name__)


@contextmanager
def flag_names(mapping: dict[str, str]):
    """Library errors name parameters (``window: ...``); say the command's flags instead (``--window: ...``)."""
    try:
        yield
    except InputError as e:
        msg = str(e)
        for name, flag in mapping.items():
            if msg.startswith(name + ":") or msg.startswith(name + " "):
                raise InputError(flag + msg[len(name):]) from None
        raise


_BUILD_FLAGS = {"window": "--window", "fps": "--fps", "mirror": "--mirror", "scheduler": "--scheduler", "clips": "CLIPS"}
_PLAN_FLAGS = {"steps": "--sequence", "graph": "--graph", "max_in_degree": "--max-in-degree"}


def register(app: typer.Typer) -> None:
    app.command("build-graph")(build_graph)
    app.command("synthesize")(synthesize)


def build_graph(
    clips: List[Path] = typer.Argument(..., help="BVH files or directories of BVH files."),
    labels: List[Path] = typer.Option([], "--labels", "-l", help="Labels: demo .labels.json, CMU clips.csv, or CSV file,label[,start,end]. Repeatable."),
    out: Path = typer.Option(..., "--out", "-o", help="Graph file (.npz)."),
    window: int = typer.Option(10, "--window", "-k", help="Comparison and blend window in frames."),
    fps: float = typer.Option(30.0, "--fps", help="Frame rate of the graph (clips are resampled)."),
    threshold: Optional[float] = typer.Option(None, "--threshold", help="RMS distance for transitions (clip length unit); default: --quantile of random pairs."),
    quantile: float = typer.Option(0.05, "--quantile", help="Quantile of the pair distance used as default threshold."),
    min_gap: Optional[int] = typer.Option(None, "--min-gap", help="No transitions within one clip between windows closer than this (frames; default 2*window)."),
    mirror: bool = typer.Option(False, "--mirror", help="Add the mirror image of every clip."),
    tile: int = typer.Option(2048, "--tile", help="Tile size of the all-pairs pass."),
    dtype: str = typer.Option("float32", "--dtype", help="GEMM precision: float32 (candidates refined in float64) or float64."),
    jobs: int = typer.Option(1, "--jobs", "-j", help="1: this process, all BLAS threads; N or -1: joblib workers."),
    scheduler: Optional[str] = typer.Option(None, "--scheduler", help="Dask scheduler address (tcp://host:port)."),
    seed: int = typer.Option(0, "--seed", help="Seed of the threshold sample."),
) -> None:
    """Build a motion graph from labelled clips (see vidstyle.formats.motiongraph for the .npz schema, version 2).

    Clips of one joint layout in other units or bone lengths are retargeted onto the first clip's skeleton
    (rotations kept, root path scaled by leg length)."""
    from ..motiongraph import MotionGraph, load_clips

    if dtype not in ("float32", "float64"):
        raise InputError(f"--dtype: float32 or float64, got {dtype!r}")
    if not 0 < quantile < 1:
        raise InputError(f"--quantile: must be in (0, 1), got {quantile}")
    if threshold is not None and not threshold > 0:
        raise InputError(f"--threshold: must be positive, got {threshold}")
    if tile < 16:
        raise InputError(f"--tile: must be at least 16, got {tile}")
    with flag_names(_BUILD_FLAGS):
        data = load_clips(clips, labels)
        graph = MotionGraph(window=window, fps=fps, threshold=threshold, threshold_quantile=quantile, min_gap=min_gap,
                            mirror=mirror, tile=tile, dtype=dtype, n_jobs=jobs, scheduler=scheduler, random_state=seed)
        graph.fit(data)
    graph.save(out)
    st = graph.stats_
    log.info("wrote %s: %d frames, %d transitions in the component (%d frames), labels %s, %.1f s",
             out, st["frames"], st["transitions_in_scc"], st["scc_frames"], graph.label_names_, st["build_seconds"])


def synthesize(
    graph_path: Path = typer.Option(..., "--graph", "-g", help="Graph file from build-graph."),
    sequence: Path = typer.Option(..., "--sequence", "-s", help="Sequence JSON (from vidstyle generate) or a JSON list of actions."),
    out: Path = typer.Option(..., "--out", "-o", help="Output BVH; <out stem>.labels.json is written beside it."),
    preview: Optional[Path] = typer.Option(None, "--preview", help="Also render a preview video (.mp4)."),
    seconds: float = typer.Option(1.0, "--seconds", help="Duration of steps given without one."),
    mismatch_penalty: float = typer.Option(5.0, "--mismatch-penalty", help="Cost of one output frame with a wrong label."),
    transition_penalty: float = typer.Option(0.2, "--transition-penalty", help="Cost added to every transition (in threshold units)."),
    strict: bool = typer.Option(False, "--strict/--lenient", help="Fail when a step gets no frame of its action within its duration (default: warn, naming the step)."),
    foot_lock: bool = typer.Option(True, "--foot-lock/--no-foot-lock", help="Hold planted feet still across seams (two-bone leg IK)."),
    max_in_degree: Optional[int] = typer.Option(None, "--max-in-degree", help="Approximate: walk only the N cheapest transitions into each frame per source label (default: exact DP)."),
) -> None:
    """Walk the graph to realise an action sequence at minimum transition cost; write BVH (+ labels, preview)."""
    from ..formats.walk import parse_walk_labels, write_walk_labels
    from ..mocap import write_bvh
    from ..motiongraph import MotionGraph, plan_walk, read_sequence, render_walk, walk_labels

    graph = MotionGraph.load(graph_path)
    steps = read_sequence(sequence, graph.fps, seconds)
    t0 = time.perf_counter()
    with flag_names(_PLAN_FLAGS):
        walk = plan_walk(graph, steps, mismatch_penalty, transition_penalty, strict=strict, max_in_degree=max_in_degree)
    motion = render_walk(graph, walk, foot_lock=foot_lock)
    elapsed = time.perf_counter() - t0
    doc = walk_labels(graph, walk, out.name)
    parse_walk_labels(doc, labels_path(out))  # checked before anything is written
    write_bvh(motion, out)
    write_walk_labels(labels_path(out), doc)
    log.info("wrote %s: %d frames (%.1f s) with %d transitions, %.0fx real time", out, motion.n_frames,
             motion.duration, len(walk.transitions_used), motion.duration / max(elapsed, 1e-9))
    if preview is not None:
        write_preview(motion, preview)


def labels_path(bvh: Path) -> Path:
    return bvh.with_name(bvh.stem + ".labels.json")


def write_preview(motion, path: Path, fps: float = 30.0) -> None:
    try:
        from ..render import render_to_file
    except ImportError:
        raise InputError("--preview: the renderer (vidstyle.render.render_to_file) is not available") from None
    render_to_file(motion, str(path), view="front", size=(640, 480), fps=fps)
    log.info("wrote preview %s", path)


@evaluate_app.command("motion")
def evaluate_motion(
    graph_path: Path = typer.Option(..., "--graph", "-g", help="Graph file."),
    motions: List[Path] = typer.Argument(None, help="Synthesised BVH files (with <stem>.labels.json); default: random walks."),
    out: Path = typer.Option(Path("metrics/motion.json"), "--out", "-o", help="Metrics JSON."),
    walks: int = typer.Option(5, "--walks", help="Random sequences to synthesise when no motions are given."),
    steps: int = typer.Option(8, "--steps", help="Steps per random sequence."),
    actions: Optional[str] = typer.Option(None, "--actions", help="Comma-separated actions for random sequences (default: every label with >= 2 s of frames)."),
    min_seconds: float = typer.Option(1.0, "--min-seconds", help="Shortest random step."),
    max_seconds: float = typer.Option(3.0, "--max-seconds", help="Longest random step."),
    seed: int = typer.Option(0, "--seed", help="Seed of the random sequences."),
    foot_lock: bool = typer.Option(True, "--foot-lock/--no-foot-lock", help="Render random walks with foot locking (compare both)."),
    sequence: Optional[Path] = typer.Option(None, "--sequence", "-s", help="Synthesise this sequence file (e.g. from vidstyle generate) instead of random ones."),
    max_in_degree: Optional[int] = typer.Option(None, "--max-in-degree", help="Approximate planning (see synthesize); default exact."),
) -> None:
    """Seam quality, foot skid, label fidelity and transitions used of synthesised motion."""
    from rich.console import Console
    from rich.table import Table

    from ..formats.walk import read_walk_labels
    from ..mocap import read_bvh
    from ..motiongraph import MotionGraph, Step, plan_walk, render_walk, walk_labels
    from ..motiongraph.evaluate import evaluate_walk, original_stats, summarise

    graph = MotionGraph.load(graph_path)
    original = original_stats(graph, seed=seed)
    results = []
    synth_seconds, synth_frames = 0.0, 0
    if motions:
        for m in motions:
            motion = read_bvh(m)
            results.append(evaluate_walk(motion, read_walk_labels(labels_path(m), motion.n_frames).doc))
    elif sequence is not None:
        from ..motiongraph import read_sequence

        seq = read_sequence(sequence, graph.fps)
        t0 = time.perf_counter()
        with flag_names(_PLAN_FLAGS):
            walk = plan_walk(graph, seq, strict=False, max_in_degree=max_in_degree)
        motion = render_walk(graph, walk, foot_lock=foot_lock)
        synth_seconds += time.perf_counter() - t0
        synth_frames += motion.n_frames
        results.append(evaluate_walk(motion, walk_labels(graph, walk, sequence.stem + ".bvh")))
    else:
        rng = np.random.default_rng(seed)
        lab = graph.labels_[graph.scc_]
        counts = {name: int((lab == i).sum()) for i, name in enumerate(graph.label_names_)}
        if actions:
            pool = [a.strip() for a in actions.split(",") if a.strip()]
        else:
            pool = [a for a, c in counts.items() if c >= 2 * graph.fps and a != "unlabelled"]
        if not pool:
            raise InputError(f"--actions: no action with enough frames in {graph_path} ({counts})")
        for w in range(walks):
            seq, prev = [], None
            for _ in range(steps):
                choices = [a for a in pool if a != prev] or pool
                prev = str(rng.choice(choices))
                seq.append(Step(prev, int(rng.integers(int(min_seconds * graph.fps), int(max_seconds * graph.fps) + 1))))
            t0 = time.perf_counter()
            with flag_names({**_PLAN_FLAGS, "steps": "--actions"}):
                walk = plan_walk(graph, seq, strict=False, max_in_degree=max_in_degree)
            motion = render_walk(graph, walk, foot_lock=foot_lock)
            synth_seconds += time.perf_counter() - t0
            synth_frames += motion.n_frames
            results.append(evaluate_walk(motion, walk_labels(graph, walk, f"walk{w}.bvh")))
    summary = summarise(results, original)
    if synth_frames:
        summary["synthesis_x_real_time"] = synth_frames / graph.fps / max(synth_seconds, 1e-9)
    metrics = {
        "graph": str(graph_path),
        "graph_stats": graph.stats_,
        "seed": seed,
        "parameters": {"walks": walks, "steps": steps, "actions": actions, "min_seconds": min_seconds, "max_seconds": max_seconds,
                       "foot_lock": foot_lock, "sequence": str(sequence) if sequence else None,
                       "max_in_degree": max_in_degree},
        "summary": summary,
        "original": original,
        "walks": results,
    }
    from ..formats.metrics import MOTION, write_metrics

    write_metrics(out, metrics, kind=MOTION)
    table = Table(title=f"motion graph: {graph_path.name}")
    for col in ("metric", "seam", "inside output", "original clips", "seam / original"):
        table.add_column(col)
    fmt = lambda v: "-" if v is None else f"{v:.3g}"  # noqa: E731
    for metric in ("velocity_jump", "jerk", "foot_skid"):
        if metric in summary:
            r = summary[metric]
            for key in ("median", "p95"):
                table.add_row(f"{metric} {key}", fmt(r[f"seam_{key}"]), fmt(r[f"inside_{key}"]), fmt(r[f"original_{key}"]),
                              fmt(r[f"seam_over_original_{key}"]))
    table.add_row("label fidelity", fmt(summary["label_fidelity"]), "", "", "")
    table.add_row("transitions used (per s)", f"{summary['transitions_used']} ({summary['transitions_per_second']:.2f})", "", "", "")
    if "synthesis_x_real_time" in summary:
        table.add_row("synthesis x real time", fmt(summary["synthesis_x_real_time"]), "", "", "")
    Console().print(table)
    log.info("wrote %s", out)
