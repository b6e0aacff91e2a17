"""``vidstyle reconstruct`` (a video's performer as 3D motion, BVH) and ``vidstyle evaluate reconstruct``."""

from __future__ import annotations

import logging
from pathlib import Path

import typer

from ..errors import InputError
from ..reconstruct import defaults as D
from ._evaluate import evaluate_app
from ._numbers import jobs_option, number

log = logging.getLogger(__name__)

_METHOD_HELP = ("olng: the online lazy neighbourhood graph keeps temporally coherent library paths (Tautges); "
                "nn: every frame's nearest library frames alone (the baseline); subsequence: windows matched "
                "to library subsequences by DTW, chained by a shortest path (Tautges ch. 4).")


def _frames(text: str | None) -> list[int] | None:
    """``"0-199"`` or ``"0,5,9"`` -> frame list."""
    if text is None:
        return None
    out: list[int] = []
    for part in text.split(","):
        part = part.strip()
        try:
            if "-" in part:
                a, b = (int(x) for x in part.split("-", 1))
                if b < a:
                    raise ValueError
                out.extend(range(a, b + 1))
            else:
                out.append(int(part))
        except ValueError:
            raise InputError(f"--frames: {part!r} is not a frame index or a range A-B") from None
    if not out or min(out) < 0:
        raise InputError("--frames: give frame indices >= 0")
    return sorted(set(out))


def register(app: typer.Typer) -> None:
    app.command("reconstruct")(reconstruct)


