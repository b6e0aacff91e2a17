"""Motion graphs (Kovar, Gleicher, Pighin 2002): windowed point-cloud frame distance computed for all
pairs by tiled GEMMs, transitions at local minima, C^1 blends, an open edge table (playback, blend, enhancement) with
per-edge costs, pruning to the largest strongly connected
component, and walks that realise an action sequence at minimum transition cost.

>>> from vidstyle.motiongraph import MotionGraph, load_clips, plan_walk, render_walk   # doctest: +SKIP
>>> graph = MotionGraph(window=10, fps=30).fit(load_clips(["clips/"], ["clips.csv"]))  # doctest: +SKIP
>>> from vidstyle.motiongraph import build_graph, synthesize, save_synthesis   # the CLI's stages  # doctest: +SKIP
>>> save_synthesis(synthesize(build_graph(["clips/"], ["clips.csv"]), "seq.json"), "out.bvh")  # doctest: +SKIP

Defaults (shared with the CLI): :mod:`vidstyle.motiongraph.defaults`.
"""

from typing import TYPE_CHECKING

from ..lazy import lazy_package

if TYPE_CHECKING:  # pragma: no cover
    from .blend import blend_frames, blend_weight, slerp
    from .distance import WindowSet, align_windows, all_pair_candidates, compute_tile, joint_weights
    from .graph import SCHEMA, Clip, EdgeKind, MotionGraph, EnhancementSegment, has_tpose_first_frame, load_clips
    from .labels import CMU_KEYWORDS, LabelBook, cmu_action
    from .pipeline import Synthesis, build_graph, labels_path, save_synthesis, synthesize
    from .synthesis import (
        Step,
        Walk,
        edge_frames,
        parse_sequence,
        plan_walk,
        read_sequence,
        render_walk,
        walk_labels,
    )

# The names below load their submodule on first use (PEP 562, :mod:`vidstyle.lazy`): the CLI reads
# ``vidstyle.motiongraph.defaults`` when it builds its options, and that must not import scikit-learn, SciPy
# or OpenCV into every command's start-up. Submodules load on first use too.
_WHERE = {
    "blend_frames": "blend",
    "blend_weight": "blend",
    "slerp": "blend",
    "WindowSet": "distance",
    "align_windows": "distance",
    "all_pair_candidates": "distance",
    "compute_tile": "distance",
    "joint_weights": "distance",
    "SCHEMA": "graph",
    "Clip": "graph",
    "EdgeKind": "graph",
    "MotionGraph": "graph",
    "EnhancementSegment": "graph",
    "has_tpose_first_frame": "graph",
    "load_clips": "graph",
    "CMU_KEYWORDS": "labels",
    "LabelBook": "labels",
    "cmu_action": "labels",
    "Synthesis": "pipeline",
    "build_graph": "pipeline",
    "labels_path": "pipeline",
    "save_synthesis": "pipeline",
    "synthesize": "pipeline",
    "Step": "synthesis",
    "Walk": "synthesis",
    "edge_frames": "synthesis",
    "parse_sequence": "synthesis",
    "plan_walk": "synthesis",
    "read_sequence": "synthesis",
    "render_walk": "synthesis",
    "walk_labels": "synthesis",
}
__getattr__ = lazy_package(__name__, _WHERE)


__all__ = [
    "CMU_KEYWORDS",
    "SCHEMA",
    "Clip",
    "EdgeKind",
    "LabelBook",
    "MotionGraph",
    "EnhancementSegment",
    "Step",
    "Synthesis",
    "Walk",
    "WindowSet",
    "align_windows",
    "all_pair_candidates",
    "blend_frames",
    "blend_weight",
    "build_graph",
    "cmu_action",
    "compute_tile",
    "edge_frames",
    "has_tpose_first_frame",
    "joint_weights",
    "labels_path",
    "load_clips",
    "parse_sequence",
    "plan_walk",
    "read_sequence",
    "render_walk",
    "save_synthesis",
    "slerp",
    "synthesize",
    "walk_labels",
]
