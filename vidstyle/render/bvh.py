"""``vidstyle render`` as a library call: a BVH file (and optionally its labels file) rendered to a video
with its ground-truth sidecar, every option checked first so a bad one leaves no output.

>>> render_bvh("walk.bvh", "walk.mp4", view="left", size=(160, 120))   # + walk.truth.npz  # doctest: +SKIP
"""

from __future__ import annotations

import os
import re
from pathlib import Path

import numpy as np

from ..errors import InputError, ParameterError
from ..formats.labels import check_length, read_labels
from ..mocap import read_bvh
from ..video import CODECS
from .appearance import Appearance
from .background import parse_background
from .camera import Camera, parse_view
from .core import render_to_file

# the defaults of ``vidstyle render`` (and of :func:`render_bvh`)
VIEW = "front"
ELEVATION_DEG = 10.0
SIZE = (160, 120)
FPS = 20.0
BACKGROUND = "plain"
APPEARANCE = "default"
NOISE_SIGMA = 2.0
SEED = 0


def load_labels(path: str | os.PathLike, n_frames: int) -> tuple[list[str], np.ndarray | None]:
    """Labels (one per mocap frame) and transition flags of a labels file (:mod:`vidstyle.formats.labels`)."""
    track = read_labels(path)
    check_length(track, n_frames, "the motion")
    flags = None
    if track.transitions is not None:
        flags = np.zeros(n_frames, dtype=bool)
        flags[track.transitions] = True
    return track.labels, flags


def appearance_from_spec(spec: str | Appearance | None) -> Appearance:
    """``"default"``, an integer seed (a random look, also as a string), an appearance ``.json`` file, or
    an :class:`Appearance` (returned as is)."""
    if isinstance(spec, Appearance):
        return spec
    if spec is None or spec == "default":
        return Appearance()
    if isinstance(spec, int) or re.fullmatch(r"\d+", str(spec)):
        return Appearance.random(int(spec))
    path = Path(spec)
    if path.suffix.lower() == ".json":
        from ..fileio import read_json

        try:
            return Appearance.from_dict(read_json(path))
        except (TypeError, ValueError) as e:
            raise InputError(f"{path}: not a valid appearance ({e})") from None
    raise ParameterError("appearance", f"expected 'default', a seed (integer) or a .json file, got {spec!r}")


def render_bvh(
    motion_file: str | os.PathLike,
    out: str | os.PathLike,
    *,
    view: str | float = VIEW,
    elevation_deg: float = ELEVATION_DEG,
    distance: float | None = None,
    size: tuple[int, int] = SIZE,
    fps: float = FPS,
    background: str = BACKGROUND,
    appearance: str | Appearance | None = APPEARANCE,
    noise_sigma: float = NOISE_SIGMA,
    seed: int = SEED,
    labels: str | os.PathLike | None = None,
) -> Path:
    """Render ``motion_file`` (BVH) to the video ``out`` (``.mp4``/``.avi``) plus ``<stem>.truth.npz``
    (returned). ``view``: front, left, right, back or an azimuth in degrees relative to the performer's
    facing; ``distance`` None fits the whole clip; ``labels``: the motion's labels file (one label per
    mocap frame, optional transitions). Parameters are checked before anything is read or written."""
    motion_file, out = Path(motion_file), Path(out)
    if out.suffix.lower() not in CODECS:
        raise ParameterError("out", f"{out}: video must end in {', '.join(CODECS)}")
    if not (fps > 0 and np.isfinite(fps)):
        raise ParameterError("fps", f"must be positive, got {fps}")
    if not noise_sigma >= 0:
        raise ParameterError("noise_sigma", f"must be >= 0, got {noise_sigma}")
    try:
        parse_view(view)
        parse_background(background)
    except ValueError as e:
        raise InputError(f"{e}") from None
    look = appearance_from_spec(appearance)
    motion = read_bvh(motion_file)
    if motion.n_frames == 0:
        raise InputError(f"{motion_file}: the motion has no frames")
    lab, trans = load_labels(labels, motion.n_frames) if labels is not None else (None, None)
    try:
        camera = Camera.for_view(motion, view=view, elevation_deg=elevation_deg, distance=distance, size=size)
        return render_to_file(motion, out, camera=camera, fps=fps, appearance=look, background=background,
                              noise_sigma=noise_sigma, seed=seed, labels=lab, transitions=trans)
    except ValueError as e:
        raise InputError(f"{motion_file}: {e}") from None
