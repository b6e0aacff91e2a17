"""The frame-wise action recognizer: vocabulary -> context histograms -> word grouping -> normalisation
-> PCA -> SVMs -> smoothing (thesis 4.2-4.3), as one estimator.

Model file (``.joblib``, owner :mod:`vidstyle.formats.recognizer_model` on the one model-file machinery
:mod:`vidstyle.formats.models`): ``{"header": <JSON str>, "model": ActionRecognizer}``; the header holds
``kind`` ("vidstyle.recognizer"), ``schema_version``, ``params``, ``seed``, ``classes``, ``training_files``
(features and labels of set B), ``vocabulary`` (its params and training files = set A), ``sklearn``
and ``vidstyle`` versions, ``n_train_frames`` and grouping statistics. :func:`read_header` reads it without
trusting anything else.
"""

from __future__ import annotations

import json
import logging
from pathlib import Path
from typing import Any, Sequence

import numpy as np
import scipy.sparse as sp
from sklearn.base import BaseEstimator

from ..errors import InputError, ParameterError
from . import defaults as D
from .framebase import CLASSIFIERS, FrameRecognizerMixin, sample_per_class
from .histograms import (NORMS, FrameFeaturizer, IdentityGrouping, WordGrouping, context_sum, frame_word_counts,
                         normalize_rows)
from .io import VideoFeatures, load_features
from .smoothing import transition_matrix
from .vocabulary import Vocabulary

log = logging.getLogger(__name__)

def _as_features(x: VideoFeatures | str | Path) -> VideoFeatures:
    return x if isinstance(x, VideoFeatures) else load_features(x)


def load_many(paths: Sequence[str | Path], n_jobs: int | None = None) -> list[VideoFeatures]:
    """Load features files in parallel (npz inflation releases the GIL, so threads suffice)."""
    from joblib import Parallel, delayed

    if len(paths) <= 1 or n_jobs in (None, 1):
        return [load_features(p) for p in paths]
    return Parallel(n_jobs=n_jobs, prefer="threads")(delayed(load_features)(p) for p in paths)


