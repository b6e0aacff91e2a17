"""The recognition stage as library calls: fit a vocabulary, train a recognizer (from a dataset split,
labels files or annotation files), recognise files.

These are what ``vidstyle vocabulary``, ``vidstyle train-recognizer`` and ``vidstyle recognize`` run; the
commands only parse arguments, call one of these and write the result. Defaults are the validated ones
of :mod:`vidstyle.recognition.defaults`, so the library with defaults gives the CLI's numbers.
"""

from __future__ import annotations

import functools
import logging
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from ..errors import InputError
from . import defaults as D
from .io import VideoFeatures, crop_features, features_path, load_features
from .recognizer import ActionRecognizer, load_many, load_model
from .vocabulary import Vocabulary

log = logging.getLogger(__name__)

PathLike = str | Path


@dataclass
class VocabularyRun:
    """A fitted vocabulary with what its file records: the training (set A) files and the split."""

    vocabulary: Vocabulary
    training_files: list[str]
    extra: dict[str, Any] = field(default_factory=dict)
    n_descriptors: int = 0


@dataclass
class TrainingRun:
    """A fitted recognizer with what its model file records: training files (features + labels of set B)
    and ``extra`` header fields (split, features parameters, vocabulary file)."""

    model: ActionRecognizer
    training_files: list[dict[str, str]]
    extra: dict[str, Any] = field(default_factory=dict)


def dataset_split(dataset: PathLike, split: str = D.SPLIT, seed: int = D.SEED, test_view: str | None = None):
    """``(dataset, Split)`` of a ``dataset.json``. Sets A and B of ``unseen-camera`` are those of
    ``unseen-performer`` (its test videos come from another dataset, which training does not need)."""
    from ..formats.dataset import read_dataset
    from .splits import make_split

    ds = read_dataset(dataset)
    kind = "unseen-performer" if split == "unseen-camera" else split
    return ds, make_split(ds, kind, seed=seed, test_view=test_view)


def split_header(sp, set_name: str) -> dict:
    """What a model or vocabulary records of the split it was trained on."""
    return {"kind": sp.kind, "seed": sp.seed, "set": set_name, "params": sp.params, "test": sp.test, "val": sp.val,
            "test_performers": sp.test_performers, "val_performers": sp.val_performers,
            "vocab_performers": sp.vocab_performers, "train_performers": sp.train_performers}


def features_params(paths: Sequence[PathLike]) -> dict | None:
    """The extraction parameters recorded in the first of the features files ``paths`` (informative:
    None when it records none or cannot be read)."""
    from ..formats.features import read_features

    for p in paths:
        try:
            return read_features(p).params or None
        except InputError:  # informative only
            return None
    return None


def _check_sources(features: Sequence, features_dir, dataset, what: str) -> None:
    if features and (features_dir or dataset):
        raise InputError(f"{what}: give FEATURES files or --features-dir with --dataset, not both")
    if not features and not (features_dir and dataset):
        raise InputError(f"{what}: give FEATURES files, or --features-dir and --dataset")


