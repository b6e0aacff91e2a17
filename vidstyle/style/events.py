"""Frame labels -> action events.

Label files (one per video) are :class:`vidstyle.formats.labels.FrameLabels` (read them with
:func:`vidstyle.formats.labels.read_labels`; ``confidence`` is optional, one value per frame).

The thesis (Chen 2012, sec. 6.1.3) feeds the HMM "only the actions classified with certainty"; here that
is made explicit: frames below ``min_confidence`` become unknown, runs shorter than ``min_run`` frames
are noise, filler classes (``Guard``, ``Step``) separate actions but are not actions of the chain. A run
that is interrupted only by a short stretch of dropped noise frames is one event, not two.

Consecutive repeats of one action (``Jab Jab``) with no filler in between show up as one long run. With
``split_repeats`` such a run is cut into ``round(length / d)`` events, where ``d`` is the typical length
of a single occurrence of that action, estimated from the shortest cluster of its runs (see
:func:`split_repeated_runs`). Runs shorter than ``repeat_factor * d`` (default 1.5 d) are never split.
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from ..errors import InputError, ParameterError
from ..formats.labels import FrameLabels
from . import defaults as D

log = logging.getLogger(__name__)

DEFAULT_IGNORE: tuple[str, ...] = D.IGNORE


@dataclass(frozen=True)
class EventParams:
    """How frame labels become events (all lengths in frames)."""

    ignore: tuple[str, ...] = DEFAULT_IGNORE
    min_confidence: float = D.MIN_CONFIDENCE
    min_run: int = D.MIN_RUN
    max_gap: int = D.MAX_GAP
    split_repeats: bool = D.SPLIT_REPEATS
    repeat_factor: float = 1.5

    def __post_init__(self) -> None:
        if not 0.0 <= self.min_confidence <= 1.0:
            raise ParameterError("min_confidence", f"must be in [0, 1], got {self.min_confidence}")
        if self.min_run < 1:
            raise ParameterError("min_run", f"must be >= 1 frame, got {self.min_run}")
        if self.max_gap < 0:
            raise ParameterError("max_gap", f"must be >= 0 frames, got {self.max_gap}")
        if self.repeat_factor <= 1.0:
            raise ParameterError("repeat_factor", f"must be > 1, got {self.repeat_factor}")

    def to_dict(self) -> dict:
        return {
            "ignore": list(self.ignore),
            "min_confidence": self.min_confidence,
            "min_run": self.min_run,
            "max_gap": self.max_gap,
            "split_repeats": self.split_repeats,
            "repeat_factor": self.repeat_factor,
        }


@dataclass
class EventSequence:
    """Action events of one video. ``actions``: (events,) int indices into ``action_names``;
    ``durations`` and ``starts``: (events,) int frames."""

    action_names: tuple[str, ...]
    actions: np.ndarray
    durations: np.ndarray
    starts: np.ndarray
    source: str = ""
    performer: str | None = None
    fps: float = 20.0
    meta: dict = field(default_factory=dict)

    def __len__(self) -> int:
        return len(self.actions)

    def names(self) -> list[str]:
        return [self.action_names[i] for i in self.actions]

    def slice(self, start: int, stop: int) -> EventSequence:
        return EventSequence(
            self.action_names, self.actions[start:stop], self.durations[start:stop],
            self.starts[start:stop], self.source, self.performer, self.fps, dict(self.meta),
        )


def runs(values: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Run-length encoding of a 1-D array: (values, starts, lengths) of maximal constant runs."""
    values = np.asarray(values)
    if values.size == 0:
        e = np.zeros(0, dtype=np.int64)
        return values[:0], e, e
    change = np.flatnonzero(values[1:] != values[:-1]) + 1
    starts = np.concatenate([[0], change])
    lengths = np.diff(np.concatenate([starts, [values.size]]))
    return values[starts], starts.astype(np.int64), lengths.astype(np.int64)


