"""``vidstyle build-graph``, ``vidstyle synthesize`` and ``vidstyle evaluate motion``: motion graphs."""

from __future__ import annotations

import logging
from contextlib import contextmanager
from pathlib import Path
from typing import List

import typer

from ..errors import InputError, ParameterError
from ..inbetween import defaults as KD
from ..motiongraph import defaults as D
from ._evaluate import evaluate_app
from ._numbers import jobs_option

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


_BUILD_FLAGS = {"window": "--window", "fps": "--fps", "mirror": "--mirror", "scheduler": "--scheduler", "clips": "CLIPS",
                "dtype": "--dtype", "threshold_quantile": "--quantile", "threshold": "--threshold", "tile": "--tile",
                "require_classes": "--require-classes"}
_PLAN_FLAGS = {"steps": "--sequence", "graph": "--graph", "max_in_degree": "--max-in-degree"}


def register(app: typer.Typer) -> None:
    app.command("build-graph")(build_graph)
    app.command("synthesize")(synthesize)


def build_graph(
    clips: List[Path] = typer.Argument(..., help="BVH files or directories of BVH files."),
    labels: List[Path] = typer.Option([], "--labels", "-l", help="Labels: demo .labels.json, CMU clips.csv, or CSV file,label[,start,end]. Repeatable."),
    out: Path = typer.Option(..., "--out", "-o", help="Graph file (.npz)."),
    window: int = typer.Option(D.WINDOW, "--window", "-k", help="Comparison and blend window in frames."),
    fps: float = typer.Option(D.FPS, "--fps", help="Frame rate of the graph (clips are resampled)."),
    threshold: float | None = typer.Option(None, "--threshold", help="RMS distance for transitions (clip length unit); default: --quantile of random pairs."),
    quantile: float = typer.Option(D.THRESHOLD_QUANTILE, "--quantile", help="Quantile of the pair distance used as default threshold."),
    min_gap: int | None = typer.Option(None, "--min-gap", help="No transitions within one clip between windows closer than this (frames; default 2*window)."),
    mirror: bool = typer.Option(D.MIRROR, "--mirror", help="Add the mirror image of every clip."),
    tile: int = typer.Option(D.TILE, "--tile", help="Tile size of the all-pairs pass."),
    dtype: str = typer.Option(D.DTYPE, "--dtype", help="GEMM precision: float32 (candidates refined in float64) or float64."),
    jobs: int = jobs_option(D.N_JOBS, help="1 (the default, unlike other commands): this process, one thread per core sharing one copy of the windows; N or -1 = all cores: joblib worker processes, each with its own copy."),
    scheduler: str | None = typer.Option(None, "--scheduler", help="Dask scheduler address (tcp://host:port)."),
    seed: int = typer.Option(D.RANDOM_STATE, "--seed", help="Seed of the threshold sample."),
    require_classes: str = typer.Option("", "--require-classes", help="Comma-separated actions the graph must have frames of (e.g. your annotations' classes): checked before the build, which is refused naming the missing ones."),
) -> None:
    """Build a motion graph from labelled clips (see vidstyle.formats.motiongraph for the .npz schema, version 2).

    Clips of one joint layout in other units or bone lengths are retargeted onto the first clip's skeleton
    (rotations kept, root path scaled by leg length)."""
    from ..motiongraph import build_graph as build

    with flag_names(_BUILD_FLAGS):
        graph = build(clips, labels, window=window, fps=fps, threshold=threshold, threshold_quantile=quantile,
                      min_gap=min_gap, mirror=mirror, tile=tile, dtype=dtype, n_jobs=jobs, scheduler=scheduler,
                      random_state=seed, require_classes=require_classes.split(","))
    graph.save(out)
    st = graph.stats_
    log.info("wrote %s: %d frames, %d transitions in the component (%d frames), labels %s, %.1f s",
             out, st["frames"], st["transitions_in_scc"], st["scc_frames"], graph.label_names_, st["build_seconds"])


