"""Defaults of the pose model (:class:`vidstyle.pose.estimator.PoseModel`, ``vidstyle train-pose``),
chosen on validation renders by ``scripts/validate_pose.py`` (table and scores:
``pipelines/kickboxing/validation/pose.json``). A light module: the CLI reads it at start-up."""

VIEWPOINT_METHODS = ("svm", "logistic", "hog", "combined")
DEFAULTS = {"n_orient": 8, "hard_rounds": 1, "viewpoint": "hog", "unary_weight": 2.0, "fg_weight": 2.0}

#: part detectors of ``vidstyle train-pose`` (``--detector``)
DETECTOR = "cnn"
#: training augmentations of the cnn detector (``train-pose --augment``, :class:`vidstyle.pose.cnn.HeatmapCNN`)
AUGMENTS = ("flip", "affine")
#: the cnn detector's defaults (:class:`vidstyle.pose.cnn.CnnPoseModel`)
CNN_DEFAULTS = {"unary_weight": 16.0, "epochs": 20, "channels": 48, "refine": 3, "stride": 2, "flip_test": True,
                "augment": "flip", "demo_performers": 30, "cmu_clips": 71, "views_per_clip": 16}
#: the training set of ``vidstyle train-pose`` (demo performers, CMU clips, azimuths per clip)
TRAIN_SET = ("demo_performers", "cmu_clips", "views_per_clip")
#: zoom factors of the pictorial structures' multi-scale inference when none are given (``vidstyle pose
#: --backend ps --scales``, :func:`vidstyle.pose.run.estimate_video`): each frame is also zoomed about the
#: person by each factor and the most confident pose kept. Chosen by ``scripts/validate_pose_scales.py`` on
#: validation renders with figures 0.3..1.4 times the training renders' (``validation/pose_scales.json``):
#: the fewest zooms within a point of the best mean PCK@0.2; at the training figure size they change nothing
PS_SCALES: tuple[float, ...] = (1.0, 1.4, 2.0)
#: environment variables the CLI reads for ``--cmu-dir`` (CMU BVH clips) and ``evaluate pose --real-dir``
CMU_ENV = "VIDSTYLE_CMU_DIR"
REAL_ENV = "VIDSTYLE_REAL_DIR"

#: the pictorial-structures model shipped inside the package (``vidstyle pose --backend ps`` without
#: ``--model``), trained by ``scripts/train_default_pose.py`` (its settings and time are in the file's
#: ``training`` record)
SHIPPED_MODEL_NAME = "ps_cnn.joblib"


def shipped_model_path():
    """Path of the shipped pose model file (it may be absent from a source tree that has not trained it)."""
    from importlib.resources import files

    return files("vidstyle.pose") / "weights" / SHIPPED_MODEL_NAME


#: most video frames either side of a marked frame (``vidstyle pose --annotations --context``; also less
#: than the video's frame count); AugMG's matching shares it (:data:`vidstyle.augmg.defaults.MAX_CONTEXT`)
MAX_CONTEXT = 1000
