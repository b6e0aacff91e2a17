"""``vidstyle vocabulary``, ``vidstyle train-recognizer``, ``vidstyle recognize`` and
``vidstyle evaluate recognition``: frame-wise action recognition (thesis 4.1-4.3)."""

from __future__ import annotations

import functools
import logging
import time
from pathlib import Path
from typing import Optional

import numpy as np
import typer

from ..errors import InputError
from ..fileio import outputs_by_stem
from ..parallel import parallel_map
from ._evaluate import evaluate_app

log = logging.getLogger(__name__)

_SPLIT_HELP = ("unseen-performer | unseen-view | unseen-camera: sets A (vocabulary), B (classifier), V (validation) "
               "and T (test) never share a performer or take; unseen-camera trains as unseen-performer.")


def register(app: typer.Typer) -> None:
    app.command("vocabulary")(vocabulary)
    app.command("train-recognizer")(train_recognizer)
    app.command("recognize")(recognize)


def _dataset_split(dataset: Path, split: str, seed: int, test_view: Optional[str]):
    """The dataset and its A/B/V/T split. Sets A and B of ``unseen-camera`` are those of
    ``unseen-performer`` (its test videos come from another dataset, which training does not need)."""
    from ..formats.dataset import read_dataset
    from ..recognition.splits import make_split

    ds = read_dataset(dataset)
    kind = "unseen-performer" if split == "unseen-camera" else split
    return ds, make_split(ds, kind, seed=seed, test_view=test_view)


def _split_header(sp, set_name: str) -> dict:
    """What a model or vocabulary records of the split it was trained on."""
    return {"kind": sp.kind, "seed": sp.seed, "set": set_name, "params": sp.params, "test": sp.test, "val": sp.val,
            "test_performers": sp.test_performers, "val_performers": sp.val_performers,
            "vocab_performers": sp.vocab_performers, "train_performers": sp.train_performers}


def _features_files(features: list[Path], features_dir: Optional[Path], dataset: Optional[Path], what: str):
    if features and (features_dir or dataset):
        raise InputError(f"{what}: give FEATURES files or --features-dir with --dataset, not both")
    if not features and not (features_dir and dataset):
        raise InputError(f"{what}: give FEATURES files, or --features-dir and --dataset")


def vocabulary(
    features: list[Path] = typer.Argument(None, help="Features .npz files of set A (or use --dataset)."),
    out: Path = typer.Option(..., "--out", "-o", help="Output vocab.npz."),
    words: int = typer.Option(1000, "--words", help="Number of words (thesis: 1000 of 500/1000/1500)."),
    method: str = typer.Option("minibatch", "--method", help="minibatch | hierarchical | kmeans."),
    branching: int = typer.Option(10, "--branching", help="Children per node of the hierarchical tree."),
    max_descriptors: int = typer.Option(100_000, "--max-descriptors", help="Fit on at most this many (sampled)."),
    dataset: Optional[Path] = typer.Option(None, "--dataset", help="dataset.json: fit on set A of --split."),
    features_dir: Optional[Path] = typer.Option(None, "--features-dir", help="Directory of <video id>.npz."),
    split: str = typer.Option("unseen-performer", "--split", help=_SPLIT_HELP),
    test_view: Optional[str] = typer.Option(None, "--test-view", help="Held-out view of an unseen-view split."),
    seed: int = typer.Option(0, "--seed", help="Random seed (sampling, k-means, split)."),
    jobs: int = typer.Option(-1, "--jobs", "-j", help="Parallel file loading (-1 = all cores)."),
) -> None:
    """Cluster 3D SIFT descriptors of set A into visual words (k-means centres)."""
    from ..recognition.io import features_path
    from ..recognition.recognizer import load_many
    from ..recognition.vocabulary import Vocabulary

    features = list(features or [])
    _features_files(features, features_dir, dataset, "vocabulary")
    extra = {}
    if dataset:
        ds, sp = _dataset_split(dataset, split, seed, test_view)
        features = [features_path(features_dir, i) for i in sp.vocab]
        extra = {"split": _split_header(sp, "A")}
    t0 = time.perf_counter()
    feats = load_many(features, n_jobs=jobs)
    dims = {f.dim for f in feats if f.descriptors.shape[0]}
    if len(dims) > 1:
        raise InputError(f"features: descriptors of different dimensions {sorted(dims)} (mixed variants?)")
    desc = [f.descriptors for f in feats if f.descriptors.shape[0]]
    if not desc:
        raise InputError("features: no descriptors in any file")
    X = np.concatenate(desc)
    voc = Vocabulary(n_words=words, method=method, branching=branching, max_descriptors=max_descriptors, random_state=seed)
    voc.fit(X)
    voc.save(out, training_files=[str(p) for p in features], extra=extra)
    log.info(
        "wrote %s: %d words (%s) from %d of %d descriptors of %d files in %.1f s",
        out, voc.n_words_, method, voc.n_fit_descriptors_, X.shape[0], len(feats), time.perf_counter() - t0,
    )


