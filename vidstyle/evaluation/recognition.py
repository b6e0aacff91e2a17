"""Recognition metrics (``docs/results.md``, terms) and the train-and-test run behind
``vidstyle evaluate recognition``.

- frame accuracy, raw and smoothed: fraction of test frames whose predicted class equals the truth;
- video accuracy: for each *single-action* test video, the most frequent predicted label among the frames
  predicted as an action (classes in ``ignore``, Guard and Step, are not actions) must equal the video's
  action; a video with no frame predicted as an action counts as wrong. Reported on the smoothed labels
  (``video_accuracy``) and on the raw ones;
- confusion matrices, row-normalised (rows = truth, columns = prediction; a class absent from the test
  truth has a zero row), as JSON and as a PNG heatmap drawn with OpenCV;
- ``segments``: per label kind, the boundary-tolerant frame accuracy at 1-3 frames and the segmental F1
  at overlaps of 10 / 25 / 50 % (:mod:`.segments`): how much of the frame error is where a boundary falls,
  and whether the actions are found as segments.

Ablations (each switches one thesis choice off, everything else equal): ``no-grouping``, ``no-context``
(histogram of frame n only), ``no-smoothing`` (window 1), ``no-mirror`` (no mirror-image training videos). Vocabulary size is ``--words``; 2D SIFT and the
two 3D SIFT variants are different *features directories* (the features stage writes them, ``--variant
thesis | scovanner2007 | sift2d``), so they are measured by pointing ``--features-dir`` at each; the metrics
record the features' ``params``. ``scripts/ablation_recognition.py`` runs the whole table.

:func:`score_labels_dir` scores label files already written by ``vidstyle recognize`` (``--labels-dir``),
for pipelines that train, recognise and evaluate as separate stages.
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from ..errors import InputError, ParameterError
from ..formats.dataset import Dataset
from ..formats.labels import check_length, read_labels
from ..formats.recognised import read_recognised
from ..recognition import defaults as D
from ..recognition.io import features_path, load_features
from ..recognition.splits import make_split
from .segments import boundary_scores

log = logging.getLogger(__name__)

ABLATIONS = ("none", "no-grouping", "no-context", "no-smoothing", "no-mirror")
IGNORE = ("Guard", "Step")


def confusion_counts(y_true: np.ndarray, y_pred: np.ndarray, n_classes: int) -> np.ndarray:
    cm = np.zeros((n_classes, n_classes), np.int64)
    np.add.at(cm, (np.asarray(y_true, np.int64), np.asarray(y_pred, np.int64)), 1)
    return cm


def row_normalise(cm: np.ndarray) -> np.ndarray:
    s = cm.sum(axis=1, keepdims=True).astype(float)
    return np.divide(cm, s, out=np.zeros(cm.shape), where=s > 0)


def video_label(pred: Sequence[str], ignore: Sequence[str] = IGNORE) -> str | None:
    """Most frequent predicted action (ties -> first in sorted order); None when no frame is an action."""
    acts = [p for p in pred if p not in set(ignore)]
    if not acts:
        return None
    names, counts = np.unique(np.asarray(acts), return_counts=True)
    return str(names[np.argmax(counts)])


def confusion_png(path: str | Path, cm: np.ndarray, classes: Sequence[str], title: str = "") -> None:
    """Row-normalised confusion matrix as a heatmap with the values written in the cells."""
    import cv2

    from ..fileio import atomic_path

    k = len(classes)
    cell, left, top = 64, 150, 150
    h, w = top + k * cell + 20, left + k * cell + 20
    img = np.full((h, w, 3), 255, np.uint8)
    vals = np.clip(np.asarray(cm, float), 0, 1)
    heat = cv2.applyColorMap((vals * 255).astype(np.uint8), cv2.COLORMAP_VIRIDIS)
    font = cv2.FONT_HERSHEY_SIMPLEX
    for i in range(k):
        for j in range(k):
            x0, y0 = left + j * cell, top + i * cell
            img[y0 : y0 + cell, x0 : x0 + cell] = heat[i, j]
            txt = f"{vals[i, j]:.2f}"
            colour = (0, 0, 0) if vals[i, j] > 0.6 else (255, 255, 255)
            cv2.putText(img, txt, (x0 + 10, y0 + cell // 2 + 5), font, 0.45, colour, 1, cv2.LINE_AA)
        cv2.putText(img, str(classes[i])[:14], (5, top + i * cell + cell // 2 + 5), font, 0.45, (0, 0, 0), 1, cv2.LINE_AA)
    # column labels, written rotated: draw on a strip and rotate it
    strip = np.full((cell * k, top - 10, 3), 255, np.uint8)
    for j in range(k):
        cv2.putText(strip, str(classes[j])[:14], (5, j * cell + cell // 2 + 5), font, 0.45, (0, 0, 0), 1, cv2.LINE_AA)
    rot = cv2.rotate(strip, cv2.ROTATE_90_COUNTERCLOCKWISE)
    img[5 : 5 + rot.shape[0], left : left + rot.shape[1]] = rot
    if title:
        cv2.putText(img, title[:60], (5, 18), font, 0.5, (0, 0, 0), 1, cv2.LINE_AA)
    cv2.putText(img, "rows: truth, columns: predicted", (5, h - 5), font, 0.4, (80, 80, 80), 1, cv2.LINE_AA)
    with atomic_path(path) as tmp:
        if not cv2.imwrite(str(tmp), img):
            raise InputError(f"{path}: could not write PNG")


def score_videos(
    classes: Sequence[str],
    truths: Sequence[Sequence[str]],
    outputs: Sequence[dict],
    ids: Sequence[str],
    actions: Sequence[str | None],
    ignore: Sequence[str] = IGNORE,
) -> dict[str, Any]:
    """Frame and video metrics of predictions (``outputs`` of :meth:`ActionRecognizer.predict_video`)."""
    classes = list(classes)
    index = {c: i for i, c in enumerate(classes)}
    K = len(classes)
    cm_raw = np.zeros((K, K), np.int64)
    cm_sm = np.zeros((K, K), np.int64)
    per_video = []
    vid_ok_sm, vid_ok_raw, n_single = 0, 0, 0
    ys = []
    for vid, truth, out, action in zip(ids, truths, outputs, actions):
        y = np.array([index[c] for c in truth], np.int64)
        ys.append(y)
        cm_raw += confusion_counts(y, out["raw"], K)
        cm_sm += confusion_counts(y, out["smoothed"], K)
        row = {
            "id": vid,
            "n_frames": int(len(y)),
            "frame_accuracy_raw": float((out["raw"] == y).mean()) if len(y) else 0.0,
            "frame_accuracy_smoothed": float((out["smoothed"] == y).mean()) if len(y) else 0.0,
        }
        if action:
            n_single += 1
            got_sm = video_label([classes[i] for i in out["smoothed"]], ignore)
            got_raw = video_label([classes[i] for i in out["raw"]], ignore)
            vid_ok_sm += got_sm == action
            vid_ok_raw += got_raw == action
            row.update(action=action, predicted=got_sm, predicted_raw=got_raw, correct=got_sm == action)
        per_video.append(row)
    n = int(cm_raw.sum())
    per_class = {
        c: {
            "n_frames": int(cm_raw[i].sum()),
            "recall_raw": float(cm_raw[i, i] / cm_raw[i].sum()) if cm_raw[i].sum() else None,
            "recall_smoothed": float(cm_sm[i, i] / cm_sm[i].sum()) if cm_sm[i].sum() else None,
        }
        for i, c in enumerate(classes)
    }
    return {
        "frame_accuracy": {
            "raw": float(np.trace(cm_raw) / n) if n else 0.0,
            "smoothed": float(np.trace(cm_sm) / n) if n else 0.0,
        },
        "video_accuracy": float(vid_ok_sm / n_single) if n_single else None,
        "video_accuracy_raw": float(vid_ok_raw / n_single) if n_single else None,
        "n_test_videos": len(ids),
        "n_test_single_videos": n_single,
        "n_test_frames": n,
        "per_class": per_class,
        "confusion": {
            "classes": classes,
            "raw": row_normalise(cm_raw).round(4).tolist(),
            "smoothed": row_normalise(cm_sm).round(4).tolist(),
            "counts_raw": cm_raw.tolist(),
            "counts_smoothed": cm_sm.tolist(),
        },
        "segments": {kind: boundary_scores(ys, [np.asarray(o[kind]) for o in outputs]) for kind in ("smoothed", "raw")},
        "videos": per_video,
    }


def ablation_params(ablation: str) -> dict[str, Any]:
    if ablation not in ABLATIONS:
        raise ParameterError("ablation", f"must be one of {', '.join(ABLATIONS)}, got {ablation!r}")
    return {
        "none": {},
        "no-grouping": {"grouping": False},
        "no-context": {"context": 0},
        "no-smoothing": {"smoothing_window": 1},
        "no-mirror": {"mirror": False},
    }[ablation]


def load_set(dataset: Dataset, features_dir: Path, ids: Sequence[str], n_jobs: int | None = None):
    """``(features, labels)`` of the videos ``ids`` of ``dataset``: each video's features file
    ``<features_dir>/<id>.npz`` and its ground-truth labels track (lengths checked), in ``ids`` order,
    loaded with ``n_jobs`` threads."""
    from joblib import Parallel, delayed

    by_id = dataset.by_id()

    def one(i):
        f = load_features(features_path(features_dir, i))
        t = read_labels(dataset.labels_path(by_id[i]))
        check_length(t, f.n_frames, f"the features file {f.path}")
        return f, t

    pairs = Parallel(n_jobs=n_jobs or 1, prefer="threads")(delayed(one)(i) for i in ids)
    return [p[0] for p in pairs], [p[1] for p in pairs]


def score_set(rec, dataset: Dataset, features_dir: Path, ids: Sequence[str], n_jobs: int | None = None) -> dict:
    """Raw and smoothed frame accuracy, video accuracy and frame count of the fitted recognizer ``rec`` on
    the videos ``ids`` of ``dataset`` (features in ``features_dir``): the validation scripts' score of a
    candidate."""
    feats, labels = load_set(dataset, features_dir, ids, n_jobs)
    by = dataset.by_id()
    actions = [by[i].action if by[i].kind == "single" else None for i in ids]
    outs = [rec.smooth(*rec.frame_scores(H)) for H in rec.histograms_many(feats)]
    m = score_videos(rec.classes_, [t.labels for t in labels], outs, list(ids), actions)
    return {"raw": m["frame_accuracy"]["raw"], "smoothed": m["frame_accuracy"]["smoothed"],
            "video": m["video_accuracy"], "frames": m["n_test_frames"]}


def evaluate_recognition(
    dataset: Dataset,
    features_dir: str | Path,
    split_kind: str = D.SPLIT,
    seed: int = D.SEED,
    ablation: str = "none",
    n_words: int = D.N_WORDS,
    vocab_method: str = D.VOCAB_METHOD,
    recognizer_params: dict | None = None,
    baseline: bool = True,
    test_view: str | None = None,
    n_jobs: int | None = None,
    test_dataset: Dataset | None = None,
    test_features_dir: str | Path | None = None,
    score_set: str = "test",
) -> dict[str, Any]:
    """Train the vocabulary on A and the recognizer on B of a seeded split, score the test set T (or, with
    ``score_set="val"``, the validation set V: what ``scripts/validate_recognition.py`` tunes on).

    ``test_dataset`` / ``test_features_dir``: the unseen-camera videos and their features
    (``split_kind="unseen-camera"``)."""
    from ..recognition.recognizer import ActionRecognizer
    from ..recognition.vocabulary import Vocabulary

    if score_set not in ("test", "val"):
        raise InputError(f"score_set: must be test or val, got {score_set!r}")
    features_dir = Path(features_dir)
    split = make_split(dataset, split_kind, seed=seed, test_view=test_view, test_dataset=test_dataset)
    log.info("split %s: A %d, B %d, V %d, T %d videos; scoring %s", split.kind, len(split.vocab), len(split.train),
             len(split.val), len(split.test), "V" if score_set == "val" else "T")
    if score_set == "val":
        score_ids, score_ds, score_dir = split.val, dataset, features_dir
    elif split.kind == "unseen-camera":
        if test_features_dir is None:
            raise InputError("unseen-camera: needs the features directory of the unseen-camera videos")
        score_ids, score_ds, score_dir = split.test, test_dataset, Path(test_features_dir)
    else:
        score_ids, score_ds, score_dir = split.test, dataset, features_dir
    params = dict(recognizer_params or {})
    params.update(ablation_params(ablation))
    params.setdefault("random_state", seed)
    params.setdefault("n_jobs", n_jobs)

    t0 = time.perf_counter()
    feats_a, _ = load_set(dataset, features_dir, split.vocab, n_jobs)
    desc = np.concatenate([f.descriptors for f in feats_a if f.descriptors.shape[0]])
    voc = Vocabulary(n_words=n_words, method=vocab_method, random_state=seed).fit(desc)
    voc.training_files_ = [f.path for f in feats_a]
    t_voc = time.perf_counter() - t0
    del feats_a, desc

    t0 = time.perf_counter()
    feats_b, labels_b = load_set(dataset, features_dir, split.train, n_jobs)
    classes = dataset.classes or sorted({c for t in labels_b for c in t.labels})
    rec = ActionRecognizer(vocabulary=voc, **params).fit(feats_b, [t.labels for t in labels_b], classes=classes)
    t_train = time.perf_counter() - t0

    t0 = time.perf_counter()
    feats_t, labels_t = load_set(score_ds, score_dir, score_ids, n_jobs)
    unknown = sorted({c for t in labels_t for c in t.labels} - set(rec.classes_))
    if unknown:
        raise InputError(f"test labels: classes not seen in training: {unknown[:5]}")
    Hs = rec.histograms_many(feats_t)
    outputs = [rec.predict_histograms(H) for H in Hs]
    t_pred = time.perf_counter() - t0

    by_id = score_ds.by_id()
    actions = [by_id[i].action if by_id[i].kind == "single" else None for i in score_ids]
    truths = [t.labels for t in labels_t]
    metrics = score_videos(rec.classes_, truths, outputs, score_ids, actions)
    feature_params = None
    try:
        from ..formats.features import read_features

        feature_params = read_features(features_path(features_dir, split.vocab[0])).params or None
    except InputError:  # params are informative only
        feature_params = None
    result: dict[str, Any] = {
        "kind": "vidstyle.metrics.recognition",
        "schema_version": 1,
        "seed": seed,
        "split": split.to_dict(),
        "scored_set": "V" if score_set == "val" else "T",
        "ablation": ablation,
        "params": {
            "vocabulary": voc.get_params(),
            "recognizer": rec.public_params(),
            "features": feature_params,
            "features_dir": str(features_dir),
        },
        "model": rec.summary(),
        **metrics,
        "timing_s": {"vocabulary": t_voc, "train": t_train, "predict": t_pred},
    }
    if baseline and rec.classifier != "svc-ovr":
        # same vocabulary, histograms and PCA features; only the classifier differs
        t0 = time.perf_counter()
        base = ActionRecognizer(vocabulary=voc, **{**params, "classifier": "svc-ovr"}).fit(
            feats_b, [t.labels for t in labels_b], classes=classes
        )
        bout = [base.predict_histograms(H) for H in Hs]
        bm = score_videos(base.classes_, truths, bout, score_ids, actions)
        result["baseline"] = {
            "classifier": "svc-ovr",
            "frame_accuracy": bm["frame_accuracy"],
            "video_accuracy": bm["video_accuracy"],
            "train_s": time.perf_counter() - t0,
        }
    return result


def score_labels_dir(
    dataset: Dataset,
    labels_dir: str | Path,
    model: str | Path | None = None,
    split_kind: str = "unseen-performer",
    seed: int = 0,
    test_view: str | None = None,
    ignore: Sequence[str] = IGNORE,
    test_dataset: Dataset | None = None,
) -> dict[str, Any]:
    """Score ``<labels_dir>/<video id>.json`` (written by ``vidstyle recognize``: ``labels`` smoothed,
    ``raw``) against the dataset's ground truth, without training anything.

    The test videos are the ``split.test`` recorded in ``model``'s header when it has one (the model knows
    which videos it must not have seen), else the ``split_kind``/``seed``/``test_view`` split of
    ``dataset``. With ``split_kind="unseen-camera"`` they are the test performers' videos of
    ``test_dataset`` (the split of the model's seed; the model must have trained on no test performer).
    Every test video needs a labels file; a model whose training files include a test video
    is refused (its scores would not be of unseen data)."""
    from ..formats import FormatError
    from ..recognition.recognizer import read_header

    labels_dir = Path(labels_dir)
    if not labels_dir.is_dir():
        raise InputError(f"{labels_dir}: labels directory not found")
    header = read_header(model) if model is not None else None
    split_doc = (header or {}).get("split") or None
    if split_kind == "unseen-camera":
        if test_dataset is None:
            raise InputError("unseen-camera: needs the dataset of the unseen-camera videos")
        sp = make_split(dataset, "unseen-camera", seed=(header or {}).get("seed", seed), test_dataset=test_dataset)
        if split_doc and split_doc.get("test_performers") and sorted(split_doc["test_performers"]) != sp.test_performers:
            raise InputError(f"{model}: its test performers {split_doc['test_performers']} are not those of the "
                             f"unseen-camera split {sp.test_performers}")
        split_info: dict[str, Any] = {**sp.to_dict(), "from": None if model is None else str(model)}
        test = sp.test
        dataset = test_dataset
    elif split_doc and split_doc.get("test"):
        test = list(split_doc["test"])
        split_info = {"kind": split_doc.get("kind"), "seed": split_doc.get("seed"), "test": test,
                      "params": split_doc.get("params"), "from": str(model)}
        for key in ("test_performers", "val_performers", "vocab_performers", "train_performers"):
            if split_doc.get(key) is not None:
                split_info[key] = split_doc[key]
    else:
        sp = make_split(dataset, split_kind, seed=seed, test_view=test_view)
        test = sp.test
        split_info = sp.to_dict()
        if header is not None:
            log.warning("%s records no split; scoring the %s split (seed %d)", model, split_kind, seed)
    by_id = dataset.by_id()
    unknown = [i for i in test if i not in by_id]
    if unknown:
        raise InputError(f"{model}: test videos not in the dataset: {unknown[:5]}")
    if header is not None:
        trained = {Path(f.get("features", "")).stem for f in header.get("training_files", [])}
        trained |= {Path(f).stem for f in header.get("vocabulary", {}).get("training_files", [])}
        leak = sorted(trained & set(test))
        if leak:
            raise InputError(f"{model}: trained on test videos {leak[:5]}; its labels cannot be scored as unseen")
    classes = list(dataset.classes) if dataset.classes else None
    truths, outputs = [], []
    decoding: set = set()
    for i in test:
        path = labels_dir / f"{i}.json"
        if not path.is_file():
            raise InputError(f"{path}: labels file of test video {i} not found")
        truth = read_labels(dataset.labels_path(by_id[i])).labels
        rec = read_recognised(path, n_frames=len(truth))
        if classes is None:
            classes = list(rec.classes)
        index = {c: k for k, c in enumerate(classes)}
        pred = {}
        for key, seq in (("smoothed", rec.labels), ("raw", rec.raw if rec.raw is not None else rec.labels)):
            bad = sorted({c for c in seq if c not in index})
            if bad:
                raise FormatError(path, "labels", f"classes {bad[:5]} are not among the dataset's classes {classes}")
            pred[key] = np.array([index[c] for c in seq], np.int64)
        outputs.append(pred)
        truths.append(truth)
        decoding.add((rec.smoothing, rec.extra.get("emission_weight"), rec.smoothing_window))
    actions = [by_id[i].action if by_id[i].kind == "single" else None for i in test]
    metrics = score_videos(classes, truths, outputs, test, actions, ignore)
    return {
        "kind": "vidstyle.metrics.recognition",
        "schema_version": 1,
        "seed": (header or {}).get("seed", seed),
        "split": split_info,
        "ablation": "none",
        "source": {"labels_dir": str(labels_dir), "model": None if model is None else str(model)},
        "params": None if header is None else {"recognizer": header.get("params"), "features": header.get("features_params")},
        "model_header": header,
        # how the labels were decoded (recognize can override the model's smoother)
        "decoding": [{"smoothing": a, "emission_weight": b, "smoothing_window": c} for a, b, c in sorted(decoding, key=str)],
        **metrics,
    }


@dataclass
class RecognitionRun:
    """A recognition evaluation: its metrics document, and the ablation and words it ran with."""

    metrics: dict[str, Any]
    ablation: str
    words: int | str


def run_evaluation(
    dataset: str | Path,
    *,
    features_dir: str | Path | None = None,
    labels_dir: str | Path | None = None,
    model: str | Path | None = None,
    split: str = D.SPLIT,
    test_view: str | None = None,
    ablation: str = "none",
    words: int = D.N_WORDS,
    vocab_method: str = D.VOCAB_METHOD,
    classifier: str = D.CLASSIFIER,
    baseline: bool = True,
    grouping_threshold: float = D.GROUPING_THRESHOLD,
    n_components: int = D.N_COMPONENTS,
    coarse_context: int = D.COARSE_CONTEXT,
    max_frames_per_class: int | None = D.MAX_FRAMES_PER_CLASS,
    smoothing_window: int = D.SMOOTHING_WINDOW,
    smoothing: str = D.SMOOTHING,
    C: float = D.C,
    emission_weight: float = D.EMISSION_WEIGHT,
    mirror: bool = D.MIRROR,
    test_dataset: str | Path | None = None,
    test_features_dir: str | Path | None = None,
    seed: int = D.SEED,
    n_jobs: int | None = -1,
) -> "RecognitionRun":
    """What ``vidstyle evaluate recognition`` computes, with the recognizer's validated defaults: with
    ``features_dir``, train a vocabulary (set A) and recognizer (set B) on ``split`` of ``dataset`` and score
    the held-out videos (:func:`evaluate_recognition`; ``unseen-camera`` tests on ``test_dataset`` /
    ``test_features_dir``); with ``labels_dir``, score the label files ``vidstyle recognize`` wrote
    (:func:`score_labels_dir`; the test videos are those of ``model``'s split, else of ``split``/``seed``).
    Returns the metrics document with the ablation and vocabulary size it ran with."""
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
        return RecognitionRun(m, "none" if model is None else "from model",
                              (m.get("model_header") or {}).get("vocabulary", {}).get("n_words", "?"))
    if features_dir is None:
        raise InputError("evaluate recognition: give --features-dir (train and test) or --labels-dir (score)")
    if model is not None:
        raise InputError("--model: only used with --labels-dir")
    params = {
        "classifier": classifier, "grouping_threshold": grouping_threshold, "n_components": n_components,
        "coarse_context": coarse_context,
        "max_frames_per_class": max_frames_per_class or None, "smoothing_window": smoothing_window,
        "smoothing": smoothing, "C": C, "emission_weight": emission_weight, "mirror": mirror,
    }
    tds = None
    if split == "unseen-camera":
        if test_dataset is None or test_features_dir is None:
            raise InputError("--split unseen-camera: give --test-dataset and --test-features-dir")
        tds = read_dataset(test_dataset)
    elif test_dataset is not None or test_features_dir is not None:
        raise InputError("--test-dataset/--test-features-dir: only used with --split unseen-camera")
    m = evaluate_recognition(
        ds, features_dir, split_kind=split, seed=seed, ablation=ablation, n_words=words, vocab_method=vocab_method,
        recognizer_params=params, baseline=baseline, test_view=test_view, n_jobs=n_jobs,
        test_dataset=tds, test_features_dir=test_features_dir,
    )
    return RecognitionRun(m, ablation, words)