class ActionRecognizer(FrameRecognizerMixin, BaseEstimator):
    """Per-frame action recognizer with scikit-learn conventions.

    Parameters
    ----------
    vocabulary: a fitted :class:`Vocabulary` (fitted on set A). ``fit`` refuses to run without one.
    context: frames on each side counted into a frame's histogram (thesis 2 -> frames n-2..n+2; 0 = ablation).
    coarse_context: when > 0, a second histogram of the frames n-coarse_context..n+coarse_context is
        appended to each frame's (multi-scale temporal context: a short action seen with what surrounds
        it); both blocks go through the same word grouping (fitted on the fine block) and are normalised
        separately before the PCA. 0 (default) = the thesis' single context.
    grouping: pool contextually related words (:class:`WordGrouping`); False = ablation.
    grouping_threshold, grouping_distribution, grouping_pooling: see :class:`WordGrouping`.
    normalize: ``l1``, ``sqrt`` (Hellinger), ``l2`` or ``none``, after grouping.
    n_components: PCA dimensions (capped by the data).
    classifier: ``"ova-ovo"`` (thesis) or ``"svc-ovr"`` (plain multi-class SVC baseline).
    C, gamma: of the RBF SVMs.
    max_frames_per_class: training frames sampled per class (RBF SVM training is O(n^2)); None = all.
    smoothing_window, smoothing, emission_weight: see :func:`smooth_labels` (``viterbi`` decodes with the
        frame-to-frame label transitions counted in the training labels, ``transitions_``; ``duration``
        with the per-class run lengths and class changes of the training labels, ``durations_``).
    mirror: also train on the left-right mirror image of every training video (a southpaw seen from the
        mirrored view), computed in descriptor space (:func:`~vidstyle.features.scovanner2007.mirror_descriptors`);
        only scovanner2007 descriptors have an exact-enough mirror, other variants train without it (logged).
    n_jobs: joblib workers for per-video work and SVM training.
    random_state: seed of every random choice.
    """

    def __init__(
        self,
        vocabulary: Vocabulary | None = None,
        context: int = D.CONTEXT,
        coarse_context: int = D.COARSE_CONTEXT,
        grouping: bool = D.GROUPING,
        grouping_threshold: float = D.GROUPING_THRESHOLD,
        grouping_distribution: str = "frames",
        grouping_pooling: str = "components",
        normalize: str = D.NORMALIZE,
        n_components: int = D.N_COMPONENTS,
        classifier: str = D.CLASSIFIER,
        # C, the per-class cap, the grouping threshold, the coarse context, the smoother and its emission
        # weight: validated defaults, see vidstyle.recognition.defaults.
        C: float = D.C,
        gamma: float | str = "scale",
        max_frames_per_class: int | None = D.MAX_FRAMES_PER_CLASS,
        smoothing_window: int = D.SMOOTHING_WINDOW,
        smoothing: str = D.SMOOTHING,
        emission_weight: float = D.EMISSION_WEIGHT,
        mirror: bool = D.MIRROR,
        n_jobs: int | None = None,
        random_state: int | None = D.SEED,
    ):
        self.vocabulary = vocabulary
        self.context = context
        self.coarse_context = coarse_context
        self.grouping = grouping
        self.grouping_threshold = grouping_threshold
        self.grouping_distribution = grouping_distribution
        self.grouping_pooling = grouping_pooling
        self.normalize = normalize
        self.n_components = n_components
        self._set_frame_params(classifier, C, gamma, max_frames_per_class, smoothing_window, smoothing,
                               emission_weight, mirror, n_jobs, random_state)

    # ------------------------------------------------------------ features
    def _check_params(self) -> None:
        if self.vocabulary is None or not hasattr(self.vocabulary, "cluster_centers_"):
            raise InputError("recognizer: needs a fitted vocabulary (vidstyle vocabulary ... --out vocab.npz)")
        if self.classifier not in CLASSIFIERS:
            raise ParameterError("classifier", f"must be one of {', '.join(CLASSIFIERS)}, got {self.classifier!r}")
        if self.normalize not in NORMS:
            raise ParameterError("normalize", f"must be one of {', '.join(NORMS)}, got {self.normalize!r}")
        if self.context < 0:
            raise ParameterError("context", f"must be >= 0, got {self.context}")
        if self.coarse_context < 0:
            raise ParameterError("coarse_context", f"must be >= 0, got {self.coarse_context}")
        if self.n_components < 1:
            raise ParameterError("n_components", f"must be >= 1, got {self.n_components}")
        self._check_prediction_params()
        if not self.C > 0:
            raise ParameterError("C", f"must be > 0, got {self.C}")
        if self.max_frames_per_class is not None and self.max_frames_per_class < 1:
            raise ParameterError("max_frames_per_class", f"must be >= 1 (or None for all), got {self.max_frames_per_class}")

    @property
    def n_blocks(self) -> int:
        """Histogram blocks per frame: 1, or 2 with a coarse context."""
        return 2 if getattr(self, "coarse_context", 0) else 1

    def histograms(self, video: VideoFeatures | str | Path) -> sp.csr_matrix:
        """(n_frames, n_words * n_blocks) context word counts of one video (the ONNX model's input): the
        context histogram, then (with ``coarse_context``) the coarse-context one."""
        v = _as_features(video)
        voc = self.vocabulary
        if v.descriptors.shape[0] and v.dim != voc.n_features_in_:
            raise InputError(
                f"{v.path or v.video}: descriptors have dimension {v.dim}, the vocabulary {voc.n_features_in_}"
                " (features from a different descriptor variant?)"
            )
        words = voc.transform(v.descriptors) if v.descriptors.shape[0] else np.zeros(0, np.int32)
        fine = FrameFeaturizer(voc.n_words_, self.context).transform_video(words, v.frame_index, v.n_frames)
        if self.n_blocks == 1:
            return fine
        counts = frame_word_counts(words, v.frame_index, v.n_frames, voc.n_words_)
        return sp.hstack([fine, context_sum(counts, self.coarse_context)], format="csr")

    def _grouped(self, H: sp.spmatrix) -> np.ndarray:
        """Grouped and normalised rows, block by block (each block is one context's histogram)."""
        W = self.vocabulary.n_words_
        blocks = [normalize_rows(self.grouping_.transform(H[:, b * W:(b + 1) * W]), self.normalize)
                  for b in range(self.n_blocks)]
        return blocks[0] if len(blocks) == 1 else np.hstack(blocks)

    def histograms_many(self, videos: Sequence) -> list[sp.csr_matrix]:
        """:meth:`histograms` of several videos (threads with ``n_jobs``), in order."""
        from joblib import Parallel, delayed

        if len(videos) <= 1 or self.n_jobs in (None, 1):
            return [self.histograms(v) for v in videos]
        return Parallel(n_jobs=self.n_jobs, prefer="threads")(delayed(self.histograms)(v) for v in videos)

    def embed(self, H: sp.spmatrix) -> np.ndarray:
        """PCA frame features (n_frames, n_components) of context histograms ``H`` (:meth:`histograms`):
        word grouping, normalisation, then the fitted PCA."""
        return self.pca_.transform(self._grouped(H))

    def transform(self, video) -> np.ndarray:
        """PCA frame features (n_frames, n_components) of one video."""
        return self.embed(self.histograms(video))

    # ----------------------------------------------------------------- fit
    def fit(self, X: Sequence, y: Sequence[Sequence[str]], classes: Sequence[str] | None = None):
        """``X``: features (paths or :class:`VideoFeatures`) of set B; ``y``: per-frame labels of each."""
        from sklearn.decomposition import PCA

        self._check_params()
        if len(X) != len(y) or not X:
            raise InputError(f"recognizer: {len(X)} feature files but {len(y)} label sequences")
        videos = [_as_features(v) for v in X]
        for v, lab in zip(videos, y):
            if len(lab) != v.n_frames:
                raise InputError(f"{v.path or v.video}: {len(lab)} labels for n_frames={v.n_frames}")
        y = list(y)
        y_original = list(y)
        self.n_mirrored_videos_ = 0
        if self.mirror:
            mirrored = [mirrored_features(v) for v in videos]
            if all(m is not None for m in mirrored):
                videos, y = videos + mirrored, y + y
                self.n_mirrored_videos_ = len(mirrored)
            else:
                log.info("recognizer: no mirror images (they need scovanner2007 descriptors)")
        all_labels = np.concatenate([np.asarray(lab, dtype=object) for lab in y]).astype(str)
        self.classes_ = np.array(list(classes) if classes is not None else sorted(set(all_labels)))
        unknown = sorted(set(all_labels) - set(self.classes_))
        if unknown:
            raise InputError(f"labels: classes not in {list(self.classes_)}: {unknown[:5]}")
        index = {c: i for i, c in enumerate(self.classes_)}
        yi = np.array([index[c] for c in all_labels], np.int64)
        vid = np.concatenate([np.full(v.n_frames, i) for i, v in enumerate(videos)])
        # frame-to-frame label chain of the training videos, for Viterbi smoothing
        bounds = np.cumsum([0] + [v.n_frames for v in videos])
        self.transitions_ = transition_matrix(
            [yi[a:b] for a, b in zip(bounds[:-1], bounds[1:])], len(self.classes_)
        )

        warn_few_frames(y_original, self.classes_, float(getattr(videos[0], "fps", 0.0) or 0.0))
        self.fit_durations(y_original)
        Hs = self.histograms_many(videos)
        H = sp.vstack(Hs).tocsr()
        rng = np.random.default_rng(self.random_state)
        rows = sample_per_class(yi, self.max_frames_per_class, rng)

        if self.grouping:
            self.grouping_ = WordGrouping(self.grouping_threshold, self.grouping_distribution, self.grouping_pooling)
        else:
            self.grouping_ = IdentityGrouping()
        self.grouping_.fit(H[:, : self.vocabulary.n_words_], y=yi, groups=vid)
        Xg = self._grouped(H[rows])
        n_comp = int(min(self.n_components, Xg.shape[0], Xg.shape[1]))
        self.pca_ = PCA(n_components=n_comp, random_state=self.random_state).fit(Xg)
        Z = self.pca_.transform(Xg)
        self.fit_classifier(Z, yi[rows])
        self.n_train_frames_ = int(len(yi))
        self.n_fit_frames_ = int(len(rows))
        self.train_class_counts_ = {str(c): int((yi == i).sum()) for i, c in enumerate(self.classes_)}
        log.info(
            "recognizer: %d frames (%d used for the SVMs), %d words -> %d bins -> %d PCA dims, %d classes",
            self.n_train_frames_, self.n_fit_frames_, H.shape[1], self.grouping_.n_groups_, n_comp, len(self.classes_),
        )
        return self

    # ------------------------------------------------------------- predict
    def frame_scores(self, H: sp.spmatrix) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Unsmoothed per-frame output of context histograms ``H`` (:meth:`histograms`):
        ``(raw, scores, confidence)`` with ``raw`` the class index into ``classes_`` per frame,
        ``scores`` (n_frames, n_classes) the classifier's class scores (0 for classes absent in training)
        and ``confidence`` the raw label's. :meth:`smooth` turns them into the smoothed labels; the two
        together are :meth:`predict_histograms` (a validation search scores once and smooths many ways)."""
        if H.shape[0] == 0:
            return np.zeros(0, np.int64), np.zeros((0, len(self.classes_))), np.zeros(0)
        return self.classify(self.embed(H))

    def predict_histograms(self, H: sp.spmatrix) -> dict[str, np.ndarray]:
        """:meth:`smooth` of :meth:`frame_scores`: see :meth:`predict_video`."""
        return self.smooth(*self.frame_scores(H))

    def predict_video(self, video) -> dict[str, np.ndarray]:
        """Class indices into ``classes_`` per frame: ``raw``, ``smoothed``, with ``confidence``,
        ``smoothed_confidence`` and ``scores`` (n_frames, n_classes)."""
        return self.predict_histograms(self.histograms(video))

    # ---------------------------------------------------------------- info
    def summary(self) -> dict[str, Any]:
        return {
            "n_train_frames": self.n_train_frames_,
            "n_mirrored_videos": getattr(self, "n_mirrored_videos_", 0),
            "n_fit_frames": self.n_fit_frames_,
            "train_class_counts": self.train_class_counts_,
            "n_words": self.vocabulary.n_words_,
            "n_groups": self.grouping_.n_groups_,
            "related_pairs": self.grouping_.n_related_pairs_,
            "largest_group": self.grouping_.largest_group_,
            "pca_components": int(self.pca_.n_components_),
            "pca_explained_variance": float(self.pca_.explained_variance_ratio_.sum()),
            "n_support_vectors": int(getattr(self.clf_, "support_vectors_", getattr(getattr(self.clf_, "svc_", None), "support_vectors_", np.zeros((0,)))).shape[0]),
        }

    def public_params(self) -> dict[str, Any]:
        p = self.get_params(deep=False)
        p.pop("vocabulary")
        return p


def mirrored_features(v: VideoFeatures) -> VideoFeatures | None:
    """The features of the left-right mirror image of ``v``, or None when its descriptors are not
    scovanner2007 (variant recorded in the file, or 640-D when the file does not say)."""
    from ..features.scovanner2007 import DIM, mirror_descriptors

    if v.variant not in ("scovanner2007", "") or v.dim != DIM:
        return None
    return VideoFeatures(mirror_descriptors(v.descriptors), v.frame_index, v.n_frames,
                         video=f"mirror:{v.video}", path=f"mirror:{v.path}", variant=v.variant)


# ------------------------------------------------------------------- files
def model_header(model: ActionRecognizer, training_files: Sequence[dict] = (), extra: dict | None = None) -> dict:
    """What a model file records of the fitted ``model`` (see the module docstring)."""
    import sklearn

    from .. import __version__

    voc = model.vocabulary
    header = {
        "params": model.public_params(),
        "seed": model.random_state,
        "classes": [str(c) for c in model.classes_],
        "training_files": list(training_files),
        "vocabulary": {
            "params": voc.get_params(),
            "n_words": voc.n_words_,
            "dim": voc.n_features_in_,
            "training_files": list(getattr(voc, "training_files_", [])),
        },
        "summary": model.summary(),
        "sklearn": sklearn.__version__,
        "vidstyle": __version__,
    }
    if extra:
        header.update(extra)
    return json.loads(json.dumps(header, default=str))


def save_model(path: str | Path, model: ActionRecognizer, training_files: Sequence[dict] = (), extra: dict | None = None) -> dict:
    """Write the fitted ``model`` to a model file (:mod:`vidstyle.formats.recognizer_model`); return its header."""
    from ..formats.recognizer_model import write_recognizer_model

    return write_recognizer_model(path, model, model_header(model, training_files, extra))


def load_model(path: str | Path) -> tuple[ActionRecognizer, dict]:
    """``(recognizer, header)`` of a model file (:mod:`vidstyle.formats.recognizer_model`): an
    :class:`ActionRecognizer`, or a :class:`~vidstyle.recognition.poserecognizer.PoseRecognizer` (header
    ``"input": "pose"``); warns when it was saved with another scikit-learn."""
    import sklearn

    from ..formats.recognizer_model import read_recognizer_model

    from .poserecognizer import PoseRecognizer

    model, header = read_recognizer_model(path, (ActionRecognizer, PoseRecognizer))
    if header.get("sklearn") != sklearn.__version__:
        log.warning("%s was saved with scikit-learn %s, running %s", path, header.get("sklearn"), sklearn.__version__)
    return model, header


def read_header(path: str | Path) -> dict:
    """The header of a model file (the model is loaded too: the header alone is not trusted)."""
    return load_model(path)[1]


def warn_few_frames(labels, classes, fps: float = 0.0, need: int | None = None) -> dict[str, int]:
    """Warn (plainly: how many frames each thin class has and how many are needed) about classes with
    fewer than ``need`` (default :data:`~.defaults.MIN_FRAMES_PER_CLASS`) labelled training frames, mirror
    images not counted; returns those classes' counts."""
    need = D.MIN_FRAMES_PER_CLASS if need is None else int(need)
    counts = {str(c): 0 for c in classes}
    for lab in labels:
        for c in lab:
            counts[str(c)] = counts.get(str(c), 0) + 1
    few = {c: n for c, n in counts.items() if n < need}
    for c, n in few.items():
        secs = f" ({n / fps:.1f} s at {fps:g} fps)" if fps > 0 else ""
        log.warning("class %r has only %d labelled training frames%s; the recognizer needs about %d per class "
                    "(%s) to recognise it in new footage: label more of it, in several takes", c, n, secs, need,
                    f"{need / fps:.0f} s" if fps > 0 else "several takes")
    return few
