"""``vidstyle vocabulary``, ``vidstyle train-recognizer``, ``vidstyle recognize`` and
``vidstyle evaluate recognition``: frame-wise action recognition (thesis 4.1-4.3)."""

from __future__ import annotations

import logging
import time
from pathlib import Path

import typer

from ..errors import InputError
from ..fileio import output_dir, outputs_by_stem
from ..recognition import defaults as D
from ._evaluate import evaluate_app
from ._numbers import jobs_option, number

log = logging.getLogger(__name__)

_SPLIT_HELP = ("How --dataset's videos are divided: unseen-performer | unseen-view | unseen-camera. The videos the "
               "vocabulary is learned on, the videos the classifier is trained on, the validation videos and the "
               "test videos never share a performer or take; unseen-camera trains as unseen-performer.")


def register(app: typer.Typer) -> None:
    app.command("vocabulary")(vocabulary)
    app.command("train-recognizer")(train_recognizer)
    app.command("recognize")(recognize)


def _paired(datasets, features_dirs, option: str) -> list[tuple[Path, Path]]:
    """``option``'s datasets with their ``option``-features directories (one each, same order)."""
    datasets, features_dirs = datasets or [], features_dirs or []
    if len(datasets) != len(features_dirs):
        raise InputError(f"{option}: {len(datasets)} datasets for {len(features_dirs)} {option}-features")
    return list(zip(datasets, features_dirs))


def vocabulary(
    features: list[Path] = typer.Argument(None, help="Features .npz files of the videos to learn the vocabulary on (or use --dataset)."),
    out: Path = typer.Option(..., "--out", "-o", help="Output vocab.npz."),
    words: int = number(D.N_WORDS, "--words", lo=2, hi=100000, help="Number of words (thesis: 1000 of 500/1000/1500)."),
    method: str = typer.Option(D.VOCAB_METHOD, "--method", help="minibatch | hierarchical | kmeans."),
    branching: int = number(D.BRANCHING, "--branching", lo=2, hi=10000, help="Children per node of the hierarchical tree."),
    max_descriptors: int = number(D.MAX_DESCRIPTORS, "--max-descriptors", lo=1, help="Fit on at most this many (sampled)."),
    dataset: Path | None = typer.Option(None, "--dataset", help="dataset.json: learn on its vocabulary videos (chosen by --split)."),
    features_dir: Path | None = typer.Option(None, "--features-dir", help="Directory of <video id>.npz."),
    split: str = typer.Option(D.SPLIT, "--split", help=_SPLIT_HELP),
    test_view: str | None = typer.Option(None, "--test-view", help="Held-out view of an unseen-view split."),
    more_performers: list[Path] = typer.Option(None, "--more-performers", help="With --dataset: another dataset.json (or its directory) of other performers than --dataset's (vidstyle demo make-dataset --first-performer K); a share of its performers (--more-performers-vocab-share, the first by id) train the vocabulary, the others the classifier. Repeatable, each with one --more-performers-features."),
    more_performers_features: list[Path] = typer.Option(None, "--more-performers-features", help="Directory of <video id>.npz of each --more-performers dataset, same order."),
    more_performers_vocab_share: float = number(D.MORE_PERFORMERS_VOCAB_SHARE, "--more-performers-vocab-share", lo=0, hi=1, help="Share of the --more-performers performers whose videos train the vocabulary (the same in `vocabulary` and `train-recognizer`)."),
    seed: int = typer.Option(D.SEED, "--seed", help="Random seed (sampling, k-means, split)."),
    jobs: int = jobs_option(-1, help="Parallel file loading (-1 = all cores)."),
) -> None:
    """Learn the visual words: cluster the 3D SIFT descriptors of the given videos (k-means centres).

    Learn them on other videos than the ones the classifier is then trained on (`train-recognizer`
    refuses training videos that built the vocabulary unless given --allow-overlap)."""
    from ..recognition.pipeline import train_vocabulary

    t0 = time.perf_counter()
    more = _paired(more_performers, more_performers_features, "--more-performers")
    run = train_vocabulary(features or [], dataset=dataset, features_dir=features_dir, split=split,
                           test_view=test_view, words=words, method=method, branching=branching,
                           max_descriptors=max_descriptors, more_performers=more,
                           more_performers_vocab_share=more_performers_vocab_share, seed=seed, n_jobs=jobs)
    voc = run.vocabulary
    voc.save(out, training_files=run.training_files, extra=run.extra)
    log.info(
        "wrote %s: %d words (%s) from %d of %d descriptors of %d files in %.1f s",
        out, voc.n_words_, method, voc.n_fit_descriptors_, run.n_descriptors, len(run.training_files),
        time.perf_counter() - t0,
    )


