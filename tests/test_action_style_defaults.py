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


def test_run_timing_and_confidence_are_the_validation_choice_and_saw_no_test_performer():
    import math

    from vidstyle.formats.validation import TEMPO_RUNS

    doc = read_validation(ROOT / "pipelines" / "kickboxing" / "validation" / "tempo_runs.json", TEMPO_RUNS)
    assert doc["chosen"] == {"run_timing": D.STYLE_RUN_TIMING, "motion_level": D.STYLE_MOTION_LEVEL,
                             "motion_filter": D.STYLE_MOTION_FILTER, "min_run_confidence": D.STYLE_MIN_RUN_CONFIDENCE,
                             "step_min_run_confidence": D.STYLE_STEP_MIN_RUN_CONFIDENCE,
                             "max_run_factor": D.STYLE_MAX_RUN_FACTOR, "min_run_factor": D.STYLE_MIN_RUN_FACTOR}
    measured = [c for c in doc["candidates"] if c["pairs_missing"] == 0]
    # the rule, reapplied to the recorded table: stage 1 picks the timing (one threshold, no floor), stage 2
    # the thresholds, cap and floor for that timing
    timing = ("run_timing", "motion_level", "motion_filter")
    first = min((c for c in measured if c["stage"] == 1), key=lambda c: c["score"])
    assert all(c["step_min_run_confidence"] is None and c["min_run_factor"] is None
               for c in doc["candidates"] if c["stage"] == 1)
    second = [c for c in measured if c["stage"] == 2]
    assert second and all({k: c[k] for k in timing} == {k: first[k] for k in timing} for c in second)
    best = min(second, key=lambda c: c["score"])
    assert {k: best[k] for k in doc["chosen"]} == doc["chosen"]
    assert doc["inputs"] == ["true", "estimated"]  # the pose stage's 2D took part in the choice
    for c in doc["candidates"]:
        assert math.isclose(c["score"], sum(c[f"error_{k}_{n}"] for k in doc["inputs"] for n in ("all", "perf0")) / 4)
    # the run's own length (the recognizer's ends) was a candidate and lost
    labels = [c for c in measured if c["run_timing"] == "labels"]
    assert labels and min(c["score"] for c in labels) > best["score"]
    # and for learn-style's reference without a population (the action model), recorded as a guide
    assert min(c["model_reference_error"] for c in labels) > best["model_reference_error"]
    assert doc["validation_performers"] == doc["split"]["V"] and not set(doc["split"]["V"]) & set(doc["split"]["T"])
