"""Keyframe to keyframe (in-betweening): given a start and an end pose and the time between them, make the
motion between, from a motion library (a fitted :class:`~vidstyle.motiongraph.MotionGraph`).

Three methods on one interface (``inbetween(start, end, n_frames) -> (rotations, roots)``, both keys
included and matched exactly):

* ``markov`` — Molina Tanco & Hilton 2000 (seed 002): PCA + k-means pose clusters, a Markov chain over
  them, the most probable cluster path of the gap's length, library segments along it
  (:mod:`.markov`);
* ``graph`` — the motion graph's shortest path between the frames nearest the keys (:mod:`.graphpath`);
* ``slerp`` — LAFAN1's LERP+SLERP baseline (:func:`.poses.slerp_inbetween`).

>>> from vidstyle.inbetween import MarkovInbetweener, Keypose        # doctest: +SKIP
>>> model = MarkovInbetweener(random_state=0).fit(graph)              # doctest: +SKIP
>>> rotations, roots = model.inbetween(start, end, n_frames=31)       # doctest: +SKIP

Whole keyframe files: :func:`.keyframes.synthesize_keyframes` (``vidstyle synthesize --keyframes``).
Defaults: :mod:`.defaults` (imported by the CLI without SciPy: the names below load on first use).
Evaluation: :mod:`vidstyle.evaluation.inbetween`.
"""

from typing import TYPE_CHECKING

from ..lazy import lazy_package

if TYPE_CHECKING:  # pragma: no cover
    from .graphpath import GraphInbetweener
    from .keyframes import KeyframeSynthesis, synthesize_keyframes
    from .markov import MarkovInbetweener, best_cluster_path, path_score, render_frames, segment_path
    from .poses import Keypose, pin, placement_onto, pose_features, slerp_inbetween

_WHERE = {
    "GraphInbetweener": "graphpath",
    "KeyframeSynthesis": "keyframes",
    "synthesize_keyframes": "keyframes",
    "MarkovInbetweener": "markov",
    "best_cluster_path": "markov",
    "path_score": "markov",
    "render_frames": "markov",
    "segment_path": "markov",
    "Keypose": "poses",
    "pin": "poses",
    "placement_onto": "poses",
    "pose_features": "poses",
    "slerp_inbetween": "poses",
}
__getattr__ = lazy_package(__name__, _WHERE)

__all__ = [
    "GraphInbetweener",
    "KeyframeSynthesis",
    "Keypose",
    "MarkovInbetweener",
    "best_cluster_path",
    "path_score",
    "pin",
    "placement_onto",
    "pose_features",
    "render_frames",
    "segment_path",
    "slerp_inbetween",
    "synthesize_keyframes",
]