def track_to_events(
    track: FrameLabels, params: EventParams, action_names: Sequence[str] | None = None
) -> EventSequence:
    """Collapse a label track into action events (see the module docstring for the rules).

    ``action_names``: the chain's actions (default: the track's classes minus ``params.ignore``); a
    class of the track that is neither ignored nor an action is an error.
    """
    ignore = set(params.ignore)
    if action_names is None:
        action_names = [c for c in track.classes if c not in ignore]
    action_names = tuple(action_names)
    act_index = {a: i for i, a in enumerate(action_names)}
    stray = [c for c in track.classes if c not in ignore and c not in act_index]
    if stray:
        raise InputError(f"{track.path}: classes {', '.join(stray)} are neither actions nor ignored")
    # per-frame code: action index >= 0, FILLER for ignored classes, UNKNOWN for low confidence
    FILLER, UNKNOWN = -1, -2
    lut = np.array([act_index.get(c, FILLER) for c in track.classes], dtype=np.int64)
    code = lut[track.indices()]
    if track.confidence is not None:
        code = np.where(track.confidence < params.min_confidence, UNKNOWN, code)

    vals, starts, lens = runs(code)
    ev_act: list[int] = []
    ev_start: list[int] = []
    ev_end: list[int] = []  # exclusive
    separated = True  # a valid filler run (or the start of the video) since the last event
    # short runs (< min_run) of an action near a kept run of the same action belong to it: the run was
    # cut by noise frames. pending[action] = (start, end) of the latest chain of such fragments.
    pending: dict[int, tuple[int, int]] = {}
    for v, s, n in zip(vals.tolist(), starts.tolist(), lens.tolist()):
        if v == FILLER:
            if n >= params.min_run:
                separated = True
                pending.clear()
            continue
        if v == UNKNOWN:
            continue
        joins_last = (
            bool(ev_act) and not separated and ev_act[-1] == v and s - ev_end[-1] <= params.max_gap
        )
        if n < params.min_run:
            if joins_last:
                ev_end[-1] = s + n
            else:
                p = pending.get(v)
                pending[v] = (p[0], s + n) if p is not None and s - p[1] <= params.max_gap else (s, s + n)
            continue
        if joins_last:
            ev_end[-1] = s + n  # the same action resumed after a short noise burst: one event
        else:
            p = pending.get(v)
            begin = p[0] if p is not None and s - p[1] <= params.max_gap else s
            ev_act.append(v)
            ev_start.append(begin)
            ev_end.append(s + n)
        pending.clear()
        separated = False
    seq = EventSequence(
        action_names=action_names,
        actions=np.asarray(ev_act, dtype=np.int64),
        durations=np.asarray(ev_end, dtype=np.int64) - np.asarray(ev_start, dtype=np.int64),
        starts=np.asarray(ev_start, dtype=np.int64),
        source=track.path,
        performer=track.performer,
        fps=track.fps,
    )
    return seq


def single_durations(sequences: Sequence[EventSequence], n_actions: int) -> np.ndarray:
    """Typical length (frames) of one occurrence of each action; NaN where an action has no runs.

    Runs of an action are a mixture of 1, 2, 3... back-to-back occurrences. The lowest cluster is
    found from the 25th percentile q: runs no longer than 1.5 q are taken as single occurrences and
    their median is the estimate (robust unless repeats outnumber single occurrences 3:1).
    """
    out = np.full(n_actions, np.nan)
    allacts = np.concatenate([s.actions for s in sequences]) if sequences else np.zeros(0, int)
    alldur = np.concatenate([s.durations for s in sequences]) if sequences else np.zeros(0, int)
    for a in range(n_actions):
        d = alldur[allacts == a].astype(float)
        if d.size == 0:
            continue
        q = np.percentile(d, 25)
        single = d[d <= 1.5 * q]
        out[a] = float(np.median(single if single.size else d))
    return out


def split_repeated_runs(
    sequences: Sequence[EventSequence], params: EventParams
) -> list[EventSequence]:
    """Cut runs that are clearly several back-to-back occurrences of one action into equal events."""
    if not params.split_repeats or not sequences:
        return list(sequences)
    n_actions = len(sequences[0].action_names)
    typical = single_durations(sequences, n_actions)
    out = []
    for seq in sequences:
        acts, durs, starts = [], [], []
        for a, d, s in zip(seq.actions.tolist(), seq.durations.tolist(), seq.starts.tolist()):
            t = typical[a]
            k = 1
            if np.isfinite(t) and t > 0 and d >= params.repeat_factor * t:
                k = max(1, round(d / t))
            edges = np.linspace(s, s + d, k + 1).round().astype(int)
            for i in range(k):
                acts.append(a)
                starts.append(int(edges[i]))
                durs.append(int(edges[i + 1] - edges[i]))
        out.append(
            EventSequence(
                seq.action_names, np.asarray(acts, dtype=np.int64), np.asarray(durs, dtype=np.int64),
                np.asarray(starts, dtype=np.int64), seq.source, seq.performer, seq.fps, dict(seq.meta),
            )
        )
    return out


def tracks_to_events(
    tracks: Sequence[FrameLabels], params: EventParams, action_names: Sequence[str] | None = None
) -> list[EventSequence]:
    """Events of several tracks with one shared action list (repeat splitting pools all tracks)."""
    if not tracks:
        return []
    if action_names is None:
        action_names = action_names_of(tracks, params)
    seqs = [track_to_events(t, params, action_names) for t in tracks]
    return split_repeated_runs(seqs, params)


def action_names_of(tracks: Sequence[FrameLabels], params: EventParams) -> tuple[str, ...]:
    """The chain's actions: classes of the first track minus the ignored ones; all tracks must agree."""
    first = tracks[0]
    for t in tracks[1:]:
        if t.classes != first.classes:
            raise InputError(
                f"{t.path}: classes {list(t.classes)} differ from {first.path}'s {list(first.classes)}"
            )
    missing = [c for c in params.ignore if c not in first.classes]
    if missing:
        log.debug("ignored classes not in %s: %s", first.path, missing)
    names = tuple(c for c in first.classes if c not in set(params.ignore))
    if len(names) < 2:
        raise InputError(
            f"{first.path}: need at least 2 action classes besides the ignored ones "
            f"({', '.join(params.ignore) or 'none'}), got {list(names)}"
        )
    return names