def train_recognizer(
    features: list[Path] = typer.Argument(None, help="Features .npz files of the videos to train the classifier on (with --labels): not the ones the vocabulary was learned on."),
    labels: list[Path] = typer.Option(None, "--labels", help="True action labels (JSON) per FEATURES file, same order."),
    annotations: list[Path] = typer.Option(
        None, "--annotations",
        help="Annotations file(s) from `vidstyle annotate`: train on the action segments of your own videos "
             "(with their FEATURES files, or --features-dir holding <video stem>.npz). Unlabelled frames are left out."),
    vocab: Path | None = typer.Option(None, "--vocab", help="vocab.npz from `vidstyle vocabulary` (learned on other videos); required with --features sift3d."),
    features_kind: str = typer.Option("sift3d", "--features", help="sift3d (3D SIFT words from FEATURES files, the default) | pose (2D pose sequences: trains on the mocap takes of --dataset's training performers (the vocabulary and classifier videos of --split), seen from --views virtual cameras)."),
    views: int = number(8, "--views", lo=1, hi=360, help="--features pose: virtual cameras per mocap take (azimuth 0-360, elevation -10..45 deg, 2.5-6 body heights)."),
    noise_sigma: float = number(0.05, "--noise-sigma", lo=0, hi=10, help="--features pose: Gaussian keypoint noise, torso lengths per coordinate."),
    outlier_rate: float = number(0.05, "--outlier-rate", lo=0, hi=1, help="--features pose: share of keypoints displaced by 0.5 torso lengths (sigma)."),
    dropout_rate: float = number(0.02, "--dropout-rate", lo=0, hi=1, help="--features pose: share of frames dropped (performer not found), in runs of 4 frames on average."),
    noise_poses: Path | None = typer.Option(None, "--noise-poses", help="--features pose: corrupt the training keypoints with your pose estimator's own errors instead of Gaussian noise: a directory of <video id>.poses.json (vidstyle pose --out-dir) of --dataset's videos; those of the training performers are compared with their true keypoints, and every training frame takes the error made on one of the --residual-k most similar poses (replaces --noise-sigma, --outlier-rate, --dropout-rate)."),
    residual_k: int = number(3, "--residual-k", lo=1, hi=100, help="--noise-poses: calibration frames each training frame's error is drawn from."),
    residual_gate: float = number(0.99, "--residual-gate", lo=0, hi=1, help="--noise-poses: a training pose further from every calibration pose than this quantile of the validation performers' true poses are takes Gaussian noise of the size the pose files' errors have instead (0: no gate; 0.99 was chosen on validation, docs/results.md)."),
    clips: list[Path] = typer.Option(None, "--clips", help="--features pose: also (or instead of --dataset) train on these labelled mocap clips (BVH files or directories; any skeleton with the 15 keypoints' joints), labelled by --clip-labels or a <clip>.labels.json beside each."),
    clip_labels: list[Path] = typer.Option(None, "--clip-labels", help="--features pose: labels of --clips: a CSV file,label[,start,end] (BVH frame numbers, end exclusive), a demo labels JSON, or a CMU clips.csv. Unlabelled frames do not train."),
    out: Path = typer.Option(..., "--out", "-o", help="Output model .joblib."),
    onnx: bool = typer.Option(False, "--onnx", help="Also write <out>.onnx (onnxruntime-ready)."),
    dataset: Path | None = typer.Option(None, "--dataset", help="dataset.json: train on its classifier videos (chosen by --split)."),
    features_dir: Path | None = typer.Option(None, "--features-dir", help="Directory of <video id>.npz."),
    split: str = typer.Option(D.SPLIT, "--split", help=_SPLIT_HELP),
    test_view: str | None = typer.Option(None, "--test-view", help="Held-out view of an unseen-view split."),
    context: int = number(D.CONTEXT, "--context", lo=0, hi=D.MAX_CONTEXT, help="Frames each side in a frame's histogram (thesis 2)."),
    coarse_context: int = number(D.COARSE_CONTEXT, "--coarse-context", lo=0, hi=D.MAX_CONTEXT, help="Frames each side of a second, coarser histogram appended to each frame's (multi-scale context; 0 = off, the thesis)."),
    grouping: bool = typer.Option(D.GROUPING, "--grouping/--no-grouping", help="Word grouping (Scovanner)."),
    grouping_threshold: float = number(D.GROUPING_THRESHOLD, "--grouping-threshold", lo=-1, hi=1, help="Correlation above which words pool."),
    normalize: str = typer.Option(D.NORMALIZE, "--normalize", help="l1 | sqrt | l2 | none."),
    components: int = number(D.N_COMPONENTS, "--components", lo=1, hi=100000, help="PCA dimensions."),
    classifier: str = typer.Option(D.CLASSIFIER, "--classifier", help="ova-ovo (thesis) | svc-ovr (baseline)."),
    c: float = number(D.C, "--C", lo=0, lo_open=True, hi=1e6, help="SVM cost (default: chosen on validation performers, pipelines/kickboxing/validation/recognition.json)."),
    max_frames_per_class: int = number(D.MAX_FRAMES_PER_CLASS, "--max-frames-per-class", lo=0, help="SVM training frames per class (0 = all; default: chosen on validation performers)."),
    window: int = number(D.SMOOTHING_WINDOW, "--window", lo=1, hi=D.MAX_WINDOW, help="Smoothing window in frames (thesis 6)."),
    smoothing: str = typer.Option(D.SMOOTHING, "--smoothing", help="duration (explicit-duration HMM: per-class run lengths of the training videos; default, chosen on validation performers) | viterbi (HMM over frame scores) | vote (thesis) | mean."),
    emission_weight: float = number(D.EMISSION_WEIGHT, "--emission-weight", lo=0, lo_open=True, hi=100, help="viterbi / duration: power of the frame scores (default: chosen on validation performers)."),
    mirror: bool = typer.Option(D.MIRROR, "--mirror/--no-mirror", help="Also train on the mirror image of every video (southpaws; scovanner2007 descriptors only)."),
    allow_overlap: bool = typer.Option(False, "--allow-overlap", help="Allow training videos the vocabulary was learned on."),
    more_views: list[Path] = typer.Option(None, "--more-views", help="With --dataset: another dataset.json (or its directory) of the same performers filmed from other cameras (vidstyle demo make-dataset --views ... --split-seed S --split-sets=B); its videos of the performers whose videos train the classifier train it too. Repeatable, each with one --more-views-features."),
    more_views_features: list[Path] = typer.Option(None, "--more-views-features", help="Directory of <video id>.npz of each --more-views dataset, same order."),
    more_performers: list[Path] = typer.Option(None, "--more-performers", help="With --dataset: another dataset.json (or its directory) of other performers than --dataset's (vidstyle demo make-dataset --first-performer K); a share of its performers (--more-performers-vocab-share, the first by id) train the vocabulary, the others the classifier. Repeatable, each with one --more-performers-features."),
    more_performers_features: list[Path] = typer.Option(None, "--more-performers-features", help="Directory of <video id>.npz of each --more-performers dataset, same order."),
    more_performers_vocab_share: float = number(D.MORE_PERFORMERS_VOCAB_SHARE, "--more-performers-vocab-share", lo=0, hi=1, help="Share of the --more-performers performers whose videos train the vocabulary (the same in `vocabulary` and `train-recognizer`)."),
    seed: int = typer.Option(D.SEED, "--seed", help="Random seed."),
    jobs: int = jobs_option(-1, help="Parallel workers (-1 = all cores)."),
) -> None:
    """Train the frame recognizer (histograms -> grouping -> PCA -> SVMs) on labelled videos other than the
    ones the vocabulary was learned on."""
    from ..recognition.pipeline import train
    from ..recognition.recognizer import save_model

    t0 = time.perf_counter()
    if features_kind == "pose" and (more_views or more_views_features):
        raise InputError("--more-views: only with --features sift3d (the pose recognizer sees its mocap from any camera already)")
    if features_kind == "pose" and (more_performers or more_performers_features):
        raise InputError("--more-performers: only with --features sift3d")
    if features_kind == "pose":
        _train_pose(dataset, out, split, test_view, views, noise_sigma, outlier_rate, dropout_rate, classifier, c,
                    max_frames_per_class, window, smoothing, emission_weight, mirror, seed, jobs, features, annotations,
                    clips or [], clip_labels or [], noise_poses, residual_k, residual_gate)
        return
    if clips or clip_labels or noise_poses:
        raise InputError("--clips / --clip-labels / --noise-poses: only with --features pose (3D SIFT trains on videos)")
    if features_kind != "sift3d":
        raise InputError(f"--features: must be sift3d or pose, got {features_kind!r}")
    if vocab is None:
        raise InputError("train-recognizer: --vocab is required with --features sift3d")
    views_pairs = _paired(more_views, more_views_features, "--more-views")
    performer_pairs = _paired(more_performers, more_performers_features, "--more-performers")
    run = train(
        vocab, features or [], labels=labels or [], annotations=annotations or [], dataset=dataset,
        features_dir=features_dir, split=split, test_view=test_view, context=context,
        coarse_context=coarse_context, grouping=grouping, grouping_threshold=grouping_threshold,
        normalize=normalize, n_components=components, classifier=classifier, C=c,
        max_frames_per_class=max_frames_per_class, smoothing_window=window, smoothing=smoothing,
        emission_weight=emission_weight, mirror=mirror, allow_overlap=allow_overlap,
        more_views=views_pairs, more_performers=performer_pairs,
        more_performers_vocab_share=more_performers_vocab_share, seed=seed, n_jobs=jobs,
    )
    rec = run.model
    header = save_model(out, rec, training_files=run.training_files, extra=run.extra)
    log.info("wrote %s (%d classes, %.1f s): %s", out, len(rec.classes_), time.perf_counter() - t0, header["summary"])
    if onnx:
        from ..recognition.onnx_export import export_onnx

        onnx_path = out.with_suffix(".onnx")
        export_onnx(rec, onnx_path)
        log.info("wrote %s", onnx_path)


