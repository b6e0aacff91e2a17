"""The reconstruction's defaults, chosen by ``scripts/validate_reconstruct.py`` on the demo's validation
performers (``pipelines/kickboxing/validation/reconstruct.json``: every value tried and its score; the test
performers never took part). ``tests/test_reconstruct_defaults.py`` checks that these are that file's
choices and that the CLI and the library default to them."""

METHOD = "olng"          # olng's best beat nn's and the subsequence graph's
K = 64                   # neighbours per frame: the fewest within 2 % of the best pose error (128 was better by less)
N_BLEND = 32             # neighbours blended
WINDOW_S = 0.25          # OLNG window, seconds (0.25-2 s alike within the 0.1 mm tie; the shortest kept)
SMOOTH_FRAMES = 1.0      # Gaussian sigma of the pose over time, frames
PIN_MAX_OFFSET = None    # no cap on how far leg IK pulls a planted foot: least pose error and least skate
REFINE_PRIOR = 0.1       # the blend bent toward the keypoints (vidstyle.reconstruct.refine): 0.1 beat off, 1, 0.03
REFINE_SMOOTH_FRAMES = 3.0  # the refined pose smoothed in time (Gaussian sigma, frames; 0: not): the least acceleration
                           # error of 0, 1, 2, 3 within 2 % of their least pose error
#: the pictorial structures' classified views tracked through the video (vidstyle.pose.viewtrack): the cost of a
#: quarter turn between frames and the least time between two quarter turns (seconds; at most one per frame),
#: chosen together by scripts/validate_view_tracking.py (validation/view_tracking.json)
VIEW_STEP_COST = 2.0
VIEW_DWELL_S = 0.1
#: Foot contacts and the pins' drift per 2D backend (``Observation.backend``), chosen last, on the validation
#: performers with each source's 2D: ``contact_threshold`` (the neighbours' vote that plants a foot),
#: ``contact_gap_s`` (lifts between planted runs bridged) and ``pin_drift`` (a planted foot moves with the root
#: lock's slow drift). A backend's own entry: the least foot skate within 2 % of the best pose error with its 2D
#: (the pictorial structures' 2D trusts the vote further: lower, and bridged); ``default`` (true 2D, an unknown
#: estimator): the least skate within 2 % of each source's best, else the least worst ratio to a best.
CONTACTS = {
    "ps": {"contact_threshold": 0.2, "contact_gap_s": 0.1, "pin_drift": True},
    "blazepose": {"contact_threshold": 0.5, "contact_gap_s": 0.0, "pin_drift": True},
    "default": {"contact_threshold": 0.5, "contact_gap_s": 0.0, "pin_drift": True},
}
