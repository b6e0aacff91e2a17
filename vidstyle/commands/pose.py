"""``vidstyle train-pose``, ``vidstyle pose`` and ``vidstyle evaluate pose`` (2D pose, method 2)."""

from __future__ import annotations

import logging
import sys
from pathlib import Path

import typer

from ..pose.defaults import MAX_CONTEXT, PS_SCALES
from ._numbers import jobs_option, number

from ..errors import InputError
from ..pose.defaults import CMU_ENV, CNN_DEFAULTS, DEFAULTS, DETECTOR, REAL_ENV
from ._evaluate import evaluate_app

log = logging.getLogger(__name__)


def register(app: typer.Typer) -> None:
    app.command("train-pose")(train_pose)
    app.command("pose")(pose)


def parse_scales(text: str | None, option: str) -> list[float] | None:
    """``"1,1.2,1.4"`` -> zoom factors of multi-scale pose inference (None for none given); a bad list
    is an :class:`InputError` naming ``option``."""
    if text is None:
        return None
    from ..pose.estimator import check_scales

    try:
        zooms = [float(x) for x in text.split(",") if x.strip()]
        check_scales(zooms)
    except ValueError as exc:
        problem = str(exc) if "zoom" in str(exc) else "not a comma-separated list of numbers"
        raise InputError(f"{option}: {text!r}: {problem}") from None
    return zooms


def parse_range(text: str | None, option: str) -> tuple[float, float] | None:
    """``"LOW,HIGH"`` -> (low, high) (None for none given); anything else an :class:`InputError` naming
    ``option``."""
    if text is None:
        return None
    try:
        lo, hi = (float(x) for x in text.split(","))
    except ValueError:
        raise InputError(f"{option}: {text!r} is not LOW,HIGH") from None
    if not (lo <= hi):  # also refuses nan
        raise InputError(f"{option}: {text!r}: LOW must not exceed HIGH")
    return lo, hi


def _render_options(elevations: str | None, figure_scales: str | None) -> dict:
    from ..pose.data import ELEVATION_RANGE, SCALE_RANGE

    return {"elevation": parse_range(elevations, "--elevations") or ELEVATION_RANGE,
            "scale": parse_range(figure_scales, "--figure-scales") or SCALE_RANGE}


_ELEV_HELP = "Camera elevations LOW,HIGH in degrees (looking down), drawn uniformly per clip [default: 0,20]."
_SCALE_HELP = ("Figure heights LOW,HIGH relative to the nominal (0.7 of the frame), drawn per clip "
               "[default: 0.9,1.1].")
_PROP_HELP = ("Vary bone lengths: arms, legs and trunk each scaled by a factor uniform in 1 +- this (0 = the "
              "skeletons as recorded).")