def train_recognizer(
    features: list[Path] = typer.Argument(None, help="Features .npz files of set B (with --labels)."),
    labels: list[Path] = typer.Option(None, "--labels", help="Labels JSON per FEATURES file, same order."),
    annotations: list[Path] = typer.Option(
        None, "--annotations",
        help="Annotations file(s) from `vidstyle annotate`: train on the action segments of your own videos "
             "(with their FEATURES files, or --features-dir holding <video stem>.npz). Unlabelled frames are left out."),
    vocab: Path = typer.Option(..., "--vocab", help="vocab.npz from `vidstyle vocabulary` (set A)."),
    out: Path = typer.Option(..., "--out", "-o", help="Output model .joblib."),
    onnx: bool = typer.Option(False, "--onnx", help="Also write <out>.onnx (onnxruntime-ready)."),
    dataset: Optional[Path] = typer.Option(None, "--dataset", help="dataset.json: train on set B of --split."),
    features_dir: Optional[Path] = typer.Option(None, "--features-dir", help="Directory of <video id>.npz."),
    split: str = typer.Option("unseen-performer", "--split", help=_SPLIT_HELP),
    test_view: Optional[str] = typer.Option(None, "--test-view", help="Held-out view of an unseen-view split."),
    context: int = typer.Option(2, "--context", help="Frames each side in a frame's histogram (thesis 2)."),
    coarse_context: int = typer.Option(0, "--coarse-context", help="Frames each side of a second, coarser histogram appended to each frame's (multi-scale context; 0 = off, the thesis)."),
    grouping: bool = typer.Option(True, "--grouping/--no-grouping", help="Word grouping (Scovanner)."),
    grouping_threshold: float = typer.Option(0.8, "--grouping-threshold", help="Correlation above which words pool."),
    normalize: str = typer.Option("sqrt", "--normalize", help="l1 | sqrt | l2 | none."),
    components: int = typer.Option(128, "--components", help="PCA dimensions."),
    classifier: str = typer.Option("ova-ovo", "--classifier", help="ova-ovo (thesis) | svc-ovr (baseline)."),
    c: float = typer.Option(100.0, "--C", help="SVM cost (default: chosen on validation performers, pipelines/kickboxing/validation/recognition.json)."),
    max_frames_per_class: int = typer.Option(1500, "--max-frames-per-class", help="SVM training frames per class (0 = all; default: chosen on validation performers)."),
    window: int = typer.Option(6, "--window", help="Smoothing window in frames (thesis 6)."),
    smoothing: str = typer.Option("duration", "--smoothing", help="duration (explicit-duration HMM: per-class run lengths of set B; default, chosen on validation performers) | viterbi (HMM over frame scores) | vote (thesis) | mean."),
    emission_weight: float = typer.Option(1.0, "--emission-weight", help="viterbi / duration: power of the frame scores (default: chosen on validation performers)."),
    mirror: bool = typer.Option(True, "--mirror/--no-mirror", help="Also train on the mirror image of every video (southpaws; scovanner2007 descriptors only)."),
    allow_overlap: bool = typer.Option(False, "--allow-overlap", help="Allow set B files that built the vocabulary."),
    seed: int = typer.Option(0, "--seed", help="Random seed."),
    jobs: int = typer.Option(-1, "--jobs", "-j", help="Parallel workers (-1 = all cores)."),
) -> None:
    """Train the frame recognizer (histograms -> grouping -> PCA -> SVMs) on set B."""
    from ..formats.labels import check_length, read_labels
    from ..recognition.io import features_path
    from ..recognition.recognizer import ActionRecognizer, load_many, save_model
    from ..recognition.vocabulary import Vocabulary

    features = list(features or [])
    labels = list(labels or [])
    annotations = list(annotations or [])
    split_info = None
    classes = None
    if annotations:
        if dataset or labels:
            raise InputError("--annotations: give it with FEATURES files or --features-dir, not with --dataset or --labels")
        if bool(features) == bool(features_dir):
            raise InputError("--annotations: give FEATURES files or --features-dir (one of them)")
        feats, ylists, classes, training = _annotated_training(annotations, features, features_dir)
        features = [Path(t["features"]) for t in training]
        labels = [Path(t["labels"]) for t in training]
    else:
        _features_files(features, features_dir, dataset, "train-recognizer")
    if dataset:
        if labels:
            raise InputError("--labels: not used with --dataset (the manifest names the labels)")
        ds, sp = _dataset_split(dataset, split, seed, test_view)
        by_id = ds.by_id()
        features = [features_path(features_dir, i) for i in sp.train]
        labels = [ds.labels_path(by_id[i]) for i in sp.train]
        classes = ds.classes or None
        split_info = _split_header(sp, "B")
    if len(labels) != len(features):
        raise InputError(f"--labels: {len(labels)} labels files for {len(features)} features files")
    voc = Vocabulary.load(vocab)
    overlap = {Path(p).resolve() for p in getattr(voc, "training_files_", [])} & {p.resolve() for p in features}
    if overlap and not allow_overlap:
        raise InputError(
            f"{vocab}: {len(overlap)} training file(s) also built the vocabulary (e.g. {sorted(overlap)[0]});"
            " sets A and B must be disjoint (or pass --allow-overlap)"
        )
    if not annotations:
        tracks = [read_labels(p) for p in labels]
        feats = load_many(features, n_jobs=jobs)
        for f, t in zip(feats, tracks):
            check_length(t, f.n_frames, f"the features file {f.path}")
        ylists = [t.labels for t in tracks]
        if classes is None:
            classes = tracks[0].classes
            for t in tracks[1:]:
                if t.classes != classes:
                    classes = sorted(set(classes) | set(t.classes))
    rec = ActionRecognizer(
        vocabulary=voc, context=context, coarse_context=coarse_context, grouping=grouping, grouping_threshold=grouping_threshold,
        normalize=normalize, n_components=components, classifier=classifier, C=c,
        max_frames_per_class=max_frames_per_class or None, smoothing_window=window, smoothing=smoothing,
        emission_weight=emission_weight, mirror=mirror, n_jobs=jobs, random_state=seed,
    )
    t0 = time.perf_counter()
    rec.fit(feats, ylists, classes=classes)
    feature_params = _feature_params(features)
    header = save_model(
        out,
        rec,
        training_files=[{"features": str(f), "labels": str(lab)} for f, lab in zip(features, labels)],
        extra={"split": split_info, "features_params": feature_params, "vocabulary_file": str(vocab)},
    )
    log.info("wrote %s (%d classes, %.1f s): %s", out, len(rec.classes_), time.perf_counter() - t0, header["summary"])
    if onnx:
        from ..recognition.onnx_export import export_onnx

        onnx_path = out.with_suffix(".onnx")
        export_onnx(rec, onnx_path)
        log.info("wrote %s", onnx_path)


