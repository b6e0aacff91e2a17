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

from typing import TYPE_CHECKING

from ..lazy import lazy_package

if TYPE_CHECKING:  # pragma: no cover
    from .descriptors import DEFAULT_VARIANT, Descriptor, describe, get_descriptor
    from .extract import extract_videos
    from .salient import SalientParams, salient_points
    from .sift3d import Sift3DParams

# The names below load their submodule on first use (PEP 562, :mod:`vidstyle.lazy`): the CLI reads
# ``vidstyle.features.defaults`` when it builds its options, and that must not import scikit-learn, SciPy
# or OpenCV into every command's start-up. Submodules load on first use too.
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
__getattr__ = lazy_package(__name__, _WHERE)


__all__ = ["DEFAULT_VARIANT", "Descriptor", "SalientParams", "Sift3DParams", "describe", "extract_videos", "get_descriptor",
           "salient_points"]