def synthesize(
    graph_path: Path = typer.Option(..., "--graph", "-g", help="Graph file from build-graph."),
    sequence: Path | None = typer.Option(None, "--sequence", "-s", help="Sequence JSON (from vidstyle generate) or a JSON list of actions."),
    keyframes: Path | None = typer.Option(None, "--keyframes", "-K", help="Instead of --sequence: keyframes JSON {\"keyframes\": [{\"clip\": BVH, \"frame\": i, \"time\": s}, ...]} (>= 2); the motion passes through each pose at its time (docs/keyframes.md)."),
    method: str | None = typer.Option(None, "--method", help=f"With --keyframes: {' | '.join(KD.METHODS)} (default {KD.METHOD}: Molina Tanco & Hilton's Markov chain over pose clusters; graph: the graph's shortest path; slerp: LERP+SLERP)."),
    out: Path = typer.Option(..., "--out", "-o", help="Output BVH; with --sequence, <out stem>.labels.json is written beside it."),
    preview: Path | None = typer.Option(None, "--preview", help="Also render a preview video (.mp4)."),
    preview_size: str = typer.Option("640x480", "--preview-size", help="WIDTHxHEIGHT of the --preview video."),
    seconds: float = typer.Option(D.STEP_SECONDS, "--seconds", help="Duration of steps given without one."),
    mismatch_penalty: float = typer.Option(D.MISMATCH_PENALTY, "--mismatch-penalty", help="Cost of one output frame with a wrong label."),
    transition_penalty: float = typer.Option(D.TRANSITION_PENALTY, "--transition-penalty", help="Cost added to every transition (in threshold units)."),
    strict: bool = typer.Option(D.STRICT, "--strict/--lenient", help="Fail when a step gets no frame of its action within its duration (default: warn, naming the step)."),
    foot_lock: bool = typer.Option(D.FOOT_LOCK, "--foot-lock/--no-foot-lock", help="Hold planted feet still across seams (two-bone leg IK)."),
    max_in_degree: int | None = typer.Option(None, "--max-in-degree", help="Approximate: walk only the N cheapest transitions into each frame per source label (default: exact DP)."),
    seed: int = typer.Option(KD.RANDOM_STATE, "--seed", help="With --keyframes --method markov: seed of the pose clustering."),
    style: Path | None = typer.Option(None, "--style", help="With --sequence: a style.json with an action-level part "
                                         "(learn-style --poses-dir): every action of the walk is replaced by this "
                                         "performer's way of doing it (needs --action-model; docs/actionmodel.md)."),
    action_model: Path | None = typer.Option(None, "--action-model", help="With --style: the action model its "
                                                "coefficients belong to (fit-actions)."),
) -> None:
    """Walk the graph to realise an action sequence at minimum transition cost (--sequence), or make motion
    from keyframe to keyframe (--keyframes); write BVH (+ labels, preview)."""
    from ..motiongraph import MotionGraph, save_synthesis
    from ..motiongraph import synthesize as synth

    from .render import parse_size

    psize = parse_size(preview_size, "--preview-size")
    if (sequence is None) == (keyframes is None):
        raise InputError("--sequence / --keyframes: give exactly one (an action sequence, or keyframes to pass through)")
    if keyframes is None and method is not None:
        raise InputError("--method: only with --keyframes (a sequence is always realised by the motion graph)")
    if (style is None) != (action_model is None):
        raise InputError("--style / --action-model: give both (the performer's action style and its action model) or neither")
    if style is not None and keyframes is not None:
        raise InputError("--style: only with --sequence")
    restyle = None
    if style is not None:  # read before the walk: a bad file fails fast
        from ..actionmodel import ActionModel
        from ..style.artifact import Style

        amodel = ActionModel.load(action_model)
        ast = Style.load(style).action_style
        if ast is None:
            raise InputError(f"{style}: no action-level style (learn it with learn-style --poses-dir --action-model)")
        ast.check_model(amodel, style)
        restyle = (ast, amodel)
    graph = MotionGraph.load(graph_path)
    if keyframes is not None:
        synthesize_from_keyframes(graph, keyframes, method or KD.METHOD, out, seed)
        if preview is not None:
            from ..mocap import read_bvh

            write_preview(read_bvh(out), preview, size=psize)
        return
    with flag_names(_PLAN_FLAGS):
        result = synth(graph, sequence, bvh_name=out.name, seconds=seconds, mismatch_penalty=mismatch_penalty,
                       transition_penalty=transition_penalty, strict=strict, foot_lock=foot_lock,
                       max_in_degree=max_in_degree)
    if restyle is not None:
        import dataclasses

        from ..actionmodel.stylefit import restyle_motion

        m2, runs = restyle_motion(result.motion, result.labels["labels"], *restyle)
        result = dataclasses.replace(result, motion=m2)
        log.info("restyled %d action(s) with %s (%s)", len(runs), style, restyle[0].global_style.lead)
    save_synthesis(result, out)
    motion = result.motion
    log.info("wrote %s: %d frames (%.1f s) with %d transitions, %.0fx real time", out, motion.n_frames,
             motion.duration, len(result.walk.transitions_used), motion.duration / max(result.seconds, 1e-9))
    if preview is not None:
        write_preview(motion, preview, size=psize)