def _train_pose(dataset, out, split, test_view, views, noise_sigma, outlier_rate, dropout_rate, classifier, c,
                max_frames_per_class, window, smoothing, emission_weight, mirror, seed, jobs, features, annotations,
                clips, clip_labels, noise_poses=None, residual_k=3, residual_gate=0.0):
    from ..formats.dataset import read_dataset
    from ..recognition.poserecognizer import save_pose_model
    from ..recognition.posetraining import KeypointNoise, clip_motions, train_from_dataset

    if features or annotations or (dataset is None and not clips):
        raise InputError("--features pose: give --dataset (its mocap takes and labels) and/or labelled --clips, "
                         "not FEATURES or --annotations")
    if clip_labels and not clips:
        raise InputError("--clip-labels: give the --clips they label")
    if noise_poses is not None and dataset is None:
        raise InputError("--noise-poses: give the --dataset whose videos the pose files are of (their truth calibrates)")
    noise = KeypointNoise(sigma=noise_sigma, outlier_rate=outlier_rate, dropout_rate=dropout_rate)
    params = {"classifier": classifier, "C": c, "max_frames_per_class": max_frames_per_class or None,
              "smoothing_window": window, "smoothing": smoothing, "emission_weight": emission_weight,
              "mirror": mirror, "n_jobs": jobs}
    ds = read_dataset(dataset) if dataset is not None else None
    if noise_poses is not None:
        noise = _residual_noise(ds, noise_poses, split, seed, test_view, residual_k, residual_gate)
    extra_motions = clip_motions(clips, clip_labels, ds.fps if ds else D.FPS,
                                 classes=(ds.classes or None) if ds else None) if clips else []
    rec, extra = train_from_dataset(ds, split, seed, test_view, views, noise, params, extra_motions=extra_motions)
    header = save_pose_model(out, rec, extra["training"], {"split": extra["split"]})
    log.info("wrote %s (pose recognizer, %d classes): %s", out, len(rec.classes_), header["summary"])


