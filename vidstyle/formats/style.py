"""A performer's learned style (``style.json``, ``vidstyle learn-style``): the owner of its schema.

Schema (``kind`` ``"vidstyle.style"``, ``schema_version`` 1; matrices are row-stochastic lists of lists,
rows and columns in the order of ``actions``; modes of model (b) are rows of its matrices)::

    {
      "schema_version": 1, "kind": "vidstyle.style",
      "seed": 0,
      "params": {"events": {ignore, min_confidence, min_run, max_gap, split_repeats, repeat_factor},
                 "seed", "alpha", "learn_emission", "emission_prior", "emission_eps", "n_init", "n_iter",
                 "tol", "k_range", "mode_criterion", "mode_alpha", "mode_emission_alpha"},
      "classes": [...],                # the label files' classes (contains every action)
      "actions": [...],                # the chain's actions = classes minus params.events.ignore (>= 2)
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
                  "scores": {"K": score | null}}, "restart_log_likelihoods", "converged", "n_iter",
                  "action_transition": [A][A]},
      "bigram": {"type": "bigram", "start": [A], "transition": [A][A], "log_likelihood": float},
      "durations": {action: {"distribution": "lognormal", "mu", "sigma", "n", "mean_frames" | null,
                             "sd_frames" | null}}
    }

Log-likelihoods are natural logs over the training events. The typed object is
:class:`vidstyle.style.artifact.Style`; :func:`read_style` / :func:`write_style` convert.
"""

from __future__ import annotations

import math
import os
from typing import TYPE_CHECKING, Any

import numpy as np

from ..errors import InputError
from ._base import Fields, FormatError, check_header, header, read_json_document, write_json_document

if TYPE_CHECKING:
    from ..style.artifact import Style

KIND = "vidstyle.style"
SCHEMA_VERSION = 1


def _finite_or_none(x: float) -> float | None:
    x = float(x)
    return x if math.isfinite(x) else None


def style_to_dict(style: Style) -> dict[str, Any]:
    a, b, g, d = style.model_a, style.model_b, style.bigram, style.durations
    return {
        **header(KIND, SCHEMA_VERSION),
        "seed": style.params.seed,
        "params": style.params.to_dict(),
        "classes": list(style.classes),
        "actions": list(style.actions),
        "fps": style.fps,
        "performer": style.performer,
        "sources": style.sources,
        "n_sequences": style.n_sequences,
        "n_events": int(style.action_counts.sum()),
        "action_counts": {n: int(c) for n, c in zip(style.actions, style.action_counts)},
        "model_a": {
            "type": "action-hmm",
            "start": a.start_, "transition": a.transition_, "emission": a.emission_,
            "log_likelihood": a.log_likelihood_,
            "restart_log_likelihoods": [_finite_or_none(x) for x in a.restart_log_likelihoods_],
            "converged": bool(a.converged_), "n_iter": int(a.n_iter_),
        },
        "model_b": {
            "type": "mode-hmm",
            "n_modes": b.n_modes_,
            "start": b.start_, "transition": b.transition_, "emission": b.emission_,
            "log_likelihood": b.log_likelihood_, "bic": _finite_or_none(b.bic_),
            "selection": {"criterion": b.criterion,
                          "scores": {str(k): _finite_or_none(v) for k, v in b.selection_scores_.items()}},
            "restart_log_likelihoods": [_finite_or_none(x) for x in b.restart_log_likelihoods_],
            "converged": bool(b.converged_), "n_iter": int(b.n_iter_),
            "action_transition": b.action_transition(),
        },
        "bigram": {"type": "bigram", "start": g.start_, "transition": g.transition_,
                   "log_likelihood": g.log_likelihood_},
        "durations": {
            n: {"distribution": "lognormal", "mu": float(d.mu_[i]), "sigma": float(d.sigma_[i]),
                "n": int(d.count_[i]),
                "mean_frames": _finite_or_none(d.mean_frames_[i]),
                "sd_frames": _finite_or_none(d.sd_frames_[i])}
            for i, n in enumerate(style.actions)
        },
    }


def _stochastic(f: Fields, key: str, shape: tuple[int, ...]) -> np.ndarray:
    m = f.array(key, shape=shape)
    if (m < 0).any():
        raise f.fail(key, "must be non-negative")
    if not np.allclose(m.sum(axis=-1), 1.0, atol=1e-6):
        raise f.fail(key, "rows must sum to 1")
    return m


def _numbers(f: Fields, key: str) -> list[float]:
    out = []
    for i, x in enumerate(f.list(key, required=False, default=[])):
        if x is None:
            out.append(float("nan"))
            continue
        from ._base import check_number

        out.append(check_number(x, f.path, f"{f.name(key)}[{i}]"))
    return out


def _params(f: Fields):
    from ..style.artifact import StyleParams
    from ..style.events import EventParams

    p = f.sub("params")
    e = p.sub("events")
    try:
        ev = EventParams(
            ignore=tuple(e.str_list("ignore")), min_confidence=e.number("min_confidence", min=0, max=1),
            min_run=e.int("min_run", min=1), max_gap=e.int("max_gap", min=0), split_repeats=e.bool("split_repeats"),
            repeat_factor=e.number("repeat_factor", required=False, default=1.5),
        )
        kw: dict[str, Any] = {"events": ev, "seed": p.int("seed", required=False, default=f.obj.get("seed", 0) or 0)}
        for key in ("alpha", "emission_prior", "emission_eps", "tol", "mode_alpha", "mode_emission_alpha"):
            if p.has(key):
                kw[key] = p.number(key)
        for key in ("n_init", "n_iter"):
            if p.has(key):
                kw[key] = p.int(key, min=1)
        if p.has("learn_emission"):
            kw["learn_emission"] = p.bool("learn_emission")
        if p.has("k_range"):
            ks = p.list("k_range", min_len=1)
            kw["k_range"] = tuple(_int_item(p, "k_range", i, x) for i, x in enumerate(ks))
        if p.has("mode_criterion"):
            kw["mode_criterion"] = p.str("mode_criterion", choices=("heldout", "bic"))
        return StyleParams(**kw)
    except FormatError:
        raise
    except InputError as e:  # a parameter out of range for the library
        raise FormatError(f.path, "params", str(e)) from None


