"""``vidstyle demo``: procedural kickboxing performers and the embedded demo dataset."""

from __future__ import annotations

import logging
import time
from pathlib import Path

import typer

from ..errors import InputError
from ._numbers import jobs_option

log = logging.getLogger(__name__)

demo_app = typer.Typer(help="Procedural kickboxing performers and the demo dataset (video + mocap + labels).",
                       no_args_is_help=True)


def register(app: typer.Typer) -> None:
    app.add_typer(demo_app, name="demo")


# options both dataset commands take
_OVERWRITE = typer.Option(False, "--overwrite", help="Replace a non-empty --out (only once the new dataset is complete).")
_JOBS = jobs_option(-1, help="Parallel workers (-1 = all cores).")
_SCHEDULER = typer.Option(None, "--scheduler", help="Dask scheduler address (tcp://host:port) instead of local workers.")


def split_set_names(text: str) -> tuple[str, ...]:
    """``--split-sets``: a comma-separated subset of A, B, V, T (upper-cased, in that order, none repeated)."""
    names = [t.strip().upper() for t in text.split(",") if t.strip()]
    bad = [n for n in names if n not in ("A", "B", "V", "T")]
    if not names or bad:
        raise InputError(f"--split-sets: give sets among A, B, V, T, got {text!r}")
    return tuple(n for n in ("A", "B", "V", "T") if n in names)


def split_performers(n_performers: int, split_seed: int, sets: tuple[str, ...]) -> list[str]:
    """The performers (p00, ...) of ``sets`` of the recognition split of ``split_seed`` among ``n_performers``."""
    from ..recognition.splits import performer_groups

    groups = performer_groups([f"p{i:02d}" for i in range(n_performers)], split_seed)
    return sorted(p for s in sets for p in groups[s])


