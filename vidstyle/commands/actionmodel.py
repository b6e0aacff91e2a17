"""Statistical action models (Du 2014, Motion Graphs++): ``fit-actions`` and ``sample-action``.

    vidstyle fit-actions clips.csv --out model.npz --variance 0.95 --seed 0
    vidstyle fit-actions mocap/p00_*.bvh --out p00.npz        # labels from <stem>.labels.json beside each
    vidstyle sample-action model.npz --label Jab -n 5 --seed 0 --out-dir samples/
    vidstyle evaluate action-style --dataset out/dataset --poses-dir P --labels-dir R --out-dir D --out m.json
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import List

import typer

from ..actionmodel import defaults as D
from ..errors import InputError, ParameterError
from ._evaluate import evaluate_app
from ._numbers import jobs_option

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


@evaluate_app.command("action-style")
def evaluate_action_style(
    dataset: Path = typer.Option(..., "--dataset", help="Demo dataset directory (vidstyle demo make-dataset: mocap, truth, labels)."),
    seed: int = typer.Option(0, "--seed", help="Split seed: the unseen-performer groups (training A+B, test) it names."),
    poses_dir: Path | None = typer.Option(None, "--poses-dir", help="<video id>.poses.json of the pose stage: the "
                                          "'estimated' input (the frames they cover), with --labels-dir."),
    labels_dir: Path | None = typer.Option(None, "--labels-dir", help="Recognised labels <video id>.json (vidstyle recognize) for the estimated input."),
    inputs: str = typer.Option("", "--inputs", help="Comma-separated: true (true 2D of every video, true labels), "
                               "estimated (--poses-dir with --labels-dir). Default: true, and estimated with --poses-dir."),
    style_dir: Path | None = typer.Option(None, "--style-dir", help="learn-style's <performer>.json: with --out-dir, "
                                          "each test performer's style is written there with its action-level part."),
    out_dir: Path | None = typer.Option(None, "--out-dir", help="Writes actions.npz (the orthodox model of the training "
                                        "performers), <label>.png (true, fitted and unfitted instance per test "
                                        "performer) and, with --style-dir, <performer>.json."),
    label: str = typer.Option("Jab", "--label", help="The action the figure shows."),
    out: Path = typer.Option(Path("metrics/action_style.json"), "--out", "-o", help="Metrics JSON (vidstyle.metrics.action_style)."),
    jobs: int = jobs_option(-1, help="Workers for the fits, one (performer, input, action) each (-1 = all cores; the "
                            "results do not depend on it)."),
) -> None:
    """A performer's action-level style fitted from 2D (lead, guard, stance, tempo, the action model's
    coefficients) on a split's test performers, against their truth: lead accuracy, correlations and the
    generated actions' MPJPE against the unfitted model's."""
    import contextlib

    from ..evaluation.actionstyle import SPLIT_INPUTS, evaluate_split, figure_png
    from ..fileio import atomic_path, check_writable, output_dir
    from ..formats.metrics import ACTION_STYLE, write_metrics

    kinds = [k.strip() for k in inputs.split(",") if k.strip()] or ["true", *(["estimated"] if poses_dir else [])]
    bad = [k for k in kinds if k not in SPLIT_INPUTS]
    if bad or not kinds:
        raise InputError(f"--inputs: {', '.join(bad) or 'none given'}: expected some of {', '.join(SPLIT_INPUTS)}")
    if "estimated" in kinds and (poses_dir is None or labels_dir is None):
        raise InputError("--inputs estimated needs --poses-dir and --labels-dir")
    if style_dir is not None and out_dir is None:
        raise InputError("--style-dir goes with --out-dir (where the styles are written)")
    if not (Path(dataset) / "dataset.json").is_file():
        raise InputError(f"{dataset}: not a demo dataset (no dataset.json)")
    check_writable(out)
    styles_in = {}
    res = evaluate_split(dataset, seed, poses_dir, labels_dir, kinds, jobs, label)
    doc = res["doc"]
    # the style files carry what the run's video gives (the pose stage's 2D) when that input ran
    style_kind = "estimated" if res["styles"].get("estimated") else doc["action_style"]["input"]
    doc["styles_input"] = style_kind
    if style_dir is not None:  # read every style before writing anything
        from ..style import Style

        for p in res["styles"][style_kind]:
            f = Path(style_dir) / f"{p}.json"
            if not f.is_file():
                raise InputError(f"{f}: style file not found (--style-dir)")
            styles_in[p] = Style.load(f)
    doc["command"] = (f"vidstyle evaluate action-style --dataset {dataset} --seed {seed} --inputs {','.join(kinds)}"
                      + (f" --poses-dir {poses_dir} --labels-dir {labels_dir}" if "estimated" in kinds else ""))
    into = output_dir(out_dir, ["actions.npz", f"{label}.png", *(f"{p}.json" for p in styles_in)]) \
        if out_dir is not None else contextlib.nullcontext()
    with into:
        if out_dir is not None:
            model_path = Path(out_dir) / "actions.npz"
            res["model"].save(model_path)
            if res["figure"]:
                png = figure_png(res["figure"], label, f"{label} of split {seed}'s test performers "
                                 f"({res['figure_input']} 2D): true, fitted, unfitted")
                with atomic_path(Path(out_dir) / f"{label}.png") as tmp:
                    tmp.write_bytes(png)
            for p, st in styles_in.items():
                ast = res["styles"][style_kind][p]
                ast.model = str(model_path)
                st.action_style = ast
                st.save(Path(out_dir) / f"{p}.json")
        write_metrics(out, doc, kind=ACTION_STYLE)
    for kind, s in doc["by_input"].items():
        typer.echo(f"{kind:10s} performers {s['performers']}  lead accuracy {s.get('lead_accuracy', 0):.3f}  "
                   f"guard r {_fmt(s.get('guard_height_r'))}  stance r {_fmt(s.get('stance_width_r'))}  "
                   f"MPJPE fitted {_fmt(s.get('fitted_mean_mm'), 1)} mm, unfitted {_fmt(s.get('unfitted_mean_mm'), 1)} mm "
                   f"(with the true lead {_fmt(s.get('unfitted_mean_true_lead_mm'), 1)}), reduction "
                   f"{_fmt(s.get('mpjpe_reduction'))}")
    log.info("wrote %s", out)


def _fmt(x, d: int = 3) -> str:
    return "-" if x is None else f"{x:.{d}f}"
