"""Defaults of the pose model (:class:`vidstyle.pose.estimator.PoseModel`, ``vidstyle train-pose``),
chosen on validation renders by ``scripts/validate_pose.py`` (table and scores:
``pipelines/kickboxing/validation/pose.json``). A light module: the CLI reads it at start-up."""

VIEWPOINT_METHODS = ("svm", "logistic", "hog", "combined")
DEFAULTS = {"n_orient": 12, "hard_rounds": 1, "viewpoint": "svm", "unary_weight": 1.0, "fg_weight": 0.0}
