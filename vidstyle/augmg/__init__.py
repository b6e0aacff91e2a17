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

from . import defaults
from .augment import Insertion, augment, augment_graph
from .index import query_views
from .match import match_poses

__all__ = ["Insertion", "augment", "augment_graph", "defaults", "match_poses", "query_views"]