def reconstruct(
    video: Path | None = typer.Argument(None, help="Input video (its frame rate and size; poses are estimated "
                                           "in it unless --poses)."),
    library: list[Path] = typer.Option(..., "--library", "-l", help="Mocap clips (BVH files or directories) to "
                                       "search; repeatable. All on one joint layout."),
    out: Path = typer.Option(..., "--out", "-o", help="BVH to write (the library's skeleton and length unit; +Y "
                             "up, the camera at the origin looking along +Z)."),
    poses: Path | None = typer.Option(None, "--poses", "-p", help="poses.json of the video (vidstyle pose) "
                                         "instead of estimating them here."),
    backend: str | None = typer.Option(None, "--backend", help="Pose backend when estimating (as vidstyle "
                                          "pose: ps or blazepose)."),
    model: Path | None = typer.Option(None, "--model", "-m", help="Pose model of --backend ps."),
    frames: str | None = typer.Option(None, "--frames", help="Frames to reconstruct: A-B or a comma list "
                                         "(default: all)."),
    skeleton: Path | None = typer.Option(None, "--skeleton", help="BVH whose skeleton the motion is put on "
                                            "(same joint layout as the library; default: the first clip's)."),
    record: Path | None = typer.Option(None, "--record", help="Also write reconstruction.json: per frame the "
                                          "blended library frames and weights, azimuth, label, foot contacts."),
    labels: Path | None = typer.Option(None, "--labels", help="Also write per-frame action labels of the "
                                          "matched library frames (needs <clip>.labels.json beside the clips)."),
    preview: Path | None = typer.Option(None, "--preview", help="Also write a side-by-side video (.mp4): the "
                                           "frames with the reconstruction projected over them, and a side view."),
    method: str = typer.Option(D.METHOD, "--method", help=_METHOD_HELP + " Default: chosen on validation performers."),
    k: int = number(D.K, "--k", lo=1, hi=1000, help="Library neighbours per frame."),
    blend: int = number(D.N_BLEND, "--blend", lo=1, hi=1000, help="Neighbours blended into a frame's pose (at most --k)."),
    window: float = number(D.WINDOW_S, "--window", lo=0, hi=10, help="OLNG window in seconds (Tautges: about 0.5; "
                           "the validation found 0.25-2 s alike)."),
    smooth: float = number(D.SMOOTH_FRAMES, "--smooth", lo=0, hi=100, help="Gaussian sigma of the pose over time, "
                           "in frames."),
    views: int = number(12, "--views", lo=1, hi=360, help="Azimuths the library is projected at."),
    focal: float | None = number(None, "--focal", integer=False, lo=0, lo_open=True,
                                    help="Focal length in pixels (default: a 60-degree lens across the longer side)."),
    estimate_focal: bool = typer.Option(False, "--estimate-focal", help="Estimate the focal length from the "
                                        "perspective within the poses (kept at the default lens unless the data "
                                        "clearly prefer another; a performer close to the camera tells most)."),
    elevation: float | None = number(None, "--elevation", integer=False, lo=-80, hi=80,
                                        help="Camera pitch in degrees, down positive (default: the library "
                                        "projection's, 10)."),
    foot_lock: bool = typer.Option(True, "--foot-lock/--no-foot-lock", help="Keep planted feet in place."),
    contact_threshold: float | None = number(None, "--contact-threshold", integer=False, lo=0, lo_open=True,
                                             hi=1, help="Share of the blended neighbours' vote that plants a foot "
                                             "(default: chosen on validation performers for the 2D's backend)."),
    contact_gap: float | None = number(None, "--contact-gap", integer=False, lo=0, hi=10,
                                       help="Seconds: a foot lifted for at most this long between two planted runs "
                                       "stays planted (0: none; default: chosen for the 2D's backend)."),
    pin_drift: bool | None = typer.Option(None, "--pin-drift/--no-pin-drift", help="A foot planted for long moves "
                                          "with the slow drift of the camera's root path instead of holding the spot "
                                          "where it landed (default: chosen for the 2D's backend)."),
    refine: bool = typer.Option(D.REFINE_PRIOR is not None, "--refine/--no-refine", help="Bend the blended pose "
                                "toward the keypoints within the span of its neighbours (the prior's weight: "
                                "chosen on validation performers)."),
    view_step_cost: float = number(D.VIEW_STEP_COST, "--view-step-cost", integer=False, lo=0, hi=1000,
                                   help="Track the pictorial structures' classified viewpoints through the video: "
                                   "the cost of a quarter turn between frames against the classifier's -log "
                                   "scores (0: each frame's own view; a front/back flip swaps left and right). "
                                   "Default: chosen on validation renders."),
    view_dwell: float = number(D.VIEW_DWELL_S, "--view-dwell", integer=False, lo=0, hi=10,
                               help="Seconds: the least time between two quarter turns of the tracked viewpoint "
                               "(at least one frame; a real turn is slower than the classifier's flicker). "
                               "Default: chosen on validation renders with --view-step-cost."),
    height: float | None = number(None, "--height", integer=False, lo=0.3, hi=3.0,
                                     help="The performer's standing height in metres, when known (with --unit-mm): "
                                     "the output is scaled to it (skeleton, root path and strides). A single camera "
                                     "cannot measure it; without it the performer has the library skeleton's size."),
    unit_mm: float | None = number(None, "--unit-mm", integer=False, lo=0, lo_open=True,
                                      help="Millimetres per length unit of the library clips, for --height (e.g. 10 "
                                      "for centimetres, 56.4 for CMU's BVH files)."),
    fps: float | None = number(None, "--fps", integer=False, lo=0, lo_open=True, hi=1000,
                                  help="Frame rate of the poses' frames when there is no VIDEO."),
    size: str | None = typer.Option(None, "--size", help="W,H: the video's size in pixels when there is no VIDEO."),
    jobs: int = jobs_option(-1, help="Parallel workers for the pose estimate and the library index (-1 = all cores)."),
    index_cache: Path | None = typer.Option(None, "--index-cache", help="Directory to keep the library index in: a "
                                            "later run on the same clips (same bytes) and settings reuses it instead "
                                            "of projecting the library again."),
) -> None:
    """The performer of a video as 3D motion (BVH): each frame's 2D pose matched against the mocap library
    projected at the frame's viewpoint, temporally coherent neighbours kept (Tautges' lazy neighbourhood
    graph) and blended, the root placed by a pinhole camera fit, planted feet locked."""
    from ..reconstruct.run import reconstruct_video

    if video is None and poses is None:
        raise InputError("reconstruct: give VIDEO, --poses, or both")
    if blend > k:
        raise InputError(f"--blend: must be at most --k ({k}), got {blend}")
    if estimate_focal and focal is not None:
        raise InputError("--estimate-focal: not with --focal (a known focal length)")
    if (height is None) != (unit_mm is None):
        raise InputError("--height and --unit-mm go together: the height in metres and the library's length unit "
                         "in millimetres (10 for centimetres, 56.4 for CMU's BVH files)")
    wh = None
    if size is not None:
        try:
            wh = tuple(int(v) for v in size.split(","))
        except ValueError:
            wh = ()
        if len(wh) != 2 or min(wh) < 1:
            raise InputError(f"--size: expected W,H (two integers >= 1), got {size!r}")
    if video is None and (fps is None or wh is None):
        raise InputError("reconstruct: without VIDEO, give --fps and --size (the poses' frame rate and image size)")
    reconstruct_video(video, library, out, poses=poses, backend=backend, model=model, frames=_frames(frames),
                      fps=fps, size=wh,
                      skeleton=skeleton, record=record, labels=labels, preview=preview, jobs=jobs, method=method,
                      k=k, n_blend=blend, window_s=window, smooth_frames=smooth, n_views=views,
                      refine_prior=(D.REFINE_PRIOR if D.REFINE_PRIOR is not None else 0.1) if refine else None, focal_px="auto" if estimate_focal else focal, elevation_deg=elevation,
                      foot_lock=foot_lock, contact_threshold=contact_threshold, contact_gap_s=contact_gap,
                      pin_drift=pin_drift, cache_dir=index_cache, view_step_cost=view_step_cost,
                      view_dwell_s=view_dwell, height=None if height is None else height * 1000.0 / unit_mm)


