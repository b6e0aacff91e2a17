"""Defaults of keyframe-to-keyframe synthesis (``vidstyle synthesize --keyframes``), one place for the CLI and
the library.

The learned model's size (``N_CLUSTERS``, ``N_COMPONENTS``), ``WARP_COST`` and ``ROOT_PATH`` were chosen on the validation
subject of the CMU split by ``scripts/validate_inbetween.py`` (lowest mean of L2P and L2Q over SLERP's on the
same windows, over gaps of 15/30/45 frames), then ``COVERAGE_SCALE`` on that subject and on each library
subject held out from the other three, recorded in ``pipelines/kickboxing/validation/inbetween.json``; never on the test subjects
(``tests/test_inbetween_defaults.py`` checks these values equal that file's choice). The level-2 costs
(``MISMATCH_COST``, ``JUMP_COST``, ``KEY_WEIGHT``) and ``VELOCITY_WEIGHT`` were set from a smaller exploration on
the same validation subject before the grid (hard cluster mismatches and cheap jumps scored worse than
soft mismatches, strong key matching and rare jumps; a velocity feature scored worse); the other numbers
are fixed by design (see each comment).
"""

from __future__ import annotations

#: method of ``synthesize --keyframes`` (``markov`` = Molina Tanco & Hilton 2000)
METHOD = "markov"
METHODS = ("markov", "graph", "slerp")
#: what ``vidstyle evaluate inbetween`` can score: the methods, and SLERP with the Hermite root path
#: (the markov default's root path on a model-free body: what the library adds beyond it)
EVAL_METHODS = (*METHODS, "slerp_hermite")

# -- chosen on validation (scripts/validate_inbetween.py -> pipelines/kickboxing/validation/inbetween.json)
N_CLUSTERS = 64
N_COMPONENTS = 64
VELOCITY_WEIGHT = 0.0
#: where the root goes between the keys (``library`` | ``hermite``, :data:`vidstyle.inbetween.poses.ROOT_PATHS`),
#: searched last, for the chosen model size
ROOT_PATH = "hermite"
#: keys far from every library pose shrink the library's body motion toward the keys' SLERP
#: (:func:`vidstyle.inbetween.markov.coverage_weight`; None: never), searched after the root path, on the
#: validation subject and on each library subject held out from the others
COVERAGE_SCALE = 1.0

# -- fixed
#: root height feature weight, per leg length (a squat of half a leg ~ a 0.5 rad joint change)
HEIGHT_WEIGHT = 1.0
#: pseudo-count added to every Markov transition count (Laplace smoothing: every path has a probability)
SMOOTHING = 0.01
#: level 2: cost of an output frame whose library frame is not in the cluster the path asks for
MISMATCH_COST = 0.1
#: level 2: cost of a jump between library segments (in units of one mismatch frame)
JUMP_COST = 30.0
#: level 2: cost of holding or skipping one library frame inside a segment (a time warp; None: no warps)
WARP_COST = 0.2
#: level 2: weight of the squared feature distance (in mean cluster spreads) of the first / last library
#: frame to the start / end keyframe
KEY_WEIGHT = 10.0
#: frames over which a jump between segments is blended (motion-graph blend weight)
BLEND_FRAMES = 5
#: graph method: cost of one blend edge in frames per threshold unit of its edge cost
GRAPH_TRANSITION_PENALTY = 5.0
RANDOM_STATE = 0

# -- evaluation (vidstyle evaluate inbetween, scripts/eval_inbetween.py, scripts/validate_inbetween.py): CMU subjects by role
EVAL_SPLIT = {"library": ("01", "05", "06", "08"), "validation": ("03",), "test": ("02", "07")}
EVAL_GAPS = (15, 30, 45)
