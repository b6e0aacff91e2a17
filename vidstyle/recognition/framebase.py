"""What every frame recognizer shares, whatever its frame features: the frame classifier (the thesis'
one-vs-all + one-vs-one SVMs or the plain SVC baseline), the label chain learned from the training labels,
and the smoothing of frame scores into labels (:func:`~vidstyle.recognition.smoothing.smooth_labels`).

:class:`~vidstyle.recognition.recognizer.ActionRecognizer` (3D SIFT words) and
:class:`~vidstyle.recognition.poserecognizer.PoseRecognizer` (pose sequences) build their frame features
their own way and inherit the rest from :class:`FrameRecognizerMixin`. A subclass has the parameters
``classifier``, ``C``, ``gamma``, ``smoothing_window``, ``smoothing``, ``emission_weight``, ``n_jobs`` and
defines ``predict_video``.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ..errors import ParameterError
from .classifier import OvaOvoSVC, OvrSVC
from .smoothing import METHODS as SMOOTHERS
from .smoothing import duration_model, smooth_labels, transition_matrix

CLASSIFIERS = ("ova-ovo", "svc-ovr")


def sample_per_class(y: np.ndarray, cap: int | None, rng: np.random.Generator) -> np.ndarray:
    """Sorted row indices with at most ``cap`` rows of each class (all rows when ``cap`` is None)."""
    if cap is None:
        return np.arange(len(y))
    rows = []
    for c in np.unique(y):
        idx = np.flatnonzero(y == c)
        if idx.size > cap:
            idx = np.sort(rng.choice(idx, cap, replace=False))
        rows.append(idx)
    return np.sort(np.concatenate(rows))


class FrameRecognizerMixin:
    """Classifier, label chain and smoothing of a frame recognizer (see the module docstring)."""

    def _set_frame_params(self, classifier, C, gamma, max_frames_per_class, smoothing_window, smoothing,
                          emission_weight, mirror, n_jobs, random_state) -> None:
        """Store the shared constructor parameters unchanged (scikit-learn convention: ``__init__`` only
        stores; checks happen in ``fit`` and ``predict``)."""
        self.classifier = classifier
        self.C = C
        self.gamma = gamma
        self.max_frames_per_class = max_frames_per_class
        self.smoothing_window = smoothing_window
        self.smoothing = smoothing
        self.emission_weight = emission_weight
        self.mirror = mirror
        self.n_jobs = n_jobs
        self.random_state = random_state

    def _check_classifier_params(self) -> None:
        if self.classifier not in CLASSIFIERS:
            raise ParameterError("classifier", f"must be one of {', '.join(CLASSIFIERS)}, got {self.classifier!r}")
        if not self.C > 0:
            raise ParameterError("C", f"must be > 0, got {self.C}")

    def _check_prediction_params(self) -> None:
        """Checks of the parameters :meth:`smooth` uses (they may be changed on a fitted model)."""
        if self.smoothing not in SMOOTHERS:
            raise ParameterError("smoothing", f"must be one of {', '.join(SMOOTHERS)}, got {self.smoothing!r}")
        if self.smoothing_window < 1:
            raise ParameterError("window", f"must be >= 1, got {self.smoothing_window}")
        if not self.emission_weight > 0:
            raise ParameterError("emission_weight", f"must be > 0, got {self.emission_weight}")

    def fit_label_chain(self, sequences: Sequence[np.ndarray]):
        """Learn ``transitions_`` (frame-to-frame label chain, for the ``viterbi`` smoother) from the class
        index sequences of the training videos."""
        self.transitions_ = transition_matrix(list(sequences), len(self.classes_))
        return self

    def fit_durations(self, y: Sequence[Sequence[str]]):
        """Learn ``durations_`` (the run lengths and class changes the ``duration`` smoother decodes with,
        :func:`~vidstyle.recognition.smoothing.duration_model`) from per-frame label sequences (set B)."""
        index = {str(c): i for i, c in enumerate(self.classes_)}
        seqs = [np.array([index[str(c)] for c in lab], np.int64) for lab in y]
        self.durations_ = duration_model(seqs, len(self.classes_))
        return self

    def fit_classifier(self, Z: np.ndarray, y: np.ndarray):
        """Fit ``clf_`` (the ``classifier`` kind) on frame features ``Z`` and class indices ``y``."""
        if self.classifier == "ova-ovo":
            self.clf_ = OvaOvoSVC(C=self.C, gamma=self.gamma, n_jobs=self.n_jobs).fit(Z, y)
        else:
            self.clf_ = OvrSVC(C=self.C, gamma=self.gamma).fit(Z, y)
        return self

    def _scores_full(self, pred: np.ndarray, scores: np.ndarray, conf: np.ndarray):
        """Map the classifier's class indices (classes seen in training) to ``classes_``."""
        present = self.clf_.classes_.astype(np.int64)
        full = np.zeros((scores.shape[0], len(self.classes_)))
        full[:, present] = scores
        return present[pred], full, conf

    def classify(self, Z: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(raw, scores, confidence)`` of frame features ``Z`` (see ``frame_scores``)."""
        if Z.shape[0] == 0:
            return np.zeros(0, np.int64), np.zeros((0, len(self.classes_))), np.zeros(0)
        return self._scores_full(*self.clf_.predict_with_scores(Z))

    def smooth(self, raw: np.ndarray, scores: np.ndarray, conf: np.ndarray,
               emission_weight: float | None = None) -> dict[str, np.ndarray]:
        """Smooth frame scores with the recognizer's ``smoothing``, ``smoothing_window`` and
        ``emission_weight`` (``emission_weight``: another power of the scores for this call, e.g. for fused
        scores; the model is not changed) and its learned ``transitions_`` / ``durations_``; returns the
        ``predict_video`` dict (``raw``, ``scores``, ``confidence``, ``smoothed``, ``smoothed_confidence``)."""
        self._check_prediction_params()
        if emission_weight is not None and not emission_weight > 0:
            raise ParameterError("emission_weight", f"must be > 0, got {emission_weight}")
        power = self.emission_weight if emission_weight is None else float(emission_weight)
        if len(raw) == 0:
            e = np.zeros(0, np.int64)
            return {"raw": e, "scores": np.zeros((0, len(self.classes_))), "confidence": np.zeros(0),
                    "smoothed": e, "smoothed_confidence": np.zeros(0)}
        sm, sconf = smooth_labels(
            raw, len(self.classes_), self.smoothing_window, conf, scores, self.smoothing,
            transitions=getattr(self, "transitions_", None), emission_weight=power,
            durations=getattr(self, "durations_", None),
        )
        return {"raw": raw, "scores": scores, "confidence": conf, "smoothed": sm, "smoothed_confidence": sconf}

    def predict(self, video) -> np.ndarray:
        """Raw per-frame class names of one video."""
        return self.classes_[self.predict_video(video)["raw"]]

    def predict_many(self, videos: Sequence) -> list[dict[str, np.ndarray]]:
        from joblib import Parallel, delayed

        if len(videos) <= 1 or self.n_jobs in (None, 1):
            return [self.predict_video(v) for v in videos]
        return Parallel(n_jobs=self.n_jobs, prefer="threads")(delayed(self.predict_video)(v) for v in videos)