def _runs(mask) -> list[tuple[int, int]]:
    """Maximal half-open runs ``[a, b)`` where ``mask`` is true."""
    m = np.concatenate([[False], np.asarray(mask, dtype=bool), [False]])
    d = np.flatnonzero(np.diff(m.astype(np.int8)))
    return [(int(a), int(b)) for a, b in zip(d[::2], d[1::2])]


def _annotated_training(annotations: list[Path], features: list[Path], features_dir: Optional[Path]):
    """Training pieces from annotation files: for every annotated video with segments, its features file
    (the FEATURES file whose recorded video is that video, or ``<features-dir>/<video stem>.npz``) cut
    into the runs of labelled frames, with the per-frame labels of its segments."""
    from ..formats import FormatError
    from ..formats.annotations import frame_labels, read_annotations, resolve_video_path
    from ..recognition.io import crop_features, load_features

    loaded = {}
    if features:
        for p in features:
            f = load_features(p)
            loaded[p] = f
    feats, ylists, training, used = [], [], [], []
    for a in annotations:
        ann = read_annotations(a)
        for k, v in enumerate(ann.videos):
            if not v.segments:
                continue
            vpath = resolve_video_path(a, v)
            if features_dir is not None:
                fp = Path(features_dir) / f"{Path(v.path).stem}.npz"
                if not fp.exists():
                    raise InputError(f"{a}: videos[{k}] ({v.path}) has segments but {fp} does not exist "
                                     f"(run `vidstyle features` on it)")
                f = load_features(fp)
            else:
                match = [p for p, f in loaded.items() if f.video and _same_video(f.video, vpath)]
                if not match:
                    match = [p for p, f in loaded.items() if Path(f.video or p).stem == vpath.stem]
                if len(match) != 1:
                    raise InputError(f"{a}: videos[{k}] ({v.path}): {len(match)} of the FEATURES files are of "
                                     f"this video (need exactly one)")
                fp, f = match[0], loaded[match[0]]
            decoded = f.source_frames if f.source_frames is not None else f.n_frames
            if decoded != v.frames:
                raise FormatError(a, f"videos[{k}].frames", f"{v.frames} decoded frames, but {fp} was made from "
                                                              f"{decoded} (features of another video?)")
            # segments are marked on decoded frames; features run at a working rate: label each working
            # frame by the decoded frame it was taken from, then train on the runs of labelled frames
            src = f.source_index if f.source_index is not None else np.arange(f.n_frames)
            y = frame_labels(v, ann.classes)[src]
            for s, e in _runs(y >= 0):
                feats.append(crop_features(f, s, e))
                ylists.append([ann.classes[i] for i in y[s:e]])
            training.append({"features": str(fp), "labels": f"{a}#videos[{k}]"})
            for c in ann.classes:
                if c not in used and any(seg.action == c for seg in v.segments):
                    used.append(c)
    if not feats:
        raise InputError(f"--annotations: no action segments in {', '.join(map(str, annotations))}")
    n = sum(len(y) for y in ylists)
    log.info("train-recognizer: %d labelled frames in %d runs of %d annotated videos, %d classes",
             n, len(feats), len(training), len(used))
    return feats, ylists, used, training


