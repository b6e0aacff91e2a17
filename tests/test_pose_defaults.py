"""The pose model's defaults are the values scripts/validate_pose.py chose on validation renders
(pipelines/kickboxing/validation/pose.json), so a rerun of the validation that changes them fails here
until the library and the pipeline follow."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from vidstyle.pose.defaults import CNN_DEFAULTS, DEFAULTS, DETECTOR, TRAIN_SET

ROOT = Path(__file__).resolve().parents[1]
VALIDATION = ROOT / "pipelines" / "kickboxing" / "validation" / "pose.json"


@pytest.fixture(scope="module")
def doc() -> dict:
    return json.loads(VALIDATION.read_text())


def test_hog_defaults_are_the_validated_ones(doc):
    ch = doc["chosen"]
    assert {k: DEFAULTS[k] for k in ("n_orient", "hard_rounds", "viewpoint", "unary_weight", "fg_weight")} == \
        {k: ch[k] for k in ("n_orient", "hard_rounds", "viewpoint", "unary_weight", "fg_weight")}


def test_detector_and_cnn_defaults_are_the_validated_ones(doc):
    ch = doc["chosen"]
    assert DETECTOR == ch["detector"]
    assert {k: CNN_DEFAULTS[k] for k in ch["cnn"]} == ch["cnn"]
    assert {k: CNN_DEFAULTS[k] for k in ("stride", "flip_test")} == \
        {"stride": ch["cnn"].get("stride", 4), "flip_test": ch["cnn"].get("flip_test", False)}
    rows = doc["detector_stage"]["rows"]
    best = max(rows, key=lambda r: (r["pcp_mean"], r["view_acc_mean"]))
    assert best["detector"] == ch["detector"]
    # the cnn's defaults: the best cnn row of the detector stage and of the cnn stage (other epochs, strides,
    # the test-time flip; scripts/validate_pose.py --cnn-models) within the speed budget
    budget = (doc.get("cnn_stage") or {}).get("budget_ms", float("inf"))
    # (rows before the training set was compared: the detector stage's set, 24 demo performers + 40 CMU clips x 8)
    train_set = {"demo_performers": 24, "cmu_clips": 40, "views_per_clip": 8}
    base = {"stride": 4, "flip_test": False, "augment": "flip", "channels": 48, **train_set}
    cnn_rows = [{**base, **r} for r in rows if r["detector"] == "cnn"]
    cnn_rows += [{"augment": "flip", "channels": 48, **train_set, **r} for r in (doc.get("cnn_stage") or {}).get("rows", [])]
    cnn = max((r for r in cnn_rows if r["cpu_ms_per_frame"] <= budget), key=lambda r: (r["pcp_mean"], r["view_acc_mean"]))
    keys = ("unary_weight", "refine", "epochs", "channels", "stride", "flip_test", "augment") + TRAIN_SET
    assert {k: cnn[k] for k in keys} == {k: ch["cnn"].get(k, base.get(k)) for k in keys}


def test_the_shipped_model_has_the_validated_detector(doc):
    """The pipeline trains no pose model: it runs the one shipped in the package, whose part detectors are
    the kind the validation chose."""
    from vidstyle.pose.defaults import shipped_model_path
    from vidstyle.pose.estimator import load_model

    model, _header = load_model(str(shipped_model_path()))
    assert model.detector == doc["chosen"]["detector"]