def train_vocabulary(
    features: Sequence[PathLike] = (),
    *,
    dataset: PathLike | None = None,
    features_dir: PathLike | None = None,
    split: str = D.SPLIT,
    test_view: str | None = None,
    words: int = D.N_WORDS,
    method: str = D.VOCAB_METHOD,
    branching: int = D.BRANCHING,
    max_descriptors: int | None = D.MAX_DESCRIPTORS,
    more_performers: Sequence[tuple[PathLike, PathLike]] = (),
    more_performers_vocab_share: float = D.MORE_PERFORMERS_VOCAB_SHARE,
    seed: int = D.SEED,
    n_jobs: int | None = -1,
) -> VocabularyRun:
    """Cluster the 3D SIFT descriptors of set A into ``words`` visual words.

    Set A is either the ``features`` files, or set A of ``split`` of ``dataset`` with the features in
    ``features_dir`` (``<video id>.npz``). ``more_performers``: (dataset, features_dir) pairs of other
    performers than ``dataset``'s (``vidstyle demo make-dataset --first-performer K``): with ``dataset``, the
    set A share of them (:func:`more_performer_sets`) joins set A. Save the result with
    :func:`vidstyle.formats.vocabulary.write_vocabulary` (``run.vocabulary``, ``run.training_files``, ``run.extra``)."""
    features = [Path(p) for p in features or []]
    _check_sources(features, features_dir, dataset, "vocabulary")
    extra: dict[str, Any] = {}
    if dataset:
        ds, sp = dataset_split(dataset, split, seed, test_view)
        features = [features_path(features_dir, i) for i in sp.vocab]
        extra = {"split": split_header(sp, "A")}
        if more_performers:
            added, record = _more_performer_videos(more_performers, {v.performer for v in ds.videos},
                                                   more_performers_vocab_share, "A", ds.classes or None)
            features += [f for f, _ in added]
            extra["split"]["more_performers"] = record
            extra["split"]["more_performers_vocab_share"] = float(more_performers_vocab_share)
    elif more_performers:
        raise InputError("--more-performers: only with --dataset (its performers are the ones left out)")
    feats = load_many(features, n_jobs=n_jobs)
    dims = {f.dim for f in feats if f.descriptors.shape[0]}
    if len(dims) > 1:
        raise InputError(f"features: descriptors of different dimensions {sorted(dims)} (mixed variants?)")
    desc = [f.descriptors for f in feats if f.descriptors.shape[0]]
    if not desc:
        raise InputError("features: no descriptors in any file")
    X = np.concatenate(desc)
    voc = Vocabulary(n_words=words, method=method, branching=branching, max_descriptors=max_descriptors,
                     random_state=seed)
    voc.fit(X)
    return VocabularyRun(voc, [str(p) for p in features], extra, int(X.shape[0]))


def _runs(mask) -> list[tuple[int, int]]:
    """Maximal half-open runs ``[a, b)`` where ``mask`` is true."""
    m = np.concatenate([[False], np.asarray(mask, dtype=bool), [False]])
    d = np.flatnonzero(np.diff(m.astype(np.int8)))
    return [(int(a), int(b)) for a, b in zip(d[::2], d[1::2])]


def _same_video(recorded: str, path: Path) -> bool:
    try:
        return Path(recorded).resolve() == path.resolve()
    except OSError:
        return False


def annotated_training(annotations: Sequence[PathLike], features: Sequence[PathLike] = (),
                       features_dir: PathLike | None = None):
    """Training pieces from annotation files (``vidstyle annotate``): for every annotated video with
    segments, its features file (the one of ``features`` whose recorded video is that video, or
    ``<features_dir>/<video stem>.npz``) cut into the runs of labelled frames, with the per-frame labels
    of its segments. Returns ``(features, label lists, classes used, training file records)``."""
    from ..formats import FormatError
    from ..formats.annotations import frame_labels, read_annotations, resolve_video_path

    loaded = {}
    for p in features or []:
        loaded[Path(p)] = load_features(p)
    feats, ylists, training, used = [], [], [], []
    for a in annotations:
        a = Path(a)
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


def _same_classes(dataset, classes, where: PathLike, what: str, subset: bool = False) -> None:
    """Refuse a second dataset (``what``, named by ``where``) whose classes are not the split's ``classes``
    (with ``subset``: not among them; labels are class names, so a dataset of some of the classes, such as
    real walks labelled ``Step``, trains the same machines)."""
    if not (classes and dataset.classes):
        return
    if subset:
        other = [c for c in dataset.classes if c not in set(classes)]
        if other:
            raise InputError(f"{where}: {what} has classes {other} the split does not have "
                             f"(the split's: {list(classes)})")
    elif list(dataset.classes) != list(classes):
        raise InputError(f"{where}: {what} has classes {list(dataset.classes)}, the split's are {list(classes)}")


