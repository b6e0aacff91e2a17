"""The learned style of a performer (``style.json``) and generation of new action sequences.

The file schema is owned by :mod:`vidstyle.formats.style` (``read_style`` / ``write_style``).
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import FormatError, InputError, ParameterError
from ..formats import style as style_format
from ..formats.labels import FrameLabels
from ..formats.style import ActionHMMRecord, BigramRecord, DurationsRecord, ModeHMMRecord, StyleRecord
from .events import EventParams, EventSequence, action_names_of, tracks_to_events
from .models import ActionHMM, BigramModel, DurationModel, ModeHMM, require_transitions

log = logging.getLogger(__name__)

MODELS = ("a", "b", "bigram")


@dataclass(frozen=True)
class StyleParams:
    """Everything that shapes a learned style besides the data."""

    events: EventParams = field(default_factory=EventParams)
    seed: int = 0
    alpha: float = 0.5
    learn_emission: bool = True
    emission_prior: float = 10.0
    emission_eps: float = 0.05
    n_init: int = 4
    n_iter: int = 200
    tol: float = 1e-3
    k_range: tuple[int, ...] = (1, 2, 3, 4, 5, 6)
    mode_criterion: str = "heldout"
    mode_alpha: float = 0.5
    mode_emission_alpha: float = 0.05

    def __post_init__(self) -> None:
        if self.n_init < 1:
            raise ParameterError("n_init", f"must be >= 1, got {self.n_init}")
        if self.n_iter < 1:
            raise ParameterError("n_iter", f"must be >= 1, got {self.n_iter}")
        if min(self.alpha, self.mode_alpha, self.mode_emission_alpha) <= 0:
            raise ParameterError("alpha", "smoothing pseudo-counts must be > 0")
        if not self.k_range or min(self.k_range) < 1:
            raise ParameterError("k_range", f"need positive mode counts, got {list(self.k_range)}")
        if self.mode_criterion not in ("heldout", "bic"):
            raise ParameterError("mode_criterion", f"'heldout' or 'bic', got {self.mode_criterion!r}")

    def to_dict(self) -> dict:
        d = asdict(self)
        d["events"] = self.events.to_dict()
        d["k_range"] = list(self.k_range)
        return d


def parse_k_range(text: str) -> tuple[int, ...]:
    """``"1-6"`` or ``"1,2,4"`` -> tuple of ints (an :class:`InputError` otherwise)."""
    try:
        out: list[int] = []
        for part in text.split(","):
            part = part.strip()
            if "-" in part:
                lo, hi = (int(x) for x in part.split("-", 1))
                out.extend(range(lo, hi + 1))
            elif part:
                out.append(int(part))
    except ValueError:
        raise ParameterError("k_range", f"expected e.g. '1-6' or '1,2,4', got {text!r}") from None
    if not out or min(out) < 1:
        raise ParameterError("k_range", f"expected positive mode counts, got {text!r}")
    return tuple(sorted(set(out)))


class Style:
    """A performer's learned style: models (a), (b), the bigram baseline and per-action durations."""

    def __init__(
        self,
        actions: Sequence[str],
        classes: Sequence[str],
        params: StyleParams,
        model_a: ActionHMM,
        model_b: ModeHMM,
        bigram: BigramModel,
        durations: DurationModel,
        fps: float = 20.0,
        sources: list[dict] | None = None,
        performer: str | None = None,
        action_counts: np.ndarray | None = None,
        n_sequences: int = 0,
    ):
        self.actions = tuple(actions)
        self.classes = tuple(classes)
        self.params = params
        self.model_a = model_a
        self.model_b = model_b
        self.bigram = bigram
        self.durations = durations
        self.fps = float(fps)
        self.sources = sources or []
        self.performer = performer
        self.action_style = None  # vidstyle.actionmodel.stylefit.ActionStyle, when fitted from 2D (learn-style --poses-dir)
        self.action_counts = (
            np.zeros(len(self.actions), dtype=np.int64) if action_counts is None else np.asarray(action_counts)
        )
        self.n_sequences = n_sequences

    # -- learning ------------------------------------------------------------------------------------

    @classmethod
    def fit(
        cls,
        sequences: Sequence[EventSequence],
        params: StyleParams,
        classes: Sequence[str] | None = None,
        what: str = "labels",
    ) -> Style:
        """Fit all models on event sequences that share one action list."""
        sequences = [s for s in sequences if len(s)]
        if not sequences:
            raise InputError(f"{what}: no action events left after filtering (check the ignored "
                             f"classes, min_confidence, min_run)")
        actions = sequences[0].action_names
        ints = [s.actions for s in sequences]
        require_transitions(ints, what)
        A = len(actions)
        seed = params.seed
        model_a = ActionHMM(
            n_actions=A, alpha=params.alpha, learn_emission=params.learn_emission,
            emission_prior=params.emission_prior, emission_eps=params.emission_eps, n_init=params.n_init,
            n_iter=params.n_iter, tol=params.tol, random_state=seed,
        ).fit(ints)
        model_b = ModeHMM(
            k_range=params.k_range, criterion=params.mode_criterion, n_actions=A, alpha=params.mode_alpha,
            emission_alpha=params.mode_emission_alpha,
            n_init=params.n_init, n_iter=params.n_iter, tol=params.tol, random_state=seed + 1,
        ).fit(ints)
        bigram = BigramModel(n_actions=A, alpha=params.alpha).fit(ints)
        durations = DurationModel(n_actions=A).fit(ints, [s.durations for s in sequences])
        performers = {s.performer for s in sequences}
        counts = np.bincount(np.concatenate(ints), minlength=A)
        sources = [
            {"labels": s.source, "video": s.meta.get("video"), "performer": s.performer,
             "n_frames": s.meta.get("n_frames"), "n_events": len(s)}
            for s in sequences
        ]
        warn_few_events(ints, A, model_b.n_modes_)
        log.info(
            "learned style from %d events in %d sequence(s): model (a) loglik %.1f, model (b) K=%d "
            "loglik %.1f, bigram loglik %.1f", int(counts.sum()), len(sequences), model_a.log_likelihood_,
            model_b.n_modes_, model_b.log_likelihood_, bigram.log_likelihood_,
        )
        return cls(
            actions, classes or actions, params, model_a, model_b, bigram, durations,
            fps=sequences[0].fps, sources=sources,
            performer=performers.pop() if len(performers) == 1 else None,
            action_counts=counts, n_sequences=len(sequences),
        )

    @classmethod
    def from_tracks(cls, tracks: Sequence[FrameLabels], params: StyleParams) -> Style:
        """Label tracks -> events -> style; every track must share one class list."""
        if not tracks:
            raise InputError("LABELS: no label files given")
        names = action_names_of(tracks, params.events)
        seqs = tracks_to_events(tracks, params.events, names)
        for t, s in zip(tracks, seqs):
            s.meta.update(video=t.video, n_frames=len(t.labels))
        if any(len(s) for s in seqs):  # (with no events at all, fit's error says it, once)
            for t, s in zip(tracks, seqs):
                if not len(s):
                    log.warning("%s: no action events after filtering", t.path)
        what = tracks[0].path if len(tracks) == 1 else f"{len(tracks)} label files"
        return cls.fit(seqs, params, classes=tracks[0].classes, what=what)

    # -- generation ----------------------------------------------------------------------------------

    def model(self, which: str):
        try:
            return {"a": self.model_a, "b": self.model_b, "bigram": self.bigram}[which]
        except KeyError:
            raise ParameterError("model", f"one of {', '.join(MODELS)}, got {which!r}") from None

    def action_index(self, name: str, option: str = "start") -> int:
        if name not in self.actions:
            hint = (f"'{name}' is ignored filler, not an action of the chain; "
                    if name in self.params.events.ignore else f"unknown action '{name}'; ")
            raise ParameterError(option, f"{hint}known actions: {', '.join(self.actions)}")
        i = self.actions.index(name)
        if self.action_counts[i] == 0:
            raise ParameterError(
                option, f"action '{name}' never occurs in the training events, so its transitions "
                f"are unknown; seen actions: "
                f"{', '.join(a for a, c in zip(self.actions, self.action_counts) if c)}"
            )
        return i

    def generate(
        self, length: int, start: str | None = None, seed: int = 0, model: str = "a"
    ) -> list[dict]:
        """``length`` events ``{"action", "duration_frames", "start_frame"}``; deterministic in ``seed``.

        The first event is ``start`` (default: drawn from the model's start distribution).
        """
        if length < 1:
            raise ParameterError("length", f"must be >= 1, got {length}")
        m = self.model(model)
        s = None if start is None else self.action_index(start)
        rng = np.random.default_rng(seed)
        acts = m.sample(int(length), start=s, random_state=rng)
        durs = self.durations.sample(acts, random_state=rng)
        starts = np.concatenate([[0], np.cumsum(durs)[:-1]])
        return [
            {"action": self.actions[a], "duration_frames": int(d), "start_frame": int(f)}
            for a, d, f in zip(acts.tolist(), durs.tolist(), starts.tolist())
        ]

    # -- serialisation (the schema is owned by vidstyle.formats.style) ---------------------------------

    def to_record(self) -> StyleRecord:
        """The style as its file's record (:class:`vidstyle.formats.style.StyleRecord`)."""
        a, b, g, d = self.model_a, self.model_b, self.bigram, self.durations
        return StyleRecord(
            actions=list(self.actions), classes=list(self.classes), params=self.params.to_dict(),
            seed=self.params.seed,
            model_a=ActionHMMRecord(a.start_, a.transition_, a.emission_, a.log_likelihood_,
                                    list(a.restart_log_likelihoods_), a.converged_, a.n_iter_),
            model_b=ModeHMMRecord(b.start_, b.transition_, b.emission_, b.log_likelihood_,
                                  list(b.restart_log_likelihoods_), b.converged_, b.n_iter_, n_modes=b.n_modes_,
                                  bic=b.bic_, criterion=b.criterion, selection_scores=dict(b.selection_scores_),
                                  action_transition=b.action_transition()),
            bigram=BigramRecord(g.start_, g.transition_, g.log_likelihood_),
            durations=DurationsRecord(d.mu_, d.sigma_, d.count_, d.mean_frames_, d.sd_frames_),
            fps=self.fps, performer=self.performer, sources=self.sources, n_sequences=self.n_sequences,
            action_counts=self.action_counts,
            action_style=None if getattr(self, "action_style", None) is None else self.action_style.to_record(),
        )

    @classmethod
    def from_record(cls, rec: StyleRecord, path: str | Path | None = None) -> Style:
        """The style a record describes. Parameters out of the estimators' ranges raise ``FormatError``
        naming ``path`` and ``params``."""
        p = dict(rec.params)
        ev = dict(p.pop("events"))
        try:
            events = EventParams(**dict(ev, ignore=tuple(ev["ignore"])))
            if "k_range" in p:
                p["k_range"] = tuple(p["k_range"])
            params = StyleParams(**dict(p, events=events))
        except InputError as e:  # a parameter out of range for the library
            raise FormatError(path, "params", str(e)) from None
        A = len(rec.actions)
        ra, rb, rg, rd = rec.model_a, rec.model_b, rec.bigram, rec.durations
        a = ActionHMM(n_actions=A, random_state=params.seed)
        a.n_actions_ = A
        a.start_, a.transition_, a.emission_ = ra.start, ra.transition, ra.emission
        a.log_likelihood_ = ra.log_likelihood
        a.restart_log_likelihoods_ = list(ra.restart_log_likelihoods)
        a.converged_, a.n_iter_ = ra.converged, ra.n_iter
        K = rb.n_modes
        b = ModeHMM(n_modes=K, n_actions=A, random_state=params.seed + 1)
        b.n_actions_, b.n_modes_ = A, K
        b.start_, b.transition_, b.emission_ = rb.start, rb.transition, rb.emission
        b.log_likelihood_ = rb.log_likelihood
        b.restart_log_likelihoods_ = list(rb.restart_log_likelihoods)
        b.converged_, b.n_iter_ = rb.converged, rb.n_iter
        b.bic_ = rb.bic
        b.criterion = params.mode_criterion if rb.criterion is None else rb.criterion
        b.selection_scores_ = dict(rb.selection_scores)
        g = BigramModel(n_actions=A, alpha=params.alpha)
        g.n_actions_ = A
        g.start_, g.transition_, g.log_likelihood_ = rg.start, rg.transition, rg.log_likelihood
        d = DurationModel(n_actions=A)
        d.n_actions_ = A
        d.mu_, d.sigma_, d.count_, d.mean_frames_, d.sd_frames_ = rd.mu, rd.sigma, rd.count, rd.mean_frames, rd.sd_frames
        style = cls(rec.actions, rec.classes, params, a, b, g, d, fps=rec.fps, sources=rec.sources,
                    performer=rec.performer, action_counts=rec.action_counts, n_sequences=rec.n_sequences)
        if rec.action_style is not None:  # schema 2: the action-level style fitted from 2D
            from ..actionmodel.stylefit import ActionStyle

            style.action_style = ActionStyle.from_record(rec.action_style)
        return style

    def to_dict(self) -> dict[str, Any]:
        return style_format.style_to_dict(self.to_record())

    @classmethod
    def from_dict(cls, doc: Any, path: str = "style.json") -> Style:
        """Rebuild a style from its JSON document (validated: a FormatError names the file and field)."""
        return cls.from_record(style_format.parse_style(doc, path), path)

    @classmethod
    def load(cls, path: str | Path) -> Style:
        """Read ``style.json`` (:mod:`vidstyle.formats.style`); a bad file raises ``FormatError``."""
        return cls.from_record(style_format.read_style(path), path)

    def save(self, path: str | Path) -> None:
        style_format.write_style(path, self.to_record())