def _same_video(recorded: str, path: Path) -> bool:
    try:
        return Path(recorded).resolve() == path.resolve()
    except OSError:
        return False


def _feature_params(paths) -> dict | None:
    from ..formats.features import read_features

    for p in paths:
        try:
            return read_features(p).params or None
        except InputError:  # informative only
            return None
    return None


def _video_features(path: Path, header: dict):
    """Compute features of a video with the features stage (same variant, salient-point parameters and
    working rate and size as the training files)."""
    import tempfile

    from ..recognition.io import load_features

    try:
        from ..features.extract import WORKING_FPS, WORKING_HEIGHT, process_video
    except ImportError:
        raise InputError(f"{path}: not a features .npz, and the features stage is not installed") from None
    fp = header.get("features_params") or {}
    variant = fp.get("variant", "scovanner2007")
    salient = None
    try:
        from ..features.salient import SalientParams

        if isinstance(fp.get("salient"), dict):
            salient = SalientParams(**fp["salient"])
    except Exception:  # older/newer params: fall back to the defaults, which is what training used by default
        log.warning("%s: could not rebuild the training salient-point parameters; using defaults", path)
    working = fp.get("working") if isinstance(fp.get("working"), dict) else None
    # features of schema 1 were computed on the video's own frames
    fps = working.get("fps") if working else (None if fp else WORKING_FPS)
    height = working.get("height") if working else (None if fp else WORKING_HEIGHT)
    with tempfile.TemporaryDirectory() as d:
        tmp = Path(d) / f"{path.stem}.npz"
        process_video(path, tmp, variant=variant, salient=salient, fps=fps, height=height)
        return load_features(tmp)


