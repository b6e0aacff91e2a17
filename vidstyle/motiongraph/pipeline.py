"""The motion-graph stages as library calls, with the CLI's validated defaults (:mod:`.defaults`):

>>> graph = build_graph(["clips/"], ["clips.csv"])                              # doctest: +SKIP
>>> result = synthesize(graph, "sequence.json")                                 # doctest: +SKIP
>>> save_synthesis(result, "out.bvh")       # out.bvh + out.labels.json          # doctest: +SKIP

``vidstyle build-graph`` is :func:`build_graph` + ``graph.save``; ``vidstyle synthesize`` is
:func:`synthesize` + :func:`save_synthesis` (+ an optional preview video).
"""

from __future__ import annotations

import logging
import os
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..formats.walk import parse_walk_labels, write_walk_labels
from ..mocap import Motion, write_bvh
from . import defaults
from .graph import Clip, MotionGraph, load_clips
from .labels import UNLABELLED
from .synthesis import Step, Walk, plan_walk, read_sequence, render_walk, walk_labels

log = logging.getLogger(__name__)


def build_graph(
    clips: Sequence[str | os.PathLike],
    labels: Sequence[str | os.PathLike] = (),
    *,
    window: int = defaults.WINDOW,
    fps: float = defaults.FPS,
    threshold: float | None = None,
    threshold_quantile: float = defaults.THRESHOLD_QUANTILE,
    min_gap: int | None = None,
    mirror: bool = defaults.MIRROR,
    tile: int = defaults.TILE,
    dtype: str = defaults.DTYPE,
    n_jobs: int = defaults.N_JOBS,
    scheduler: str | None = None,
    random_state: int = defaults.RANDOM_STATE,
    require_classes: Sequence[str] = (),
) -> MotionGraph:
    """Load labelled clips (BVH files or directories; labels: demo ``.labels.json``, CMU ``clips.csv`` or
    ``file,label[,start,end]`` CSV) and fit a :class:`MotionGraph`. The parameters are checked before
    any clip is read (:class:`~vidstyle.errors.ParameterError`). ``require_classes``: actions the graph
    must have frames of (the classes of your annotations or style): checked once the labels are read,
    before the all-pairs pass (:func:`check_classes`)."""
    graph = MotionGraph(window=window, fps=fps, threshold=threshold, threshold_quantile=threshold_quantile,
                        min_gap=min_gap, mirror=mirror, tile=tile, dtype=dtype, n_jobs=n_jobs, scheduler=scheduler,
                        random_state=random_state)
    graph.check_params()
    loaded = load_clips(list(clips), list(labels))
    check_classes(loaded, require_classes, fps=fps, window=window)
    graph.fit(loaded)
    warn_unwalkable(graph)
    return graph


def warn_unwalkable(graph: MotionGraph) -> list[str]:
    """Warn about (and return) the actions with frames in the graph but none in its walkable part (the
    largest strongly connected component): synthesize cannot perform them."""
    names = graph.label_names_
    have = {names[i] for i in np.unique(graph.labels_)} - {UNLABELLED}
    walkable = {names[i] for i in np.unique(graph.labels_[graph.scc_])} if graph.scc_.any() else set()
    lost = sorted(have - walkable)
    if lost:
        log.warning("the graph has frames of %s but no transitions into them from the rest (none is in its "
                    "walkable part, %d of %d frames), so synthesize cannot perform %s: raise --quantile or "
                    "--threshold, or add clips that move between these actions",
                    ", ".join(map(repr, lost)), int(graph.scc_.sum()), len(graph.labels_),
                    "it" if len(lost) == 1 else "them")
    return lost


def library_seconds(clips: Sequence[Clip]) -> dict[str, float]:
    """Seconds of motion per label in ``clips`` (unlabelled frames included under their label)."""
    out: dict[str, float] = {}
    for c in clips:
        per_frame = 1.0 / float(c.motion.fps)
        for label in c.labels:
            out[label] = out.get(label, 0.0) + per_frame
    return out


