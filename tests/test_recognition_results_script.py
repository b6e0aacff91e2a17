"""scripts/recognition_results.py trains with params.yaml's recognizer values through options that
train-recognizer really has (a renamed option or a params key left out would fail here, not after an hour)."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import typer
import yaml

from vidstyle.cli import app

ROOT = Path(__file__).resolve().parents[1]
spec = importlib.util.spec_from_file_location("recognition_results", ROOT / "scripts" / "recognition_results.py")
rr = importlib.util.module_from_spec(spec)
spec.loader.exec_module(rr)


def test_train_args_are_train_recognizer_options_with_the_params_values():
    rp = yaml.safe_load((ROOT / "pipelines" / "kickboxing" / "params.yaml").read_text())["recognition"]
    args = rr._train_args(rp)
    cmd = typer.main.get_command(app).commands["train-recognizer"]
    known = {o for p in cmd.params for o in p.opts}
    flags = args[::2]
    assert set(flags) <= known
    values = dict(zip(flags, args[1::2]))
    assert values["--max-frames-per-class"] == str(rp["max_frames_per_class"])
    assert values["--smoothing"] == rp["smoothing"] and values["--coarse-context"] == str(rp["coarse_context"])
    ctx = cmd.make_context("train-recognizer", ["--vocab", "v.npz", "--out", "m.joblib", *args])
    assert ctx.params["smoothing"] == rp["smoothing"] and ctx.params["c"] == rp["C"]


def test_each_seed_trains_with_its_own_validation_choice(tmp_path):
    """--validation: seed S's recognizer takes the values chosen on seed S's validation performers; a seed
    without exactly one validation file is refused (never silently falls back to another seed's)."""
    import json
    from types import SimpleNamespace

    import pytest

    base = {"variant": "scovanner2007", "points": 10, "words": 1000, "grouping_threshold": 0.8, "C": 100.0,
            "max_frames_per_class": 1500, "coarse_context": 0, "smoothing": "duration", "emission_weight": 1.0}
    for seed, points, c in ((0, 20, 100.0), (1, 40, 30.0)):
        doc = {"kind": "vidstyle.validation.recognition", "schema_version": 2, "seed": seed, "split": {"val_performers": ["p0"]},
               "final_config": {**base, "points": points, "C": c}}
        (tmp_path / f"recognition_seed{seed}.json").write_text(json.dumps(doc))
    (tmp_path / "pose.json").write_text(json.dumps({"kind": "vidstyle.validation.pose", "seed": 2}))
    rp = {**base, "window": 6}
    args = SimpleNamespace(validation=tmp_path)
    one = rr.config_for_seed(args, rp, 1)
    assert (one["points"], one["C"], one["window"]) == (40, 30.0, 6)
    assert rr.config_for_seed(args, rp, 0)["points"] == 20
    with pytest.raises(SystemExit, match="0 recognition validation files of seed 2"):
        rr.config_for_seed(args, rp, 2)
    assert rr.config_for_seed(SimpleNamespace(validation=None), rp, 1) == rp
    dirs = {("scovanner2007", 40): tmp_path / "f40"}
    assert rr._pick(dirs, one, "--features") == tmp_path / "f40"
    with pytest.raises(SystemExit, match="20 points"):
        rr._pick(dirs, rr.config_for_seed(args, rp, 0), "--features")
