"""Defaults of :class:`vidstyle.actionmodel.ActionModel` and ``vidstyle fit-actions`` / ``sample-action``.

``VARIANCE`` and ``WARP_SMOOTHING`` were chosen by ``scripts/validate_actionmodel.py`` on the validation
performers of the demo (split seed 0; never the test performers): ``pipelines/kickboxing/validation/actionmodel.json`` holds the
candidates, their scores and the rule. The others are Du's (2014) values or plain choices, documented in
``docs/actionmodel.md``.
"""

VARIANCE = 1.0  # fraction of variance each functional PCA keeps (spatial, temporal); validation/actionmodel.json
SLOPE_LIMIT = 5  # DTW: at most 5 consecutive horizontal or vertical steps (Du 3.2.2)
MAX_COMPONENTS = 6  # GMM components tried (1..MAX_COMPONENTS), the number chosen by BIC
COVARIANCE_TYPE = "full"
MIN_FRAMES = 6  # an instance has at least this many frames
MIN_RUN = 3  # contact runs shorter than this (frames) are absorbed by their neighbours
MIN_PRIMITIVE = 3  # a primitive has at least this many frames (keyframes included)
MIN_INSTANCES = 3  # a label with fewer instances (of its most common signature) is not modelled
MEDOID_CANDIDATES = 40  # the medoid is searched among at most this many instances (seeded draw)
WARP_SMOOTHING = 4.0  # Gaussian sigma (reference frames) of the DTW warp's deviation; validation/actionmodel.json
BLEND_FRAMES = 3  # foot pinning: frames of blending either side of a contact run
RANDOM_STATE = 0

# --- fitting a performer from 2D (vidstyle.actionmodel.stylefit); STYLE_PRIOR_WEIGHT and STYLE_LOSS_SCALE
# chosen by scripts/validate_action_style.py on the validation performers (validation/action_style.json)
STYLE_N_FIT = 30  # spatial coefficients fitted per segment (the leading ones; the rest at the prior mean); validation/action_style.json
STYLE_PRIOR_WEIGHT = 0.01  # weight of the GMM prior (whitened squared distance) against the 2D data term; validation/action_style.json
STYLE_LOSS_SCALE = 0.05  # Cauchy loss scale, torso lengths; validation/action_style.json
STYLE_ELEVATION_DEG = 10.0  # assumed camera elevation (the demo's cameras)
STYLE_MAX_NFEV = 30  # least-squares function evaluations per segment
STYLE_MAX_SEGMENTS = 8  # segments fitted per performer and label (a seeded spread over all)
STYLE_LEAD_CUE = "stance"  # the lead from the front foot's image side before the jab rules; validation/lead_cue.json
STYLE_MIN_RUN_CONFIDENCE = 0.0  # recognised labels: runs of lower mean confidence do not measure a length; validation/tempo_runs.json
STYLE_STEP_MIN_RUN_CONFIDENCE: float | None = None  # the same for Step runs (they time the speed; None: STYLE_MIN_RUN_CONFIDENCE); validation/tempo_runs.json
STYLE_MIN_RUN_FACTOR: float | None = 0.7  # recognised runs shorter than this times the population's length of the label do not measure (None: all); validation/tempo_runs.json
STYLE_MAX_RUN_FACTOR: float | None = 1.8  # recognised runs longer than this times the population's length of the label do not measure (None: all); validation/tempo_runs.json
STYLE_RUN_TIMING = "motion"  # recognised labels: an action run's length from the width of its motion ("labels": the run's own); validation/tempo_runs.json
STYLE_MOTION_LEVEL = 0.3  # the level (share of the run's peak displacement from guard) whose crossings time it; validation/tempo_runs.json
STYLE_MOTION_FILTER = 5  # median filter (frames) of the displacement before timing (1: none); validation/tempo_runs.json
STYLE_MIN_STANCE_FRAMES = 50  # frames the stance cue needs (2.5 s at the demo's 20 fps), else the jab rules decide
STYLE_ROUNDS = 2  # linearisations of the decoded keypoints per segment (Gauss-Newton rounds)
STYLE_BLEND_FRAMES = 4  # synthesize --style: frames cross-faded at either end of a restyled action
STYLE_MIN_FRACTION = 0.6  # synthesize --style: runs shorter than this share of the mean instance keep the graph frames
