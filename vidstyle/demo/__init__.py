"""Procedural kickboxing performers and the demo dataset (the embedded stand-in for the thesis'
kickboxing database: six actions, several performers, front/left/right views, 160x120 at 20 fps).

>>> from vidstyle.demo import Performer, build_take, single_action_plan   # doctest: +SKIP
>>> rng = np.random.default_rng(0); p = Performer.random("p00", rng)      # doctest: +SKIP
>>> take = build_take(p, single_action_plan(p, "Jab", 160, rng), rng)    # doctest: +SKIP
>>> take.motion, take.labels                                             # doctest: +SKIP

Layers: :mod:`.skeleton` (CMU layout + body proportions), :mod:`.rig` (pose channels -> joint
rotations by IK), :mod:`.actions` (keyframes), :mod:`.performer` (style + Markov chain),
:mod:`.timeline` (plans -> continuous motion + labels), :mod:`.dataset` (files on disk).
"""

from .actions import ACTIONS, CLASSES
from .dataset import DatasetParams, label_document, make_dataset, make_performer, make_take
from .performer import Chain, Performer, MovementTraits
from .skeleton import UNIT_M, Body, build_skeleton
from .timeline import PlanStep, Take, build_take, performance_plan, single_action_plan

__all__ = [
    "ACTIONS", "CLASSES", "UNIT_M", "Body", "Chain", "DatasetParams", "Performer", "PlanStep", "MovementTraits", "Take",
    "build_skeleton", "build_take", "label_document", "make_dataset", "make_performer", "make_take",
    "performance_plan", "single_action_plan",
]

from . import pose_sources  # noqa: F401  - registers the demo performers as a pose training source