def _residual_noise(ds, poses_dir: Path, split: str, seed: int, test_view: str | None, k: int, gate: float = 0.0):
    """--noise-poses: the ResidualNoise of the pose files in ``poses_dir`` of the split's training
    performers' videos (sets A and B: the ones the recognizer trains on; never validation or test videos);
    with ``gate`` > 0, gated at that quantile of the validation performers' true poses' distances, the
    fallback a Gaussian of the training pose files' error."""
    from ..evaluation.poserecognition import (
        gated_residual_noise,
        measure_pose_error,
        noise_from_error,
        pose_pairs,
        residual_noise,
    )
    from ..recognition.splits import make_split

    if not Path(poses_dir).is_dir():
        raise InputError(f"{poses_dir}: --noise-poses must be a directory of <video id>.poses.json")
    sp = make_split(ds, "unseen-performer" if split == "unseen-camera" else split, seed=seed, test_view=test_view)
    ids = [i for i in list(sp.vocab) + list(sp.train) if (Path(poses_dir) / f"{i}.poses.json").is_file()]
    if not ids:
        raise InputError(f"{poses_dir}: no <video id>.poses.json of the training videos of --dataset's split "
                         f"(e.g. {(list(sp.vocab) + list(sp.train))[0]}.poses.json)")
    if gate > 0 and not sp.val:
        raise InputError("--residual-gate: the split has no validation performers to set the gate (use 0)")
    pairs = pose_pairs(ds, Path(poses_dir), ids)  # read once: the bank and the fallback's error both use them
    noise = residual_noise(ds, Path(poses_dir), ids, k=k, pairs=pairs)
    if gate > 0:
        fallback = noise_from_error(measure_pose_error(ds, Path(poses_dir), ids, pairs=pairs))
        noise = gated_residual_noise(noise, ds, list(sp.val), gate, fallback)
    log.info("training noise: the pose errors of %d training videos (%s)", len(ids), noise.to_dict())
    return noise


