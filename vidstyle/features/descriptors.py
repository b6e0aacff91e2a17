"""The descriptor variants behind one small interface, registered in one place (this file).

A :class:`Descriptor` turns salient points of a grayscale volume into one row each:

- ``describe(volume, points) -> (n, dimension)`` array of ``dtype``; ``volume`` is (frames, height,
  width) in [0, 1], ``points`` (n, 3) integer (frame, row, column);
- ``dimension`` (int) and ``dtype``;
- ``parameters()``: every parameter, JSON-able, with ``"variant"`` (stored in each features file);
- ``temporal_margin``: frames on each side of a point's frame that ``describe`` reads, directly or through
  gradients and smoothing. Describing the points of frames ``[s, e)`` on the slab of frames
  ``[s - margin, e + margin)`` (clipped to the video) gives exactly the descriptors of the whole volume:
  that is what lets ``vidstyle features`` stream a video in windows;
- ``mirror_permutation()``: ``None``, or the column permutation that maps descriptors of a video to
  (nearly) those of its left-right mirror image.

Variants: ``scovanner2007`` (the default, of the library as of the CLI), ``thesis``, ``sift2d``. Adding a
variant is one class here decorated with :func:`register`.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from typing import Any, ClassVar

import numpy as np

from ..errors import InputError
from . import defaults as D

#: The default variant of the library and of ``vidstyle features --variant`` (see that option's note).
DEFAULT_VARIANT = D.VARIANT

REGISTRY: dict[str, type["Descriptor"]] = {}


def register(cls: type["Descriptor"]) -> type["Descriptor"]:
    REGISTRY[cls.name] = cls
    return cls


class Descriptor(ABC):
    name: ClassVar[str]
    dtype: ClassVar[type]

    @property
    @abstractmethod
    def dimension(self) -> int: ...

    @property
    @abstractmethod
    def temporal_margin(self) -> int: ...

    @abstractmethod
    def parameters(self) -> dict[str, Any]: ...

    @abstractmethod
    def _describe(self, volume: np.ndarray, points: np.ndarray) -> np.ndarray: ...

    def describe(self, volume: np.ndarray, points: np.ndarray) -> np.ndarray:
        from .sift3d import check_points, check_volume

        vol = check_volume(volume)
        pts = check_points(vol, points)
        return self._describe(vol, pts)

    def mirror_permutation(self) -> np.ndarray | None:
        return None

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.parameters()})"


@register
class Scovanner2007(Descriptor):
    """The authors' released code: 80 icosahedral bins, no rotation, 640-D uint8 (no parameters)."""

    name = "scovanner2007"
    dtype = np.uint8

    def __init__(self, params: None = None) -> None:
        if params is not None:
            raise InputError("variant scovanner2007: takes no parameters (it is fixed by the released code)")

    @property
    def dimension(self) -> int:
        from .scovanner2007 import DIM

        return DIM

    @property
    def temporal_margin(self) -> int:
        from .scovanner2007 import HALF

        return HALF + 1  # samples at +-HALF frames, their time derivative one frame further

    def parameters(self) -> dict[str, Any]:
        from .scovanner2007 import PARAMS

        return {"variant": self.name, **PARAMS}

    def _describe(self, volume, points):
        from .scovanner2007 import describe

        return describe(volume, points)

    def mirror_permutation(self) -> np.ndarray:
        from .scovanner2007 import mirror_permutation

        return mirror_permutation()


@register
class Thesis(Descriptor):
    """3D SIFT as the paper and thesis describe it (8x4 bins, rotation-invariant, float32, 256-D)."""

    name = "thesis"
    dtype = np.float32

    def __init__(self, params=None) -> None:
        from .sift3d import Sift3DParams

        if params is not None and not isinstance(params, Sift3DParams):
            raise InputError("variant thesis: params must be a Sift3DParams")
        self.params = params if params is not None else Sift3DParams()

    @property
    def dimension(self) -> int:
        return self.params.dim

    @property
    def temporal_margin(self) -> int:
        from .sift3d import SMOOTH_TRUNCATE, ball_offsets

        offs = ball_offsets(self.params.sample_radius)
        R = int(np.abs(offs[:, 0]).max()) if len(offs) else 0
        sig_t, _ = self.params.smooth_sigmas
        kt = math.ceil(SMOOTH_TRUNCATE * sig_t) if sig_t > 0 else 0
        return R + 1 + kt  # samples, central difference, temporal smoothing

    def parameters(self) -> dict[str, Any]:
        return {"variant": self.name, **self.params.to_dict()}

    def _describe(self, volume, points):
        from .sift3d import neighbourhood_batches, describe_batch

        p = self.params
        out = np.zeros((len(points), p.dim), dtype=np.float32)
        for idx, arrays in neighbourhood_batches(volume, points, p):
            out[idx] = describe_batch(*arrays, p)[0]
        return out


@register
class Sift2D(Descriptor):
    """Ablation: 2D SIFT of the frame patch (4x4 cells x 8 bins, rotation-invariant, float32, 128-D)."""

    name = "sift2d"
    dtype = np.float32

    def __init__(self, params=None) -> None:
        from .sift2d import Sift2DParams

        if params is not None and not isinstance(params, Sift2DParams):
            raise InputError("variant sift2d: params must be a Sift2DParams")
        self.params = params if params is not None else Sift2DParams()

    @property
    def dimension(self) -> int:
        return self.params.dim

    @property
    def temporal_margin(self) -> int:
        return 0  # one frame

    def parameters(self) -> dict[str, Any]:
        return {"variant": self.name, **self.params.to_dict()}

    def _describe(self, volume, points):
        from .sift2d import describe

        return describe(volume, points, self.params)


VARIANTS = tuple(REGISTRY)


def get_descriptor(variant: str = DEFAULT_VARIANT, params: Any = None) -> Descriptor:
    """The descriptor ``variant`` with its parameter object (``None``: its defaults)."""
    if isinstance(variant, Descriptor):
        return variant
    cls = REGISTRY.get(variant)
    if cls is None:
        raise InputError(f"variant: expected one of {', '.join(REGISTRY)}, got {variant!r}")
    return cls(params)


def describe(volume: np.ndarray, points: np.ndarray, variant: str = DEFAULT_VARIANT, params: Any = None) -> np.ndarray:
    """Descriptors (n, d) of ``points`` in ``volume`` with ``variant`` (default: the CLI's default)."""
    return get_descriptor(variant, params).describe(volume, points)
