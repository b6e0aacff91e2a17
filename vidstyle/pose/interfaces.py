"""What varies in 2D pose, one interface each (as :class:`vidstyle.features.descriptors.Descriptor` is for
descriptors), and the registries that choose an implementation by name instead of string ``if``s:

- :class:`PoseBackend`: frames -> :class:`~vidstyle.formats.poses.PoseFrame` (``vidstyle pose --backend``):
  ``"ps"`` (pictorial structures, a trained :class:`~vidstyle.pose.estimator.PoseModel` file) and
  ``"blazepose"`` (:class:`~vidstyle.pose.blazepose.BlazePoseEstimator`, MediaPipe);
- :class:`PartDetector`: the unary terms of the pictorial structures (``train-pose --detector``): ``"hog"``
  (HOG cells + linear templates, :class:`~vidstyle.pose.estimator.PoseModel`) and ``"cnn"`` (keypoint
  heatmaps, :class:`~vidstyle.pose.cnn.CnnPoseModel`);
- :class:`ViewpointClassifier`: viewpoint features -> view name (``train-pose --viewpoint``): ``"svm"``,
  ``"logistic"``, ``"hog"``, ``"combined"`` (:mod:`vidstyle.pose.estimator`) and ``"cnn"`` (the network's
  head, :class:`~vidstyle.pose.cnn.CnnPoseModel`).

Registries hold import paths ("module:attribute"), resolved on use: this module stays light (the CLI reads
the names at start-up) and heavy backends (PyTorch, MediaPipe) load only when chosen.
"""

from __future__ import annotations

import importlib
from typing import Any, Protocol, runtime_checkable

import numpy as np

from ..errors import ParameterError
from ..formats.poses import PoseFrame


@runtime_checkable
class PoseBackend(Protocol):
    """Pose of one frame (BGR, any size; keypoints in that frame's pixels)."""

    #: whether :meth:`estimate` uses a static-camera ``background`` (the person prior)
    uses_background: bool

    def estimate(self, frame: np.ndarray, index: int = 0, background: np.ndarray | None = None) -> PoseFrame: ...

    def working_height(self, native_height: int) -> int: ...

    def set_inference(self, scales=None) -> Any: ...

    def close(self) -> None: ...


@runtime_checkable
class PartDetector(Protocol):
    """The unary terms of the pictorial structures: a strategy a pose model is composed with
    (``model.parts_``). Stateless: the learned parts live in the model (trees, network), every method takes
    the model it serves, so model files pickle no strategy object."""

    #: trains on colour renders; adds the person prior of a video's background (``fg_weight``)
    needs_colour: bool
    uses_foreground: bool

    def fit(self, model: Any, samples: list, jobs: int = -1, scheduler: str | None = None) -> Any: ...

    def prepare(self, model: Any, frame: np.ndarray) -> tuple[Any, float]: ...

    def view_features(self, model: Any, f: Any, full: bool | None = None,
                      which: str | None = None) -> tuple[dict, Any]: ...

    def foreground_map(self, model: Any, frame: np.ndarray, background: np.ndarray | None, f: Any): ...

    def solve(self, model: Any, model_name: str, S: np.ndarray, scale: float, fg=None, f=None,
              fg_weight: float | None = None) -> np.ndarray: ...


@runtime_checkable
class ViewpointClassifier(Protocol):
    """Viewpoint features of frames -> view names and per-view scores (softmax-like, summing to 1)."""

    #: the viewpoint features it reads ("torso", "parts", "hog", "cnn")
    NEEDS: tuple[str, ...]

    def input_of(self, feats: dict) -> Any: ...

    def predict(self, X) -> np.ndarray: ...

    def scores(self, X) -> list[dict[str, float]]: ...


#: ``vidstyle pose --backend``: name -> the class or loader (``backend_factory``)
BACKENDS = {"ps": "vidstyle.pose.estimator:load_backend", "blazepose": "vidstyle.pose.blazepose:BlazePoseEstimator"}
#: ``vidstyle train-pose --detector``: name -> the pose model class that trains with those part detectors
DETECTORS = {"hog": "vidstyle.pose.estimator:PoseModel", "cnn": "vidstyle.pose.cnn:CnnPoseModel"}
#: the part detector strategies (:class:`PartDetector`) a pose model's ``detector`` names
PART_DETECTORS = {"hog": "vidstyle.pose.estimator:HogParts", "cnn": "vidstyle.pose.cnn:CnnParts"}
_PART_INSTANCES: dict = {}
#: backends that read a trained pose model file
MODEL_BACKENDS = ("ps",)


def _resolve(table: dict[str, str], name: str, param: str, what: str):
    if name not in table:
        raise ParameterError(param, f"{name!r} is not {' or '.join(table)}" if len(table) == 2
                             else f"{name!r} is not one of {', '.join(table)} ({what})")
    module, attr = table[name].split(":")
    return getattr(importlib.import_module(module), attr)


def check_backend(name: str) -> str:
    if name not in BACKENDS:
        _resolve(BACKENDS, name, "backend", "pose backends")
    return name


def backend_factory(name: str):
    """``factory(model_path) -> PoseBackend`` of backend ``name`` (:class:`ParameterError` ``backend``)."""
    target = _resolve(BACKENDS, name, "backend", "pose backends")
    if name in MODEL_BACKENDS:
        return target
    return lambda _model_path=None: target()


def part_detector(name: str) -> PartDetector:
    """The (stateless, shared) part detector strategy called ``name``."""
    if name not in _PART_INSTANCES:
        _PART_INSTANCES[name] = _resolve(PART_DETECTORS, name, "detector", "part detectors")()
    return _PART_INSTANCES[name]


def detector_class(name: str) -> type:
    """The pose model class of part detector ``name`` (:class:`ParameterError` ``detector``)."""
    return _resolve(DETECTORS, name, "detector", "part detectors")