def more_view_ids(dataset, performers, classes=None, where: PathLike = "--more-views") -> list[str]:
    """Ids (sorted) of the videos of ``performers`` in ``dataset``, a ``--more-views`` dataset (the same
    performers filmed from other cameras); one with other classes than ``classes``, or with none of the
    performers, is refused (``where`` names it in the error)."""
    _same_classes(dataset, classes, where, "--more-views dataset")
    want = set(performers)
    ids = sorted(v.id for v in dataset.videos if v.performer in want)
    if not ids:
        raise InputError(f"{where}: --more-views dataset has no video of the training performers {sorted(want)}")
    return ids


def _more_view_videos(more_views, performers, classes) -> list[tuple[Path, Path]]:
    """(features file, labels file) of the :func:`more_view_ids` videos of each (dataset, features_dir) pair."""
    from ..formats.dataset import read_dataset

    out: list[tuple[Path, Path]] = []
    for d, fdir in more_views:
        xd = read_dataset(d)
        by_id = xd.by_id()
        out += [(features_path(fdir, i), xd.labels_path(by_id[i])) for i in more_view_ids(xd, performers, classes, d)]
    return out


def more_performer_sets(dataset, exclude, vocab_share: float = D.MORE_PERFORMERS_VOCAB_SHARE, classes=None,
                        where: PathLike = "--more-performers") -> tuple[list[str], list[str]]:
    """Video ids (sorted) of ``dataset``'s performers that are not among ``exclude`` (the main dataset's
    performers), divided by performer: the first ``round(vocab_share * n)`` of the n new performers (sorted by
    id) go to set A (the vocabulary), the others to set B (the classifier), so the two stay disjoint by
    performer. Its classes may be some of ``classes`` (real walks labelled ``Step``: ``vidstyle demo
    make-cmu-dataset --actions Step=walk``); a dataset with a class ``classes`` lacks, or without a new
    performer, is refused."""
    _same_classes(dataset, classes, where, "dataset", subset=True)
    if not 0.0 <= float(vocab_share) <= 1.0:
        raise InputError(f"{where}: the vocabulary's share of the performers must be in 0..1, got {vocab_share}")
    new = sorted({v.performer for v in dataset.videos} - set(exclude))
    if not new:
        raise InputError(f"{where}: every performer of the dataset is one of --dataset's "
                         f"(make it with `vidstyle demo make-dataset --first-performer K`, K past them)")
    n_a = int(round(float(vocab_share) * len(new)))
    a, b = set(new[:n_a]), set(new[n_a:])
    return (sorted(v.id for v in dataset.videos if v.performer in a),
            sorted(v.id for v in dataset.videos if v.performer in b))


def _more_performer_videos(more_performers, exclude, vocab_share, set_name: str, classes=None):
    """(features file, labels file) of the set ``set_name`` ("A" or "B") share of :func:`more_performer_sets`
    of each (dataset, features_dir) pair, and what a model or vocabulary records of them."""
    from ..formats.dataset import read_dataset

    out: list[tuple[Path, Path]] = []
    record = []
    for d, fdir in more_performers:
        xd = read_dataset(d)
        by_id = xd.by_id()
        a, b = more_performer_sets(xd, exclude, vocab_share, classes, d)
        ids = a if set_name == "A" else b
        out += [(features_path(fdir, i), xd.labels_path(by_id[i])) for i in ids]
        record.append({"dataset": str(d), "features_dir": str(fdir), "set": set_name,
                       "performers": sorted({by_id[i].performer for i in ids}), "videos": len(ids)})
        if classes and xd.classes and list(xd.classes) != list(classes):
            record[-1]["classes"] = list(xd.classes)  # some of the split's classes only (real walks: Step)
    return out, record