def recognize(
    inputs: list[Path] = typer.Argument(..., help="Features .npz of videos (or the videos themselves)."),
    model: Path = typer.Option(..., "--model", "-m", help="Model .joblib from train-recognizer."),
    out: Optional[Path] = typer.Option(None, "--out", "-o", help="Output labels JSON (one input)."),
    out_dir: Optional[Path] = typer.Option(
        None, "--out-dir", help="Output directory: <input stem>.json per input (any number of inputs)."
    ),
    window: Optional[int] = typer.Option(None, "--window", help="Smoothing window (default: the model's)."),
    smoothing: Optional[str] = typer.Option(None, "--smoothing", help="vote | mean | viterbi | duration (default: the model's)."),
    emission_weight: Optional[float] = typer.Option(None, "--emission-weight", help="viterbi / duration: power of the frame scores (default: the model's)."),
    fps: Optional[float] = typer.Option(None, "--fps", help="Frame rate to record (default: from the features, else 20)."),
    jobs: int = typer.Option(1, "--jobs", "-j", help="Inputs recognised in parallel (-1: all cores; each worker loads the model once)."),
    scheduler: Optional[str] = typer.Option(
        None, "--scheduler", help="Dask scheduler address (tcp://HOST:PORT): recognise on that cluster; its workers must see the same paths."
    ),
) -> None:
    """Per-frame action labels with confidence, raw and smoothed.

    One input with --out FILE, or any number with --out-dir DIR (the model is loaded once per worker, so
    a pipeline stage pays the start-up once, not per video)."""
    if (out is None) == (out_dir is None):
        raise InputError("recognize: give exactly one of --out FILE (one input) or --out-dir DIR")
    if out is not None and len(inputs) != 1:
        raise InputError(f"--out: {len(inputs)} inputs; use --out-dir DIR for several")
    for p in inputs:
        if not p.exists():
            raise InputError(f"{p}: file not found")
    targets = [out] if out is not None else outputs_by_stem(inputs, out_dir, ".json")
    _load_model_for(str(model), window, smoothing, emission_weight)  # a bad model fails here, once, before any work
    items = [(str(model), window, smoothing, emission_weight, str(p), str(t), fps) for p, t in zip(inputs, targets)]
    from ._flags import as_flags

    with as_flags(jobs="--jobs", scheduler="--scheduler"):
        parallel_map(_recognize_task, items, jobs=jobs, scheduler=scheduler, description="recognize")
    if out_dir is not None:
        log.info("recognize: %d input(s) -> %s", len(inputs), out_dir)


def _load_model_for(model: str, window: Optional[int], smoothing: Optional[str], emission_weight: Optional[float] = None):
    """The model, loaded once per process and file version (a retrained file at the same path reloads)."""
    try:
        st = Path(model).stat()
    except OSError:
        raise InputError(f"{model}: model file not found") from None
    return _load_model_cached(model, st.st_mtime_ns, st.st_size, window, smoothing, emission_weight)