def _performer_style(item) -> tuple[str, Style | InputError]:
    """One performer's style of :func:`dataset_styles` (a worker's item): the style, or the
    :class:`InputError` that learning it raised."""
    from ..formats.labels import read_labels

    pid, files, params = item
    try:
        return pid, Style.from_tracks([read_labels(p) for p in files], params)
    except InputError as e:
        return pid, e


def dataset_styles(dataset, params: StyleParams, labels_dir=None, views=None, jobs: int = 1) -> list[tuple[str, Style]]:
    """One style per performer of ``dataset`` (a :class:`~vidstyle.formats.dataset.Dataset`), learned from
    the labels of its performance videos: ground truth, or with ``labels_dir`` the recognised labels.
    ``views``: only these views. Every performer needs at least one performance video. ``jobs``: performers
    learned in parallel (-1: all cores; each style is the same for any number)."""
    from ..parallel import parallel_map

    items = []
    for pid in dataset.performer_ids():
        files = dataset.performer_label_files(pid, labels_dir, views)
        if not files:
            raise InputError(f"{dataset.path or dataset.root}: performer {pid} has no performance video"
                             + (f" in views {','.join(views)}" if views else ""))
        items.append((pid, [p for _, p in files], params))
    out = []
    for pid, style in parallel_map(_performer_style, items, jobs=jobs, description="styles"):
        if isinstance(style, InputError):
            if labels_dir is None:  # ground truth always holds a chain
                raise style
            # recognised labels may hold too few events (a weak recognizer): no style for this performer,
            # the others are still learned
            log.warning("performer %s: no style learned from its recognised labels (%s)", pid, style)
            continue
        style.performer = pid  # recognised label files do not name their performer; the dataset does
        out.append((pid, style))
    if not out:
        raise InputError(f"{labels_dir}: no performer's recognised labels hold enough events to learn a style")
    return out


