"""AugMG (thesis 5.2): annotated transition frames -> 2D pose -> match against the mocap library
projected at that viewpoint -> reference point -> enhancement nodes in the motion graph.

Layers: :mod:`.keypoints` (15 body keypoints), :mod:`.projection` (facing-relative 2D projection and
joint-angle features), :mod:`.index` (kNN over the projected library, temporal coherence),
:mod:`.enhance` (enhanced distance, reference point, two-half transition), :mod:`.augment` (enhancement
nodes in a motion graph), :mod:`.defaults` (the validated defaults). The demo's library maker is
:mod:`vidstyle.demo.library`; the evaluation harness is :mod:`vidstyle.evaluation.augmg`.

Entry points (the commands' library calls, defaults from :mod:`.defaults`):

>>> from vidstyle.augmg import augment, match_poses                         # doctest: +SKIP
>>> matches = match_poses("v.poses.json", ["library/clips"])                # vidstyle match-pose
>>> graph, inserted = augment("graph.npz", "annotations.json", ["library/clips"],
...                           poses=["v.poses.json"])                      # vidstyle augment
"""

from typing import TYPE_CHECKING

from ..lazy import lazy_package

if TYPE_CHECKING:  # pragma: no cover
    from .augment import Insertion, augment, augment_graph
    from .index import query_views
    from .match import match_poses

# The names below load their submodule on first use (PEP 562, :mod:`vidstyle.lazy`): the CLI reads
# ``vidstyle.augmg.defaults`` when it builds its options, and that must not import scikit-learn, SciPy
# or OpenCV into every command's start-up. Submodules load on first use too.
_WHERE = {
    "Insertion": "augment",
    "augment": "augment",
    "augment_graph": "augment",
    "query_views": "index",
    "match_poses": "match",
}
__getattr__ = lazy_package(__name__, _WHERE)


__all__ = ["Insertion", "augment", "augment_graph", "defaults", "match_poses", "query_views"]
