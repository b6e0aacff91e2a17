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

from ..errors import InputError, ParameterError
from ..formats.labels import FrameLabels
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

    def to_dict(self) -> dict[str, Any]:
        from ..formats.style import style_to_dict

        return style_to_dict(self)

    @classmethod
    def from_dict(cls, doc: Any, path: str = "style.json") -> Style:
        """Rebuild a style from its JSON document (validated: a FormatError names the file and field)."""
        from ..formats.style import parse_style

        return parse_style(doc, path)

    @classmethod
    def load(cls, path: str | Path) -> Style:
        from ..formats.style import read_style

        return read_style(path)

    def save(self, path: str | Path) -> None:
        from ..formats.style import write_style

        write_style(path, self)


def dataset_styles(dataset, params: StyleParams, labels_dir=None, views=None) -> list[tuple[str, Style]]:
    """One style per performer of ``dataset`` (a :class:`~vidstyle.formats.dataset.Dataset`), learned from
    the labels of its performance videos: ground truth, or with ``labels_dir`` the recognised labels.
    ``views``: only these views. Every performer needs at least one performance video."""
    from ..formats.labels import read_labels

    out = []
    for pid in dataset.performer_ids():
        files = dataset.performer_label_files(pid, labels_dir, views)
        if not files:
            raise InputError(f"{dataset.path or dataset.root}: performer {pid} has no performance video"
                             + (f" in views {','.join(views)}" if views else ""))
        try:
            style = Style.from_tracks([read_labels(p) for _, p in files], params)
        except InputError as e:
            if labels_dir is None:  # ground truth always holds a chain
                raise
            # recognised labels may hold too few events (a weak recognizer): no style for this performer,
            # the others are still learned
            log.warning("performer %s: no style learned from its recognised labels (%s)", pid, e)
            continue
        style.performer = pid  # recognised label files do not name their performer; the dataset does
        out.append((pid, style))
    if not out:
        raise InputError(f"{labels_dir}: no performer's recognised labels hold enough events to learn a style")
    return out
