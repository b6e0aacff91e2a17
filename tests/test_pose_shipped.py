"""The pose model shipped inside the package: present in the installed package, made by
``scripts/train_default_pose.py`` with its settings, and the default of ``vidstyle pose --backend ps``,
which finds the keypoints of a held-out demo performer (true 2D from the renderer)."""

from __future__ import annotations

import importlib.util
import json
import subprocess
import sys
from pathlib import Path

import numpy as np

import vidstyle.demo  # noqa: F401 - registers the demo performers
from vidstyle.pose.data import make_specs, render_spec
from vidstyle.pose.defaults import shipped_model_path
from vidstyle.pose.estimator import load_model

ROOT = Path(__file__).resolve().parents[1]


def _script_settings() -> dict:
    spec = importlib.util.spec_from_file_location("train_default_pose", ROOT / "scripts" / "train_default_pose.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod.SETTINGS


def test_the_shipped_model_is_the_scripts_model():
    path = Path(str(shipped_model_path()))
    assert path.is_file() and path.stat().st_size < 5_000_000
    model, header = load_model(path)
    training = header["training"]
    settings = _script_settings()
    for key in ("demo_performers", "cmu_clips", "views_per_clip", "proportions", "seconds", "fps"):
        assert training[key] == settings[key], key
    assert tuple(training["elevation"]) == settings["elevation"] and tuple(training["scale"]) == settings["scale"]
    assert model.epochs == settings["epochs"] and training["script"] == "scripts/train_default_pose.py"


def test_pose_with_the_ps_backend_and_no_model_finds_a_held_out_performer(tmp_path):
    from video_util import write_lossless

    spec = make_specs("test", 1, 0, 1, 5, None)[0]  # a test performer (never trained on), a held-out azimuth
    samples = render_spec(spec, keep_bgr=True)
    video = write_lossless(tmp_path / "clip.mov", [s.bgr for s in samples])
    out = tmp_path / "poses.json"
    run = subprocess.run([sys.executable, "-m", "vidstyle", "pose", str(video), "--backend", "ps", "--jobs", "1",
                          "--out", str(out)], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    doc = json.loads(out.read_text())
    assert doc["backend"] == "ps" and len(doc["frames"]) == len(samples)
    pred = np.array([f["points"] for f in doc["frames"]], dtype=float)[:, :, :2]
    truth = np.stack([s.keypoints for s in samples])
    torso = np.linalg.norm(truth[:, 1] - truth[:, 2], axis=-1)[:, None]
    pck = float((np.linalg.norm(pred - truth, axis=-1) <= 0.2 * torso).mean())
    assert pck >= 0.7, pck