def warn_few_events(sequences: Sequence[np.ndarray], n_actions: int, n_modes: int) -> list[str]:
    """Warn, saying how many are needed and how many were given, when the events are too few for the
    models being fitted: model (a) estimates ``n_actions x n_actions`` transition probabilities and needs
    at least :data:`~.defaults.MIN_TRANSITIONS_PER_CELL` observed transitions per probability; model (b)
    with ``n_modes`` modes has :meth:`ModeHMM.n_free_parameters` and needs
    :data:`~.defaults.MIN_EVENTS_PER_PARAMETER` events per parameter. Returns the messages."""
    from . import defaults as SD

    n_events = int(sum(len(s) for s in sequences))
    n_trans = int(sum(max(len(s) - 1, 0) for s in sequences))
    msgs = []
    need_a = SD.MIN_TRANSITIONS_PER_CELL * n_actions * n_actions
    if n_trans < need_a:
        msgs.append(
            f"learn-style: only {n_trans} action-to-action transitions ({n_events} events in {len(sequences)} "
            f"label file(s)) for {n_actions} actions; model (a) estimates {n_actions} x {n_actions} transition "
            f"probabilities and needs at least {need_a} transitions (more is better): the style is mostly "
            f"its smoothing prior. Give more labelled footage of this performer (about {need_a - n_trans} more "
            "transitions), or fewer classes")
    need_b = SD.MIN_EVENTS_PER_PARAMETER * ModeHMM.n_free_parameters(n_modes, n_actions)
    if n_modes > 1 and n_events < need_b:
        msgs.append(
            f"learn-style: model (b) took {n_modes} behaviour modes from only {n_events} events; "
            f"{n_modes} modes over {n_actions} actions have {ModeHMM.n_free_parameters(n_modes, n_actions)} "
            f"free parameters and need at least {need_b} events: its modes are not to be trusted (--modes 1 "
            "fits one mode; generate uses model (a) unless --model b)")
    for m in msgs:
        log.warning("%s", m)
    return msgs