def _int_item(p: Fields, key: str, i: int, x: Any) -> int:
    from ._base import check_int

    return check_int(x, p.path, f"{p.name(key)}[{i}]", 1)


def parse_style(doc: Any, path: str | os.PathLike | None = None) -> Style:
    """Validate a style document and build the :class:`~vidstyle.style.artifact.Style` it describes."""
    from ..style.artifact import Style
    from ..style.models import ActionHMM, BigramModel, DurationModel, ModeHMM

    check_header(doc, path, KIND, (SCHEMA_VERSION,))
    f = Fields(doc, path)
    actions = f.str_list("actions", unique=True, min_len=2)
    classes = f.str_list("classes", required=False, unique=True) or list(actions)
    lost = [a for a in actions if a not in classes]
    if lost:
        raise FormatError(path, "classes", f"lacks the actions {', '.join(lost)}")
    A = len(actions)
    params = _params(f)
    fps = f.number("fps", required=False, default=20.0, positive=True)
    performer = None if doc.get("performer") is None else f.str("performer")
    sources = f.list("sources", required=False, default=[])
    for i, src in enumerate(sources):
        sf = Fields(src, path, f"sources[{i}]")  # an object of provenance (paths, counts)
        for key, value in src.items():
            if isinstance(value, float) and not math.isfinite(value):
                raise sf.fail(key, f"must be a finite number, got {value}")
            if isinstance(value, (dict, list)):
                raise sf.fail(key, "expected a string, number or null")
    n_sequences = f.int("n_sequences", required=False, default=0, min=0)
    ac = f.sub("action_counts")
    counts = np.array([ac.int(n, min=0) for n in actions], dtype=np.int64)

    fa = f.sub("model_a")
    a = ActionHMM(n_actions=A, random_state=params.seed)
    a.n_actions_ = A
    a.start_ = _stochastic(fa, "start", (A,))
    a.transition_ = _stochastic(fa, "transition", (A, A))
    a.emission_ = _stochastic(fa, "emission", (A, A))
    a.log_likelihood_ = fa.number("log_likelihood")
    a.restart_log_likelihoods_ = _numbers(fa, "restart_log_likelihoods")
    a.converged_ = fa.bool("converged", required=False, default=True)
    a.n_iter_ = fa.int("n_iter", required=False, default=0, min=0)

    fb = f.sub("model_b")
    K = fb.int("n_modes", min=1)
    b = ModeHMM(n_modes=K, n_actions=A, random_state=params.seed + 1)
    b.n_actions_, b.n_modes_ = A, K
    b.start_ = _stochastic(fb, "start", (K,))
    b.transition_ = _stochastic(fb, "transition", (K, K))
    b.emission_ = _stochastic(fb, "emission", (K, A))
    b.log_likelihood_ = fb.number("log_likelihood")
    b.restart_log_likelihoods_ = _numbers(fb, "restart_log_likelihoods")
    b.converged_ = fb.bool("converged", required=False, default=True)
    b.n_iter_ = fb.int("n_iter", required=False, default=0, min=0)
    b.bic_ = float("nan") if doc["model_b"].get("bic") is None else fb.number("bic")
    sel = fb.sub("selection", required=False)
    b.criterion = params.mode_criterion
    b.selection_scores_ = {}
    if sel is not None:
        b.criterion = sel.str("criterion", required=False, default=params.mode_criterion, choices=("heldout", "bic"))
        scores = sel.sub("scores", required=False)
        for k, v in (scores.obj.items() if scores is not None else ()):
            try:
                kk = int(k)
            except ValueError:
                raise FormatError(path, scores.name(k), "mode counts must be integers") from None
            b.selection_scores_[kk] = float("nan") if v is None else scores.number(k)

    fg = f.sub("bigram")
    g = BigramModel(n_actions=A, alpha=params.alpha)
    g.n_actions_ = A
    g.start_ = _stochastic(fg, "start", (A,))
    g.transition_ = _stochastic(fg, "transition", (A, A))
    g.log_likelihood_ = fg.number("log_likelihood")

    fd = f.sub("durations")
    d = DurationModel(n_actions=A)
    d.n_actions_ = A
    rows = [fd.sub(n) for n in actions]
    d.mu_ = np.array([r.number("mu") for r in rows])
    d.sigma_ = np.array([r.number("sigma", min=0) for r in rows])
    d.count_ = np.array([r.int("n", min=0) for r in rows], dtype=np.int64)
    d.mean_frames_ = np.array([np.nan if r.obj.get("mean_frames") is None else r.number("mean_frames", min=0)
                               for r in rows])
    d.sd_frames_ = np.array([np.nan if r.obj.get("sd_frames") is None else r.number("sd_frames", min=0) for r in rows])
    return Style(actions, classes, params, a, b, g, d, fps=fps, sources=sources, performer=performer,
                 action_counts=counts, n_sequences=n_sequences)


def read_style(path: str | os.PathLike) -> Style:
    return parse_style(read_json_document(path), path)


def write_style(path: str | os.PathLike, style: Style) -> None:
    import json

    from ..fileio import json_default

    doc = json.loads(json.dumps(style_to_dict(style), default=json_default))
    parse_style(doc, path)  # an invalid style never reaches disk
    write_json_document(path, doc)
