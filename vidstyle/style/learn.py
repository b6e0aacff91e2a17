"""The behaviour-style stage as library calls: what ``vidstyle learn-style`` and ``vidstyle generate`` run,
with the defaults of :mod:`vidstyle.style.defaults` (a Python user with defaults gets the CLI's styles)."""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path

from ..errors import InputError
from . import defaults as D
from .artifact import Style, StyleParams, dataset_styles, parse_k_range
from .events import EventParams

PathLike = str | os.PathLike


def style_params(
    ignore: str | Sequence[str] = D.IGNORE,
    min_confidence: float = D.MIN_CONFIDENCE,
    min_run: int = D.MIN_RUN,
    max_gap: int = D.MAX_GAP,
    split_repeats: bool = D.SPLIT_REPEATS,
    seed: int = D.SEED,
    n_init: int = D.N_INIT,
    n_iter: int = D.N_ITER,
    alpha: float = D.ALPHA,
    learn_emission: bool = D.LEARN_EMISSION,
    emission_prior: float = D.EMISSION_PRIOR,
    modes: str | Sequence[int] = D.MODES,
    mode_criterion: str = D.MODE_CRITERION,
) -> StyleParams:
    """Checked :class:`StyleParams` (events, HMM fitting, behaviour modes). ``ignore``: class names or a
    comma-separated string; ``modes``: mode counts or a range such as ``"1-6"`` / ``"1,2,4"``."""
    if isinstance(ignore, str):
        ignore = [x for x in ignore.split(",")]
    events = EventParams(
        ignore=tuple(x.strip() for x in ignore if x.strip()), min_confidence=min_confidence,
        min_run=min_run, max_gap=max_gap, split_repeats=split_repeats,
    )
    k_range = parse_k_range(modes) if isinstance(modes, str) else tuple(int(k) for k in modes)
    return StyleParams(
        events=events, seed=seed, alpha=alpha, learn_emission=learn_emission, emission_prior=emission_prior,
        n_init=n_init, n_iter=n_iter, k_range=k_range, mode_criterion=mode_criterion,
    )


def learn(
    labels: Sequence[PathLike] = (),
    *,
    dataset: PathLike | None = None,
    labels_dir: PathLike | None = None,
    views: Sequence[str] | None = None,
    params: StyleParams | None = None,
    jobs: int = 1,
) -> list[tuple[str | None, Style]]:
    """Learn styles (HMMs + durations) from frame labels: one from the label files ``labels`` of one
    performer (returned as ``[(None, style)]``), or one per performer of ``dataset`` from its performance
    videos (``[(performer, style), ...]``; ground truth, or the recognised ``<video id>.json`` of
    ``labels_dir``; ``views``: only these; ``jobs``: performers in parallel, -1 all cores). ``params``:
    :func:`style_params` (default: all defaults).
    Everything is learned before anything is returned, so a bad file leaves nothing half-done."""
    from ..formats.dataset import read_dataset
    from ..formats.labels import read_labels

    params = params if params is not None else style_params()
    if dataset is None:
        if not labels:
            raise InputError("learn-style: give LABELS... --out FILE, or --dataset DIR --out-dir DIR")
        return [(None, Style.from_tracks([read_labels(p) for p in labels], params))]
    if labels:
        raise InputError("learn-style: with --dataset give --out-dir (and no LABELS or --out)")
    return list(dataset_styles(read_dataset(dataset), params, Path(labels_dir) if labels_dir else None,
                               list(views) if views is not None else None, jobs=jobs))


def generate_sequence(style: Style, length: int = D.GENERATE_LENGTH, start: str | None = None, seed: int = D.SEED,
                      model: str = D.MODEL, style_path: PathLike | None = None):
    """A new action sequence (:class:`~vidstyle.formats.sequence.ActionSequence`, events with durations)
    in ``style``: ``length`` events from model ``a`` (thesis HMM), ``b`` (behaviour modes) or ``bigram``,
    first ``start`` (default: drawn), deterministic in ``seed``."""
    from ..formats.sequence import ActionSequence

    events = style.generate(length, start=start, seed=seed, model=model)
    return ActionSequence.from_events(events, style.fps, style=str(style_path), model=model, seed=seed)
