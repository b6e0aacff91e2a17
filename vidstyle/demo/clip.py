"""``vidstyle demo performer`` as library calls: one procedural clip of a demo performer, repeating an
action or performing their own chain, and its BVH + labels files."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from ..errors import ParameterError
from ..formats.labels import write_labels
from ..mocap import write_bvh
from .actions import ACTIONS
from .dataset import DatasetParams, label_document, make_performer
from .performer import Performer
from .timeline import Take, build_take, performance_plan, single_action_plan

SECONDS = 8.0
MOCAP_FPS = 60
MIN_SECONDS = 1.5


def performer_clip(seed: int = 0, index: int = 0, action: str | None = None, seconds: float = SECONDS,
                   fps: int = MOCAP_FPS) -> tuple[Performer, Take]:
    """Performer ``index`` of the dataset of ``seed`` and a ``seconds`` long take at ``fps`` (a multiple of
    20): ``action`` repeated (case-insensitive name) or, with None, a performance following their chain."""
    if action is not None:
        match = [a for a in ACTIONS if a.lower() == action.lower()]
        if not match:
            raise ParameterError("action", f"unknown action {action!r} (one of {', '.join(ACTIONS)})")
        action = match[0]
    if fps <= 0 or fps % 20:
        raise ParameterError("fps", f"must be a positive multiple of 20, got {fps}")
    if seconds < MIN_SECONDS:
        raise ParameterError("seconds", f"must be at least {MIN_SECONDS}, got {seconds}")
    if index < 0:
        raise ParameterError("index", f"must be >= 0, got {index}")
    params = DatasetParams(seed=seed, mocap_fps=fps)
    performer = make_performer(params, index)
    rng = np.random.default_rng(np.random.SeedSequence([seed, index, 999]))
    n = int(round(seconds * 20))
    plan = single_action_plan(performer, action, n, rng) if action else performance_plan(performer, n, rng)
    return performer, build_take(performer, plan, rng, video_fps=20, ratio=fps // 20)


def write_performer_clip(out: str | os.PathLike, seed: int = 0, index: int = 0, action: str | None = None,
                         seconds: float = SECONDS, fps: int = MOCAP_FPS) -> tuple[Performer, Take, Path]:
    """:func:`performer_clip` written as the BVH ``out`` and ``<stem>.labels.json`` beside it (returned)."""
    out = Path(out)
    performer, take = performer_clip(seed, index, action, seconds, fps)
    write_bvh(take.motion, out)
    labels_path = out.with_name(out.stem + ".labels.json")
    write_labels(labels_path, label_document(take.labels, float(fps), take.chain, bvh=out.name, performer=performer.id))
    return performer, take, labels_path
