"""Statistical action models (Du 2014, Motion Graphs++): ``fit-actions`` and ``sample-action``.

    vidstyle fit-actions clips.csv --out model.npz --variance 0.95 --seed 0
    vidstyle fit-actions mocap/p00_*.bvh --out p00.npz        # labels from <stem>.labels.json beside each
    vidstyle sample-action model.npz --label Jab -n 5 --seed 0 --out-dir samples/
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import List

import typer

from ..actionmodel import defaults as D
from ..errors import InputError, ParameterError

log = logging.getLogger(__name__)


def register(app: typer.Typer) -> None:
    app.command("fit-actions")(fit_actions)
    app.command("sample-action")(sample_action)


def fit_actions(
    clips: List[Path] = typer.Argument(..., help="Label CSVs file,label[,start,end] (file: a BVH, relative to the CSV), or BVH files / directories (labels from <stem>.labels.json beside each, or --labels)."),
    out: Path = typer.Option(..., "--out", "-o", help="Model file (.npz)."),
    labels: List[Path] = typer.Option([], "--labels", "-l", help="More label files for BVH arguments (demo .labels.json, CMU clips.csv, CSV file,label[,start,end]). Repeatable."),
    variance: float = typer.Option(D.VARIANCE, "--variance", help="Fraction of variance each functional PCA keeps, in (0, 1]."),
    seed: int = typer.Option(D.RANDOM_STATE, "--seed", help="Seed of the medoid candidates and the GMM fits."),
    max_components: int = typer.Option(D.MAX_COMPONENTS, "--max-components", help="Most GMM components tried (the number is chosen by BIC)."),
    slope_limit: int = typer.Option(D.SLOPE_LIMIT, "--slope-limit", help="DTW: most consecutive horizontal or vertical steps."),
    only: str = typer.Option("", "--only", help="Comma-separated labels to model (default: every action label)."),
    mirror: str = typer.Option("", "--mirror", help="Comma-separated performers (clip-name prefix pXX_) whose clips are "
                               "mirrored left/right before fitting: the southpaws, for the orthodox model that "
                               "learn-style --poses-dir fits (docs/actionmodel.md)."),
) -> None:
    """Learn one statistical model per action label (DTW to the medoid, functional PCA, GMM by BIC) from labelled mocap clips."""
    from ..actionmodel import ActionModel, load_labelled

    if not 0 < variance <= 1:
        raise ParameterError("--variance", f"must be in (0, 1], got {variance}")
    if out.suffix.lower() != ".npz":
        raise InputError(f"{out}: the model file must end in .npz")
    wanted = tuple(x.strip() for x in only.split(",") if x.strip()) or None
    model = ActionModel(variance=variance, random_state=seed, max_components=max_components,
                        slope_limit=slope_limit, labels=wanted)
    try:
        model.check_params()
    except ParameterError as e:
        raise ParameterError("--" + e.param.replace("_", "-"), e.problem) from None
    loaded = load_labelled(clips, labels)
    south = {x.strip() for x in mirror.split(",") if x.strip()}
    if south:
        from ..actionmodel.stylefit import orthodox_clips

        loaded = orthodox_clips(loaded, south)
    model.fit(loaded)
    model.save(out)
    for label in model.labels_:
        lm = model.models_[label]
        log.info("%s: %d instances (%d of another contact signature), %d primitive(s), %d+%d coefficients, "
                 "%d GMM component(s), %.2f s", label, lm.n_instances, lm.n_other_signature, len(lm.keyframes),
                 lm.n_spatial, lm.n_temporal, lm.n_components, lm.fit_seconds)
    log.info("wrote %s: %d action models", out, len(model.labels_))


def sample_action(
    model_path: Path = typer.Argument(..., help="Model file from fit-actions."),
    label: str = typer.Option(..., "--label", help="The action to sample."),
    n: int = typer.Option(1, "-n", "--n", help="Number of instances."),
    seed: int = typer.Option(0, "--seed", help="Seed of the draws."),
    out_dir: Path = typer.Option(..., "--out-dir", "-o", help="Directory for <label>_<k>.bvh and <label>_<k>.labels.json."),
    pin: bool = typer.Option(True, "--pin/--no-pin", help="Hold planted feet on the floor (leg IK)."),
    style: Path = typer.Option(None, "--style", help="A style.json with an action-level part (learn-style "
                               "--poses-dir): draw this performer's way of doing the action (instance 0 their mean, "
                               "others from the spread of their fitted segments; a southpaw stays southpaw)."),
) -> None:
    """Draw new instances of an action from a fitted model; write them as BVH on the source skeleton, with per-frame labels."""
    from ..actionmodel import ActionModel
    from ..formats.labels import write_labels
    from ..mocap import write_bvh

    if n < 1:
        raise ParameterError("-n", f"must be >= 1, got {n}")
    model = ActionModel.load(model_path)
    if label not in model.labels_:
        raise ParameterError("--label", f"no model for {label!r} in {model_path} (labels: {', '.join(model.labels_)})")
    if out_dir.exists() and not out_dir.is_dir():
        raise InputError(f"{out_dir}: not a directory")
    if style is not None:
        from ..style.artifact import Style

        ast = Style.load(style).action_style
        if ast is None:
            raise InputError(f"{style}: no action-level style (learn it with learn-style --poses-dir --action-model)")
        ast.check_model(model, style)
        if label not in ast.coefficients:
            raise ParameterError("--label", f"{style} has no fitted {label!r} (fitted: {', '.join(sorted(ast.coefficients))})")
        motions = [ast.realise(model, label, sample=k > 0, random_state=[seed, k], pin=pin) for k in range(n)]
    else:
        motions = model.sample(label, n, random_state=seed, pin=pin)
    for k, m in enumerate(motions):
        bvh = out_dir / f"{label}_{k:03d}.bvh"
        write_bvh(m, bvh)
        write_labels(bvh.with_name(bvh.stem + ".labels.json"),
                     {"bvh": bvh.name, "fps": m.fps, "classes": [label], "labels": [label] * m.n_frames,
                      "model": str(model_path), "seed": seed, "index": k})
    log.info("wrote %d %s instance(s) to %s", len(motions), label, out_dir)
