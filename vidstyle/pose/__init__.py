"""2D pose of video frames (method 2 of the thesis, AugMG's first step).

- :mod:`.dt`: generalised distance transform (Felzenszwalb-Huttenlocher lower envelope) + brute force.
- :mod:`.features`: dense gradient-orientation cells of rotated copies of a frame.
- :mod:`.model`: pictorial structures for one viewpoint (rotated part templates, tree prior, exact
  min-sum inference).
- :mod:`.estimator`: viewpoint-specific + generic models and the viewpoint SVMs (``train-pose``).
- :mod:`.cnn`: convolutional part detectors (keypoint heatmaps) for the same trees.
- :mod:`.blazepose`: MediaPipe BlazePose backend mapped onto the same 15 keypoints.
- :mod:`.interfaces`: the pose backend, part detector and viewpoint classifier interfaces and registries.
- :mod:`.data`: labelled frames rendered from mocap (training sources: :func:`.data.register_source`);
  :mod:`.run`: poses of a video; :mod:`.training`: ``train-pose`` as a library call; :mod:`.defaults`:
  the validated defaults. Its evaluation harness (strict PCP, PCK, viewpoint confusion) is
  :mod:`vidstyle.evaluation.pose`.

The library entry points (what the commands call, with the same defaults)::

    model, training = vidstyle.pose.train(cmu_dir=None)             # vidstyle train-pose
    vidstyle.pose.save_model("pose.joblib", model, {"training": training})
    poses = vidstyle.pose.estimate_video("clip.mp4", "ps", "pose.joblib")       # vidstyle pose
    poses = vidstyle.pose.estimate_marks("clip.mp4", "ann.json", "ps", "pose.joblib")  # pose --annotations
"""

from __future__ import annotations

import importlib

_EXPORTS = {
    "train": ".training", "make_model": ".training", "estimate_video": ".run", "estimate_marks": ".run",
    "mark_frames": ".run", "parse_frames": ".run", "save_model": ".estimator", "load_model": ".estimator",
    "PoseModel": ".estimator", "CnnPoseModel": ".cnn", "register_source": ".data",
}
__all__ = ["CnnPoseModel", "PoseModel", "estimate_marks", "estimate_video", "load_model", "make_model", "mark_frames",
           "parse_frames", "register_source", "save_model", "train"]


def __getattr__(name: str):  # the entry points load on first use: ``import vidstyle.pose.defaults`` stays light
    if name in _EXPORTS:
        return getattr(importlib.import_module(_EXPORTS[name], __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
