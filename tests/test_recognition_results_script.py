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
