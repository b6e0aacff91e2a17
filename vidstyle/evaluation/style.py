"""``vidstyle evaluate style``: style metrics on performers whose true chains are known.

For every performer of a dataset manifest (``DIR/dataset.json``), the performance videos are split
into training and held-out parts (by video when there are at least two, else by time: the last
``heldout_fraction`` of the events). A :class:`~vidstyle.style.artifact.Style` is learned on the
training part, then (``docs/design.md``, "Behaviour"; terms in ``docs/results.md``):

* transition-matrix error: mean absolute difference between the learned and the true action
  transition matrix, for model (a), the bigram baseline and the transition implied by model (b);
* style fidelity: Jensen-Shannon divergence (bits) of bigram and trigram distributions of generated
  sequences against the held-out sequences of the same performer, and (mean) of the other performers;
* identification: generated sequences are attributed to the performer whose held-out data (a smoothed
  bigram fitted on it) explains them best; also with the true chains as the judge, and real held-out
  sequences attributed by the learned models (a);
* held-out log-likelihood per event of models (a), (b) and the bigram baseline.

Run once on ground-truth labels and, with ``labels_dir``, once on recognised labels; the difference
is the cost of recognition errors. Recognised labels are scored only for ``performers`` (the recognizer's
*test* performers: a performer whose videos trained or tuned the recognizer would be recognised from
seen data), and the ground truth is scored on those performers too (``ground_truth_test_performers``), so
the two columns differ only by recognition errors.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import InputError, ParameterError
from ..formats import FormatError
from ..formats.dataset import Dataset, read_dataset
from ..formats.labels import read_labels
from ..style.artifact import Style, StyleParams
from ..style.events import EventSequence, tracks_to_events
from ..style.models import BigramModel, normalise_rows
from ..style.ngram import ngram_jsd

log = logging.getLogger(__name__)

TARGETS = {"transition_mae": 0.05, "identification_accuracy": 0.90, "min_performers": 5}


@dataclass(frozen=True)
class EvalParams:
    style: StyleParams = field(default_factory=StyleParams)
    heldout_fraction: float = 0.34
    n_generate: int = 20
    generate_length: int = 40

    def __post_init__(self) -> None:
        if not 0.0 < self.heldout_fraction < 1.0:
            raise ParameterError("heldout_fraction", f"must be in (0, 1), got {self.heldout_fraction}")
        if self.n_generate < 1:
            raise ParameterError("n_generate", f"must be >= 1, got {self.n_generate}")
        if self.generate_length < 3:
            raise ParameterError("generate_length", f"must be >= 3, got {self.generate_length}")

    def to_dict(self) -> dict:
        return {"style": self.style.to_dict(), "heldout_fraction": self.heldout_fraction,
                "n_generate": self.n_generate, "generate_length": self.generate_length}


@dataclass
class PerformerData:
    pid: str
    train: list[EventSequence]
    heldout: list[EventSequence]
    true_start: np.ndarray  # (A,) in manifest action order
    true_transition: np.ndarray  # (A, A)
    true_duration_mean: np.ndarray  # (A,) frames, NaN if unknown


def load_manifest(dataset_dir: str | Path) -> Dataset:
    """``DIR/dataset.json`` with what style evaluation needs: >= 2 actions, every performer's true chain."""
    ds = read_dataset(dataset_dir)
    if len(ds.actions) < 2:
        raise FormatError(ds.path, "actions", f"need at least 2 actions, got {len(ds.actions)}")
    for i, p in enumerate(ds.performers):
        if p.chain is None:
            raise FormatError(ds.path, f"performers[{i}].chain", f"missing (performer {p.id}: style evaluation "
                              "compares against the true chain)")
    return ds


