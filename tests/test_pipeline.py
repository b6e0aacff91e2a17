"""The kickboxing DVC pipeline end to end on a tiny dataset, with real DVC and real Chromium.

One module-scoped run (a few minutes on 2 cores) is shared by the tests: outputs, the report in a
browser, `dvc repro` rerunning only what changed, and recovery from an interrupted stage.
"""

from __future__ import annotations

import hashlib
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import yaml

from browser import dump_dom, screenshot

PIPELINE = Path(__file__).resolve().parents[1] / "pipelines" / "kickboxing"
BIN = Path(sys.executable).parent

# 5 performers: the split's test set gets 2 of them, the fewest the style evaluation of recognised labels
# (test performers only) can compare
TINY = {
    "dataset": {"performers": 5, "views": "front,left", "single_seconds": 5, "performances": 1,
                "performance_seconds": 40},
    "recognition": {"words": 150},
    "style": {"length": 10},
    "graph": {"clips": "out/dataset/mocap/p00_*.bvh"},
    "synthesize": {"performers": "p00"},
    "pose": {"demo_performers": 1, "views_per_clip": 12},  # 12 azimuths: every view has frames
    "augmg": {"annotations": "annotations.json", "videos": "p03_perf0_front p04_perf0_front", "synthesize": "p03"},
}


def _env() -> dict:
    env = dict(os.environ)
    env["PATH"] = f"{BIN}{os.pathsep}{env.get('PATH', '')}"
    env["DVC_NO_ANALYTICS"] = "1"
    return env


def _dvc(cwd: Path, *args: str, check: bool = True, timeout: float = 1200) -> subprocess.CompletedProcess:
    res = subprocess.run([str(BIN / "dvc"), *args], cwd=cwd, env=_env(), capture_output=True, text=True,
                         timeout=timeout)
    if check and res.returncode != 0:
        raise AssertionError(f"dvc {' '.join(args)} failed:\n{res.stdout[-3000:]}\n{res.stderr[-3000:]}")
    return res


def _setup(root: Path) -> Path:
    work = root / "kickboxing"
    work.mkdir()
    shutil.copy(PIPELINE / "dvc.yaml", work / "dvc.yaml")
    params = yaml.safe_load((PIPELINE / "params.yaml").read_text())
    for section, values in TINY.items():
        params[section].update(values)
    params["jobs"] = 2
    (work / "params.yaml").write_text(yaml.safe_dump(params))
    # the tiny dataset's transition marks, made as the bundled annotations/demo.json is made (the videos are
    # rendered there exactly as make_dataset will render them, so their sha256 match)
    res = subprocess.run([sys.executable, str(PIPELINE.parents[1] / "scripts" / "make_demo_annotations.py"), "3", "4",
                          "--params", str(work / "params.yaml"), "--out", str(work / "annotations.json"),
                          "--video-dir", "out/dataset/videos"], capture_output=True, text=True, timeout=600)
    assert res.returncode == 0, res.stderr[-3000:]
    _dvc(work, "init", "--no-scm", "-q")
    return work


def _digest(directory: Path) -> dict[str, str]:
    return {p.name: hashlib.sha256(p.read_bytes()).hexdigest() for p in sorted(directory.iterdir())}


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    work = _setup(tmp_path_factory.mktemp("pipeline"))
    t0 = time.perf_counter()
    _dvc(work, "repro")
    print(f"tiny pipeline: {time.perf_counter() - t0:.1f} s")
    return work


