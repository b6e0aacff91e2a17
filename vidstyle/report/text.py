"""The headline numbers of a run as a few grouped lines of text (``vidstyle report RUN_DIR --text``): one
group per method stage, every line at most ``width`` characters (120 by default), so a terminal shows
what ``dvc metrics show`` spreads over one 900-character row. Numbers missing from the run are left
out; a group with none is not printed.

>>> print(headline_text({"seed": 0, "recognition": {"frame_accuracy_smoothed": 0.8123}}))
recognition  frame accuracy 0.812
run          seed 0
"""

from __future__ import annotations

import textwrap
from typing import Any

WIDTH = 120
INDENT = 13  # the group name column


def _num(v: Any) -> str | None:
    if v is None or isinstance(v, bool):
        return None
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        return f"{v:.0f}" if abs(v) >= 1000 else f"{v:.1f}" if abs(v) >= 10 else f"{v:.3f}"
    if isinstance(v, (list, tuple)):
        return ", ".join(map(str, v)) if v else None
    return str(v)


def _items(doc: dict, spec: list[tuple[str, str, str]]) -> list[str]:
    """``label value[unit]`` for each (key, label, unit) of ``spec`` whose value is present."""
    out = []
    for key, label, unit in spec:
        text = _num((doc or {}).get(key))
        if text is not None:
            out.append(f"{label} {text}{unit}")
    return out


# group -> (key in the headline document, words, unit)
GROUPS: list[tuple[str, str, list[tuple[str, str, str]]]] = [
    ("recognition", "recognition", [
        ("frame_accuracy_smoothed", "frame accuracy", ""),
        ("frame_accuracy_raw", "unsmoothed", ""),
        ("frame_accuracy_within_1_frame", "within a frame of the true boundaries", ""),
        ("segmental_f1_50", "segmental F1@50", ""),
        ("video_accuracy", "video accuracy", ""),
        ("unseen_camera_frame_accuracy_smoothed", "unseen camera: frame accuracy", ""),
        ("unseen_camera_video_accuracy", "video accuracy", ""),
        ("test_frames", "test frames", ""),
    ]),
    ("style", "style", [
        ("transition_mae_truth", "transition MAE: true labels", ""),
        ("transition_mae_truth_test", "true labels of test performers", ""),
        ("transition_mae_recognised", "recognised labels", ""),
        ("identification_truth", "identification: true labels", ""),
        ("identification_recognised", "recognised labels", ""),
        ("heldout_loglik_truth", "held-out log-likelihood per event: true labels", ""),
        ("heldout_loglik_recognised", "recognised labels", ""),
        ("recognised_performers", "recognised performers:", ""),
    ]),
    ("motion", "motion", [
        ("graph_frames", "graph frames", ""),
        ("transitions_in_scc", "walkable transitions", ""),
        ("label_fidelity", "label fidelity", ""),
        ("velocity_jump_seam_over_clip", "velocity jump seam/clip", ""),
        ("foot_skid_seam_over_clip", "foot skid seam/clip", ""),
    ]),
    ("augmg", "augmg", [
        ("retrieval_mpjpe", "retrieval MPJPE", " mm"),
        ("transition_error_plain", "transition error: plain graph", " mm"),
        ("transition_error_augmg", "with AugMG", " mm"),
        ("blazepose_retrieval_mpjpe", "BlazePose poses: retrieval MPJPE", " mm"),
        ("blazepose_transition_error_augmg", "transition error with AugMG", " mm"),
    ]),
    ("reconstruct", "reconstruct", [
        ("mpjpe_mm", "root-relative MPJPE", " mm"),
        ("mpjpe_height_given_mm", "at the performer's height", " mm"),
        ("mpjpe_performer_skeleton_mm", "on the performer's skeleton", " mm"),
        ("pa_mpjpe_mm", "PA-MPJPE", " mm"),
        ("mpjpe_true2d_mm", "with true 2D", " mm"),
        ("foot_skate_mm_per_frame", "foot skate", " mm/frame"),
        ("source", "2D:", ""),
        ("method", "method:", ""),
    ]),
    ("action_style", "action style", [
        ("lead_accuracy", "lead accuracy", ""),
        ("mpjpe_reduction", "MPJPE below the unfitted model", ""),
        ("mpjpe_reduction_vs_true_lead", "below it given the lead", ""),
        ("estimated_lead_accuracy", "pose-stage 2D: lead accuracy", ""),
        ("estimated_mpjpe_reduction", "MPJPE below unfitted", ""),
        ("input", "2D:", ""),
    ]),
    ("inbetween", "keyframes", [
        *((f"{m}_l2p_{g}", f"{name} L2P at {g} frames" if g == 15 else f"{g}", "")
          for m, name in (("markov", "Markov"), ("slerp", "SLERP")) for g in (15, 30, 45)),
    ]),
]


def _pack(name: str, items: list[str], width: int) -> list[str]:
    """``items`` after the group ``name``, as many to a line as fit in ``width`` (a line breaks only between
    items; an item longer than a line is cut into pieces)."""
    lines, cur = [], f"{name:<{INDENT - 1}} "
    fresh = True
    for item in items:
        add = item if fresh else ", " + item
        if not fresh and len(cur) + len(add) + 1 > width:  # the comma ending the line counts
            lines.append(cur + ",")
            cur, fresh, add = " " * INDENT, True, item
        cur += add
        fresh = False
    lines.append(cur)
    out = []
    for line in lines:  # only an item longer than a whole line is wider
        out.extend(textwrap.wrap(line, width, subsequent_indent=" " * INDENT, drop_whitespace=False) or [line])
    return [line.rstrip() for line in out]


def headline_text(head: dict, width: int = WIDTH) -> str:
    """Grouped summary lines of a headline document (:func:`vidstyle.report.build.headline_metrics`), each
    at most ``width`` characters; ``kind`` and ``schema_version`` (not metrics) are left out, the seed is
    the last line."""
    lines = []
    groups = GROUPS + [("", "run", [("seed", "seed", "")])]
    for key, name, spec in groups:
        doc = head.get(key) if key else head
        if not isinstance(doc, dict):
            continue
        items = _items(doc, spec)
        if items:
            lines.extend(_pack(name, items, width))
    return "\n".join(lines)
