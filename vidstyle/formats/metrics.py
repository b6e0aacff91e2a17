"""Metrics files (DVC metrics; what ``vidstyle report`` reads): the owner of their headers and of the
fields the report relies on.

Every metrics file is a JSON object with a header and its seed::

    {"kind": "vidstyle.metrics.<what>", "schema_version": 1, "seed": 0, ...}

Kinds and the fields checked (others are carried along; ``null`` marks a figure that could not be
computed, e.g. video accuracy without single-action test videos):

* ``vidstyle.metrics.recognition`` (``vidstyle evaluate recognition``): ``frame_accuracy.raw`` and
  ``.smoothed`` in [0, 1]; ``video_accuracy`` in [0, 1] or null; ``n_test_videos``, ``n_test_frames``
  >= 0; ``split`` an object (``kind`` a string, ``test`` a list of video ids); ``confusion.classes`` unique
  names and ``confusion.smoothed`` / ``.raw`` (K, K) in [0, 1]; optional ``segments``, per label kind
  (``smoothed``, ``raw``) ``boundary_tolerant_accuracy`` (tolerance in frames -> [0, 1] or null) and
  ``segmental_f1`` (overlap in percent -> [0, 1] or null; :mod:`vidstyle.evaluation.segments`).
* ``vidstyle.metrics.style`` (``vidstyle evaluate style``): ``sources`` an object of label sources, each
  with ``summary.transition_mae`` (numbers or null), ``summary.identification``, ``summary.fidelity`` and
  ``summary.heldout_loglik_per_event`` (objects of numbers or null per model).
* ``vidstyle.metrics.motion`` (``vidstyle evaluate motion``; files without ``kind`` are schema 1):
  ``summary`` with ``label_fidelity`` in [0, 1] or null, ``transitions_per_second`` >= 0 or null, and
  per seam metric (``velocity_jump``, ``jerk``, ``foot_skid``) an object of numbers or null;
  ``graph_stats`` an object.
* ``vidstyle.metrics.strikes`` (``vidstyle evaluate strikes``): ``cameras`` a non-empty list, each with
  ``name``, ``action_video_frames`` >= 0 and ``smoothed`` / ``raw`` holding ``punch``, ``kick``,
  ``other`` counts >= 0 and ``punch_fraction`` in [0, 1] or null; ``overall`` alike; ``rule`` (the
  action-frame rule's thresholds, or the labels file it was replaced by) and ``params`` objects; ``action_frames.segments`` a list.
* ``vidstyle.metrics.pose`` (``vidstyle evaluate pose``): ``n_frames`` >= 0; ``pcp``: per backend (``ps``,
  ``blazepose``, ...) per viewpoint an object of per-part strict PCP in [0, 1] or null and ``n`` >= 0;
  ``pck@0.2``: per backend an object of numbers in [0, 1] or null (``all`` and one per keypoint);
  ``viewpoint``: per classifier ``accuracy`` in [0, 1] or null (and, when present, ``tolerant_accuracy``,
  ``unambiguous.accuracy``, ``boundary.accuracy_either_neighbour`` and every
  ``tolerant_per_view_accuracy`` in [0, 1] or null, ``boundary.n`` >= 0); ``params`` an object.
* ``vidstyle.metrics.multiview_pose`` (``vidstyle evaluate pose --calibration``): ``references`` an object
  per reference (``dlt``, ``robust``), each with ``overall``, ``per_view`` and ``per_keypoint`` blocks
  holding ``n`` >= 0, ``median_error`` >= 0 or null and ``pck@0.1`` / ``pck@0.2`` in [0, 1] or null;
  ``views`` a list of camera names; ``params`` an object.
* ``vidstyle.metrics.people`` (``vidstyle evaluate people``): ``views`` a list; ``modes`` an object per
  mode (``naive``, ``tracked``) with ``identity_switches_per_100_frames`` >= 0, ``pck@0.2`` and
  ``multiview_pck@0.2`` in [0, 1] or null and ``per_view`` an object; ``params`` an object.
* ``vidstyle.metrics.reconstruct`` (``vidstyle evaluate reconstruct``): ``runs`` a non-empty list, each
  with ``data``, ``source``, ``method`` and ``skeleton`` strings, ``frames`` >= 0, and ``mpjpe_mm``,
  ``mpjpe_root_relative_mm``, ``pa_mpjpe_mm``, ``acceleration_error_mm_per_frame2``,
  ``foot_skate_mm_per_frame`` each >= 0 or null; ``params`` and ``headline`` objects.
* ``vidstyle.metrics.real_motion`` (``vidstyle evaluate real-motion``): ``recognizers`` a non-empty list;
  ``rows`` a non-empty list, each with ``clip``, ``family``, ``camera`` strings, ``recognizer`` one of
  ``recognizers``, ``frames`` >= 0, ``family_counts`` (``punch``, ``kick``, ``other`` >= 0, summing to
  ``frames``) and ``family_accuracy`` in [0, 1] or null; ``overall`` an object per recognizer with
  ``family_accuracy`` in [0, 1] or null; ``params`` an object.
* ``vidstyle.metrics.inbetween`` (``vidstyle evaluate inbetween``, ``scripts/eval_inbetween.py``): ``gaps`` a
  non-empty list of integers >= 1; ``methods`` an object per method (``markov``, ``graph``, ``slerp``) with one
  block per gap (its decimal string) holding ``l2p``, ``l2q``, ``ms_per_request`` >= 0 and ``windows`` >= 1;
  ``split`` and ``params`` objects.
* ``vidstyle.metrics.actionmodel`` (``scripts/eval_actionmodel.py``): ``command`` a string; ``labels`` a
  non-empty object, per action label an object whose leaves are numbers, null, booleans or strings
  (naturalness of samples and source clips, reconstruction MPJPE, fit and sample times); ``params``
  and ``split`` objects.
* ``vidstyle.metrics.headline`` (``vidstyle report --metrics``): ``recognition``, ``style``, ``motion``:
  flat objects of numbers or null (and ``augmg``, ``reconstruct`` when present).
* ``vidstyle.metrics.timing`` (``vidstyle timing``; no seed): the pipeline's stage-time table. ``records_dir``
  a string; ``recorded`` a boolean (the records directory existed); ``dvc_file`` a string or null;
  ``started`` / ``finished`` Unix seconds or null (both null, or ``finished`` >= ``started``);
  ``run_wall_seconds`` >= 0 or null; ``stages_wall_seconds``, ``cpu_seconds`` >= 0;
  ``unreadable_records`` >= 0; ``stages`` a list of unique ``stage`` names, each with ``status`` one of
  :data:`TIMING_STATUSES`, ``invocations`` and ``failed`` >= 0 (``failed`` <= ``invocations``; a stage with
  invocations has ``wall_seconds``, ``cpu_seconds``, ``peak_rss_mb`` >= 0, one without has them null),
  ``commands`` a list of strings.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from typing import Any

from ._base import (
    Fields,
    FormatError,
    check_array,
    check_header,
    check_int,
    check_leaves,
    read_json_document,
    write_json_document,
)

RECOGNITION = "vidstyle.metrics.recognition"
STYLE = "vidstyle.metrics.style"
MOTION = "vidstyle.metrics.motion"
HEADLINE = "vidstyle.metrics.headline"
AUGMG = "vidstyle.metrics.augmg"
STRIKES = "vidstyle.metrics.strikes"
POSE = "vidstyle.metrics.pose"
MULTIVIEW_POSE = "vidstyle.metrics.multiview_pose"
PEOPLE = "vidstyle.metrics.people"
TIMING = "vidstyle.metrics.timing"
RECONSTRUCT = "vidstyle.metrics.reconstruct"
REAL_MOTION = "vidstyle.metrics.real_motion"
INBETWEEN = "vidstyle.metrics.inbetween"
ACTIONMODEL = "vidstyle.metrics.actionmodel"
ACTION_STYLE = "vidstyle.metrics.action_style"
KINDS = (RECOGNITION, STYLE, MOTION, HEADLINE, AUGMG, STRIKES, POSE, MULTIVIEW_POSE, PEOPLE, TIMING, RECONSTRUCT,
         REAL_MOTION, INBETWEEN, ACTIONMODEL, ACTION_STYLE)
SCHEMA_VERSION = 1
#: a stage's status in the timing table: its records show it ran (all exit 0) or failed (one did not); it is
#: the stage of the ``vidstyle timing`` run itself (running); no record of it while records were kept (skipped:
#: DVC found it up to date); no records kept at all (not recorded: the pipeline ran without VIDSTYLE_TIMINGS)
TIMING_STATUSES = ("ran", "failed", "running", "skipped", "not recorded")


@dataclass
class Metrics:
    """A validated metrics document: ``doc`` is the whole JSON object (fields as documented above)."""

    kind: str
    schema_version: int
    seed: Any
    doc: dict[str, Any] = field(default_factory=dict)
    path: str = ""

    def get(self, *keys, default=None):
        d: Any = self.doc
        for k in keys:
            if not isinstance(d, dict) or k not in d:
                return default
            d = d[k]
        return d


def _opt_number(f: Fields, key: str, lo: float | None = None, hi: float | None = None) -> float | None:
    if f.obj.get(key) is None:
        return None
    return f.number(key, min=lo, max=hi)


def _numbers_or_null(f: Fields, key: str, required: bool = True) -> None:
    """``key`` is an object whose leaves are finite numbers, null, booleans or strings (nested objects and
    lists allowed)."""
    sub = f.sub(key, required=required)
    if sub is not None:
        check_leaves(sub.obj, f.path, sub.prefix)


def _recognition(f: Fields) -> None:
    fa = f.sub("frame_accuracy")
    fa.number("raw", min=0, max=1)
    fa.number("smoothed", min=0, max=1)
    _opt_number(f, "video_accuracy", 0, 1)
    f.int("n_test_videos", min=0)
    f.int("n_test_frames", min=0)
    sp = f.sub("split")
    if sp.obj.get("kind") is not None:
        sp.str("kind")
    if sp.obj.get("test") is not None:
        sp.str_list("test")
    if f.obj.get("test_performers") is not None:
        f.str_list("test_performers")
    c = f.sub("confusion")
    classes = c.str_list("classes", unique=True, min_len=1)
    K = len(classes)
    for key in ("smoothed", "raw"):
        if c.obj.get(key) is not None:
            m = c.array(key, shape=(K, K))
            if m.size and (m.min() < 0 or m.max() > 1 + 1e-9):
                raise c.fail(key, "row-normalised values must lie in [0, 1]")
    segs = f.sub("segments", required=False)
    if segs is not None:  # per label kind (smoothed, raw): two objects of scores in [0, 1] or null
        for kind in segs.obj:
            block = segs.sub(kind)
            for key in ("boundary_tolerant_accuracy", "segmental_f1"):
                scores = block.sub(key)
                for name in scores.obj:
                    _opt_number(scores, name, 0, 1)


def _style(f: Fields) -> None:
    srcs = f.sub("sources")
    if not srcs.obj:
        raise srcs.fail(None, "no label source")
    for name in srcs.obj:
        s = srcs.sub(name).sub("summary")
        for key in ("transition_mae", "heldout_loglik_per_event", "identification", "fidelity"):
            _numbers_or_null(s, key)


def _motion(f: Fields) -> None:
    s = f.sub("summary")
    _opt_number(s, "label_fidelity", 0, 1)
    _opt_number(s, "transitions_per_second", 0)
    for key in ("velocity_jump", "jerk", "foot_skid"):
        if s.obj.get(key) is not None:
            _numbers_or_null(s, key)
    f.sub("graph_stats", required=False)


def _headline(f: Fields) -> None:
    for key in ("recognition", "style", "motion"):
        _numbers_or_null(f, key)
    for key in ("augmg", "reconstruct", "action_style"):
        if f.obj.get(key) is not None:
            _numbers_or_null(f, key)


#: the figures of every run of a reconstruct metrics file (>= 0 or null)
RECONSTRUCT_FIGURES = ("mpjpe_mm", "mpjpe_root_relative_mm", "pa_mpjpe_mm", "acceleration_error_mm_per_frame2",
                       "foot_skate_mm_per_frame")


def _reconstruct(f: Fields) -> None:
    runs = f.list("runs", min_len=1)
    for i, raw in enumerate(runs):
        r = Fields(raw, f.path, f"runs[{i}]")
        for key in ("data", "source", "method", "skeleton"):
            r.str(key, nonempty=True)
        r.int("frames", min=0)
        for key in RECONSTRUCT_FIGURES:
            _opt_number(r, key, 0, None)
    f.sub("params")
    f.sub("headline")


def _real_motion(f: Fields) -> None:
    names = f.list("recognizers", min_len=1)
    f.sub("params")
    rows = f.list("rows", min_len=1)
    for i, raw in enumerate(rows):
        r = Fields(raw, f.path, f"rows[{i}]")
        for key in ("clip", "family", "camera", "recognizer"):
            r.str(key, nonempty=True)
        if r.get("recognizer") not in names:
            raise r.fail("recognizer", f"not one of the recognizers {names}")
        n = r.int("frames", min=0)
        counts = r.sub("family_counts")
        total = 0
        for fam in ("punch", "kick", "other"):
            total += counts.int(fam, min=0)
        if total != n:
            raise r.fail("family_counts", f"sum to {total}, not the {n} frames")
        _opt_number(r, "family_accuracy", 0, 1)
    o = f.sub("overall")
    for name in names:
        _opt_number(o.sub(name), "family_accuracy", 0, 1)


def _inbetween(f: Fields) -> None:
    gaps = f.list("gaps", min_len=1)
    for i, g in enumerate(gaps):
        check_int(g, f.path, f"gaps[{i}]", 1)
    methods = f.sub("methods")
    if not methods.obj:
        raise methods.fail(None, "no method")
    for name in methods.obj:
        m = methods.sub(name)
        for g in gaps:
            b = m.sub(str(int(g)))
            for key in ("l2p", "l2q", "ms_per_request"):
                b.number(key, min=0)
            b.int("windows", min=1)
    f.sub("split")
    f.sub("params")


def _actionmodel(f: Fields) -> None:
    f.str("command", nonempty=True)
    labels = f.sub("labels")
    if not labels.obj:
        raise labels.fail(None, "no label")
    for name in labels.obj:
        _numbers_or_null(labels, name)
    f.sub("params")
    f.sub("split")


def _action_style(f: Fields) -> None:
    """``scripts/eval_action_style.py``: ``by_input`` (input kind -> summary over test performers),
    ``action_style`` (the headline figures: ``lead_accuracy``, ``mpjpe_reduction``)."""
    f.str("command", nonempty=True)
    by = f.sub("by_input")
    if not by.obj:
        raise by.fail(None, "no input kind")
    for name in by.obj:
        s = by.sub(name)
        s.int("performers", min=0)
    a = f.sub("action_style")
    a.number("lead_accuracy", min=0, max=1)
    a.number("mpjpe_reduction", max=1)
    f.sub("params")


def _augmg(f: Fields) -> None:
    by = f.sub("by_source")
    if not by.obj:
        raise by.fail(None, "no 2D source")
    for name in by.obj:
        s = by.sub(name)
        s.int("queries", min=0)
        for key in ("retrieval_mpjpe_mm", "transition_plain_mm", "transition_augmg_mm"):
            s.number(key, min=0)
        for key in ("recall_at_1", "recall_at_10"):
            s.number(key, min=0, max=1)
        if s.get("transition_reduction_ci95", required=False) is not None:  # optional: [low, high]
            ci = s.array("transition_reduction_ci95", shape=(2,))
            if not ci[0] <= ci[1]:
                raise s.fail("transition_reduction_ci95", f"low {ci[0]} above high {ci[1]}")
    f.sub("headline")


def _strike_counts(s: Fields) -> None:
    for key in ("punch", "kick", "other"):
        s.int(key, min=0)
    _opt_number(s, "punch_fraction", 0, 1)


def _strikes(f: Fields) -> None:
    f.sub("rule")
    f.sub("params")
    f.sub("action_frames").list("segments")
    cams = f.list("cameras")
    if not cams:
        raise f.fail("cameras", "no camera")
    for i in range(len(cams)):
        c = Fields(cams[i], f.path, f"cameras[{i}]")
        c.str("name")
        c.int("action_video_frames", min=0)
        for key in ("smoothed", "raw"):
            _strike_counts(c.sub(key))
    o = f.sub("overall")
    for key in ("smoothed", "raw"):
        _strike_counts(o.sub(key))


def _pose(f: Fields) -> None:
    f.int("n_frames", min=0)
    pcp = f.sub("pcp")
    for backend in pcp.obj:
        views = pcp.sub(backend)
        for view in views.obj:
            row = views.sub(view)
            for part in row.obj:
                if part == "n":
                    row.int("n", min=0)
                else:
                    _opt_number(row, part, 0, 1)
    pck = f.sub("pck@0.2")
    for backend in pck.obj:
        b = pck.sub(backend)
        for key in b.obj:
            _opt_number(b, key, 0, 1)
    vp = f.sub("viewpoint")
    for name in vp.obj:
        c = vp.sub(name)
        _opt_number(c, "accuracy", 0, 1)
        if c.has("tolerant_accuracy"):  # files before the boundary-aware scores lack them
            _opt_number(c, "tolerant_accuracy", 0, 1)
            _opt_number(c.sub("unambiguous"), "accuracy", 0, 1)
            b = c.sub("boundary")
            b.int("n", min=0)
            _opt_number(b, "accuracy_either_neighbour", 0, 1)
            t = c.sub("tolerant_per_view_accuracy")
            for v in t.obj:
                _opt_number(t, v, 0, 1)
    f.sub("params")


def _pck_block(b: Fields) -> None:
    b.int("n", min=0)
    if b.has("median_error") and b.obj["median_error"] is not None:
        b.number("median_error", min=0)
    for key in ("pck@0.1", "pck@0.2"):
        _opt_number(b, key, 0, 1)


def _multiview_pose(f: Fields) -> None:
    views = f.str_list("views")
    refs = f.sub("references")
    if not refs.obj:
        raise refs.fail(None, "no reference")
    for name in refs.obj:
        r = refs.sub(name)
        _pck_block(r.sub("overall"))
        for group in ("per_view", "per_keypoint"):
            g = r.sub(group)
            for key in g.obj:
                _pck_block(g.sub(key))
        if set(r.sub("per_view").obj) != set(views):
            raise r.fail("per_view", "must have one block per view")
    f.sub("params")


def _people(f: Fields) -> None:
    f.str_list("views")
    modes = f.sub("modes")
    if not modes.obj:
        raise modes.fail(None, "no mode")
    for name in modes.obj:
        m = modes.sub(name)
        m.number("identity_switches_per_100_frames", min=0)
        _opt_number(m, "pck@0.2", 0, 1)
        _opt_number(m, "multiview_pck@0.2", 0, 1)
        m.sub("per_view")
    f.sub("params")


def _timing(f: Fields) -> None:
    f.str("records_dir")
    f.bool("recorded")
    if f.obj.get("dvc_file") is not None:
        f.str("dvc_file")
    started, finished = _opt_number(f, "started", 0), _opt_number(f, "finished", 0)
    if (started is None) != (finished is None):
        raise f.fail("finished", "started and finished are both numbers or both null")
    if started is not None and finished < started:
        raise f.fail("finished", f"{finished} is before started {started}")
    _opt_number(f, "run_wall_seconds", 0)
    f.number("stages_wall_seconds", min=0)
    f.number("cpu_seconds", min=0)
    f.int("unreadable_records", min=0)
    if f.obj.get("cores") is not None:  # the machine's core count (written since 2026-12; optional)
        f.int("cores", min=1)
    seen = set()
    for i, row in enumerate(f.list("stages")):
        s = Fields(row, f.path, f"stages[{i}]")
        name = s.str("stage", nonempty=True)
        if name in seen:
            raise s.fail("stage", f"{name!r} appears more than once")
        seen.add(name)
        s.str("status", choices=TIMING_STATUSES)
        n = s.int("invocations", min=0)
        if s.int("failed", min=0) > n:
            raise s.fail("failed", f"more than the {n} invocation(s)")
        for key in ("wall_seconds", "cpu_seconds", "peak_rss_mb"):
            if n:
                s.number(key, min=0)
            elif s.get(key) is not None:
                raise s.fail(key, "must be null for a stage without invocations")
        s.str_list("commands", nonempty_items=False)


_CHECKS = {RECOGNITION: _recognition, STYLE: _style, MOTION: _motion, HEADLINE: _headline, AUGMG: _augmg,
           STRIKES: _strikes, POSE: _pose, MULTIVIEW_POSE: _multiview_pose, PEOPLE: _people, TIMING: _timing,
           RECONSTRUCT: _reconstruct, REAL_MOTION: _real_motion, INBETWEEN: _inbetween,
           ACTIONMODEL: _actionmodel, ACTION_STYLE: _action_style}


def parse_metrics(doc: Any, path: str | os.PathLike | None = None, kind: str | None = None) -> Metrics:
    """Validate a metrics document of ``kind`` (default: the kind it declares, one of :data:`KINDS`)."""
    if kind is None:
        kind = doc.get("kind") if isinstance(doc, dict) and doc.get("kind") in KINDS else None
        if kind is None:
            raise FormatError(path, "kind", f"expected one of {', '.join(KINDS)}, got "
                              f"{doc.get('kind') if isinstance(doc, dict) else None!r}")
    version = check_header(doc, path, kind, (SCHEMA_VERSION,), legacy=kind == MOTION)
    f = Fields(doc, path)
    _CHECKS[kind](f)
    return Metrics(kind, version, doc.get("seed"), doc, "" if path is None else str(path))


def read_metrics(path: str | os.PathLike, kind: str | None = None) -> Metrics:
    return parse_metrics(read_json_document(path), path, kind)


def write_metrics(path: str | os.PathLike, doc: dict[str, Any] | Metrics, kind: str | None = None) -> None:
    """Validate ``doc`` (of the kind it declares, or ``kind``, which is then set) and write it atomically."""
    import json

    from ..fileio import json_default

    d = dict(doc.doc if isinstance(doc, Metrics) else doc)
    if kind is not None:
        d = {"kind": kind, "schema_version": SCHEMA_VERSION, **{k: v for k, v in d.items() if k not in ("kind", "schema_version")}}
    d = json.loads(json.dumps(d, default=json_default, allow_nan=True), parse_constant=lambda c: None)
    parse_metrics(d, path)
    write_json_document(path, d)


__all__ = [
    "ACTIONMODEL",
    "ACTION_STYLE",
    "AUGMG",
    "HEADLINE",
    "INBETWEEN",
    "KINDS",
    "MOTION",
    "MULTIVIEW_POSE",
    "PEOPLE",
    "POSE",
    "REAL_MOTION",
    "RECOGNITION",
    "RECONSTRUCT",
    "STRIKES",
    "STYLE",
    "TIMING",
    "TIMING_STATUSES",
    "Metrics",
    "check_array",
    "parse_metrics",
    "read_metrics",
    "write_metrics",
]
