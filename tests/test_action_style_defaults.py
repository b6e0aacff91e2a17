"""The action-level style's lead cue comes from its committed validation table (non-test performers only)."""

from __future__ import annotations

from pathlib import Path

from vidstyle.actionmodel import defaults as D
from vidstyle.actionmodel.stylefit import LEAD_CUES
from vidstyle.formats.validation import LEAD_CUE, read_validation

ROOT = Path(__file__).resolve().parents[1]


def test_lead_cue_is_the_validation_choice_and_saw_no_test_performer():
    doc = read_validation(ROOT / "pipelines" / "kickboxing" / "validation" / "lead_cue.json", LEAD_CUE)
    assert doc["chosen"] == D.STYLE_LEAD_CUE and D.STYLE_LEAD_CUE in LEAD_CUES
    best = max(doc["by_cue"], key=lambda c: (doc["by_cue"][c]["lead_accuracy"], doc["by_cue"][c]["mean_margin"]))
    assert best == doc["chosen"]
    seen = {r["performer"] for r in doc["rows"]}
    assert seen and not seen & set(doc["split"]["T"])
    assert seen == set(doc["split"]["A"] + doc["split"]["B"] + doc["split"]["V"])
    for cue, s in doc["by_cue"].items():  # the summary is the rows'
        rs = [r for r in doc["rows"] if r["cue"] == cue]
        assert s["lead_accuracy"] == sum(r["correct"] for r in rs) / len(rs)