def train_pose(
    out: Path = typer.Option(..., "--out", "-o", help="Pose model file to write (.joblib)."),
    cmu_dir: Path | None = typer.Option(None, "--cmu-dir", envvar=CMU_ENV, help="CMU BVH clips to render as well as "
                                        "the demo performers (none given: the demo performers only, as the log "
                                        "says; e.g. ../shared/data/mocap/cmu)."),
    demo_performers: int = typer.Option(CNN_DEFAULTS["demo_performers"], "--demo-performers",
                                        help="Demo performers rendered for training (at most 30: the training "
                                        "performers)."),
    cmu_clips: int = typer.Option(CNN_DEFAULTS["cmu_clips"], "--cmu-clips",
                                  help="CMU clips (of the training subjects) rendered."),
    views_per_clip: int = typer.Option(CNN_DEFAULTS["views_per_clip"], "--views-per-clip",
                                       help="Camera azimuths per clip."),
    seconds: float = typer.Option(2.0, "--seconds", help="Seconds of each clip rendered."),
    fps: float = typer.Option(4.0, "--fps", help="Rendered frames per second of clip."),
    n_orient: int = typer.Option(DEFAULTS["n_orient"], "--orientations", help="Part orientation bins."),
    hard_rounds: int = typer.Option(DEFAULTS["hard_rounds"], "--hard-rounds",
                                    help="Rounds of hard-negative mining (0 or 1)."),
    viewpoint: str = typer.Option(DEFAULTS["viewpoint"], "--viewpoint", help="Viewpoint classifier: svm (thesis: "
                                  "torso scores, one-vs-all + one-vs-one SVMs), logistic (every part's score), "
                                  "hog (linear SVM on a whole-person HOG) or combined (product of logistic and "
                                  "hog). All are trained; this one is used."),
    unary_weight: float | None = typer.Option(None, "--unary-weight", help="Weight of the part detectors against "
                                              f"the tree prior [default: {DEFAULTS['unary_weight']} (hog), "
                                              f"{CNN_DEFAULTS['unary_weight']} (cnn)]."),
    fg_weight: float = typer.Option(DEFAULTS["fg_weight"], "--fg-weight", help="Weight of the person prior on video "
                                    "input (foreground against the video's median background; 0 = off; hog only)."),
    detector: str = typer.Option(DETECTOR, "--detector", help="Part detectors: hog (HOG cells + linear templates, "
                                 "per viewpoint, with --viewpoint's classifier) or cnn (a convolutional network's "
                                 "keypoint heatmaps as the unary terms and its viewpoint head; needs PyTorch)."),
    epochs: int = typer.Option(CNN_DEFAULTS["epochs"], "--epochs", help="Training epochs of the cnn detector."),
    channels: int = typer.Option(CNN_DEFAULTS["channels"], "--channels", help="Width (feature channels) of the cnn "
                                 "detector's deeper layers; the network's time grows about with its square."),
    stride: int = typer.Option(CNN_DEFAULTS["stride"], "--heatmap-stride", help="Pixels per heatmap cell of "
                               "the cnn detector: 4 (the tree's grid) or 2 (an upsampling head; the tree "
                               "works on the maps pooled to 4 px, the refinement on the 2-px maps)."),
    flip_test: bool = typer.Option(CNN_DEFAULTS["flip_test"], "--flip-test/--no-flip-test", help="cnn detector: "
                                   "average the heatmaps and viewpoint of each frame and its mirror image (twice "
                                   "the network's time)."),
    refine: int = typer.Option(CNN_DEFAULTS["refine"], "--refine", help="cnn detector: radius (4-px cells) of the "
                               "keypoint refinement on the full-resolution heatmaps after the tree (0 = off)."),
    augment: str = typer.Option(CNN_DEFAULTS["augment"], "--augment", help="cnn detector's training augmentation: "
                                "flip (mirror images and colour jitter) or affine (also random scale 0.8-1.25, "
                                "rotation up to 20 degrees and shift)."),
    elevations: str | None = typer.Option(None, "--elevations", help=_ELEV_HELP),
    figure_scales: str | None = typer.Option(None, "--figure-scales", help=_SCALE_HELP),
    proportions: float = typer.Option(0.0, "--proportions", help=_PROP_HELP),
    seed: int = typer.Option(0, "--seed", help="Seed of rendering, negatives and classifiers."),
    jobs: int = jobs_option(-1, help="Parallel workers (-1 = all cores)."),
    scheduler: str | None = typer.Option(None, "--scheduler", help="Dask scheduler address (tcp://HOST:PORT)."),
) -> None:
    """Train the pictorial-structures pose model (viewpoint-specific + generic tree priors, part
    detectors, viewpoint classifier) on frames rendered from the demo performers and CMU clips."""
    from ..demo import pose_sources  # noqa: F401 - registers the demo performers as a training source
    from ..pose.estimator import save_model
    from ..pose.training import train

    model, training = train(cmu_dir, detector=detector, demo_performers=demo_performers, cmu_clips=cmu_clips,
                            views_per_clip=views_per_clip, seconds=seconds, fps=fps, seed=seed, jobs=jobs,
                            scheduler=scheduler, n_orient=n_orient, hard_rounds=hard_rounds, viewpoint=viewpoint,
                            unary_weight=unary_weight, fg_weight=fg_weight, epochs=epochs, channels=channels,
                            stride=stride, flip_test=flip_test, refine=refine, augment=augment,
                            proportions=proportions, **_render_options(elevations, figure_scales))
    save_model(out, model, {"training": training})
    log.info("wrote %s (%d training frames)", out, model.n_train_frames_)