def check_classes(clips: Sequence[Clip], required: Sequence[str], *, fps: float = defaults.FPS,
                  window: int = defaults.WINDOW) -> None:
    """Refuse (:class:`~vidstyle.errors.InputError`) a library without frames of one of the ``required``
    actions, naming them and what the library has, before the expensive build; warn about an action with
    fewer frames than one blend window (``window`` frames at ``fps``), which synthesis can hardly show."""
    required = [c for c in dict.fromkeys(str(r).strip() for r in required) if c]
    if not required:
        return
    have = library_seconds(clips)
    known = sorted(k for k in have if k != UNLABELLED)
    missing = [c for c in required if c not in have or c == UNLABELLED]
    if missing:
        raise InputError(
            f"require_classes: the library has no frames labelled {', '.join(map(repr, missing))} "
            f"(it has {', '.join(known) if known else 'no labelled frames'}), so synthesize could not perform "
            f"{'it' if len(missing) == 1 else 'them'}: label library clips with those actions (--labels, a CSV "
            "file,label[,start,end] of frames of the BVH files) or name your classes like the library's")
    need = window / float(fps)
    for c in required:
        if have[c] < need:
            log.warning("the library has only %.2f s of %r (%d frames at %g fps); a step of it needs at least "
                        "one blend window, %d frames (%.2f s): label more library frames with %r",
                        have[c], c, round(have[c] * fps), fps, window, need, c)


@dataclass
class Synthesis:
    """What :func:`synthesize` returns: the planned ``walk``, the rendered ``motion``, its labels document
    (``labels``, :mod:`vidstyle.formats.walk`) and the planning + rendering time in ``seconds``."""

    walk: Walk
    motion: Motion
    labels: dict
    seconds: float


def labels_path(bvh: str | os.PathLike) -> Path:
    """Where the labels of a synthesised BVH go: ``<stem>.labels.json`` beside it."""
    bvh = Path(bvh)
    return bvh.with_name(bvh.stem + ".labels.json")


def synthesize(
    graph: MotionGraph,
    sequence: str | os.PathLike | Sequence[Step],
    *,
    bvh_name: str | None = None,
    seconds: float = defaults.STEP_SECONDS,
    mismatch_penalty: float = defaults.MISMATCH_PENALTY,
    transition_penalty: float = defaults.TRANSITION_PENALTY,
    strict: bool = defaults.STRICT,
    foot_lock: bool = defaults.FOOT_LOCK,
    max_in_degree: int | None = None,
) -> Synthesis:
    """Walk ``graph`` to realise ``sequence`` (a sequence file, see :func:`.read_sequence`, or steps) at
    minimum transition cost, render the walk and label it: plan -> render -> labels. ``seconds``: duration
    of steps given without one; ``bvh_name``: the BVH the labels name (default: the sequence's stem)."""
    if isinstance(sequence, (str, os.PathLike)):
        steps = read_sequence(sequence, graph.fps, seconds)
        name = bvh_name or Path(sequence).stem + ".bvh"
    else:
        steps = list(sequence)
        name = bvh_name or "walk.bvh"
    t0 = time.perf_counter()
    walk = plan_walk(graph, steps, mismatch_penalty, transition_penalty, strict=strict, max_in_degree=max_in_degree)
    motion = render_walk(graph, walk, foot_lock=foot_lock)
    elapsed = time.perf_counter() - t0
    return Synthesis(walk, motion, walk_labels(graph, walk, name), elapsed)


def save_synthesis(result: Synthesis, out: str | os.PathLike) -> Path:
    """Write the motion to ``out`` (BVH) and its labels beside it (returned); the labels are checked
    before anything is written. The labels name ``out``'s file name."""
    out = Path(out)
    doc = dict(result.labels, bvh=out.name)
    dest = labels_path(out)
    parse_walk_labels(doc, dest)  # checked before anything is written
    write_bvh(result.motion, out)
    write_walk_labels(dest, doc)
    return dest