@demo_app.command("make-dataset")
def make_dataset_cmd(
    out: Path = typer.Option(..., "--out", "-o", help="Output directory (created; must be empty or absent)."),
    seed: int = typer.Option(0, "--seed", help="Everything is drawn from this seed (same seed, same files)."),
    performers: int = typer.Option(None, "--performers", help="Number of performers [10; --small: 4]."),
    views: str = typer.Option(None, "--views", help="Comma-separated views: front,left,right,back or azimuths "
                              "in degrees relative to the performer's facing [front,left,right; --small: front,left]."),
    single_seconds: float = typer.Option(None, "--single-seconds", help="Length of each single-action video "
                                         "[16; --small: 4]."),
    performances: int = typer.Option(None, "--performances", help="Performance takes per performer [2; --small: 1]."),
    performance_seconds: float = typer.Option(None, "--performance-seconds",
                                              help="Length of each performance [60; --small: 8]."),
    performance_views: str = typer.Option(None, "--performance-views", help="Views the performances are "
                                          "rendered in [same as --views]."),
    background: str = typer.Option(None, "--background", help="Video background: texture, texture:NAME "
                                   "(brick, grass, gravel, moon) or plain [texture: brick, grass or gravel]."),
    elevation: float = typer.Option(None, "--elevation", help="Camera elevation in degrees [10]."),
    only_performers: str = typer.Option(None, "--only-performers", help="Comma-separated performer ids "
                                        "(p00, ...): render only these [all]."),
    first_performer: int = typer.Option(None, "--first-performer", help="Render only performers from this number on "
                                        "(p<K> .. the last of --performers): performers no dataset of fewer "
                                        "performers holds, e.g. for `vocabulary / train-recognizer --more-performers`."),
    footwork: float = typer.Option(None, "--footwork", help="Punches with footwork, 0..1: the weight shifts, the lead "
                                   "foot steps in on the jab, the rear foot pivots, as real fighters move; each performer's "
                                   "amount is drawn up to this [0: the lower body stays in the guard while punching]."),
    unseen_camera: bool = typer.Option(False, "--unseen-camera", help="Test videos for `evaluate recognition "
                                       "--split unseen-camera`: views 30,150 at elevation 30 before the moon "
                                       "texture (none used by default datasets), one performance each."),
    split_seed: int = typer.Option(None, "--split-seed", help="Render only the performers of --split-sets of the "
                                   "recognition split of this seed (with --unseen-camera: its test performers)."),
    split_sets: str = typer.Option(None, "--split-sets", help="With --split-seed: comma-separated sets of the split "
                                   "whose performers are rendered: A (vocabulary), B (classifier), V (validation), T "
                                   "(test) [T]. B: more camera views for `train-recognizer --more-views`."),
    no_video: bool = typer.Option(False, "--no-video", help="Write mocap and labels only (no rendering; the manifest's video and truth paths then do not exist)."),
    small: bool = typer.Option(False, "--small", help="A small dataset for tests and CI (explicit options still apply)."),
    overwrite: bool = _OVERWRITE,
    jobs: int = _JOBS,
    scheduler: str = _SCHEDULER,
) -> None:
    """Generate the demo dataset: single-action videos (every performer x action x view) and long
    performances of each performer following their own action chain, each with per-frame labels,
    transition frames, the true chain, the ground-truth sidecar and the BVH it was rendered from.

    Layout: DIR/dataset.json, DIR/videos/<id>.mp4 (+ .truth.npz), DIR/labels/<id>.json,
    DIR/mocap/<take>.bvh (+ .labels.json). Deterministic in --seed.
    """
    from ..demo.dataset import DatasetParams, make_dataset, with_overrides

    base = DatasetParams.small(seed) if small else DatasetParams(seed=seed)
    view_list = None
    if views is not None:
        view_list = tuple(v.strip() for v in views.split(",") if v.strip())
    if background is not None:
        from ..render.background import parse_background

        try:
            parse_background(background)
        except ValueError as e:
            raise InputError(f"--background: {e}") from None
    if split_sets is not None and split_seed is None:
        raise InputError("--split-sets: give --split-seed too")
    if split_seed is not None and only_performers is not None:
        raise InputError("--split-seed: give it or --only-performers, not both")
    if first_performer is not None:
        if split_seed is not None or only_performers is not None:
            raise InputError("--first-performer: give it, --split-seed or --only-performers, not two of them")
        n = with_overrides(base, performers=performers).performers
        if not 0 <= first_performer < n:
            raise InputError(f"--first-performer: must be in 0..{n - 1} (--performers {n}), got {first_performer}")
        only_performers = ",".join(f"p{i:02d}" for i in range(first_performer, n))
    sets = split_set_names(split_sets) if split_sets is not None else ("T",)
    if unseen_camera:
        base = DatasetParams.unseen_camera(with_overrides(base, performers=performers),
                                           split_seed if sets == ("T",) else None)
    if split_seed is not None and not (unseen_camera and sets == ("T",)):
        only_performers = ",".join(split_performers(with_overrides(base, performers=performers).performers,
                                                    split_seed, sets))
    perf_views = None
    if performance_views is not None:
        perf_views = tuple(v.strip() for v in performance_views.split(",") if v.strip())
    params = with_overrides(base, performers=performers, views=view_list, single_seconds=single_seconds,
                            performances=performances, performance_seconds=performance_seconds,
                            performance_views=perf_views,
                            background=background, render=False if no_video else None, elevation_deg=elevation,
                            footwork=footwork,
                            only_performers=None if only_performers is None else
                            tuple(p.strip() for p in only_performers.split(",") if p.strip()))
    t0 = time.perf_counter()
    manifest = make_dataset(out, params, overwrite=overwrite, jobs=jobs, scheduler=scheduler)
    log.info("dataset %s ready in %.1f s", manifest, time.perf_counter() - t0)


@demo_app.command("performer")
def performer_cmd(
    out: Path = typer.Option(..., "--out", "-o", help="Output BVH (a .labels.json with per-frame labels is "
                             "written beside it)."),
    seed: int = typer.Option(0, "--seed", help="Seed of the dataset the performer belongs to."),
    index: int = typer.Option(0, "--performer", help="Performer number within that seed (p00 = 0)."),
    action: str = typer.Option(None, "--action", help="Repeat one action (Jab, Hook, Uppercut, Defense, LowKick, "
                               "RoundhouseKick); default: a performance following the performer's chain."),
    seconds: float = typer.Option(8.0, "--seconds", help="Length of the clip."),
    fps: int = typer.Option(60, "--fps", help="Mocap frame rate (a multiple of 20)."),
) -> None:
    """Write one procedural clip as BVH: a performer repeating an action, or performing their chain."""
    from ..demo.clip import write_performer_clip

    performer, take, labels_path = write_performer_clip(out, seed, index, action, seconds, fps)
    log.info("wrote %s (%d frames at %d fps, %s) and %s", out, take.motion.n_frames, fps,
             performer.style.lead, labels_path)