def pose(
    videos: list[Path] = typer.Argument(..., metavar="VIDEO", help="Input video; several with --out-dir (one process for all: "
                                        "the backend's libraries are loaded once)."),
    out: Path | None = typer.Option(None, "--out", "-o", help="poses.json to write (one VIDEO)."),
    out_dir: Path | None = typer.Option(None, "--out-dir", help="Write <video stem>.poses.json here, one per "
                                        "VIDEO (each what a run with that video alone and --out writes)."),
    model: Path | None = typer.Option(None, "--model", "-m", help="Pose model (train-pose) of --backend ps "
                                      "[default: the model shipped with vidstyle, when it ships one]."),
    backend: str | None = typer.Option(None, "--backend", help="ps (pictorial structures) or blazepose (MediaPipe) "
                                       "[default: ps with --model, else blazepose]."),
    frames: str | None = typer.Option(None, "--frames", help="Comma-separated frame indices (default: all)."),
    annotations: Path | None = typer.Option(
        None, "--annotations", "-a", help="Annotations file (vidstyle annotate): the frames are this video's "
        "transition marks (the video must be the annotated one: same sha256); the performer chosen for it "
        "there (a frame and a pixel) is followed, unless --person or --no-track."),
    context: int = number(0, "--context", lo=0, hi=MAX_CONTEXT, help="With --annotations: also the frames up to this many "
                           "either side of every mark (AugMG's temporal coherence matches them too; less than the "
                           "video's frame count)."),
    scales: str | None = typer.Option(None, "--scales", help="ps backend: comma-separated zoom factors of "
                                      "multi-scale inference, e.g. 1,1.2,1.4 (each frame is also zoomed about the "
                                      "person by each factor and the most confident pose kept; for people smaller "
                                      "or larger than the training figures; time grows with their number). Default: "
                                      + ",".join(f"{z:g}" for z in PS_SCALES) + ", chosen on validation renders "
                                      "(validation/pose_scales.json)."),
    track: bool | None = typer.Option(None, "--track/--no-track", help="Follow one performer through the video "
                                      "(other people are ignored; frames without the performer get no pose) "
                                      "[default: on for blazepose without --annotations; with --annotations, on "
                                      "when a performer is chosen (--person, or in the file)]."),
    person: str | None = typer.Option(None, "--person", help="X,Y: follow the person at this pixel of the first "
                                      "frame with people (default: the performer chosen in --annotations, else "
                                      "the most prominent, i.e. largest and clearest)."),
    smooth: bool = typer.Option(False, "--smooth", help="One-Euro filter the keypoint tracks (jitter)."),
    overlay: Path | None = typer.Option(None, "--overlay", help="Also write every frame with its keypoints drawn "
                                        "(DIR/<frame>.jpg), to check the poses by eye."),
    jobs: int = jobs_option(-1, help="Parallel workers (-1 = all cores)."),
    scheduler: str | None = typer.Option(None, "--scheduler", help="Dask scheduler address (tcp://HOST:PORT)."),
) -> None:
    """2D pose (15 keypoints) and viewpoint of chosen frames of a video -> poses.json (x = column,
    y = row in the input video's pixels, as a player shows the video); several videos -> one poses.json
    each in --out-dir."""
    import contextlib

    from ..fileio import check_writable, output_dir, outputs_by_stem
    from ..formats.poses import write_poses
    from ..pose.run import (
        check_estimate_params,
        default_backend,
        estimate_marks,
        estimate_video,
        parse_frames,
        parse_person,
    )
    from ..video import VideoReader

    if annotations is not None and frames is not None:
        raise InputError("--frames: not used with --annotations (the marks give the frames)")
    if (out is None) == (out_dir is None):
        raise InputError("pose: give --out (one VIDEO) or --out-dir")
    if out is not None and len(videos) > 1:
        raise InputError("pose: several videos need --out-dir")
    if overlay is not None and len(videos) > 1:
        raise InputError("--overlay: one video only")
    if out is not None:
        check_writable(out)
        dests = [out]
    else:
        dests = outputs_by_stem(videos, out_dir, ".poses.json")
        for v in videos:
            if not Path(v).is_file():
                raise InputError(f"{v}: file not found")
    backend = default_backend(model) if backend is None else backend
    zooms = parse_scales(scales, "--scales")
    check_estimate_params(backend, model, zooms)
    who = parse_person(person)
    # every video first, written afterwards: a failing video leaves no partial set of outputs
    done = []
    for video in videos:
        if annotations is not None:
            poses = estimate_marks(video, annotations, backend, model, context, jobs=jobs, scheduler=scheduler,
                                   scales=zooms, track=True if who is not None else track, person=who)
        else:
            with VideoReader(video) as r:
                idx = parse_frames(frames, len(r))
            poses = estimate_video(video, backend, model, idx, jobs=jobs, scheduler=scheduler, scales=zooms,
                                   track=track if who is None else True, person=who, smooth=smooth)
        done.append(poses)
    with output_dir(out_dir, dests) if out_dir is not None else contextlib.nullcontext():
        for dest, poses in zip(dests, done):
            write_poses(dest, poses)
            missing = sum(not f.found for f in poses.frames)
            log.info("wrote %s (%d frames, backend %s%s)", dest, len(poses.frames), backend,
                     f"; {missing} without the performer" if missing else "")
    if overlay is not None:
        from ..pose.overlay import write_overlays

        log.info("wrote %d overlay frames to %s", write_overlays(videos[0], done[0], overlay), overlay)


