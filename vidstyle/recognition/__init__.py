"""Frame-wise action recognition (thesis chapter 4.1-4.3): vocabulary, frame histograms, word grouping,
PCA, one-vs-all + one-vs-one SVMs, smoothing; splits, metrics and ONNX export.

Modules:

- :mod:`~vidstyle.recognition.io` — the features reader (labels and manifest: :mod:`vidstyle.formats`).
- :mod:`~vidstyle.recognition.vocabulary` — :class:`Vocabulary` (MiniBatch, hierarchical tree, full k-means).
- :mod:`~vidstyle.recognition.histograms` — :class:`FrameFeaturizer`, :class:`WordGrouping`, normalisation.
- :mod:`~vidstyle.recognition.classifier` — :class:`OvaOvoSVC` (thesis) and :class:`OvrSVC` (baseline).
- :mod:`~vidstyle.recognition.smoothing` — :func:`smooth_labels` (Viterbi over frame scores with the
  training label chain, the default; window vote as the thesis; or mean score).
- :mod:`~vidstyle.recognition.recognizer` — :class:`ActionRecognizer`, model files.
- :mod:`~vidstyle.recognition.onnx_export` — ONNX graph + :class:`OnnxRecognizer`.
- :mod:`~vidstyle.recognition.splits` — disjoint sets A / B / test by performer or view.
- :mod:`~vidstyle.recognition.defaults` — the validated defaults of the library and the CLI.
- :mod:`~vidstyle.recognition.pipeline` — the stage as library calls: :func:`train_vocabulary`,
  :func:`train`, :func:`recognize_file`, :func:`recognize` (what the commands run).

Evaluation (metrics, confusion PNG, the evaluation run) lives in :mod:`vidstyle.evaluation.recognition`.
- :mod:`~vidstyle.recognition.synthetic` — synthetic feature files with known labels (tests, benchmarks).
"""

from typing import TYPE_CHECKING

from ..lazy import lazy_package

if TYPE_CHECKING:  # pragma: no cover
    from .classifier import OvaOvoSVC, OvrSVC, combine_ova_ovo
    from .histograms import FrameFeaturizer, WordGrouping, normalize_rows
    from .io import VideoFeatures, load_features
    from .pipeline import (
        TrainingRun,
        VocabularyRun,
        load_recognizer,
        recognize,
        recognize_file,
        train,
        train_vocabulary,
    )
    from .recognizer import ActionRecognizer, load_model, save_model
    from .smoothing import smooth_labels
    from .splits import Split, make_split
    from .vocabulary import Vocabulary

# The names below load their submodule on first use (PEP 562, :mod:`vidstyle.lazy`): the CLI reads
# ``vidstyle.recognition.defaults`` when it builds its options, and that must not import scikit-learn, SciPy
# or OpenCV into every command's start-up. Submodules load on first use too.
_WHERE = {
    "OvaOvoSVC": "classifier",
    "OvrSVC": "classifier",
    "combine_ova_ovo": "classifier",
    "FrameFeaturizer": "histograms",
    "WordGrouping": "histograms",
    "normalize_rows": "histograms",
    "VideoFeatures": "io",
    "load_features": "io",
    "TrainingRun": "pipeline",
    "VocabularyRun": "pipeline",
    "load_recognizer": "pipeline",
    "recognize": "pipeline",
    "recognize_file": "pipeline",
    "train": "pipeline",
    "train_vocabulary": "pipeline",
    "ActionRecognizer": "recognizer",
    "load_model": "recognizer",
    "save_model": "recognizer",
    "smooth_labels": "smoothing",
    "Split": "splits",
    "make_split": "splits",
    "Vocabulary": "vocabulary",
}
__getattr__ = lazy_package(__name__, _WHERE)


__all__ = [
    "ActionRecognizer",
    "FrameFeaturizer",
    "OvaOvoSVC",
    "OvrSVC",
    "Split",
    "TrainingRun",
    "VideoFeatures",
    "Vocabulary",
    "VocabularyRun",
    "WordGrouping",
    "combine_ova_ovo",
    "load_features",
    "load_model",
    "load_recognizer",
    "make_split",
    "normalize_rows",
    "recognize",
    "recognize_file",
    "save_model",
    "smooth_labels",
    "train",
    "train_vocabulary",
]