def recognize(
    inputs: list[Path] = typer.Argument(..., help="Features .npz of videos (or the videos themselves)."),
    model: Path = typer.Option(..., "--model", "-m", help="Model .joblib from train-recognizer."),
    out: Path | None = typer.Option(None, "--out", "-o", help="Output labels JSON (one input)."),
    out_dir: Path | None = typer.Option(
        None, "--out-dir", help="Output directory: <input stem>.json per input (any number of inputs)."
    ),
    window: int | None = number(None, "--window", integer=True, lo=1, hi=D.MAX_WINDOW, help="Smoothing window (default: the model's)."),
    smoothing: str | None = typer.Option(None, "--smoothing", help="vote | mean | viterbi | duration (default: the model's)."),
    emission_weight: float | None = number(None, "--emission-weight", integer=False, lo=0, lo_open=True, hi=100, help="viterbi / duration: power of the frame scores (default: the model's)."),
    fps: float | None = number(None, "--fps", integer=False, lo=0, lo_open=True, hi=1000, help="Frame rate to record (default: from the features, else 20)."),
    jobs: int = jobs_option(-1, help="Inputs recognised in parallel (-1 = all cores; each worker loads the model once)."),
    scheduler: str | None = typer.Option(
        None, "--scheduler", help="Dask scheduler address (tcp://HOST:PORT): recognise on that cluster; its workers must see the same paths."
    ),
    pose_model: Path | None = typer.Option(None, "--pose-model", help="Late fusion with this pose-sequence "
                                              "recognizer (train-recognizer --features pose) on --poses-dir."),
    poses_dir: Path | None = typer.Option(None, "--poses-dir", help="With --pose-model: <input stem>.poses.json "
                                             "per input (vidstyle pose VIDEOS --out-dir)."),
    fusion_weight: float = number(D.FUSION_WEIGHT, "--fusion-weight", integer=False, lo=0, hi=1,
                                  help="With --pose-model: the weight of the pose recognizer's scores (the rest is the "
                                  "3D SIFT recognizer's)."),
    fusion_emission_weight: float = number(D.FUSION_EMISSION_WEIGHT, "--fusion-emission-weight", integer=False, lo=0,
                                           lo_open=True, hi=100,
                                           help="With --pose-model: the power of the fused frame scores in the pose "
                                           "recognizer's smoother (validated with --fusion-weight)."),
) -> None:
    """Per-frame action labels with confidence, raw and smoothed.

    One input with --out FILE, or any number with --out-dir DIR (the model is loaded once per worker, so
    a pipeline stage pays the start-up once, not per video)."""
    from ..recognition.pipeline import recognize as run

    if (out is None) == (out_dir is None):
        raise InputError("recognize: give exactly one of --out FILE (one input) or --out-dir DIR")
    if out is not None and len(inputs) != 1:
        raise InputError(f"--out: {len(inputs)} inputs; use --out-dir DIR for several")
    for p in inputs:
        if not p.exists():
            raise InputError(f"{p}: file not found")
    targets = [out] if out is not None else outputs_by_stem(inputs, out_dir, ".json")
    if (pose_model is None) != (poses_dir is None):
        raise InputError("recognize: --pose-model and --poses-dir go together (late fusion)")
    poses = None if poses_dir is None else [poses_dir / f"{p.stem}.poses.json" for p in inputs]
    import contextlib

    from ._flags import as_flags

    # --out-dir: created if missing (removed again if the run fails and it is empty), with the temporaries
    # a killed run left for these outputs swept
    into = output_dir(out_dir, targets) if out_dir is not None else contextlib.nullcontext()
    with as_flags(jobs="--jobs", scheduler="--scheduler"), into:
        run(model, inputs, targets, window=window, smoothing=smoothing, emission_weight=emission_weight, fps=fps,
            jobs=jobs, scheduler=scheduler, pose_model=pose_model, poses=poses, fusion_weight=fusion_weight,
            fusion_emission_weight=fusion_emission_weight)
    if out_dir is not None:
        log.info("recognize: %d input(s) -> %s", len(inputs), out_dir)