@evaluate_app.command("pose")
def evaluate_pose(
    views: list[Path] | None = typer.Argument(None, help="With --calibration: poses.json of each synchronised "
                                              "view (matched to cameras by name in the file name, else in the "
                                              "calibration's order)."),
    calibration: Path | None = typer.Option(None, "--calibration", help="Score VIEWS without labels by "
                                            "leave-one-view-out consistency: a Qualisys .qca.txt or "
                                            "OpenCV/Pose2Sim .toml calibration of the views."),
    model: Path | None = typer.Option(None, "--model", "-m", help="Pose model (train-pose; default: the shipped one): score it on held-out "
                                      "renders (without --calibration)."),
    out: Path | None = typer.Option(None, "--out", "-o", help="Metrics JSON to write."),
    cmu_dir: Path | None = typer.Option(None, "--cmu-dir", envvar=CMU_ENV,
                                        help="CMU BVH clips (held-out subjects are rendered; none: demo only)."),
    demo_performers: int = typer.Option(3, "--demo-performers", help="Held-out demo performers rendered."),
    cmu_clips: int = typer.Option(6, "--cmu-clips", help="Held-out CMU clips rendered."),
    views_per_clip: int = typer.Option(4, "--views-per-clip", help="Held-out azimuths per clip."),
    seconds: float = typer.Option(2.0, "--seconds", help="Seconds of each clip rendered."),
    fps: float = typer.Option(4.0, "--fps", help="Rendered frames per second of clip."),
    real_dir: Path | None = typer.Option(None, "--real-dir", envvar=REAL_ENV, help="Real footage to compare the "
                                         "backends on (e.g. ../shared/data/video/real; none given or 'none': skipped, "
                                         "as the log says)."),
    overlay_dir: Path = typer.Option(Path("pose_overlays"), "--overlay-dir", help="Where overlay PNGs go."),
    real_frames: int = typer.Option(6, "--real-frames", help="Frames per real video."),
    other_dir: Path | None = typer.Option(None, "--other-dir", help="BVH clips of another skeleton or subjects "
                                          "the model never saw (e.g. ../shared/data/mocap/bandai), rendered as "
                                          "well and scored as their own group."),
    other_clips: int = typer.Option(6, "--other-clips", help="Clips of --other-dir rendered (chosen by --seed)."),
    elevations: str | None = typer.Option(None, "--elevations", help=_ELEV_HELP),
    figure_scales: str | None = typer.Option(None, "--figure-scales", help=_SCALE_HELP),
    proportions: float = typer.Option(0.0, "--proportions", help=_PROP_HELP),
    seed: int = typer.Option(0, "--seed", help="Seed of the held-out renders."),
    jobs: int = jobs_option(-1, help="Parallel workers for rendering (-1 = all cores)."),
) -> None:
    """Strict PCP per part (Table 5 layout), PCK@0.2 and viewpoint confusion (Table 6 layout) on
    held-out renders for both backends; backend agreement and overlays on real footage. With
    --calibration: real accuracy without labels, from synchronised calibrated views (median error and
    PCK@0.1/0.2 of each view against the others' triangulation, per view and keypoint)."""
    if calibration is not None:
        from ..evaluation.multiview import evaluate_views, format_table
        from ..formats.metrics import MULTIVIEW_POSE, write_metrics

        if model is not None:
            raise InputError("--model: not used with --calibration (give the views' poses files)")
        metrics = evaluate_views(calibration, views or [])
        if out is not None:
            write_metrics(out, {"seed": seed, **metrics}, kind=MULTIVIEW_POSE)
        sys.stdout.write(format_table(metrics) + "\n")
        return
    if views:
        raise InputError("VIEWS: poses files are scored with --calibration")
    from ..demo import pose_sources  # noqa: F401 - registers the demo performers as a training source
    from ..evaluation.pose import evaluate, format_tables
    from ..formats.metrics import POSE, write_metrics

    from ..pose.run import resolve_model

    model = resolve_model("ps", model)
    metrics = evaluate(model, cmu_dir, demo_performers, cmu_clips, views_per_clip, seconds, fps, real_dir, overlay_dir,
                       real_frames, seed, jobs, other_dir=other_dir, other_clips=other_clips, proportions=proportions,
                       **_render_options(elevations, figure_scales))
    if out is not None:
        write_metrics(out, {"seed": seed, **metrics}, kind=POSE)
    sys.stdout.write(format_tables(metrics) + "\n")


@evaluate_app.command("people")
def evaluate_people(
    crowd: Path = typer.Argument(..., help="A take of several people (vidstyle demo make-crowd)."),
    out: Path | None = typer.Option(None, "--out", "-o", help="Metrics JSON to write."),
    backend: str = typer.Option("blazepose", "--backend", help="Pose backend (blazepose, or ps with --model)."),
    model: Path | None = typer.Option(None, "--model", "-m", help="Pose model (train-pose) for --backend ps "
                                      "[default: the shipped one]."),
) -> None:
    """Following one performer among several people: identity switches per 100 frames and PCK@0.2 against
    the person chosen first, per view, with the backend alone (naive) and followed (tracked)."""
    from ..evaluation.people import evaluate_crowd, format_table
    from ..formats.metrics import PEOPLE, write_metrics
    from ..pose.run import check_estimate_params

    check_estimate_params(backend, model, None)
    metrics = evaluate_crowd(crowd, backend, None if model is None else str(model))
    metrics["params"] = {"crowd": str(crowd), "backend": backend, "model": None if model is None else str(model)}
    if out is not None:
        write_metrics(out, {"seed": 0, **metrics}, kind=PEOPLE)
    sys.stdout.write(format_table(metrics) + "\n")