def synthesize_from_keyframes(graph, keyframes: Path, method: str, out: Path, seed: int) -> None:
    """``synthesize --keyframes``: in-between every consecutive pair, write the BVH (atomically)."""
    from ..inbetween import synthesize_keyframes
    from ..mocap import write_bvh

    with flag_names({"method": "--method"}):
        result = synthesize_keyframes(graph, keyframes, method, random_state=seed)
    write_bvh(result.motion, out)
    log.info("wrote %s: %d frames (%.1f s) through %d keyframes (%s), %.0f ms", out, result.motion.n_frames,
             result.motion.duration, len(result.key_frames), method, 1000 * result.seconds)


def write_preview(motion, path: Path, fps: float = 30.0, size: tuple[int, int] = (640, 480)) -> None:
    try:
        from ..render import render_to_file
    except ImportError:
        raise InputError("--preview: the renderer (vidstyle.render.render_to_file) is not available") from None
    # one preview (640x480 by default): x264 on a thread of its own while the frames are drawn (the same file)
    render_to_file(motion, str(path), view="front", size=size, fps=fps, background_encode=True)
    log.info("wrote preview %s", path)


@evaluate_app.command("motion")
def evaluate_motion(
    graph_path: Path = typer.Option(..., "--graph", "-g", help="Graph file."),
    motions: List[Path] = typer.Argument(None, help="Synthesised BVH files (with <stem>.labels.json); default: random walks."),
    out: Path = typer.Option(Path("metrics/motion.json"), "--out", "-o", help="Metrics JSON."),
    walks: int = typer.Option(D.EVAL_WALKS, "--walks", help="Random sequences to synthesise when no motions are given."),
    steps: int = typer.Option(D.EVAL_STEPS, "--steps", help="Steps per random sequence."),
    actions: str | None = typer.Option(None, "--actions", help="Comma-separated actions for random sequences (default: every label with >= 2 s of frames)."),
    min_seconds: float = typer.Option(D.EVAL_MIN_SECONDS, "--min-seconds", help="Shortest random step."),
    max_seconds: float = typer.Option(D.EVAL_MAX_SECONDS, "--max-seconds", help="Longest random step."),
    seed: int = typer.Option(0, "--seed", help="Seed of the random sequences."),
    foot_lock: bool = typer.Option(D.FOOT_LOCK, "--foot-lock/--no-foot-lock", help="Render random walks with foot locking (compare both)."),
    sequence: Path | None = typer.Option(None, "--sequence", "-s", help="Synthesise this sequence file (e.g. from vidstyle generate) instead of random ones."),
    max_in_degree: int | None = typer.Option(None, "--max-in-degree", help="Approximate planning (see synthesize); default exact."),
) -> None:
    """Seam quality, foot skid, label fidelity and transitions used of synthesised motion."""
    from rich.console import Console
    from rich.table import Table

    from ..evaluation.motion import evaluate
    from ..formats.metrics import MOTION, write_metrics
    from ..motiongraph import MotionGraph

    graph = MotionGraph.load(graph_path)
    flags = _PLAN_FLAGS if motions or sequence is not None else {**_PLAN_FLAGS, "steps": "--actions"}
    try:
        with flag_names(flags):
            result = evaluate(graph, motions or (), sequence=sequence, walks=walks, steps=steps, actions=actions,
                              min_seconds=min_seconds, max_seconds=max_seconds, seed=seed, foot_lock=foot_lock,
                              max_in_degree=max_in_degree)
    except InputError as e:
        if str(e).startswith("--actions: no action with enough frames in the graph"):
            raise InputError(str(e).replace("the graph", str(graph_path), 1)) from None
        raise
    metrics = {"graph": str(graph_path), **result}
    write_metrics(out, metrics, kind=MOTION)
    summary = result["summary"]
    table = Table(title=f"motion graph: {graph_path.name}")
    for col in ("metric", "seam", "inside output", "original clips", "seam / original"):
        table.add_column(col)
    fmt = lambda v: "-" if v is None else f"{v:.3g}"
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