@evaluate_app.command("recognition")
def evaluate_recognition(
    dataset: Path = typer.Option(..., "--dataset", help="dataset.json (or its directory)."),
    features_dir: Path | None = typer.Option(None, "--features-dir", help="Directory of <video id>.npz (train and test here)."),
    labels_dir: Path | None = typer.Option(
        None, "--labels-dir", help="Score these <video id>.json from `vidstyle recognize` instead (no training)."
    ),
    model: Path | None = typer.Option(
        None, "--model", "-m", help="With --labels-dir: the model that made them (its split names the test videos)."
    ),
    out: Path = typer.Option(..., "--out", "-o", help="Output metrics JSON (a PNG confusion matrix goes beside it)."),
    split: str = typer.Option(D.SPLIT, "--split", help=_SPLIT_HELP),
    test_view: str | None = typer.Option(None, "--test-view", help="Held-out view (unseen-view; default: seeded draw)."),
    ablation: str = typer.Option("none", "--ablation", help="none | no-grouping | no-context | no-smoothing | no-mirror."),
    words: int = number(D.N_WORDS, "--words", lo=2, hi=100000, help="Vocabulary size (ablation: 500/1000/1500)."),
    vocab_method: str = typer.Option(D.VOCAB_METHOD, "--vocab-method", help="minibatch | hierarchical | kmeans."),
    classifier: str = typer.Option(D.CLASSIFIER, "--classifier", help="ova-ovo | svc-ovr."),
    baseline: bool = typer.Option(True, "--baseline/--no-baseline", help="Also score a plain SVC on the same features."),
    grouping_threshold: float = number(D.GROUPING_THRESHOLD, "--grouping-threshold", lo=-1, hi=1, help="Word grouping correlation threshold."),
    components: int = number(D.N_COMPONENTS, "--components", lo=1, hi=100000, help="PCA dimensions."),
    coarse_context: int = number(D.COARSE_CONTEXT, "--coarse-context", lo=0, hi=D.MAX_CONTEXT, help="Multi-scale context: frames each side of a second histogram (0 = off)."),
    max_frames_per_class: int = number(D.MAX_FRAMES_PER_CLASS, "--max-frames-per-class", lo=0, help="SVM training frames per class (0 = all; default: chosen on validation performers)."),
    window: int = number(D.SMOOTHING_WINDOW, "--window", lo=1, hi=D.MAX_WINDOW, help="Smoothing window."),
    smoothing: str = typer.Option(D.SMOOTHING, "--smoothing", help="duration (explicit-duration HMM: per-class run lengths of the training videos; default, chosen on validation performers) | viterbi (HMM over frame scores) | vote (thesis) | mean."),
    c: float = number(D.C, "--C", lo=0, lo_open=True, hi=1e6, help="SVM cost (default: chosen on validation performers, pipelines/kickboxing/validation/recognition.json)."),
    emission_weight: float = number(D.EMISSION_WEIGHT, "--emission-weight", lo=0, lo_open=True, hi=100, help="viterbi / duration: power of the frame scores (default: chosen on validation performers)."),
    mirror: bool = typer.Option(D.MIRROR, "--mirror/--no-mirror", help="Also train on mirror images (scovanner2007)."),
    test_dataset: Path | None = typer.Option(
        None, "--test-dataset", help="unseen-camera: dataset.json of the test performers filmed from new cameras "
        "(vidstyle demo make-dataset --unseen-camera)."),
    test_features_dir: Path | None = typer.Option(
        None, "--test-features-dir", help="unseen-camera: features directory of --test-dataset's videos."),
    seed: int = typer.Option(D.SEED, "--seed", help="Random seed (split, vocabulary, sampling)."),
    jobs: int = jobs_option(-1, help="Parallel workers (-1 = all cores)."),
) -> None:
    """Learn a vocabulary and train a recognizer on a split's training videos (each on its own share), test on
    held-out videos, write metrics.

    With --labels-dir, score label files already written by `vidstyle recognize` against the ground truth
    instead (no training): the test videos are the split recorded in --model, else the --split/--seed one."""
    import numpy as np

    from ..evaluation.recognition import confusion_png, run_evaluation
    from ..formats.metrics import write_metrics

    r = run_evaluation(
        dataset, features_dir=features_dir, labels_dir=labels_dir, model=model, split=split, test_view=test_view,
        ablation=ablation, words=words, vocab_method=vocab_method, classifier=classifier, baseline=baseline,
        grouping_threshold=grouping_threshold, n_components=components, coarse_context=coarse_context,
        max_frames_per_class=max_frames_per_class, smoothing_window=window, smoothing=smoothing, C=c,
        emission_weight=emission_weight, mirror=mirror, test_dataset=test_dataset,
        test_features_dir=test_features_dir, seed=seed, n_jobs=jobs,
    )
    m, ablation, words = r.metrics, r.ablation, r.words
    write_metrics(out, m)
    png = out.with_suffix(".png")
    cm = np.asarray(m["confusion"]["smoothed"])
    confusion_png(png, cm, m["confusion"]["classes"], f"{split}, {ablation}: smoothed frame acc {m['frame_accuracy']['smoothed']:.3f}")
    confusion_png(out.with_name(out.stem + "_raw.png"), np.asarray(m["confusion"]["raw"]), m["confusion"]["classes"],
                  f"{split}, {ablation}: raw frame acc {m['frame_accuracy']['raw']:.3f}")
    from rich.console import Console
    from rich.table import Table

    kind = (m.get("split") or {}).get("kind") or split
    t = Table(title=f"recognition ({kind}, ablation {ablation}, {words} words)")
    for col in ("metric", "value"):
        t.add_column(col)
    t.add_row("frame accuracy raw", f"{m['frame_accuracy']['raw']:.3f}")
    t.add_row("frame accuracy smoothed", f"{m['frame_accuracy']['smoothed']:.3f}")
    seg = (m.get("segments") or {}).get("smoothed") or {}
    tol, f1 = seg.get("boundary_tolerant_accuracy") or {}, seg.get("segmental_f1") or {}
    if tol.get("1") is not None:
        t.add_row("smoothed, within 1 / 2 frames of the true boundaries",
                  " / ".join(f"{tol[k]:.3f}" for k in ("1", "2") if tol.get(k) is not None))
    if f1.get("50") is not None:
        t.add_row("segmental F1 @10 / @25 / @50",
                  " / ".join("n/a" if f1.get(k) is None else f"{f1[k]:.3f}" for k in ("10", "25", "50")))
    va = m["video_accuracy"]
    t.add_row("video accuracy", "n/a" if va is None else f"{va:.3f} of {m['n_test_single_videos']}")
    if "baseline" in m:
        b = m["baseline"]
        t.add_row("baseline svc-ovr raw / smoothed", f"{b['frame_accuracy']['raw']:.3f} / {b['frame_accuracy']['smoothed']:.3f}")
    t.add_row("test videos / frames", f"{m['n_test_videos']} / {m['n_test_frames']}")
    if "timing_s" in m:
        t.add_row("time vocab / train / predict (s)", " / ".join(f"{m['timing_s'][k]:.1f}" for k in ("vocabulary", "train", "predict")))
    Console().print(t)
    log.info("wrote %s, %s", out, png)