def train(
    vocabulary: Vocabulary | PathLike,
    features: Sequence[PathLike] = (),
    *,
    labels: Sequence[PathLike] = (),
    annotations: Sequence[PathLike] = (),
    dataset: PathLike | None = None,
    features_dir: PathLike | None = None,
    split: str = D.SPLIT,
    test_view: str | None = None,
    context: int = D.CONTEXT,
    coarse_context: int = D.COARSE_CONTEXT,
    grouping: bool = D.GROUPING,
    grouping_threshold: float = D.GROUPING_THRESHOLD,
    normalize: str = D.NORMALIZE,
    n_components: int = D.N_COMPONENTS,
    classifier: str = D.CLASSIFIER,
    C: float = D.C,
    max_frames_per_class: int | None = D.MAX_FRAMES_PER_CLASS,
    smoothing_window: int = D.SMOOTHING_WINDOW,
    smoothing: str = D.SMOOTHING,
    emission_weight: float = D.EMISSION_WEIGHT,
    mirror: bool = D.MIRROR,
    allow_overlap: bool = False,
    more_views: Sequence[tuple[PathLike, PathLike]] = (),
    more_performers: Sequence[tuple[PathLike, PathLike]] = (),
    more_performers_vocab_share: float = D.MORE_PERFORMERS_VOCAB_SHARE,
    seed: int = D.SEED,
    n_jobs: int | None = -1,
) -> TrainingRun:
    """Train the frame recognizer (histograms -> grouping -> PCA -> SVMs -> smoother) on set B.

    Set B is one of: ``features`` files with one ``labels`` file each (same order); ``annotations`` files
    with their ``features`` files or a ``features_dir`` of ``<video stem>.npz``; set B of ``split`` of
    ``dataset`` with its features in ``features_dir``. ``vocabulary`` is a fitted :class:`Vocabulary` or
    its file; set B must not share files with the vocabulary's set A unless ``allow_overlap``.
    ``max_frames_per_class`` 0 or None = all frames. ``more_views``: (dataset, features_dir) pairs of the
    same performers filmed from other cameras (``vidstyle demo make-dataset --views ... --split-seed S
    --split-sets B``): with ``dataset``, their videos of set B's performers join set B (the split, and so
    every test and validation video, stays ``dataset``'s). ``more_performers``: (dataset, features_dir)
    pairs of other performers than ``dataset``'s: with ``dataset``, the set B share of them
    (:func:`more_performer_sets`, the complement of the vocabulary's) joins set B. Save the result with
    :func:`vidstyle.recognition.save_model` (``run.model``, ``run.training_files``, ``run.extra``)."""
    from ..formats.labels import check_length, read_labels

    features = [Path(p) for p in features or []]
    labels = [Path(p) for p in labels or []]
    annotations = [Path(p) for p in annotations or []]
    vocab_file = None
    if not isinstance(vocabulary, Vocabulary):
        vocab_file = Path(vocabulary)
    split_info = None
    classes = None
    if annotations:
        if dataset or labels:
            raise InputError("--annotations: give it with FEATURES files or --features-dir, not with --dataset or --labels")
        if bool(features) == bool(features_dir):
            raise InputError("--annotations: give FEATURES files or --features-dir (one of them)")
        feats, ylists, classes, training = annotated_training(annotations, features, features_dir)
        features = [Path(t["features"]) for t in training]
        labels = [Path(t["labels"]) for t in training]
    else:
        _check_sources(features, features_dir, dataset, "train-recognizer")
    if dataset:
        if labels:
            raise InputError("--labels: not used with --dataset (the manifest names the labels)")
        ds, sp = dataset_split(dataset, split, seed, test_view)
        by_id = ds.by_id()
        features = [features_path(features_dir, i) for i in sp.train]
        labels = [ds.labels_path(by_id[i]) for i in sp.train]
        classes = ds.classes or None
        split_info = split_header(sp, "B")
        added = _more_view_videos(more_views, sp.train_performers, classes)
        features += [f for f, _ in added]
        labels += [lab for _, lab in added]
        if more_views:
            split_info["more_views"] = [{"dataset": str(d), "features_dir": str(f)} for d, f in more_views]
            split_info["more_views_videos"] = len(added)
        if more_performers:
            added, record = _more_performer_videos(more_performers, {v.performer for v in ds.videos},
                                                   more_performers_vocab_share, "B", classes)
            features += [f for f, _ in added]
            labels += [lab for _, lab in added]
            split_info["more_performers"] = record
            split_info["more_performers_vocab_share"] = float(more_performers_vocab_share)
    elif more_views:
        raise InputError("--more-views: only with --dataset (its split names the performers whose other views train)")
    elif more_performers:
        raise InputError("--more-performers: only with --dataset (its performers are the ones left out)")
    if len(labels) != len(features):
        raise InputError(f"--labels: {len(labels)} labels files for {len(features)} features files")
    voc = Vocabulary.load(vocab_file) if vocab_file is not None else vocabulary
    overlap = {Path(p).resolve() for p in getattr(voc, "training_files_", [])} & {p.resolve() for p in features}
    if overlap and not allow_overlap:
        raise InputError(
            f"{vocab_file or 'vocabulary'}: {len(overlap)} training file(s) also built the vocabulary "
            f"(e.g. {sorted(overlap)[0]}); train the classifier on other videos than the vocabulary's (or pass --allow-overlap)"
        )
    if not annotations:
        tracks = [read_labels(p) for p in labels]
        feats = load_many(features, n_jobs=n_jobs)
        for f, t in zip(feats, tracks):
            check_length(t, f.n_frames, f"the features file {f.path}")
        ylists = [t.labels for t in tracks]
        if classes is None:
            classes = tracks[0].classes
            for t in tracks[1:]:
                if t.classes != classes:
                    classes = sorted(set(classes) | set(t.classes))
    rec = ActionRecognizer(
        vocabulary=voc, context=context, coarse_context=coarse_context, grouping=grouping,
        grouping_threshold=grouping_threshold, normalize=normalize, n_components=n_components,
        classifier=classifier, C=C, max_frames_per_class=max_frames_per_class or None,
        smoothing_window=smoothing_window, smoothing=smoothing, emission_weight=emission_weight, mirror=mirror,
        n_jobs=n_jobs, random_state=seed,
    )
    rec.fit(feats, ylists, classes=classes)
    return TrainingRun(
        rec,
        [{"features": str(f), "labels": str(lab)} for f, lab in zip(features, labels)],
        {"split": split_info, "features_params": features_params(features),
         "vocabulary_file": str(vocab_file) if vocab_file is not None else None},
    )


