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

import sys
from importlib import import_module
from importlib.util import find_spec
from types import ModuleType
from typing import TYPE_CHECKING

if TYPE_CHECKING:  # pragma: no cover
    from .augment import Insertion, augment, augment_graph
    from .index import query_views
    from .match import match_poses

# The names below load their submodule on first use (PEP 562), as in :mod:`vidstyle.motiongraph`: the
# CLI reads ``vidstyle.augmg.defaults`` when it builds its options, and that must not import
# scikit-learn, SciPy or OpenCV into every command's start-up. Submodules load on first use too.
_WHERE = {
    "Insertion": "augment",
    "augment": "augment",
    "augment_graph": "augment",
    "query_views": "index",
    "match_poses": "match",
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


class _Package(ModuleType):
    """The package module. The import system binds a submodule to its package's attribute when it first
    loads it; ``augmg.augment`` stays the function of the API (as when this file imported everything),
    whoever loads the submodule ``augment`` first."""

    def __setattr__(self, name: str, value) -> None:
        if name in _WHERE and isinstance(value, ModuleType):
            return
        super().__setattr__(name, value)


sys.modules[__name__].__class__ = _Package


__all__ = ["Insertion", "augment", "augment_graph", "defaults", "match_poses", "query_views"]