def _split(seqs: list[EventSequence], frac: float, takes: list[str] | None = None
           ) -> tuple[list[EventSequence], list[EventSequence]]:
    """Train / held-out events that never share a moment of the same performance.

    The views of one performance take are the same motion seen twice, so whole takes are held out
    (every view of them). With a single take every view is cut at the same frame: the first
    ``1 - frac`` of the take trains, the rest is held out.
    """
    takes = list(takes) if takes is not None else [str(i) for i in range(len(seqs))]
    if len(takes) != len(seqs):
        raise ValueError("one take name per sequence")
    order = list(dict.fromkeys(t for t, s in zip(takes, seqs) if len(s)))
    if len(order) >= 2:
        n_held = min(len(order) - 1, max(1, round(frac * len(order))))
        held_takes = set(order[-n_held:])
        train = [s for t, s in zip(takes, seqs) if len(s) and t not in held_takes]
        held = [s for t, s in zip(takes, seqs) if len(s) and t in held_takes]
        return train, held
    seqs = [s for s in seqs if len(s)]
    if not seqs or min(len(s) for s in seqs) < 4:
        return seqs, []
    end = max(int(s.starts[-1] + s.durations[-1]) for s in seqs)
    cut = (1 - frac) * end
    train, held = [], []
    for s in seqs:
        k = int(np.searchsorted(s.starts, cut, side="left"))
        if k > 0:
            train.append(s.slice(0, k))
        if k < len(s):
            held.append(s.slice(k, len(s)))
    return train, held


def _nanmean(xs) -> float:
    """Mean of the finite values; NaN when there is none."""
    xs = [x for x in xs if np.isfinite(x)]
    return float(np.mean(xs)) if xs else float("nan")


def load_performers(
    dataset: Dataset, params: EvalParams, labels_dir: str | Path | None = None, performers: list[str] | None = None,
) -> list[PerformerData]:
    """Events of every performer's (or only ``performers``') performance videos, split into train / held-out."""
    actions = list(dataset.actions)
    out = []
    if performers is not None:
        unknown = sorted(set(performers) - {p.id for p in dataset.performers})
        if unknown:
            raise InputError(f"{dataset.path}: no performer {unknown[0]!r}")
    for p in dataset.performers:
        if performers is not None and p.id not in performers:
            continue
        files = dataset.performer_label_files(p.id, labels_dir)
        if not files:
            log.warning("performer %s has no performance videos; skipped", p.id)
            continue
        tracks = [read_labels(path) for _, path in files]
        seqs = tracks_to_events(tracks, params.style.events, actions)
        for s in seqs:
            s.performer = p.id
        takes = [v.take for v, _ in files]
        train, held = _split(seqs, params.heldout_fraction, takes)
        start, trans, dur = p.chain.reordered(actions)
        out.append(PerformerData(p.id, train, held, start, trans, dur))
    return out


def _mean(xs) -> float | None:
    xs = [x for x in xs if x is not None and np.isfinite(x)]
    return float(np.mean(xs)) if xs else None


def _fit_style(item) -> Style:
    """The style of one performer's training sequences (a worker's item of :func:`evaluate_dataset`)."""
    p, style_params = item
    return Style.fit(p.train, style_params, what=f"performer {p.pid} training labels")