# ---------------------------------------------------------------------------------------- recognise
def video_features(path: PathLike, header: dict) -> VideoFeatures:
    """Features of a video computed with the features stage as the model's training files were (same
    variant, salient-point parameters, working rate and size, from the model ``header``)."""
    import tempfile

    path = Path(path)
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


def load_recognizer(model: PathLike, window: int | None = None, smoothing: str | None = None,
                    emission_weight: float | None = None) -> tuple[ActionRecognizer, dict]:
    """``(recognizer, header)`` of a model file with the smoothing overrides applied (None keeps the
    model's). Loaded once per process and file version (a retrained file at the same path reloads)."""
    try:
        st = Path(model).stat()
    except OSError:
        raise InputError(f"{model}: model file not found") from None
    return _load_cached(str(model), st.st_mtime_ns, st.st_size, window, smoothing, emission_weight)


@functools.lru_cache(maxsize=2)
def _load_cached(model: str, _mtime_ns: int, _size: int, window: int | None, smoothing: str | None,
                 emission_weight: float | None):
    rec, header = load_model(Path(model))
    if window is not None:
        rec.smoothing_window = window
    if smoothing is not None:
        rec.smoothing = smoothing
    if emission_weight is not None:
        rec.emission_weight = emission_weight
    rec._check_prediction_params()
    return rec, header


