"""Training a pose model (``vidstyle train-pose``) as one library call, with the validated defaults of
:mod:`vidstyle.pose.defaults`: a Python user calling :func:`train` with defaults gets the CLI's model.

The CMU clips are explicit: ``cmu_dir`` (``--cmu-dir``, or the ``VIDSTYLE_CMU_DIR`` environment variable
the CLI reads); without one, training renders the demo performers only, and the log says so. (The source
tree's ``../shared/data/mocap/cmu`` is no longer picked up silently: an installed package would not see it.)
"""

from __future__ import annotations

import inspect
import logging
import os
from pathlib import Path
from typing import Any

from ..errors import InputError, ParameterError
from .data import ELEVATION_RANGE, SCALE_RANGE
from .defaults import CMU_ENV, CNN_DEFAULTS, DETECTOR
from .interfaces import detector_class

log = logging.getLogger(__name__)

#: every model parameter of every detector (:func:`make_model` takes them all, uses the chosen one's)
_ALL_PARAMS = {"n_orient", "cell", "C", "neg_per_pos", "hard_rounds", "viewpoint", "dt", "unary_weight", "hog_C",
               "fg_weight", "seed", "refine", "channels", "epochs", "batch_size", "lr", "sigma", "threads", "stride",
               "flip_test", "augment"}


def resolve_cmu_dir(cmu_dir: str | os.PathLike | None, cmu_clips: int) -> Path | None:
    """``cmu_dir`` checked (an :class:`InputError` when it is not a directory); None stays None, and
    the log states that no CMU clips are rendered when ``cmu_clips`` asked for some."""
    if cmu_dir is None or str(cmu_dir) == "":
        if cmu_clips:
            log.info("no CMU directory given (--cmu-dir or %s): rendering the demo performers only", CMU_ENV)
        return None
    path = Path(cmu_dir)
    if not path.is_dir():
        raise InputError(f"{path}: CMU BVH directory not found")
    return path


def make_model(detector: str = DETECTOR, **params: Any):
    """An unfitted pose model with part detectors ``detector`` (:data:`vidstyle.pose.interfaces.DETECTORS`),
    its parameters checked (:class:`ParameterError` naming the first bad one). ``params``: any of the
    hog model's (:class:`~vidstyle.pose.estimator.PoseModel`) and the cnn model's
    (:class:`~vidstyle.pose.cnn.CnnPoseModel`) constructor parameters; those the chosen model does not
    take are not used, and a value of None means the model's validated default."""
    cls = detector_class(detector)
    accepted = set(inspect.signature(cls.__init__).parameters) - {"self"}
    known = accepted | _ALL_PARAMS
    unknown = sorted(set(params) - known)
    if unknown:
        raise TypeError(f"make_model() got unexpected parameters {', '.join(unknown)}")
    return cls(**{k: v for k, v in params.items() if k in accepted and v is not None}).check_params()


def train(cmu_dir: str | os.PathLike | None = None, *, detector: str = DETECTOR,
          demo_performers: int = CNN_DEFAULTS["demo_performers"], cmu_clips: int = CNN_DEFAULTS["cmu_clips"],
          views_per_clip: int = CNN_DEFAULTS["views_per_clip"], seconds: float = 2.0, fps: float = 4.0,
          seed: int = 0, jobs: int = -1, scheduler: str | None = None,
          elevation: tuple[float, float] = ELEVATION_RANGE, scale: tuple[float, float] = SCALE_RANGE,
          proportions: float = 0.0, **params: Any) -> tuple[Any, dict]:
    """Train a pose model on frames rendered from the demo performers (the ``"demo"`` training source,
    registered by :mod:`vidstyle.demo`) and ``cmu_clips`` CMU clips of ``cmu_dir`` (training subjects),
    ``views_per_clip`` azimuths each, at camera elevations in ``elevation`` (degrees), figure sizes in
    ``scale`` and, with ``proportions`` > 0, bone lengths varied by up to that fraction
    (:func:`vidstyle.pose.data.make_specs`). ``params``: the model's (:func:`make_model`). Returns the fitted
    model and the ``training`` record its file keeps (:func:`vidstyle.pose.estimator.save_model`)."""
    from .data import MAX_PERFORMERS, make_specs

    model = make_model(detector, seed=seed, **params)
    if not 0 <= demo_performers <= MAX_PERFORMERS["train"]:
        raise ParameterError("demo_performers", f"must be between 0 and {MAX_PERFORMERS['train']} (the training "
                             "performers; the next ones are validation performers)")
    if cmu_clips < 0:
        raise ParameterError("cmu_clips", "must be at least 0")
    if views_per_clip < 1:
        raise ParameterError("views_per_clip", "must be at least 1")
    cmu = resolve_cmu_dir(cmu_dir, cmu_clips)
    try:
        specs = make_specs("train", demo_performers, cmu_clips, views_per_clip, seed, cmu, fps=fps, seconds=seconds,
                           elevation=elevation, scale=scale, proportions=proportions)
    except ValueError as exc:
        name = str(exc).split(" ", 1)[0]
        raise ParameterError(name, str(exc).split(" ", 1)[1]) from None
    model.fit_specs(specs, jobs=jobs, scheduler=scheduler)
    training = {"demo_performers": demo_performers, "cmu_clips": cmu_clips, "views_per_clip": views_per_clip,
                "seconds": seconds, "fps": fps, "cmu_dir": None if cmu is None else str(cmu), "n_specs": len(specs),
                "elevation": list(map(float, elevation)), "scale": list(map(float, scale)), "proportions": proportions}
    return model, training
