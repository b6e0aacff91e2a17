"""Validated defaults of the recognition stage, in one place.

The library (:class:`~vidstyle.recognition.recognizer.ActionRecognizer`,
:class:`~vidstyle.recognition.vocabulary.Vocabulary`, :func:`vidstyle.recognition.train`,
:func:`vidstyle.recognition.train_vocabulary`, :func:`vidstyle.recognition.recognize_file`) and the CLI
(``vidstyle vocabulary``, ``train-recognizer``, ``recognize``, ``evaluate recognition``) take their
defaults from here, so a Python user calling the library with defaults gets the CLI's numbers.

C, the per-class frame cap, the grouping threshold, the coarse context, the smoother and its emission
weight were chosen by ``scripts/validate_recognition.py``, which scores candidates on the demo's
validation performers (never the test performers); ``pipelines/kickboxing/validation/recognition.json``
records every candidate, the value chosen and the validation score it won with. The rest are the
thesis' values (4.2-4.3).
"""

from __future__ import annotations

# ------------------------------------------------------------------ vocabulary (set A)
N_WORDS = 1000                 # thesis: 1000 of 500/1000/1500
VOCAB_METHOD = "minibatch"     # minibatch | hierarchical | kmeans
BRANCHING = 10                 # children per node of the hierarchical tree
MAX_DESCRIPTORS = 100_000      # fit on at most this many (sampled)

# ------------------------------------------------------------------ recognizer (set B)
CONTEXT = 2                    # frames each side in a frame's histogram (thesis 2)
COARSE_CONTEXT = 0             # multi-scale context off (the thesis; validated)
GROUPING = True                # word grouping (Scovanner)
GROUPING_THRESHOLD = 0.8       # validated
NORMALIZE = "sqrt"             # Hellinger
N_COMPONENTS = 128             # PCA dimensions
CLASSIFIER = "ova-ovo"         # thesis
C = 100.0                      # validated
MAX_FRAMES_PER_CLASS = 1500    # validated (0 / None = all)
SMOOTHING_WINDOW = 6           # thesis
# --more-performers (procedural performers outside the split): the share of them whose videos join the
# vocabulary's set A; the rest join the classifier's set B, so A and B stay disjoint by performer.
# scripts/validate_training_views.py tried it on the validation performers (validation/training_views.json)
MORE_PERFORMERS_VOCAB_SHARE = 1 / 3
SMOOTHING = "duration"         # validated: explicit-duration HMM over frame scores
EMISSION_WEIGHT = 1.0          # validated
MIRROR = True                  # also train on mirror images (scovanner2007 descriptors only)
# libsvm's kernel cache (MB), shared by the binary SVMs trained at once (OvaOvoSVC, n_jobs): a speed setting, the
# fitted machines are the same at any size. The demo's training (37,302 frames at the cap 5000) fitted its largest
# one-vs-all machine in 110.5 s with scikit-learn's 500 MB per machine, 41.8 s with 1000, 33.3 s with 2000 and
# 38.9 s with 4000 (one core each, 2026-12-06); the whole training stage of the demo went from 241 s to 105 s
# with the same model (scripts/bench_demo.py --baseline c3221c0 measures the demo with and without it)
SVM_CACHE_MB = 4000.0

# ------------------------------------------------------------------ late fusion with the pose recognizer
# the weight of the pose-sequence recognizer's scores (vidstyle recognize --pose-model): chosen by
# scripts/pose_recognition_results.py on seed 0's validation performers and the real-motion validation clips
# (pictorial-structures 2D, the real-motion clips at the pose command's zooms; the training noise calibrated
# on the validation performers); the two runs, with and without CMU walks labelled Step in the pose
# recognizer's training, chose the same weight, and the one with them scored higher
# (pipelines/kickboxing/validation/pose_recognition{,_cmuwalks}_seed0.json)
FUSION_WEIGHT = 0.5
# the power of the fused frame scores in the pose recognizer's duration smoother, chosen by the same runs after
# the weight (their stage 2 rows): higher powers smooth the flatter fused scores better on the validation
# performers and call more real walking frames strikes; both runs kept the pose recognizer's own, 1
FUSION_EMISSION_WEIGHT = 1.0

# ------------------------------------------------------------------ runs
SPLIT = "unseen-performer"     # unseen-performer | unseen-view | unseen-camera
SEED = 0
FPS = 20.0                     # frame rate recorded when neither the caller nor the features give one

RECOGNIZER_PARAMS = {
    "context": CONTEXT, "coarse_context": COARSE_CONTEXT, "grouping": GROUPING,
    "grouping_threshold": GROUPING_THRESHOLD, "normalize": NORMALIZE, "n_components": N_COMPONENTS,
    "classifier": CLASSIFIER, "C": C, "max_frames_per_class": MAX_FRAMES_PER_CLASS,
    "smoothing_window": SMOOTHING_WINDOW, "smoothing": SMOOTHING, "emission_weight": EMISSION_WEIGHT,
    "mirror": MIRROR,
}
"""The recognizer's validated parameters by :class:`ActionRecognizer` argument name."""

#: most frames each side of a frame's histogram (``--context``, ``--coarse-context``)
MAX_CONTEXT = 1000
#: largest smoothing window in frames (``--window``)
MAX_WINDOW = 1000

#: labelled frames per class below which training warns (at the 20 fps working rate, 5 s of the action:
#: a few takes, the least from which the SVMs see more than one performance of it)
MIN_FRAMES_PER_CLASS = 100