@functools.lru_cache(maxsize=2)
def _load_model_cached(model: str, _mtime_ns: int, _size: int, window: Optional[int], smoothing: Optional[str],
                       emission_weight: Optional[float] = None):
    from ..recognition.recognizer import load_model

    rec, header = load_model(Path(model))
    if window is not None:
        rec.smoothing_window = window
    if smoothing is not None:
        rec.smoothing = smoothing
    if emission_weight is not None:
        rec.emission_weight = emission_weight
    return rec, header


def _recognize_task(item: tuple) -> None:
    """One input of `vidstyle recognize` (module level, so joblib and Dask workers can run it)."""
    model, window, smoothing, emission_weight, input, target, fps = item
    rec, header = _load_model_for(model, window, smoothing, emission_weight)
    _recognize_one(rec, header, Path(model), Path(input), Path(target), fps)


def _recognize_one(rec, header: dict, model: Path, input: Path, out: Path, fps: Optional[float]) -> None:
    from ..formats.recognised import RecognisedLabels, write_recognised
    from ..recognition.io import load_features

    if input.suffix.lower() == ".npz":
        feats = load_features(input)
        video = feats.video or str(input)
    else:
        feats = _video_features(input, header)
        video = str(input)
    if fps is None:
        fps = feats.fps if feats.fps > 0 else None
    res = rec.predict_video(feats)
    classes = [str(c) for c in rec.classes_]
    track = RecognisedLabels(
        labels=[classes[i] for i in res["smoothed"]], classes=tuple(classes), fps=float(fps) if fps else 20.0,
        video=video, confidence=np.clip(np.round(res["smoothed_confidence"], 4), 0, 1),
        raw=[classes[i] for i in res["raw"]], raw_confidence=np.clip(np.round(res["confidence"], 4), 0, 1),
        smoothing=str(rec.smoothing), smoothing_window=int(rec.smoothing_window), model=str(model),
        features=str(input), extra={"emission_weight": rec.emission_weight},
    )
    write_recognised(out, track)
    n = track.n_frames
    log.info("wrote %s: %d frames, %s", out, n, ", ".join(f"{c} {track.labels.count(c)}" for c in classes if c in track.labels))


