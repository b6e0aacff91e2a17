"""The pose-sequence frame recognizer (issue 28): :class:`PoseFeaturizer` frame features -> standardisation
-> the same SVMs and smoothing as the 3D SIFT recognizer (:class:`FrameRecognizerMixin`).

Model files are recognizer model files (:mod:`vidstyle.formats.recognizer_model`) whose header says
``"input": "pose"`` and whose model is a :class:`PoseRecognizer`; see :func:`save_pose_model`.
"""

from __future__ import annotations

import json
import logging
from collections.abc import Sequence
from typing import Any

import numpy as np
from sklearn.base import BaseEstimator

from ..errors import InputError, ParameterError
from . import defaults as D
from .framebase import FrameRecognizerMixin, sample_per_class
from .posefeatures import PoseFeaturizer, PoseTrack, mirror_track

log = logging.getLogger(__name__)


def _as_track(x) -> PoseTrack:
    return x if isinstance(x, PoseTrack) else PoseTrack(np.asarray(x, dtype=np.float64))


class PoseRecognizer(FrameRecognizerMixin, BaseEstimator):
    """Per-frame action recognizer on 2D pose sequences, with scikit-learn conventions.

    ``fit(X, y)``: ``X`` pose tracks (:class:`PoseTrack` or (F, 15, 2) keypoint arrays, NaN = missing) at
    the working rate ``fps``; ``y`` per-frame label sequences. ``velocity_steps``, ``accel_steps``,
    ``window_offsets``, ``max_gap``, ``scale_window``: of the :class:`PoseFeaturizer`. ``mirror``: also
    train on the left-right mirror image of every track (a southpaw). ``classifier``, ``C``, ``gamma``,
    ``max_frames_per_class``, ``smoothing*``, ``emission_weight``: as for
    :class:`~vidstyle.recognition.recognizer.ActionRecognizer` (the shared classifier and smoothers).
    """

    def __init__(self, velocity_steps=(1, 2, 4), accel_steps=(2, 4), window_offsets=(-8, -4, 4, 8),
                 max_gap: int = 5, scale_window: int = 10, fps: float = D.FPS, classifier: str = D.CLASSIFIER,
                 C: float = 10.0, gamma: float | str = "scale", max_frames_per_class: int | None = D.MAX_FRAMES_PER_CLASS,
                 smoothing_window: int = D.SMOOTHING_WINDOW, smoothing: str = D.SMOOTHING,
                 emission_weight: float = D.EMISSION_WEIGHT, mirror: bool = True, n_jobs: int | None = None,
                 random_state: int | None = D.SEED):
        self.velocity_steps = velocity_steps
        self.accel_steps = accel_steps
        self.window_offsets = window_offsets
        self.max_gap = max_gap
        self.scale_window = scale_window
        self.fps = fps
        self._set_frame_params(classifier, C, gamma, max_frames_per_class, smoothing_window, smoothing,
                               emission_weight, mirror, n_jobs, random_state)

    @property
    def featurizer(self) -> PoseFeaturizer:
        return PoseFeaturizer(self.velocity_steps, self.accel_steps, self.window_offsets, self.max_gap,
                              self.scale_window)

    def features(self, track) -> np.ndarray:
        """Unscaled frame features (F, dimension) of one track."""
        return self.featurizer.transform(_as_track(track))

    def fit(self, X: Sequence, y: Sequence[Sequence[str]], classes: Sequence[str] | None = None):
        from sklearn.preprocessing import StandardScaler

        self._check_classifier_params()
        self._check_prediction_params()
        if not self.fps > 0:
            raise ParameterError("fps", f"must be > 0, got {self.fps}")
        if self.max_frames_per_class is not None and self.max_frames_per_class < 1:
            raise ParameterError("max_frames_per_class", f"must be >= 1 (or None for all), got {self.max_frames_per_class}")
        if len(X) != len(y) or not X:
            raise InputError(f"pose recognizer: {len(X)} pose tracks but {len(y)} label sequences")
        tracks = [_as_track(t) for t in X]
        for i, (t, lab) in enumerate(zip(tracks, y)):
            if len(lab) != t.n_frames:
                raise InputError(f"pose track {i} ({t.source or 'unnamed'}): {len(lab)} labels for {t.n_frames} frames")
        all_labels = np.concatenate([np.asarray(lab, dtype=object) for lab in y]).astype(str)
        self.classes_ = np.array(list(classes) if classes is not None else sorted(set(all_labels)))
        unknown = sorted(set(all_labels) - set(self.classes_))
        if unknown:
            raise InputError(f"labels: classes not in {list(self.classes_)}: {unknown[:5]}")
        index = {c: i for i, c in enumerate(self.classes_)}
        seqs = [np.array([index[str(c)] for c in lab], np.int64) for lab in y]
        self.fit_label_chain(seqs)
        self.fit_durations(y)
        feat = self.featurizer
        Xs = [feat.transform(t) for t in tracks]
        ys = list(seqs)
        if self.mirror:
            Xs += [feat.transform(mirror_track(t.xy)) for t in tracks]
            ys += list(seqs)
        Xa = np.concatenate(Xs)
        ya = np.concatenate(ys)
        rng = np.random.default_rng(self.random_state)
        rows = sample_per_class(ya, self.max_frames_per_class, rng)
        self.scaler_ = StandardScaler().fit(Xa[rows])
        self.fit_classifier(self.scaler_.transform(Xa[rows]), ya[rows])
        self.n_train_frames_ = int(sum(len(s) for s in seqs))
        self.n_fit_frames_ = len(rows)
        self.n_features_in_ = int(Xa.shape[1])
        self.train_class_counts_ = {str(c): int((ya == i).sum()) for i, c in enumerate(self.classes_)}
        log.info("pose recognizer: %d tracks (%d frames, mirrored %s), %d used for the SVMs, %d features, %d classes",
                 len(tracks), self.n_train_frames_, self.mirror, self.n_fit_frames_, Xa.shape[1], len(self.classes_))
        return self

    def frame_scores(self, track) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(raw, scores, confidence)`` per frame of one track (unsmoothed)."""
        X = self.features(track)
        return self.classify(self.scaler_.transform(X) if len(X) else X)

    def predict_video(self, track) -> dict[str, np.ndarray]:
        """Class indices into ``classes_`` per frame: ``raw``, ``smoothed``, with ``confidence``,
        ``smoothed_confidence`` and ``scores`` (n_frames, n_classes)."""
        return self.smooth(*self.frame_scores(track))

    def summary(self) -> dict[str, Any]:
        return {"n_train_frames": self.n_train_frames_, "n_fit_frames": self.n_fit_frames_,
                "n_features": self.n_features_in_, "train_class_counts": self.train_class_counts_,
                "featurizer": self.featurizer.parameters()}

    def public_params(self) -> dict[str, Any]:
        return json.loads(json.dumps(self.get_params(deep=False), default=list))


def save_pose_model(path, model: PoseRecognizer, training: dict | None = None, extra: dict | None = None) -> dict:
    """Write a fitted :class:`PoseRecognizer` to a recognizer model file (header ``"input": "pose"``)."""
    import sklearn

    from .. import __version__
    from ..formats.recognizer_model import write_recognizer_model

    header = {"input": "pose", "params": model.public_params(), "seed": model.random_state,
              "classes": [str(c) for c in model.classes_], "training": training or {},
              "summary": model.summary(), "sklearn": sklearn.__version__, "vidstyle": __version__}
    if extra:
        header.update(extra)
    return write_recognizer_model(path, model, json.loads(json.dumps(header, default=str)))
