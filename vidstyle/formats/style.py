"""A performer's learned style (``style.json``, ``vidstyle learn-style``): the owner of its schema.

Schema (``kind`` ``"vidstyle.style"``, ``schema_version`` 2; version 1 files, which lack
``action_style``, still load; matrices are row-stochastic lists of lists,
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
                             "sd_frames" | null}},
      "action_style": null | {         # version 2: the action-level style fitted from 2D
          "model": path,               # the action model file (vidstyle fit-actions) the coefficients are of
          "params": {...},             # the fit's parameters (prior_weight, loss_scale, n_fit, ...)
          "global": {"lead": "orthodox" | "southpaw", "lead_score", "guard_height", "stance_width",
                     "crouch" (numbers or null), "tempo": {action: factor}, "relative_tempo": {action: x},
                     "n_videos", "n_jabs",
                     "speed" (number or null; optional), "action_tempo": {action: x} (optional)},
          "labels": {label: {"coefficients": [k], "spread": [k], "segments": n}}   # orthodox frame
      }
    }

Log-likelihoods are natural logs over the training events. The owner reads and writes a
:class:`StyleRecord` (the document's fields, checked and typed); the learned object
:class:`vidstyle.style.artifact.Style` builds itself from one (``Style.from_record``) and returns one
(``style.to_record()``). The ranges of the estimator parameters are the domain's (``StyleParams``); this
module checks their types.
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..fileio import json_default
from ._base import (
    Fields,
    FormatError,
    check_header,
    check_int,
    check_number,
    header,
    read_json_document,
    write_json_document,
)

KIND = "vidstyle.style"
SCHEMA_VERSION = 2
READABLE_VERSIONS = (1, 2)


@dataclass
class ActionHMMRecord:
    """Model (a): ``start`` (A,), ``transition`` (A, A), ``emission`` (A, A), row-stochastic."""

    start: Any
    transition: Any
    emission: Any
    log_likelihood: float
    restart_log_likelihoods: list[float] = field(default_factory=list)  # NaN: a restart that failed
    converged: bool = True
    n_iter: int = 0


@dataclass
class ModeHMMRecord(ActionHMMRecord):
    """Model (b): ``start`` (K,), ``transition`` (K, K), ``emission`` (K, A). ``criterion`` None: the file
    names none (the style's ``params.mode_criterion`` holds). ``action_transition`` is derived (written for
    readers of the file, not read back)."""

    n_modes: int = 1
    bic: float = float("nan")
    criterion: str | None = None
    selection_scores: dict[int, float] = field(default_factory=dict)
    action_transition: Any = None


@dataclass
class BigramRecord:
    start: Any
    transition: Any
    log_likelihood: float


@dataclass
class DurationsRecord:
    """Per action (in the order of ``actions``): log-normal ``mu``, ``sigma``, event ``count``, and the mean
    and standard deviation in frames (NaN: none)."""

    mu: Any
    sigma: Any
    count: Any
    mean_frames: Any
    sd_frames: Any


@dataclass
class StyleRecord:
    """The content of a ``style.json``. ``params``: the document's ``params`` object (``events`` a dict,
    ``k_range`` a list; keys the file lacks are absent)."""

    actions: list[str]
    classes: list[str]
    params: dict[str, Any]
    seed: int
    model_a: ActionHMMRecord
    model_b: ModeHMMRecord
    bigram: BigramRecord
    durations: DurationsRecord
    fps: float = 20.0
    performer: str | None = None
    sources: list[dict] = field(default_factory=list)
    n_sequences: int = 0
    action_counts: Any = None
    action_style: ActionStyleRecord | None = None


@dataclass
class ActionStyleRecord:
    """``action_style`` of a version-2 file (:class:`vidstyle.actionmodel.stylefit.ActionStyle` builds itself
    from one). ``global_style``: the checked ``global`` object; ``labels``: label -> (coefficients (k,),
    spread (k,), segments)."""

    model: str
    params: dict[str, Any]
    global_style: dict[str, Any]
    labels: dict[str, tuple[np.ndarray, np.ndarray, int]]


def _finite_or_none(x: float) -> float | None:
    x = float(x)
    return x if math.isfinite(x) else None


def style_to_dict(rec: StyleRecord) -> dict[str, Any]:
    a, b, g, d = rec.model_a, rec.model_b, rec.bigram, rec.durations
    counts = np.zeros(len(rec.actions), np.int64) if rec.action_counts is None else np.asarray(rec.action_counts)
    return {
        **header(KIND, SCHEMA_VERSION),
        "seed": rec.seed,
        "params": rec.params,
        "classes": list(rec.classes),
        "actions": list(rec.actions),
        "fps": rec.fps,
        "performer": rec.performer,
        "sources": rec.sources,
        "n_sequences": rec.n_sequences,
        "n_events": int(counts.sum()),
        "action_counts": {n: int(c) for n, c in zip(rec.actions, counts)},
        "model_a": {
            "type": "action-hmm",
            "start": a.start, "transition": a.transition, "emission": a.emission,
            "log_likelihood": a.log_likelihood,
            "restart_log_likelihoods": [_finite_or_none(x) for x in a.restart_log_likelihoods],
            "converged": bool(a.converged), "n_iter": int(a.n_iter),
        },
        "model_b": {
            "type": "mode-hmm",
            "n_modes": b.n_modes,
            "start": b.start, "transition": b.transition, "emission": b.emission,
            "log_likelihood": b.log_likelihood, "bic": _finite_or_none(b.bic),
            "selection": {"criterion": b.criterion,
                          "scores": {str(k): _finite_or_none(v) for k, v in b.selection_scores.items()}},
            "restart_log_likelihoods": [_finite_or_none(x) for x in b.restart_log_likelihoods],
            "converged": bool(b.converged), "n_iter": int(b.n_iter),
            "action_transition": b.action_transition,
        },
        "bigram": {"type": "bigram", "start": g.start, "transition": g.transition,
                   "log_likelihood": g.log_likelihood},
        "durations": {
            n: {"distribution": "lognormal", "mu": float(d.mu[i]), "sigma": float(d.sigma[i]),
                "n": int(d.count[i]),
                "mean_frames": _finite_or_none(d.mean_frames[i]),
                "sd_frames": _finite_or_none(d.sd_frames[i])}
            for i, n in enumerate(rec.actions)
        },
        "action_style": None if rec.action_style is None else _action_style_dict(rec.action_style),
    }


def _action_style_dict(r: ActionStyleRecord) -> dict[str, Any]:
    g = dict(r.global_style)
    for k in ("lead_score", "guard_height", "stance_width", "crouch"):
        g[k] = None if g.get(k) is None else _finite_or_none(g[k])
    for k in ("tempo", "relative_tempo", "action_tempo"):
        g[k] = {a: _finite_or_none(v) for a, v in (g.get(k) or {}).items()}
    g["speed"] = None if g.get("speed") is None else _finite_or_none(g["speed"])
    return {"model": r.model, "params": r.params, "global": g,
            "labels": {lab: {"coefficients": [float(x) for x in c], "spread": [float(x) for x in sp], "segments": int(n)}
                       for lab, (c, sp, n) in r.labels.items()}}


def _opt_number(f: Fields, key: str) -> float:
    return float("nan") if f.obj.get(key) is None else f.number(key)


def _parse_action_style(f: Fields) -> ActionStyleRecord:
    model = f.str("model", required=False, default="")
    params = f.sub("params").obj
    for k, v in params.items():
        if isinstance(v, float) and not math.isfinite(v):
            raise f.fail("params", f"{k}: must be finite")
    g = f.sub("global")
    glob: dict[str, Any] = {"lead": g.str("lead", choices=("orthodox", "southpaw"))}
    for k in ("lead_score", "guard_height", "stance_width", "crouch", "speed"):
        glob[k] = _opt_number(g, k)
    for k in ("tempo", "relative_tempo", "action_tempo"):
        t = g.sub(k, required=False)
        glob[k] = {} if t is None else {a: _opt_number(t, a) for a in t.obj}
    glob["n_videos"] = g.int("n_videos", required=False, default=0, min=0)
    glob["n_jabs"] = g.int("n_jabs", required=False, default=0, min=0)
    labs = f.sub("labels")
    labels = {}
    for lab in labs.obj:
        lf = labs.sub(lab)
        c = lf.array("coefficients")
        sp = lf.array("spread")
        if c.ndim != 1 or c.size == 0 or sp.shape != c.shape:
            raise lf.fail("spread", f"coefficients and spread must be non-empty vectors of one length, got {c.shape} and {sp.shape}")
        if (sp < 0).any():
            raise lf.fail("spread", "must be non-negative")
        labels[lab] = (c, sp, lf.int("segments", min=1))
    return ActionStyleRecord(model, dict(params), glob, labels)


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
        out.append(check_number(x, f.path, f"{f.name(key)}[{i}]"))
    return out


def _params(f: Fields) -> dict[str, Any]:
    """The ``params`` object, every value type-checked (ranges: ``StyleParams``, when a Style is built)."""
    p = f.sub("params")
    e = p.sub("events")
    ev = dict(
        ignore=list(e.str_list("ignore")), min_confidence=e.number("min_confidence", min=0, max=1),
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
        kw["k_range"] = [_int_item(p, "k_range", i, x) for i, x in enumerate(ks)]
    if p.has("mode_criterion"):
        kw["mode_criterion"] = p.str("mode_criterion", choices=("heldout", "bic"))
    return kw


def _int_item(p: Fields, key: str, i: int, x: Any) -> int:
    return check_int(x, p.path, f"{p.name(key)}[{i}]", 1)


def parse_style(doc: Any, path: str | os.PathLike | None = None) -> StyleRecord:
    """Validate a style document and return its :class:`StyleRecord`."""
    check_header(doc, path, KIND, READABLE_VERSIONS)
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
    a = ActionHMMRecord(
        start=_stochastic(fa, "start", (A,)),
        transition=_stochastic(fa, "transition", (A, A)),
        emission=_stochastic(fa, "emission", (A, A)),
        log_likelihood=fa.number("log_likelihood"),
        restart_log_likelihoods=_numbers(fa, "restart_log_likelihoods"),
        converged=fa.bool("converged", required=False, default=True),
        n_iter=fa.int("n_iter", required=False, default=0, min=0),
    )

    fb = f.sub("model_b")
    K = fb.int("n_modes", min=1)
    b = ModeHMMRecord(
        n_modes=K,
        start=_stochastic(fb, "start", (K,)),
        transition=_stochastic(fb, "transition", (K, K)),
        emission=_stochastic(fb, "emission", (K, A)),
        log_likelihood=fb.number("log_likelihood"),
        restart_log_likelihoods=_numbers(fb, "restart_log_likelihoods"),
        converged=fb.bool("converged", required=False, default=True),
        n_iter=fb.int("n_iter", required=False, default=0, min=0),
        action_transition=doc["model_b"].get("action_transition"),
    )
    b.bic = float("nan") if doc["model_b"].get("bic") is None else fb.number("bic")
    sel = fb.sub("selection", required=False)
    if sel is not None:
        b.criterion = sel.str("criterion", required=False, default=params.get("mode_criterion"),
                              choices=("heldout", "bic"))
        scores = sel.sub("scores", required=False)
        for k, v in (scores.obj.items() if scores is not None else ()):
            try:
                kk = int(k)
            except ValueError:
                raise FormatError(path, scores.name(k), "mode counts must be integers") from None
            b.selection_scores[kk] = float("nan") if v is None else scores.number(k)

    fg = f.sub("bigram")
    g = BigramRecord(start=_stochastic(fg, "start", (A,)), transition=_stochastic(fg, "transition", (A, A)),
                     log_likelihood=fg.number("log_likelihood"))

    fd = f.sub("durations")
    rows = [fd.sub(n) for n in actions]
    d = DurationsRecord(
        mu=np.array([r.number("mu") for r in rows]),
        sigma=np.array([r.number("sigma", min=0) for r in rows]),
        count=np.array([r.int("n", min=0) for r in rows], dtype=np.int64),
        mean_frames=np.array([np.nan if r.obj.get("mean_frames") is None else r.number("mean_frames", min=0)
                              for r in rows]),
        sd_frames=np.array([np.nan if r.obj.get("sd_frames") is None else r.number("sd_frames", min=0)
                            for r in rows]),
    )
    ast = None
    if doc.get("action_style") is not None:
        ast = _parse_action_style(f.sub("action_style"))
    return StyleRecord(actions, classes, params, params["seed"], a, b, g, d, fps=fps, performer=performer,
                       sources=sources, n_sequences=n_sequences, action_counts=counts, action_style=ast)


def read_style(path: str | os.PathLike) -> StyleRecord:
    return parse_style(read_json_document(path), path)


def write_style(path: str | os.PathLike, rec: StyleRecord) -> None:
    doc = json.loads(json.dumps(style_to_dict(rec), default=json_default))
    parse_style(doc, path)  # an invalid style never reaches disk
    write_json_document(path, doc)