def recognize_file(model: ActionRecognizer, header: dict, input: PathLike, fps: float | None = None,
                   model_path: PathLike | None = None, fusion: tuple | None = None):
    """Per-frame labels of one features ``.npz`` (or video: its features are computed as the model's
    training files were) as a :class:`~vidstyle.formats.recognised.RecognisedLabels`: raw and smoothed
    labels with confidence. ``fps``: frame rate to record (default: the features', else 20).

    ``fusion = (pose_model, poses_path, weight[, emission_weight])``: late fusion
    (:mod:`vidstyle.recognition.fusion`) with a pose-sequence recognizer on that video's ``poses.json``,
    ``weight`` on the pose recognizer's scores; the labels are then smoothed by the pose recognizer's
    smoother (its classes name them) with the fused scores to the power ``emission_weight`` (default
    :data:`.defaults.FUSION_EMISSION_WEIGHT`)."""
    from ..formats.recognised import RecognisedLabels

    input = Path(input)
    if header.get("input") == "pose":
        return _recognize_poses(model, input, fps, model_path)
    if input.suffix.lower() == ".npz":
        feats = load_features(input)
        video = feats.video or str(input)
    else:
        feats = video_features(input, header)
        video = str(input)
    if fps is None:
        fps = feats.fps if feats.fps > 0 else None
    res = model.predict_video(feats)
    extra = {"emission_weight": model.emission_weight}
    if fusion is not None:
        from ..formats.poses import read_poses
        from .fusion import fusion_power, smooth_fused
        from .posefeatures import track_from_poses

        pose_model, poses_path, weight = fusion[:3]
        power = fusion_power(fusion[3] if len(fusion) > 3 else None)
        n = len(res["raw"])
        pres = pose_model.predict_video(track_from_poses(read_poses(poses_path), float(pose_model.fps), n))
        if len(pres["raw"]) != n:
            raise InputError(f"{poses_path}: {len(pres['raw'])} pose frames for the {n} frames of {input}")
        res = smooth_fused(pose_model, pres["scores"], model, res["scores"], weight, power)
        model = pose_model
        extra.update(emission_weight=power, fusion={"poses": str(poses_path), "weight_pose": weight})
    classes = [str(c) for c in model.classes_]
    return RecognisedLabels(
        labels=[classes[i] for i in res["smoothed"]], classes=tuple(classes), fps=float(fps) if fps else D.FPS,
        video=video, confidence=np.clip(np.round(res["smoothed_confidence"], 4), 0, 1),
        raw=[classes[i] for i in res["raw"]], raw_confidence=np.clip(np.round(res["confidence"], 4), 0, 1),
        smoothing=str(model.smoothing), smoothing_window=int(model.smoothing_window), model=str(model_path),
        features=str(input), extra=extra,
    )


def _recognize_poses(model, input: Path, fps: float | None, model_path):
    """:func:`recognize_file` of a pose model: ``input`` is a ``poses.json`` (``vidstyle pose``) whose
    frames are a video's decoded frames at ``fps`` (default: the model's working rate)."""
    from ..formats.poses import read_poses
    from ..formats.recognised import RecognisedLabels
    from .posefeatures import track_from_poses

    if input.suffix.lower() != ".json":
        raise InputError(f"{input}: a pose model recognises poses.json files (run `vidstyle pose VIDEO --out P` first)")
    fps = float(fps or model.fps)
    if abs(fps - float(model.fps)) > 1e-6:
        raise InputError(f"{input}: poses at {fps:g} fps, the model was trained at {model.fps:g} fps "
                         "(resampling is not implemented yet)")
    poses = read_poses(input)
    res = model.predict_video(track_from_poses(poses, fps))
    classes = [str(c) for c in model.classes_]
    return RecognisedLabels(
        labels=[classes[i] for i in res["smoothed"]], classes=tuple(classes), fps=fps, video=poses.video,
        confidence=np.clip(np.round(res["smoothed_confidence"], 4), 0, 1),
        raw=[classes[i] for i in res["raw"]], raw_confidence=np.clip(np.round(res["confidence"], 4), 0, 1),
        smoothing=str(model.smoothing), smoothing_window=int(model.smoothing_window), model=str(model_path),
        features=str(input), extra={"emission_weight": model.emission_weight, "input": "pose"},
    )