@evaluate_app.command("recognition")
def evaluate_recognition(
    dataset: Path = typer.Option(..., "--dataset", help="dataset.json (or its directory)."),
    features_dir: Optional[Path] = typer.Option(None, "--features-dir", help="Directory of <video id>.npz (train and test here)."),
    labels_dir: Optional[Path] = typer.Option(
        None, "--labels-dir", help="Score these <video id>.json from `vidstyle recognize` instead (no training)."
    ),
    model: Optional[Path] = typer.Option(
        None, "--model", "-m", help="With --labels-dir: the model that made them (its split names the test videos)."
    ),
    out: Path = typer.Option(..., "--out", "-o", help="Output metrics JSON (a PNG confusion matrix goes beside it)."),
    split: str = typer.Option("unseen-performer", "--split", help=_SPLIT_HELP),
    test_view: Optional[str] = typer.Option(None, "--test-view", help="Held-out view (unseen-view; default: seeded draw)."),
    ablation: str = typer.Option("none", "--ablation", help="none | no-grouping | no-context | no-smoothing | no-mirror."),
    words: int = typer.Option(1000, "--words", help="Vocabulary size (ablation: 500/1000/1500)."),
    vocab_method: str = typer.Option("minibatch", "--vocab-method", help="minibatch | hierarchical | kmeans."),
    classifier: str = typer.Option("ova-ovo", "--classifier", help="ova-ovo | svc-ovr."),
    baseline: bool = typer.Option(True, "--baseline/--no-baseline", help="Also score a plain SVC on the same features."),
    grouping_threshold: float = typer.Option(0.8, "--grouping-threshold", help="Word grouping correlation threshold."),
    components: int = typer.Option(128, "--components", help="PCA dimensions."),
    coarse_context: int = typer.Option(0, "--coarse-context", help="Multi-scale context: frames each side of a second histogram (0 = off)."),
    max_frames_per_class: int = typer.Option(1500, "--max-frames-per-class", help="SVM training frames per class (0 = all; default: chosen on validation performers)."),
    window: int = typer.Option(6, "--window", help="Smoothing window."),
    smoothing: str = typer.Option("duration", "--smoothing", help="duration (explicit-duration HMM: per-class run lengths of set B; default, chosen on validation performers) | viterbi (HMM over frame scores) | vote (thesis) | mean."),
    c: float = typer.Option(100.0, "--C", help="SVM cost (default: chosen on validation performers, pipelines/kickboxing/validation/recognition.json)."),
    emission_weight: float = typer.Option(1.0, "--emission-weight", help="viterbi / duration: power of the frame scores (default: chosen on validation performers)."),
    mirror: bool = typer.Option(True, "--mirror/--no-mirror", help="Also train on mirror images (scovanner2007)."),
    test_dataset: Optional[Path] = typer.Option(
        None, "--test-dataset", help="unseen-camera: dataset.json of the test performers filmed from new cameras "
        "(vidstyle demo make-dataset --unseen-camera)."),
    test_features_dir: Optional[Path] = typer.Option(
        None, "--test-features-dir", help="unseen-camera: features directory of --test-dataset's videos."),
    seed: int = typer.Option(0, "--seed", help="Random seed (split, vocabulary, sampling)."),
    jobs: int = typer.Option(-1, "--jobs", "-j", help="Parallel workers (-1 = all cores)."),
) -> None:
    """Train vocabulary (set A) and recognizer (set B) on a split, test on held-out videos, write metrics.

    With --labels-dir, score label files already written by `vidstyle recognize` against the ground truth
    instead (no training): the test videos are the split recorded in --model, else the --split/--seed one."""
    from ..formats.metrics import write_metrics
    from ..evaluation.recognition import confusion_png, evaluate_recognition as run, score_labels_dir
    from ..formats.dataset import read_dataset

    ds = read_dataset(dataset)
    if labels_dir is not None:
        if features_dir is not None:
            raise InputError("--labels-dir: scores existing labels; --features-dir is not used with it")
        tds = read_dataset(test_dataset) if test_dataset is not None else None
        if (split == "unseen-camera") != (tds is not None):
            raise InputError("--test-dataset: required with, and only used with, --split unseen-camera")
        m = score_labels_dir(ds, labels_dir, model=model, split_kind=split, seed=seed, test_view=test_view,
                             test_dataset=tds)
        ablation = "none" if model is None else "from model"
        words = (m.get("model_header") or {}).get("vocabulary", {}).get("n_words", "?")
    else:
        if features_dir is None:
            raise InputError("evaluate recognition: give --features-dir (train and test) or --labels-dir (score)")
        if model is not None:
            raise InputError("--model: only used with --labels-dir")
        params = {
            "classifier": classifier, "grouping_threshold": grouping_threshold, "n_components": components,
            "coarse_context": coarse_context,
            "max_frames_per_class": max_frames_per_class or None, "smoothing_window": window,
            "smoothing": smoothing, "C": c, "emission_weight": emission_weight, "mirror": mirror,
        }
        tds = None
        if split == "unseen-camera":
            if test_dataset is None or test_features_dir is None:
                raise InputError("--split unseen-camera: give --test-dataset and --test-features-dir")
            tds = read_dataset(test_dataset)
        elif test_dataset is not None or test_features_dir is not None:
            raise InputError("--test-dataset/--test-features-dir: only used with --split unseen-camera")
        m = run(
            ds, features_dir, split_kind=split, seed=seed, ablation=ablation, n_words=words, vocab_method=vocab_method,
            recognizer_params=params, baseline=baseline, test_view=test_view, n_jobs=jobs,
            test_dataset=tds, test_features_dir=test_features_dir,
        )
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
