"""The learned style of a performer (``style.json``) and generation of new action sequences.

``style.json`` schema (``schema_version`` 1; matrices are row-stochastic lists of lists, rows and
columns in the order of ``actions``; modes of model (b) are rows of its matrices)::

    {
      "schema_version": 1, "kind": "vidstyle.style",
      "seed": 0,
      "params": {"events": {ignore, min_confidence, min_run, max_gap, split_repeats, repeat_factor},
                 "alpha", "learn_emission", "emission_prior", "emission_eps", "n_init", "n_iter", "tol",
                 "k_range", "mode_criterion", "mode_alpha", "mode_emission_alpha"},
      "classes": [...],                # the label files' classes
      "actions": [...],                # the chain's actions = classes minus params.events.ignore
      "fps": 20.0,
      "performer": "p03" | null,       # when every label file names the same performer
      "sources": [{"labels": path, "video", "performer", "n_frames", "n_events"}],
      "n_sequences": int, "n_events": int,
      "action_counts": {action: events},
      "model_a": {"type": "action-hmm", "start": [A], "transition": [A][A], "emission": [A][A],
                  "log_likelihood": float, "restart_log_likelihoods": [...], "converged": bool,
                  "n_iter": int},
      "model_b": {"type": "mode-hmm", "n_modes": K, "start": [K], "transition": [K][K],
                  "emission": [K][A], "log_likelihood", "bic", "selection": {"criterion",
                  "scores": {"K": score}}, "restart_log_likelihoods", "converged", "n_iter",
                  "action_transition": [A][A]},
      "bigram": {"type": "bigram", "start": [A], "transition": [A][A], "log_likelihood": float},
      "durations": {action: {"distribution": "lognormal", "mu", "sigma", "n", "mean_frames",
                             "sd_frames"}}
    }

Log-likelihoods are natural logs over the training events.
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import InputError
from .events import EventParams, EventSequence, LabelTrack, action_names_of, tracks_to_events
from .models import ActionHMM, BigramModel, DurationModel, ModeHMM, require_transitions

log = logging.getLogger(__name__)

SCHEMA_VERSION = 1
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
            raise InputError(f"--n-init: must be >= 1, got {self.n_init}")
        if self.n_iter < 1:
            raise InputError(f"--n-iter: must be >= 1, got {self.n_iter}")
        if min(self.alpha, self.mode_alpha, self.mode_emission_alpha) <= 0:
            raise InputError("--alpha: smoothing pseudo-counts must be > 0")
        if not self.k_range or min(self.k_range) < 1:
            raise InputError(f"--modes: need positive mode counts, got {list(self.k_range)}")
        if self.mode_criterion not in ("heldout", "bic"):
            raise InputError(f"--mode-criterion: 'heldout' or 'bic', got {self.mode_criterion!r}")

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
        raise InputError(f"--modes: expected e.g. '1-6' or '1,2,4', got {text!r}") from None
    if not out or min(out) < 1:
        raise InputError(f"--modes: expected positive mode counts, got {text!r}")
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
            raise InputError(f"{what}: no action events left after filtering (check --ignore, "
                             f"--min-confidence, --min-run)")
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
    def from_tracks(cls, tracks: Sequence[LabelTrack], params: StyleParams) -> Style:
        """Label tracks -> events -> style; every track must share one class list."""
        if not tracks:
            raise InputError("LABELS: no label files given")
        names = action_names_of(tracks, params.events)
        seqs = tracks_to_events(tracks, params.events, names)
        for t, s in zip(tracks, seqs):
            s.meta.update(video=t.video, n_frames=len(t.labels))
            if not len(s):
                log.warning("%s: no action events after filtering", t.path)
        what = tracks[0].path if len(tracks) == 1 else f"{len(tracks)} label files"
        return cls.fit(seqs, params, classes=tracks[0].classes, what=what)

    # -- generation ----------------------------------------------------------------------------------

    def model(self, which: str):
        try:
            return {"a": self.model_a, "b": self.model_b, "bigram": self.bigram}[which]
        except KeyError:
            raise InputError(f"--model: one of {', '.join(MODELS)}, got {which!r}") from None

    def action_index(self, name: str, option: str = "--start") -> int:
        if name not in self.actions:
            hint = (f"'{name}' is ignored filler, not an action of the chain; "
                    if name in self.params.events.ignore else f"unknown action '{name}'; ")
            raise InputError(f"{option}: {hint}known actions: {', '.join(self.actions)}")
        i = self.actions.index(name)
        if self.action_counts[i] == 0:
            raise InputError(
                f"{option}: action '{name}' never occurs in the training events, so its transitions "
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
            raise InputError(f"--length: must be >= 1, got {length}")
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

    # -- serialisation -------------------------------------------------------------------------------

    def to_dict(self) -> dict[str, Any]:
        a, b, g, d = self.model_a, self.model_b, self.bigram, self.durations
        return {
            "schema_version": SCHEMA_VERSION,
            "kind": "vidstyle.style",
            "seed": self.params.seed,
            "params": self.params.to_dict(),
            "classes": list(self.classes),
            "actions": list(self.actions),
            "fps": self.fps,
            "performer": self.performer,
            "sources": self.sources,
            "n_sequences": self.n_sequences,
            "n_events": int(self.action_counts.sum()),
            "action_counts": {n: int(c) for n, c in zip(self.actions, self.action_counts)},
            "model_a": {
                "type": "action-hmm",
                "start": a.start_, "transition": a.transition_, "emission": a.emission_,
                "log_likelihood": a.log_likelihood_,
                "restart_log_likelihoods": a.restart_log_likelihoods_,
                "converged": a.converged_, "n_iter": a.n_iter_,
            },
            "model_b": {
                "type": "mode-hmm",
                "n_modes": b.n_modes_,
                "start": b.start_, "transition": b.transition_, "emission": b.emission_,
                "log_likelihood": b.log_likelihood_, "bic": b.bic_,
                "selection": {"criterion": b.criterion,
                              "scores": {str(k): v for k, v in b.selection_scores_.items()}},
                "restart_log_likelihoods": b.restart_log_likelihoods_,
                "converged": b.converged_, "n_iter": b.n_iter_,
                "action_transition": b.action_transition(),
            },
            "bigram": {"type": "bigram", "start": g.start_, "transition": g.transition_,
                       "log_likelihood": g.log_likelihood_},
            "durations": {
                n: {"distribution": "lognormal", "mu": float(d.mu_[i]), "sigma": float(d.sigma_[i]),
                    "n": int(d.count_[i]),
                    "mean_frames": None if np.isnan(d.mean_frames_[i]) else float(d.mean_frames_[i]),
                    "sd_frames": None if np.isnan(d.sd_frames_[i]) else float(d.sd_frames_[i])}
                for i, n in enumerate(self.actions)
            },
        }

    @classmethod
    def from_dict(cls, doc: Any, path: str = "style.json") -> Style:
        """Rebuild a style from its JSON document (validated: an :class:`InputError` names the field)."""
        if not isinstance(doc, dict) or doc.get("kind") != "vidstyle.style":
            raise InputError(f"{path}: not a vidstyle style file (missing \"kind\": \"vidstyle.style\")")
        if doc.get("schema_version") != SCHEMA_VERSION:
            raise InputError(f"{path}: schema_version {doc.get('schema_version')!r} is not supported "
                             f"(expected {SCHEMA_VERSION})")
        try:
            actions = [str(x) for x in doc["actions"]]
            A = len(actions)
            p = doc["params"]
            ev = EventParams(**{**p["events"], "ignore": tuple(p["events"]["ignore"])})
            params = StyleParams(**{**p, "events": ev, "k_range": tuple(p["k_range"])})

            def mat(section: str, key: str, shape: tuple[int, ...]) -> np.ndarray:
                m = np.asarray(doc[section][key], dtype=float)
                if m.shape != shape or not np.all(np.isfinite(m)) or np.any(m < 0):
                    raise InputError(f"{path}: {section}.{key} must be a {shape} non-negative array")
                if not np.allclose(m.sum(axis=-1), 1.0, atol=1e-6):
                    raise InputError(f"{path}: {section}.{key} rows must sum to 1")
                return m

            a = ActionHMM(n_actions=A, random_state=params.seed)
            a.n_actions_ = A
            a.start_ = mat("model_a", "start", (A,))
            a.transition_ = mat("model_a", "transition", (A, A))
            a.emission_ = mat("model_a", "emission", (A, A))
            a.log_likelihood_ = float(doc["model_a"]["log_likelihood"])
            a.restart_log_likelihoods_ = list(doc["model_a"].get("restart_log_likelihoods", []))
            a.converged_ = bool(doc["model_a"].get("converged", True))
            a.n_iter_ = int(doc["model_a"].get("n_iter", 0))
            K = int(doc["model_b"]["n_modes"])
            b = ModeHMM(n_modes=K, n_actions=A, random_state=params.seed + 1)
            b.n_actions_, b.n_modes_ = A, K
            b.start_ = mat("model_b", "start", (K,))
            b.transition_ = mat("model_b", "transition", (K, K))
            b.emission_ = mat("model_b", "emission", (K, A))
            b.log_likelihood_ = float(doc["model_b"]["log_likelihood"])
            b.restart_log_likelihoods_ = list(doc["model_b"].get("restart_log_likelihoods", []))
            b.converged_ = bool(doc["model_b"].get("converged", True))
            b.n_iter_ = int(doc["model_b"].get("n_iter", 0))
            b.bic_ = float(doc["model_b"].get("bic", float("nan")))
            sel = doc["model_b"].get("selection", {})
            b.criterion = sel.get("criterion", params.mode_criterion)
            b.selection_scores_ = {int(k): float(v) for k, v in sel.get("scores", {}).items()}
            g = BigramModel(n_actions=A, alpha=params.alpha)
            g.n_actions_ = A
            g.start_ = mat("bigram", "start", (A,))
            g.transition_ = mat("bigram", "transition", (A, A))
            g.log_likelihood_ = float(doc["bigram"]["log_likelihood"])
            d = DurationModel(n_actions=A)
            d.n_actions_ = A
            d.mu_ = np.array([float(doc["durations"][n]["mu"]) for n in actions])
            d.sigma_ = np.array([float(doc["durations"][n]["sigma"]) for n in actions])
            d.count_ = np.array([int(doc["durations"][n]["n"]) for n in actions])
            d.mean_frames_ = np.array([np.nan if doc["durations"][n].get("mean_frames") is None
                                       else float(doc["durations"][n]["mean_frames"]) for n in actions])
            d.sd_frames_ = np.array([np.nan if doc["durations"][n].get("sd_frames") is None
                                     else float(doc["durations"][n]["sd_frames"]) for n in actions])
            counts = np.array([int(doc["action_counts"][n]) for n in actions])
        except InputError:
            raise
        except (KeyError, TypeError, ValueError) as e:
            raise InputError(f"{path}: malformed style file ({type(e).__name__}: {e})") from None
        return cls(
            actions, doc.get("classes", actions), params, a, b, g, d, fps=float(doc.get("fps", 20.0)),
            sources=doc.get("sources", []), performer=doc.get("performer"), action_counts=counts,
            n_sequences=int(doc.get("n_sequences", 0)),
        )

    @classmethod
    def load(cls, path: str | Path) -> Style:
        from ..fileio import read_json

        return cls.from_dict(read_json(path), str(path))