@demo_app.command("make-cmu-dataset")
def make_cmu_dataset_cmd(
    cmu: Path = typer.Option(..., "--cmu", help="CMU mocap directory with *.bvh and clips.csv "
                             "(e.g. ../shared/data/mocap/cmu)."),
    out: Path = typer.Option(..., "--out", "-o", help="Output directory (created; must be empty or absent)."),
    actions: str = typer.Option("walk,run,jump,punch,dance,basketball", "--actions",
                                help="Comma-separated classes: a CMU action (walk, run, jump, punch, dance, "
                                "basketball, climb, swordplay, or a keyword such as jog or dribble) or a merge "
                                "CLASS=ACTION+ACTION (e.g. walk,nonwalk=run+jump+punch+dance+basketball)."),
    views: str = typer.Option("front,left,right", "--views", help="Comma-separated views: front,left,right,back "
                              "or azimuths in degrees relative to the performer's facing."),
    segment_seconds: float = typer.Option(4.0, "--segment-seconds", help="Length of the windows cut from each clip."),
    min_seconds: float = typer.Option(1.0, "--min-seconds", help="A clip shorter than one window but at least this "
                                      "long gives one window of its own length; shorter clips are dropped."),
    max_per_subject: int = typer.Option(12, "--max-per-subject", help="At most this many windows per subject and "
                                        "CMU action (a seeded draw; 0 = all), so no subject dominates a class."),
    background: str = typer.Option("texture", "--background", help="Video background: texture or plain."),
    camera: str = typer.Option("fit", "--camera", help="fit: a static camera framing the whole window; follow: "
                               "remove the performer's horizontal drift (a panning camera), so walkers are not "
                               "drawn smaller than performers who stay on the spot."),
    subjects: str = typer.Option("", "--subjects", help="Comma-separated CMU subjects whose clips are used "
                                 "(e.g. 03); default: every subject."),
    seed: int = typer.Option(0, "--seed", help="Everything is drawn from this seed (same seed, same files)."),
    overwrite: bool = _OVERWRITE,
    jobs: int = _JOBS,
    scheduler: str = _SCHEDULER,
) -> None:
    """Render CMU mocap clips into a recognition dataset with the demo's layout and schema, one performer
    per CMU subject (so an unseen-performer split tests on unseen subjects).

    Each clip of the chosen actions loses its T-pose frame, is cut into --segment-seconds windows and
    rendered in every view with its subject's appearance. A class keeps the case it is given in
    (Step=walk makes walking windows of the demo's class Step, to train a demo recognizer on real walks).
    Logs clips, windows and subjects per class, and warns about classes recorded by fewer than 3
    subjects. Deterministic in --seed.
    """
    from ..demo.cmu import CMUParams, make_cmu_dataset, parse_actions

    view_list = tuple(v.strip() for v in views.split(",") if v.strip())
    params = CMUParams(seed=seed, classes=parse_actions(actions), views=view_list, segment_seconds=segment_seconds,
                       min_seconds=min_seconds, max_per_subject=max_per_subject, background=background,
                       camera=camera, subjects=tuple(x.strip().zfill(2) for x in subjects.split(",") if x.strip()))
    t0 = time.perf_counter()
    manifest = make_cmu_dataset(cmu, out, params, overwrite=overwrite, jobs=jobs, scheduler=scheduler)
    log.info("dataset %s ready in %.1f s", manifest, time.perf_counter() - t0)


@demo_app.command("make-crowd")
def make_crowd_cmd(
    out: Path = typer.Option(..., "--out", "-o", help="Directory to write (replaced whole when complete)."),
    people: int = typer.Option(2, "--people", help="Performers in the scene (sparring partners for 2)."),
    views: int = typer.Option(4, "--views", help="Calibrated cameras around them."),
    seconds: float = typer.Option(6.0, "--seconds", help="Length of the take."),
    width: int = typer.Option(320, "--width", help="Video width in pixels."),
    height: int = typer.Option(240, "--height", help="Video height in pixels."),
    seed: int = typer.Option(0, "--seed", help="Performers, motion and rendering are drawn from this seed."),
) -> None:
    """Several demo performers in one scene filmed by calibrated cameras, with everyone's true 2D pose:
    camNN.mp4, calibration.toml (OpenCV/Pose2Sim) and truth.npz (see vidstyle.demo.crowd)."""
    from ..demo.crowd import make_crowd
    from ..errors import ParameterError

    if not 1 <= people <= 6:
        raise ParameterError("people", f"must be in 1..6, got {people}")
    if not 2 <= views <= 16:
        raise ParameterError("views", f"must be in 2..16, got {views}")
    if not 0.5 <= seconds <= 600:
        raise ParameterError("seconds", f"must be in [0.5, 600], got {seconds}")
    if not (64 <= width <= 4096 and 64 <= height <= 4096):
        raise ParameterError("width", f"the video must be 64..4096 pixels a side, got {width} x {height}")
    path = make_crowd(out, people, views, seconds, size=(width, height), seed=seed)
    log.info("wrote %s (%d people, %d views)", path, people, views)
