"""Validation and diagnostics documents the recognition scripts commit (``pipelines/kickboxing/validation/``,
``strikes/``, ``results/``): owner of their headers, writing and reading.

============================================  ========  ==================================================
kind                                          version   written by
============================================  ========  ==================================================
``vidstyle.validation.recognition``           2         ``scripts/validate_recognition.py``
``vidstyle.strikes_diagnostics``              1         ``scripts/strikes_diagnostics.py``
``vidstyle.strikes_real_variety``             1         ``scripts/strikes_real_variety.py``
``vidstyle.metrics.style_viterbi_prior``      1         ``scripts/style_viterbi_prior.py``
``vidstyle.validation.reconstruct_reference`` 1         ``scripts/real_reference.py``
``vidstyle.validation.pose_recognition``      1         ``scripts/pose_recognition_results.py``
``vidstyle.validation.inbetween``             1         ``scripts/validate_inbetween.py``
``vidstyle.validation.actionmodel``           1         ``scripts/validate_actionmodel.py``
``vidstyle.validation.lead_cue``              1         ``scripts/validate_lead_cue.py``
``vidstyle.validation.tempo_runs``            2         ``scripts/validate_tempo_runs.py``
``vidstyle.validation.pose_scales``           1         ``scripts/validate_pose_scales.py``
``vidstyle.validation.view_tracking``         1         ``scripts/validate_view_tracking.py``
``vidstyle.validation.training_views``        2         ``scripts/validate_training_views.py``
``vidstyle.validation.real_walks``            1         ``scripts/validate_real_walks.py``
============================================  ========  ==================================================

Each is a JSON object with ``kind`` and ``schema_version`` first, then what its script records (see the
script's docstring). :func:`write_validation` checks the header, writes atomically and keeps each kind's
committed layout (indentation, final newline), so a rerun rewrites a committed file byte for byte;
:func:`read_validation` reads one back and checks its header.
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

from ..fileio import json_default, read_json_document, write_text
from ._base import FormatError, check_header

RECOGNITION = "vidstyle.validation.recognition"
STRIKES_DIAGNOSTICS = "vidstyle.strikes_diagnostics"
STRIKES_REAL_VARIETY = "vidstyle.strikes_real_variety"
STYLE_VITERBI_PRIOR = "vidstyle.metrics.style_viterbi_prior"
RECONSTRUCT_REFERENCE = "vidstyle.validation.reconstruct_reference"
RECONSTRUCT_HELDOUT = "vidstyle.validation.reconstruct_heldout"
RECONSTRUCT_DEFAULTS = "vidstyle.validation.reconstruct_defaults"
POSE_RECOGNITION = "vidstyle.validation.pose_recognition"
INBETWEEN = "vidstyle.validation.inbetween"
ACTIONMODEL_DEFAULTS = "vidstyle.validation.actionmodel"
ACTION_STYLE_POSES = "vidstyle.validation.action_style_poses"
LEAD_CUE = "vidstyle.validation.lead_cue"
TEMPO_RUNS = "vidstyle.validation.tempo_runs"
POSE_SCALES = "vidstyle.validation.pose_scales"
VIEW_TRACKING = "vidstyle.validation.view_tracking"
TRAINING_VIEWS = "vidstyle.validation.training_views"
REAL_WALKS = "vidstyle.validation.real_walks"

# kind -> (schema version, JSON indent, final newline, non-JSON values as str)
LAYOUTS: dict[str, tuple[int, int, bool, bool]] = {
    RECOGNITION: (2, 1, True, False),
    STRIKES_DIAGNOSTICS: (1, 1, False, True),
    STRIKES_REAL_VARIETY: (1, 1, False, True),
    STYLE_VITERBI_PRIOR: (1, 2, True, False),
    RECONSTRUCT_REFERENCE: (1, 1, True, False),
    RECONSTRUCT_HELDOUT: (1, 1, True, False),
    RECONSTRUCT_DEFAULTS: (1, 1, True, False),
    POSE_RECOGNITION: (1, 1, True, False),
    INBETWEEN: (2, 1, True, False),
    ACTIONMODEL_DEFAULTS: (1, 1, True, False),
    ACTION_STYLE_POSES: (1, 1, True, False),
    LEAD_CUE: (1, 1, True, False),
    TEMPO_RUNS: (4, 1, True, False),
    POSE_SCALES: (1, 1, True, False),
    VIEW_TRACKING: (1, 1, True, False),
    TRAINING_VIEWS: (2, 1, True, False),
    REAL_WALKS: (1, 1, True, False),
}


def validation_header(kind: str) -> dict[str, Any]:
    """``{"kind": kind, "schema_version": <its version>}``, to start a document with."""
    if kind not in LAYOUTS:
        raise ValueError(f"unknown validation document kind {kind!r}")
    return {"kind": kind, "schema_version": LAYOUTS[kind][0]}


def dumps_validation(doc: dict[str, Any]) -> str:
    """The text :func:`write_validation` writes for ``doc`` (its header checked)."""
    kind = doc.get("kind") if isinstance(doc, dict) else None
    if kind not in LAYOUTS:
        raise FormatError(None, "kind", f"not a validation document kind: {kind!r}")
    check_header(doc, None, kind, (LAYOUTS[kind][0],))
    _v, indent, newline, as_str = LAYOUTS[kind]
    text = json.dumps(doc, indent=indent, default=str if as_str else json_default)
    return text + "\n" if newline else text


def write_validation(path: str | os.PathLike, doc: dict[str, Any]) -> Path:
    """Write a validation document atomically (parent directories are made); return the path."""
    text = dumps_validation(doc)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    write_text(path, text)
    return path


def read_validation(path: str | os.PathLike, kind: str) -> dict[str, Any]:
    """A validation document of ``kind`` (header checked; every problem is a :class:`FormatError`)."""
    if kind not in LAYOUTS:
        raise ValueError(f"unknown validation document kind {kind!r}")
    doc = read_json_document(path)
    check_header(doc, path, kind, (LAYOUTS[kind][0],))
    return doc
