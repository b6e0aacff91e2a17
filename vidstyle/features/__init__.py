"""Feature extraction: salient points on video frames and their 3D SIFT descriptors.

Modules:

- :mod:`~vidstyle.features.descriptors` — the descriptor variants behind one interface
  (``describe``, ``dimension``, ``parameters``, ``temporal_margin``, ``mirror_permutation``), registered
  in one place; :func:`~vidstyle.features.descriptors.get_descriptor`. Default ``scovanner2007``.
- :mod:`~vidstyle.features.salient` — per-frame salient points: frame-difference silhouette, dense optical
  flow, the N largest-flow silhouette pixels at least a minimum distance apart (thesis N = 10).
- :mod:`~vidstyle.features.sift3d` — 3D SIFT (Scovanner, Ali, Shah 2007) as the thesis describes it:
  8x4 (theta, phi) orientation bins normalised by solid angle, Gaussian weighting, rotation to the
  dominant orientation, 2x2x2 sub-regions -> 256-D; and the
  thesis variant's entry point :func:`~vidstyle.features.sift3d.describe`.
- :mod:`~vidstyle.features.scovanner2007` — the descriptor as the authors' released code computes it
  (80 icosahedral bins, no rotation, 640-D uint8), bit-exact by its own definition.
- :mod:`~vidstyle.features.sift2d` — the 2D SIFT ablation (``variant="sift2d"``): 4x4 cells x 8 bins of the
  frame patch at the point, rotated to the dominant orientation, 128-D.
- :mod:`~vidstyle.features.extract` — one video -> one ``.npz`` (schema in
  :mod:`vidstyle.formats.features`), streamed through :class:`vidstyle.video.VideoReader` in windows of
  frames; many videos in parallel; :func:`~vidstyle.features.extract.extract_videos` is the stage with
  its validated defaults (:mod:`~vidstyle.features.defaults`), what ``vidstyle features`` runs.
"""

from importlib import import_module
from importlib.util import find_spec
from typing import TYPE_CHECKING

if TYPE_CHECKING:  # pragma: no cover
    from .descriptors import DEFAULT_VARIANT, Descriptor, describe, get_descriptor
    from .extract import extract_videos
    from .salient import SalientParams, salient_points
    from .sift3d import Sift3DParams

# The names below load their submodule on first use (PEP 562), as in :mod:`vidstyle.motiongraph`: the
# CLI reads ``vidstyle.features.defaults`` when it builds its options, and that must not import
# scikit-learn, SciPy or OpenCV into every command's start-up. Submodules load on first use too.
_WHERE = {
    "DEFAULT_VARIANT": "descriptors",
    "Descriptor": "descriptors",
    "describe": "descriptors",
    "get_descriptor": "descriptors",
    "extract_videos": "extract",
    "SalientParams": "salient",
    "salient_points": "salient",
    "Sift3DParams": "sift3d",
}


def __getattr__(name: str):
    if name in _WHERE:
        value = getattr(import_module(f".{_WHERE[name]}", __name__), name)
    elif not name.startswith("_") and find_spec(f"{__name__}.{name}") is not None:  # a submodule
        value = import_module(f".{name}", __name__)
    else:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    globals()[name] = value
    return value


__all__ = ["DEFAULT_VARIANT", "Descriptor", "SalientParams", "Sift3DParams", "describe", "extract_videos", "get_descriptor",
           "salient_points"]
