"""``vidstyle evaluate real-motion``: real mocap clips rendered at unseen cameras through the recognizers,
scored by action family (:mod:`vidstyle.evaluation.realmotion`)."""

from __future__ import annotations

import logging
from pathlib import Path

import typer

from ._evaluate import evaluate_app

log = logging.getLogger(__name__)


def register(app: typer.Typer) -> None:  # the command lives in the shared evaluate group
    pass


@evaluate_app.command("real-motion")
def evaluate_real_motion_cmd(
    clips: Path = typer.Option(..., "--clips", help="Clip list CSV: file,family[,frames[,start,end]] (family "
                               "punch | kick | other; frames all | strikes; paths relative to the CSV), e.g. "
                               "pipelines/kickboxing/realmotion_test.csv."),
    model: Path = typer.Option(None, "--model", "-m", help="3D SIFT recognizer (recognizer.joblib)."),
    pose_model: Path = typer.Option(None, "--pose-model", help="Pose-sequence recognizer (train-recognizer "
                                    "--features pose)."),
    fusion_weight: float = typer.Option(None, "--fusion-weight", help="Also their late fusion, this weight on "
                                        "the pose recognizer's scores (0..1)."),
    fusion_emission_weight: float = typer.Option(None, "--fusion-emission-weight", help="The fused scores' power "
                                                 "in the pose recognizer's smoother (default: the validated one, as "
                                                 "vidstyle recognize)."),
    pose_input: str = typer.Option("ps", "--pose-input", help="The pose recognizer's input: ps or blazepose (that "
                                   "pose backend on each render) or true (the clip's keypoints projected)."),
    cameras: str = typer.Option(None, "--cameras", help="AZIMUTH:ELEVATION:BACKGROUND, comma-separated (default: "
                                "cameras no demo training video uses: 30:30:texture:moon, 150:30:texture:moon, "
                                "-45:20:texture)."),
    seed: int = typer.Option(0, "--seed", help="Seed of the looks and the sensor noise."),
    work_dir: Path = typer.Option(None, "--work-dir", help="Keep the renders, features and poses here."),
    out: Path = typer.Option(..., "--out", "-o", help="Metrics JSON (kind vidstyle.metrics.real_motion)."),
) -> None:
    """Real motion the demo never showed, filmed from cameras it never used: is a real punch a punch, and
    real footwork neither punch nor kick? Renders every clip of CLIPS from every camera with a random
    look, runs each recognizer given (and their fusion) on the render, and scores the frames by action
    family. Prints a Markdown table."""
    from ..errors import InputError, ParameterError
    from ..evaluation.realmocap import StrikeEvalParams, parse_cameras
    from ..evaluation.realmotion import (
        TEST_CAMERAS,
        Recognizers,
        evaluate_real_motion,
        read_clip_list,
        real_motion_table,
    )
    from ..fileio import check_writable
    from ..formats.metrics import REAL_MOTION, write_metrics
    from ..recognition.recognizer import load_model

    check_writable(out)
    try:
        cams = TEST_CAMERAS if cameras is None else parse_cameras(cameras)
        params = StrikeEvalParams(pose_input=pose_input)
        recs = Recognizers()
        if fusion_weight is not None:
            recs.fusion_weight = fusion_weight
        recs.fusion_emission_weight = fusion_emission_weight
        for path, slot in ((model, "sift"), (pose_model, "pose")):
            if path is not None:
                m, _ = load_model(path)
                m.n_jobs = 1
                is_pose = m.__class__.__name__ == "PoseRecognizer"
                if is_pose != (slot == "pose"):
                    raise InputError(f"{path}: a {'pose-sequence' if is_pose else '3D SIFT'} recognizer given as "
                                     f"{'--pose-model' if slot == 'pose' else '--model'}")
                setattr(recs, slot, m)
        recs.check()
    except ParameterError as e:
        raise InputError(f"--{e.param.replace('_', '-')}: {e.problem}") from None
    doc = evaluate_real_motion(read_clip_list(clips), recs, cams, params, seed=seed, work_dir=work_dir)
    doc["command"] = "vidstyle evaluate real-motion"
    doc["models"] = {"sift": str(model) if model else None, "pose": str(pose_model) if pose_model else None}
    write_metrics(out, doc, kind=REAL_MOTION)
    typer.echo(real_motion_table(doc))
    log.info("wrote %s", out)
