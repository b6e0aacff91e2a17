"""``vidstyle evaluate strikes``: real mocap of punches, filmed from several cameras, through a trained
recognizer (:mod:`vidstyle.evaluation.realmocap`)."""

from __future__ import annotations

import logging
from pathlib import Path

import typer

from ._evaluate import evaluate_app

log = logging.getLogger(__name__)

_DEFAULT_CAMERAS = "0:10:texture,90:10:texture,-90:10:texture,30:30:texture:moon,150:30:texture:moon,-45:20:texture"


def register(app: typer.Typer) -> None:  # the command lives in the shared evaluate group
    pass


@evaluate_app.command("strikes")
def evaluate_strikes_cmd(
    bvh: Path = typer.Option(..., "--bvh", help="Real mocap of strikes on the CMU 31-joint skeleton (e.g. "
                             "../shared/data/mocap/cmu/02_05.bvh, CMU 'punch/strike')."),
    model: Path = typer.Option(..., "--model", "-m", help="Trained recognizer (recognizer.joblib); used as given."),
    out: Path = typer.Option(..., "--out", "-o", help="Metrics JSON (kind vidstyle.metrics.strikes)."),
    cameras: str = typer.Option(
        _DEFAULT_CAMERAS, "--cameras",
        help="Cameras as AZIMUTH:ELEVATION:BACKGROUND, comma-separated (azimuth relative to the performer's "
        "median facing, 0 front, +90 their left; background 'texture', 'texture:moon', 'plain', ...). Default: "
        "the demo's training cameras, the unseen-camera dataset's and an oblique one.",
    ),
    seed: int = typer.Option(0, "--seed", help="Seed of the looks (clothes, build) and the sensor noise."),
    start: int = typer.Option(1, "--start", help="First motion frame (frame 0 of a CMU file is a T-pose)."),
    stop: int = typer.Option(0, "--stop", help="Motion frame after the last (0: the end of the clip)."),
    extension_min: float = typer.Option(0.8, "--extension-min", help="Action-frame rule: hand-shoulder distance "
                                        "in arm lengths at least this."),
    reach_min: float = typer.Option(0.6, "--reach-min", help="Action-frame rule: hand in front of the shoulder "
                                    "along the pelvis' facing, in arm lengths, at least this."),
    variant: str = typer.Option(None, "--variant", help="Descriptor of the recognizer's features (as `vidstyle "
                                "features --variant`; default: the one MODEL was trained on)."),
    points: int = typer.Option(None, "--points", help="Salient points per frame (as `vidstyle features --points`; "
                               "default: the count MODEL's features were extracted with)."),
    work_dir: Path = typer.Option(None, "--work-dir", help="Keep the rendered videos and their features here "
                                  "(default: a temporary directory, removed)."),
    actions_out: Path = typer.Option(None, "--actions-out", help="Also write the action frames as a labels "
                                     "JSON (vidstyle.labels, one label Rest/Strike per motion frame)."),
    plot: Path = typer.Option(None, "--plot", help="Also write a PNG of the action-frame rule's signals."),
    actions: Path = typer.Option(None, "--actions", help="Take the action frames from this labels JSON "
                                 "(vidstyle.labels, one label per frame of the whole BVH, e.g. a demo take's "
                                 "mocap/<take>.labels.json) instead of the rule."),
    pose_input: str = typer.Option("ps", "--pose-input", help="A pose-sequence recognizer's input (MODEL trained "
                                   "with --features pose): ps or blazepose (that pose backend on each rendered "
                                   "video), or true (the clip's keypoints projected through the camera: the upper "
                                   "bound)."),
    action_labels: str = typer.Option("Strike,Jab,Hook,Uppercut", "--action-labels",
                                      help="With --actions: the labels that mark action frames, comma-separated."),
) -> None:
    """Real mocap of punches, filmed from several cameras, through a recognizer: punches or kicks?

    Renders BVH from several cameras with the demo's renderer, looks and backgrounds, runs MODEL on each
    video, and reports how many of the clip's action frames come out as
    punches (Jab, Hook, Uppercut) rather than kicks (LowKick, RoundhouseKick). Action frames come from
    the mocap alone (an arm extended and reaching forward; vidstyle.evaluation.realmocap), never from
    the recognizer; the clip trains, tunes and selects nothing. Prints a Markdown table."""
    from ..errors import InputError, ParameterError
    from ..evaluation.realmocap import (
        StrikeEvalParams,
        StrikeRule,
        action_frames,
        action_labels_document,
        evaluate_strikes,
        parse_cameras,
        plot_action_frames,
        strikes_table,
    )
    from ..formats.labels import write_labels
    from ..formats.metrics import STRIKES, write_metrics
    from ..mocap import read_bvh

    try:
        cams = parse_cameras(cameras)
        rule = StrikeRule(extension_min=extension_min, reach_min=reach_min).validate()
        params = StrikeEvalParams.for_model(model, variant=variant, points=points, start=start, stop=stop or None,
                                            pose_input=pose_input)
    except ParameterError as e:
        raise InputError(f"--{e.param.replace('_', '-')}: {e.problem}") from None
    if stop < 0:
        raise InputError(f"--stop: must be 0 (the end) or above --start, got {stop}")
    labels_list = [x.strip() for x in action_labels.split(",") if x.strip()]
    if actions is not None and not labels_list:
        raise InputError("--action-labels: give at least one label")
    doc = evaluate_strikes(bvh, model, cams, rule, params, seed=seed, work_dir=work_dir, actions=actions,
                           action_labels=labels_list)
    doc["command"] = "vidstyle evaluate strikes"
    write_metrics(out, doc, kind=STRIKES)
    if (actions_out is not None or plot is not None) and actions is None:
        motion = read_bvh(bvh)[start:(stop or None)]
        mask = action_frames(motion, rule)
        if actions_out is not None:
            labels = action_labels_document(mask, motion.fps, bvh.name, rule)
            labels["frame_offset"] = start
            write_labels(actions_out, labels)
        if plot is not None:
            plot_action_frames(motion, mask, rule, plot,
                               title=f"{bvh.name} (from frame {start}): {int(mask.sum())} of {len(mask)} "
                               f"frames are action frames")
    typer.echo(strikes_table(doc))
    log.info("wrote %s", out)