@evaluate_app.command("reconstruct")
def evaluate_reconstruct(
    dataset: Path = typer.Option(..., "--dataset", "-d", help="Demo dataset directory (renders with their true "
                                 "3D motion)."),
    library: list[Path] = typer.Option(..., "--library", "-l", help="Library clips or directories (repeatable)."),
    out: Path = typer.Option(Path("metrics/reconstruct.json"), "--out", "-o", help="Metrics JSON."),
    video: list[str] = typer.Option([], "--video", help="Video ids to reconstruct (repeatable; default: one "
                                    "performance of every test performer)."),
    poses_dir: list[Path] = typer.Option([], "--poses-dir", help="Directory of <video id>.poses.json (vidstyle "
                                         "pose): an estimated 2D source named by its backend; repeatable."),
    method: list[str] = typer.Option(["nn", "olng", "subsequence"], "--method", help="Methods to score "
                                     "(repeatable). " + _METHOD_HELP + " subsequence: Tautges' subsequence graph."),
    max_frames: int | None = number(None, "--max-frames", lo=1, hi=10**7, help="Score the first frames of "
                                       "each video only."),
    seed: int = typer.Option(0, "--seed", help="Seed of the split that names the test performers."),
    unit_mm: float | None = number(None, "--unit-mm", integer=False, lo=0, lo_open=True,
                                      help="Millimetres per mocap length unit (default: the dataset's)."),
    headline: Path | None = typer.Option(None, "--headline", help="Also merge reconstruct.* keys into this "
                                            "headline JSON."),
    animation: Path | None = typer.Option(None, "--animation", help="Also write a video (.mp4) of the first "
                                             "video's reconstruction against the truth, front and side."),
    jobs: int = jobs_option(-1, help="Parallel workers for the library index (-1 = all cores)."),
) -> None:
    """Root-relative / aligned / PA-MPJPE, acceleration error and foot skate of reconstructions of held-out
    renders against their true 3D motion, per 2D source (true 2D, each --poses-dir), method and skeleton
    (the library's, or the performer's own)."""
    from rich.console import Console
    from rich.table import Table

    from ..evaluation.reconstruct import evaluate
    from ..formats.metrics import RECONSTRUCT, write_metrics
    from ._evaluate import merge_headline

    metrics = evaluate(dataset, library, videos=video or None, poses_dirs=poses_dir, methods=method,
                       max_frames=max_frames, seed=seed, unit_mm=unit_mm, jobs=jobs,
                       animation=animation)
    write_metrics(out, metrics, kind=RECONSTRUCT)
    if headline is not None:
        merge_headline(headline, metrics["headline"])
    table = Table(title=f"Reconstruction of {len(metrics['videos'])} held-out videos "
                        f"({metrics['params']['library_frames']} indexed library frames)")
    for col in ("2D source", "method", "skeleton", "frames", "root-rel. MPJPE mm", "MPJPE mm", "PA-MPJPE mm",
                "accel. mm/f^2", "foot skate mm/f"):
        table.add_column(col)

    def f(x):
        return "-" if x is None else f"{x:.1f}"

    for r in metrics["runs"]:
        if r["data"] != "demo test performers":
            continue
        table.add_row(r["source"], r["method"], r["skeleton"], str(r["frames"]), f(r["mpjpe_root_relative_mm"]),
                      f(r["mpjpe_mm"]), f(r["pa_mpjpe_mm"]), f(r["acceleration_error_mm_per_frame2"]),
                      f(r["foot_skate_mm_per_frame"]))
    Console(width=150).print(table)
    log.info("wrote %s", out)