def evaluate_performers(perfs: list[PerformerData], params: EvalParams,
                        fitted: dict[str, Style] | None = None) -> dict[str, Any]:
    """All style metrics for one label source (see the module docstring). ``fitted``: performer id ->
    style already fitted on their training sequences (:func:`_fit_style`); the others are fitted here."""
    if len(perfs) < 2:
        raise InputError(f"dataset: need at least 2 performers with events, got {len(perfs)}")
    seed = params.style.seed
    fitted = fitted or {}
    styles: dict[str, Style] = {}
    rows: list[dict[str, Any]] = []
    generated: dict[str, dict[str, list[np.ndarray]]] = {}
    for i, p in enumerate(perfs):
        if not p.heldout:
            raise InputError(f"performer {p.pid}: too few events to hold any out")
        st = fitted[p.pid] if p.pid in fitted else _fit_style((p, params.style))
        styles[p.pid] = st
        held = [s.actions for s in p.heldout]
        n_held = int(sum(len(h) for h in held))
        gens = {}
        for j, which in enumerate(("a", "b")):
            rng = np.random.default_rng([seed, i, j])
            m = st.model(which)
            gens[which] = [m.sample(params.generate_length, random_state=rng) for _ in range(params.n_generate)]
        generated[p.pid] = gens
        dmask = np.isfinite(p.true_duration_mean) & (st.action_counts > 0)
        rows.append({
            "performer": p.pid,
            "n_train_events": int(st.action_counts.sum()),
            "n_heldout_events": n_held,
            "n_train_sequences": len(p.train),
            "n_heldout_sequences": len(p.heldout),
            "transition_mae": {
                "a": float(np.abs(st.model_a.transition_ - p.true_transition).mean()),
                "bigram": float(np.abs(st.bigram.transition_ - p.true_transition).mean()),
                "b_implied": float(np.abs(st.model_b.action_transition() - p.true_transition).mean()),
            },
            "duration_mean_abs_error_frames": (
                float(np.abs(st.durations.mean_frames_[dmask] - p.true_duration_mean[dmask]).mean())
                if dmask.any() else None
            ),
            "heldout_loglik_per_event": {
                "a": st.model_a.score_per_event(held),
                "b": st.model_b.score_per_event(held),
                "bigram": st.bigram.score_per_event(held),
            },
            "n_modes": st.model_b.n_modes_,
            "model_a_converged": st.model_a.converged_,
            "model_b_converged": st.model_b.converged_,
        })
        log.info("performer %s: %d train / %d held-out events, MAE(a) %.3f, K=%d", p.pid,
                 rows[-1]["n_train_events"], n_held, rows[-1]["transition_mae"]["a"], st.model_b.n_modes_)

    pids = [p.pid for p in perfs]
    held_by = {p.pid: [s.actions for s in p.heldout] for p in perfs}
    A = len(perfs[0].true_transition)
    judges = {
        "heldout_bigram": {q: BigramModel(n_actions=A, alpha=params.style.alpha).fit(held_by[q]) for q in pids},
        "true_chain": {},
    }
    for p in perfs:
        g = BigramModel(n_actions=A)
        g.n_actions_ = A
        g.start_ = normalise_rows(np.clip(p.true_start, 1e-12, None))
        g.transition_ = normalise_rows(np.clip(p.true_transition, 1e-12, None))
        judges["true_chain"][p.pid] = g

    def identify(seqs_by_pid: dict[str, list[np.ndarray]], judge: dict) -> tuple[float, dict]:
        correct = total = 0
        confusion = {p: {q: 0 for q in pids} for p in pids}
        for p, seqs in seqs_by_pid.items():
            for s in seqs:
                scores = [judge[q].score([s]) for q in pids]
                guess = pids[int(np.argmax(scores))]
                confusion[p][guess] += 1
                correct += guess == p
                total += 1
        return correct / max(total, 1), confusion

    fidelity: dict[str, Any] = {}
    ident: dict[str, Any] = {}
    for which in ("a", "b"):
        gen = {p: generated[p][which] for p in pids}
        fid = {}
        for n in (2, 3):
            # NaN where a performer's held-out events hold no n-gram (too few events): left out of the means
            same = [ngram_jsd(gen[p], held_by[p], n) for p in pids]
            other = [_nanmean([ngram_jsd(gen[p], held_by[q], n) for q in pids if q != p]) for p in pids]
            fid[f"jsd_{n}gram_same"] = _nanmean(same)
            fid[f"jsd_{n}gram_other"] = _nanmean(other)
            pairs = [s < o for s, o in zip(same, other) if np.isfinite(s) and np.isfinite(o)]
            fid[f"jsd_{n}gram_same_lt_other_fraction"] = float(np.mean(pairs)) if pairs else float("nan")
            for r, s, o in zip(rows, same, other):
                r.setdefault("jsd", {})[f"{which}_{n}gram"] = {"same": s, "other": o}
        # reference: the real training data of each performer against its own held-out data
        fid["jsd_2gram_train_vs_heldout"] = _nanmean(
            [ngram_jsd([s.actions for s in p.train], held_by[p.pid], 2) for p in perfs])
        fidelity[which] = fid
        acc, conf = identify(gen, judges["heldout_bigram"])
        acc_true, _ = identify(gen, judges["true_chain"])
        ident[which] = {"accuracy_by_heldout_data": acc, "accuracy_by_true_chain": acc_true,
                        "confusion_by_heldout_data": conf}
    acc_real, conf_real = identify(held_by, {p: styles[p].model_a for p in pids})
    ident["heldout_sequences_by_model_a"] = {"accuracy": acc_real, "confusion": conf_real}

    def pooled_ll(key: str) -> float:
        num = sum(r["heldout_loglik_per_event"][key] * r["n_heldout_events"] for r in rows)
        return num / sum(r["n_heldout_events"] for r in rows)

    mae_a = [r["transition_mae"]["a"] for r in rows]
    ll = {k: pooled_ll(k) for k in ("a", "b", "bigram")}
    summary = {
        "n_performers": len(rows),
        "n_train_events": int(sum(r["n_train_events"] for r in rows)),
        "n_heldout_events": int(sum(r["n_heldout_events"] for r in rows)),
        "transition_mae": {k: _mean(r["transition_mae"][k] for r in rows) for k in ("a", "bigram", "b_implied")},
        "transition_mae_max_a": float(max(mae_a)),
        "duration_mean_abs_error_frames": _mean(r["duration_mean_abs_error_frames"] for r in rows),
        "heldout_loglik_per_event": ll,
        "b_minus_bigram_loglik_per_event": ll["b"] - ll["bigram"],
        "fidelity": fidelity,
        "identification": ident,
        "n_modes": {r["performer"]: r["n_modes"] for r in rows},
        "targets": {
            "transition_mae_a_le_0.05": _mean(mae_a) <= TARGETS["transition_mae"],
            "identification_a_ge_0.90": ident["a"]["accuracy_by_heldout_data"] >= TARGETS["identification_accuracy"],
            "n_performers_ge_5": len(rows) >= TARGETS["min_performers"],
            "b_beats_bigram_heldout": ll["b"] > ll["bigram"],
        },
    }
    return {"summary": summary, "performers": rows}