@pytest.mark.slow
def test_pipeline_outputs(run):
    out = run / "out"
    for rel in ("metrics/recognition.json", "metrics/style.json", "metrics/motion.json", "report.html",
                "models/recognizer.onnx", "style/p00.json", "generated/p00.json", "motion/p00.bvh", "motion/p00.mp4"):
        assert (out / rel).is_file(), rel
    import json

    rec = json.loads((out / "metrics/recognition.json").read_text())
    assert rec["seed"] == 0
    # better than saying the most frequent test class everywhere (what a recognizer that learned nothing does)
    from collections import Counter

    labels = Counter(x for v in rec["split"]["test"]
                     for x in json.loads((out / "dataset" / "labels" / f"{v}.json").read_text())["labels"])
    majority = max(labels.values()) / sum(labels.values())
    assert rec["frame_accuracy"]["smoothed"] > majority + 0.1, (rec["frame_accuracy"], majority)
    cam = json.loads((out / "metrics/recognition_unseen_camera.json").read_text())
    assert cam["split"]["kind"] == "unseen-camera" and cam["n_test_frames"] > 0
    assert sorted(cam["split"]["test_performers"]) == sorted({v.split("_")[0] for v in rec["split"]["test"]})
    style = json.loads((out / "metrics/style.json").read_text())
    assert style["recognised_performers"] == cam["split"]["test_performers"]  # test performers only
    head = json.loads((out / "metrics/headline.json").read_text())
    assert head["recognition"]["frame_accuracy_smoothed"] == rec["frame_accuracy"]["smoothed"]
    assert head["seed"] == 0 and head["motion"]["graph_frames"] > 0
    shown = _dvc(run, "metrics", "show").stdout
    assert "headline.json" in shown and "recognition.frame_accuracy_smoothed" in shown
    assert "confusion" not in shown  # the full documents are outputs, not metric columns


@pytest.mark.slow
def test_report_renders_in_chromium(run, tmp_path):
    report = run / "out" / "report.html"
    dom = dump_dom(report)
    assert 'data-rendered="ok"' in dom and "data-errors" not in dom
    for heading in ("Action recognition", "Timeline", "Behaviour style", "Generated action sequences",
                    "Motion graph", "Synthesized motion"):
        assert heading in dom, heading
    assert 'class="missing"' not in dom  # every section had its inputs
    assert "data:image/gif;base64," in dom
    import cv2

    img = cv2.imread(str(screenshot(report, tmp_path / "report.png")))
    assert img is not None and img.std() > 10  # not a blank page


@pytest.mark.slow
def test_repro_reruns_only_what_changed(run):
    again = _dvc(run, "repro")
    assert "Running stage" not in again.stdout
    params = yaml.safe_load((run / "params.yaml").read_text())
    params["style"]["length"] = 12
    (run / "params.yaml").write_text(yaml.safe_dump(params))
    changed = _dvc(run, "repro").stdout
    assert "Running stage 'generate'" in changed
    for untouched in ("make_dataset", "features", "train_recognizer", "build_graph"):
        assert f"Running stage '{untouched}'" not in changed


@pytest.mark.slow
def test_interrupted_stage_leaves_no_corrupt_artifact(run):
    features = run / "out" / "features"
    before = _digest(features)
    proc = subprocess.Popen([str(BIN / "dvc"), "repro", "--force", "-s", "features"], cwd=run, env=_env(),
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
    # kill the whole process group as soon as the rerun has written some, not all, of its outputs
    deadline = time.time() + 120
    while time.time() < deadline and proc.poll() is None:
        done = [f for f in features.glob("*.npz") if not f.name.startswith(".")] if features.exists() else []
        if 0 < len(done) < len(before):
            break
        time.sleep(0.02)
    os.killpg(proc.pid, signal.SIGKILL)
    proc.wait()
    if features.exists():
        # whatever carries a final name is complete; a SIGKILL can only leave a hidden temporary file
        # (never under a final name), and the rerun below clears it
        for f in features.iterdir():
            if f.name.startswith("."):
                assert ".tmp" in f.name, f
                continue
            with np.load(f) as z:
                assert len(z["descriptors"]) == len(z["points"])
    _dvc(run, "repro")
    assert _digest(features) == before  # same files, same bytes, no leftovers


@pytest.mark.slow
def test_stage_with_corrupt_input_fails_with_one_line(run, tmp_path):
    video = next((run / "out" / "dataset" / "videos").glob("*.mp4"))
    bad = tmp_path / video.name
    bad.write_bytes(video.read_bytes()[:2000])
    res = subprocess.run([str(BIN / "vidstyle"), "features", str(bad), "--out", str(tmp_path / "f")],
                         env=_env(), capture_output=True, text=True)
    assert res.returncode != 0
    lines = [ln for ln in res.stderr.splitlines() if ln.startswith("vidstyle: error:")]
    assert len(lines) == 1 and bad.name in lines[0]
    assert not (tmp_path / "f" / f"{video.stem}.npz").exists()