@evaluate_app.command("inbetween")
def evaluate_inbetween(
    cmu: Path | None = typer.Option(None, "--cmu", help="Folder of CMU BVH clips named <subject>_<trial>.bvh (with clips.csv)."),
    graph: Path | None = typer.Option(None, "--graph", help="Instead of --cmu: this motion graph (build-graph) is the "
                                      "library, and --clips are the held-out windows' clips."),
    clips: List[Path] = typer.Option([], "--clips", help="With --graph: held-out BVH clips (none of the graph's)."),
    max_windows: int | None = typer.Option(None, "--max-windows", help="With --graph: at most this many windows (an even spread)."),
    library: str = typer.Option(",".join(KD.EVAL_SPLIT["library"]), "--library", help="Comma-separated subjects the methods learn from."),
    test: str = typer.Option(",".join(KD.EVAL_SPLIT["test"]), "--test", help="Comma-separated held-out subjects whose windows are scored (none of --library)."),
    gaps: str = typer.Option(",".join(map(str, KD.EVAL_GAPS)), "--gaps", help="Comma-separated gap lengths in frames at 30 fps."),
    methods: str = typer.Option(",".join(KD.EVAL_METHODS), "--methods", help=f"Comma-separated: {', '.join(KD.EVAL_METHODS)} (slerp_hermite: SLERP with the keys' Hermite root path)."),
    graph_cache: Path | None = typer.Option(None, "--graph-cache", help="Motion graph of the library: read when it exists, else built and written there."),
    out: Path = typer.Option(Path("metrics/inbetween.json"), "--out", "-o", help="Metrics JSON."),
    seed: int = typer.Option(KD.RANDOM_STATE, "--seed", help="Seed of the graph's threshold sample and the pose clustering."),
) -> None:
    """Keyframe in-betweening on held-out windows: LAFAN1's L2P and L2Q per gap and method, ms per request."""
    from ..evaluation.inbetween import evaluate, evaluate_on_graph, table
    from ..formats.metrics import INBETWEEN, write_metrics

    if (cmu is None) == (graph is None):
        raise InputError("evaluate inbetween: give --cmu DIR, or --graph G with --clips")
    if graph is not None:
        from ..fileio import check_writable
        from ..motiongraph import MotionGraph

        if not clips:
            raise InputError("--graph: give the held-out --clips")
        if max_windows is not None and max_windows < 1:
            raise ParameterError("--max-windows", f"must be at least 1, got {max_windows}")
        for c in clips:
            if not Path(c).is_file():
                raise InputError(f"{c}: clip not found")
        gap_list = _gaps(gaps)
        names = _methods(methods)
        check_writable(out)
        g = MotionGraph.load(graph)
        try:
            doc = evaluate_on_graph(g, clips, gap_list, names, seed, max_windows, library=str(graph),
                                    command=f"vidstyle evaluate inbetween --graph {graph} --clips ...")
        except ValueError as e:
            raise InputError(f"--clips: {e}") from None
    else:
        lib = [s.strip() for s in library.split(",") if s.strip()]
        held = [s.strip() for s in test.split(",") if s.strip()]
        if set(lib) & set(held):
            raise InputError(f"--test: subject(s) {', '.join(sorted(set(lib) & set(held)))} are also in --library")
        gap_list = _gaps(gaps)
        names = _methods(methods)
        if not cmu.is_dir():
            raise InputError(f"--cmu: {cmu} is not a folder")
        for group, flag in ((lib, "--library"), (held, "--test")):
            if not group or not any(any(cmu.glob(f"{s}_*.bvh")) for s in group):
                raise InputError(f"{flag}: no clips <subject>_*.bvh of {', '.join(group) or 'no subject'} in {cmu}")
        try:
            doc = evaluate(cmu, lib, held, gap_list, names, seed, graph_cache,
                           command=f"vidstyle evaluate inbetween --cmu {cmu} --library {','.join(lib)} --test {','.join(held)}")
        except ValueError as e:
            raise InputError(f"--test: {e}") from None
    write_metrics(out, doc, kind=INBETWEEN)
    typer.echo(table(doc))
    log.info("wrote %s", out)


def _gaps(gaps: str) -> list[int]:
    try:
        gap_list = [int(g) for g in gaps.split(",") if g.strip()]
    except ValueError:
        raise InputError(f"--gaps: expected comma-separated integers, got {gaps!r}") from None
    if not gap_list or min(gap_list) < 1 or max(gap_list) > 54:
        raise InputError(f"--gaps: each gap must be 1 .. 54 frames (windows are 65 frames), got {gaps!r}")
    return gap_list


def _methods(methods: str) -> list[str]:
    names = [m.strip() for m in methods.split(",") if m.strip()]
    unknown = [m for m in names if m not in KD.EVAL_METHODS]
    if unknown or not names:
        raise InputError(f"--methods: {', '.join(unknown) or 'none given'}: expected some of {', '.join(KD.EVAL_METHODS)}")
    return names
