"""Defaults of building a motion graph and synthesising walks: the values ``vidstyle build-graph``,
``vidstyle synthesize`` and ``vidstyle evaluate motion`` use, and the defaults of the library's
:class:`~vidstyle.motiongraph.MotionGraph`, :func:`~vidstyle.motiongraph.build_graph` and
:func:`~vidstyle.motiongraph.synthesize` (one place, so a Python user gets the CLI's numbers).

Graph: Kovar et al.'s window of 1/3 s at 30 fps, transitions below the 5 % quantile of random window
pairs, float32 GEMM in 2048-row tiles (candidates refined in float64). Walks: a wrong-label frame costs
5, each transition 0.2 (threshold units); missing actions are warned about, not fatal; feet are locked.
"""

from __future__ import annotations

# build-graph / MotionGraph
WINDOW = 10
FPS = 30.0
THRESHOLD_QUANTILE = 0.05
TILE = 2048
MIN_TILE = 16
DTYPE = "float32"
DTYPES = ("float32", "float64")
N_JOBS = 1
N_SAMPLES = 200_000
RANDOM_STATE = 0
MIRROR = False
DROP_TPOSE = True

# synthesize / plan_walk / render_walk
STEP_SECONDS = 1.0
MISMATCH_PENALTY = 5.0
TRANSITION_PENALTY = 0.2
STRICT = False
FOOT_LOCK = True

# evaluate motion (random walks)
EVAL_WALKS = 5
EVAL_STEPS = 8
EVAL_MIN_SECONDS = 1.0
EVAL_MAX_SECONDS = 3.0