def evaluate_dataset(
    dataset_dir: str | Path, params: EvalParams, labels_dir: str | Path | None = None,
    performers: list[str] | None = None, jobs: int = 1,
) -> dict[str, Any]:
    """Metrics document: ground-truth labels of every performer, and with ``labels_dir`` the recognised
    labels of ``performers`` (required then: the recognizer's test performers) beside their ground truth."""
    manifest = load_manifest(dataset_dir)
    if labels_dir is not None and not performers:
        raise InputError("evaluate style: recognised labels need the recognizer's test performers (performers), "
                         "so that no scored video trained or tuned the recognizer")
    # load every label file before any fitting, so a missing or bad file fails fast
    inputs = {"ground_truth": load_performers(manifest, params)}
    if labels_dir is not None:
        inputs["ground_truth_test_performers"] = load_performers(manifest, params, None, performers)
        inputs["recognised"] = load_performers(manifest, params, labels_dir, performers)
    # every source's styles fitted first, ``jobs`` at a time (each is the same for any number of workers)
    from ..parallel import parallel_map

    items = [(name, p) for name, perfs in inputs.items() for p in perfs if p.heldout]
    done = parallel_map(_fit_style, [(p, params.style) for _, p in items], jobs=jobs, description="styles")
    styles: dict[str, dict[str, Style]] = {name: {} for name in inputs}
    for (name, p), st in zip(items, done):
        styles[name][p.pid] = st
    sources = {name: evaluate_performers(perfs, params, styles[name]) for name, perfs in inputs.items()}
    return {
        "kind": "vidstyle.metrics.style",
        "schema_version": 1,
        "seed": params.style.seed,
        "params": params.to_dict(),
        "dataset": str(dataset_dir),
        "dataset_seed": manifest.seed,
        "labels_dir": None if labels_dir is None else str(labels_dir),
        "recognised_performers": None if labels_dir is None else sorted(performers),
        "targets": TARGETS,
        "sources": sources,
    }