def _recognize_task(item: tuple) -> None:
    """One input of :func:`recognize` (module level, so joblib and Dask workers can run it)."""
    from ..formats.recognised import write_recognised

    model, window, smoothing, emission_weight, input, target, fps, fusion = item
    rec, header = load_recognizer(model, window, smoothing, emission_weight)
    fuse = None
    if fusion is not None:
        pose_path, poses, weight, power = fusion
        fuse = (load_recognizer(pose_path)[0], poses, weight, power)
    track = recognize_file(rec, header, input, fps, model_path=model, fusion=fuse)
    write_recognised(target, track)
    classes = [str(c) for c in rec.classes_]
    log.info("wrote %s: %d frames, %s", target, track.n_frames,
             ", ".join(f"{c} {track.labels.count(c)}" for c in classes if c in track.labels))


def recognize(model: PathLike, inputs: Sequence[PathLike], targets: Sequence[PathLike], *,
              window: int | None = None, smoothing: str | None = None,
              emission_weight: float | None = None, fps: float | None = None, jobs: int = 1,
              scheduler: str | None = None, pose_model: PathLike | None = None,
              poses: Sequence[PathLike] | None = None, fusion_weight: float | None = None,
              fusion_emission_weight: float | None = None) -> None:
    """Recognise every input (features ``.npz`` or video) with the model file ``model`` and write its
    labels JSON to the matching target, in parallel (``jobs`` workers or a Dask ``scheduler``; each worker
    loads the model once). With ``pose_model``, ``poses`` (one ``poses.json`` per input) and
    ``fusion_weight``: the late fusion of ``model`` (3D SIFT) with that pose-sequence recognizer
    (:func:`recognize_file`; ``fusion_emission_weight``: the fused scores' power in its smoother, default
    :data:`.defaults.FUSION_EMISSION_WEIGHT`). A bad model or missing input fails before any work."""
    from ..parallel import parallel_map

    if len(inputs) != len(targets):
        raise InputError(f"recognize: {len(inputs)} inputs for {len(targets)} outputs")
    for p in inputs:
        if not Path(p).exists():
            raise InputError(f"{p}: file not found")
    rec, header = load_recognizer(model, window, smoothing, emission_weight)  # a bad model fails here, once
    fusion = [None] * len(inputs)
    if pose_model is not None:
        if header.get("input") == "pose":
            raise InputError(f"{model}: fusion needs a 3D SIFT recognizer as the model, this is a pose recognizer")
        prec, pheader = load_recognizer(pose_model)
        if pheader.get("input") != "pose":
            raise InputError(f"{pose_model}: not a pose-sequence recognizer (train-recognizer --features pose)")
        if poses is None or len(poses) != len(inputs):
            raise InputError(f"recognize: fusion needs one poses.json per input ({len(inputs)})")
        for p in poses:
            if not Path(p).exists():
                raise InputError(f"{p}: file not found (the poses of an input; vidstyle pose VIDEO --out-dir)")
        if fusion_weight is None or not 0.0 <= fusion_weight <= 1.0:
            raise InputError(f"recognize: the fusion weight must be in [0, 1], got {fusion_weight}")
        from .fusion import fusion_power

        power = fusion_power(fusion_emission_weight)
        fusion = [(str(pose_model), str(p), float(fusion_weight), power) for p in poses]
    items = [(str(model), window, smoothing, emission_weight, str(p), str(t), fps, f)
             for p, t, f in zip(inputs, targets, fusion)]
    parallel_map(_recognize_task, items, jobs=jobs, scheduler=scheduler, description="recognize")
