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
    "augmg": {"annotations": "annotations.json", "videos": "p03_perf0_front p04_perf0_front", "synthesize": "p03"},
    "reconstruct": {"videos": "p03_perf0_front", "show": "p03_perf0_front", "frames": 40},
    "inbetween": {"clips": "p03_perf0", "max_windows": 8},
}


def _env(timings: Path | None = None) -> dict:
    env = dict(os.environ)
    if timings is not None:  # as make demo runs it: every vidstyle process records its time
        env["VIDSTYLE_TIMINGS"] = str(timings)
    env["PATH"] = f"{BIN}{os.pathsep}{env.get('PATH', '')}"
    env["DVC_NO_ANALYTICS"] = "1"
    return env


def _dvc(cwd: Path, *args: str, check: bool = True, timeout: float = 1200,
         timings: Path | None = None) -> subprocess.CompletedProcess:
    res = subprocess.run([str(BIN / "dvc"), *args], cwd=cwd, env=_env(timings), capture_output=True, text=True,
                         timeout=timeout)
    if check and res.returncode != 0:
        raise AssertionError(f"dvc {' '.join(args)} failed:\n{res.stdout[-3000:]}\n{res.stderr[-3000:]}")
    return res


def _setup(root: Path) -> Path:
    # the repository's layout (pipelines/kickboxing beside the package): the stages depend on package
    # files by ../../vidstyle/... (the shipped pose model, AugMG's validated defaults)
    work = root / "pipelines" / "kickboxing"
    work.mkdir(parents=True)
    (root / "vidstyle").symlink_to(PIPELINE.parents[1] / "vidstyle", target_is_directory=True)
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
    (work / "out" / "timings").mkdir(parents=True)
    _dvc(work, "repro", timings=work / "out" / "timings")
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
    # a boundary tolerance can only forgive errors: its accuracies grow with the tolerance from the exact one
    tol = rec["segments"]["smoothed"]["boundary_tolerant_accuracy"]
    assert rec["frame_accuracy"]["smoothed"] <= tol["1"] <= tol["2"] <= tol["3"] <= 1.0
    cam = json.loads((out / "metrics/recognition_unseen_camera.json").read_text())
    assert cam["split"]["kind"] == "unseen-camera" and cam["n_test_frames"] > 0
    assert sorted(cam["split"]["test_performers"]) == sorted({v.split("_")[0] for v in rec["split"]["test"]})
    style = json.loads((out / "metrics/style.json").read_text())
    assert style["recognised_performers"] == cam["split"]["test_performers"]  # test performers only
    head = json.loads((out / "metrics/headline.json").read_text())
    assert head["recognition"]["frame_accuracy_within_1_frame"] == tol["1"]
    assert head["recognition"]["frame_accuracy_smoothed"] == rec["frame_accuracy"]["smoothed"]
    assert head["seed"] == 0 and head["motion"]["graph_frames"] > 0
    rc = json.loads((out / "metrics/reconstruct.json").read_text())
    assert rc["headline"]["reconstruct.mpjpe_mm"] == head["reconstruct"]["mpjpe_mm"] > 0
    assert (out / "reconstruct" / "p03_perf0_front.bvh").is_file() and (out / "reconstruct" / "compare.mp4").is_file()
    inb = json.loads((out / "metrics/inbetween.json").read_text())
    assert inb["split"]["windows"] == 8 and inb["split"]["eval_clips"] == ["p03_perf0"]
    assert head["inbetween"]["markov_l2p_30"] == inb["methods"]["markov"]["30"]["l2p"] > 0
    ast = json.loads((out / "metrics/action_style.json").read_text())
    test_performers = ast["splits"]["0"]["T"]
    assert [r["performer"] for r in ast["rows"]["true"]] == test_performers
    assert head["action_style"]["lead_accuracy"] == ast["by_input"]["true"]["lead_accuracy"]
    assert (out / "action_style" / "actions.npz").is_file() and (out / "action_style" / "Jab.png").is_file()
    for p in test_performers:
        assert json.loads((out / "action_style" / f"{p}.json").read_text())["action_style"]["global"]["lead"] in (
            "orthodox", "southpaw")
    shown = _dvc(run, "metrics", "show").stdout
    assert "headline.json" in shown and "recognition.frame_accuracy_smoothed" in shown
    assert "confusion" not in shown  # the full documents are outputs, not metric columns


@pytest.mark.slow
def test_pipeline_augmg_outputs_against_the_plain_graph(run):
    """The AugMG stages' outputs: the augmented graph is the plain graph plus enhancement edges built from
    the accepted marked transitions, it routes a marked transition (from-action -> through the stored
    segment -> to-action) where the plain graph has no such edge, and the measured transition error is
    finite and lower with AugMG than without."""
    import json

    from vidstyle.motiongraph import MotionGraph

    out = run / "out"
    plain, aug = MotionGraph.load(out / "graph/graph.npz"), MotionGraph.load(out / "graph/graph_augmg.npz")
    ENH = 2  # edge_kind: 0 PLAYBACK, 1 BLEND, 2 ENHANCEMENT
    # same frames; every plain edge kept as it was; what is added is enhancement edges only
    assert np.array_equal(plain.rotations_, aug.rotations_) and plain.label_names_ == aug.label_names_
    assert not np.any(plain.edge_kind_ == ENH) and not plain.segments_
    edges = lambda g, m: set(zip(g.edge_src_[m].tolist(), g.edge_dst_[m].tolist(), g.edge_kind_[m].tolist()))
    assert edges(aug, aug.edge_kind_ != ENH) == edges(plain, np.ones(len(plain.edge_kind_), bool))
    enh = np.nonzero(aug.edge_kind_ == ENH)[0]
    assert len(enh) > 0 and aug.segments_
    assert np.all(np.isfinite(aug.edge_cost_[enh])) and np.all(aug.edge_cost_[enh] >= 0)
    # the stored segments are accepted marked transitions of the AugMG videos
    ann = json.loads((run / "annotations.json").read_text())
    videos = set(TINY["augmg"]["videos"].split())
    marked = {f"{t['from_action']}->{t['to_action']}" for v in ann["videos"] if Path(v["path"]).stem in videos
              for t in v["transitions"] if t["status"] == "accepted"}
    assert {s.label for s in aug.segments_} <= marked
    # routing: some marked transition a->b is a path of the augmented graph: an `a` frame, playback through
    # frames of no other action, an enhancement edge of that segment, a `b` frame; the plain graph has
    # none of those edges
    names = aug.label_names_
    plain_pairs = {(s, d) for s, d, _ in edges(plain, np.ones(len(plain.edge_kind_), bool))}
    routed = []
    for e in enh:
        a_name, b_name = aug.segments_[aug.edge_segment_[e]].label.split("->")
        src, dst = int(aug.edge_src_[e]), int(aug.edge_dst_[e])
        assert (src, dst) not in plain_pairs
        if names[aug.labels_[dst]] != b_name:
            continue
        f = src
        while f > 0 and aug.frame_clip_[f - 1] == aug.frame_clip_[src] and names[aug.labels_[f]] not in (a_name, b_name) \
                and src - f < 60:
            f -= 1
        if names[aug.labels_[f]] == a_name:
            routed.append((a_name, f, src, dst, b_name))
    assert routed, "no marked transition is routed through an enhancement edge"
    # the walk synthesised on the augmented graph
    walk = json.loads((out / "motion_augmg" / f"{TINY['augmg']['synthesize']}.labels.json").read_text())
    assert len(walk["transition_kinds"]) == len(walk["transitions_used"]) and walk["labels"]
    assert (out / "motion_augmg" / f"{TINY['augmg']['synthesize']}.bvh").is_file()
    # the metrics: finite, and the AugMG transition error below the plain graph's where poses are exact
    # (gt) and with the backend that built the graph (blazepose); never above it
    m = json.loads((out / "metrics/augmg.json").read_text())
    for source, r in m["by_source"].items():
        for key in ("transition_plain_mm", "transition_augmg_mm", "retrieval_mpjpe_mm", "transition_reduction"):
            assert np.isfinite(r[key]), (source, key)
        assert r["queries"] > 0 and r["transition_augmg_mm"] <= r["transition_plain_mm"] + 1e-9, source
    graph_poses = yaml.safe_load((run / "params.yaml").read_text())["augmg"]["graph_poses"]
    graph_source = "blazepose" if graph_poses.rstrip("/").endswith("poses_blazepose") else "model"
    for source in ("gt", graph_source):
        r = m["by_source"][source]
        assert r["transition_augmg_mm"] < r["transition_plain_mm"] and r["transition_reduction"] > 0, (source, r)
    head = json.loads((out / "metrics/headline.json").read_text())["augmg"]
    assert head["transition_error_augmg"] == m["by_source"]["model"]["transition_augmg_mm"]


@pytest.mark.slow
def test_report_renders_in_chromium(run, tmp_path):
    report = run / "out" / "report.html"
    dom = dump_dom(report)
    assert 'data-rendered="ok"' in dom and "data-errors" not in dom
    for heading in ("Action recognition", "Timeline", "Behaviour style", "Generated action sequences",
                    "Motion graph", "Synthesized motion", "Stage times"):
        assert heading in dom, heading
    assert 'class="missing"' not in dom  # every section had its inputs (the stage times too)
    assert "<td>features</td><td>ran</td>" in dom.replace(" ", "")  # this run's own stages, timed
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
def test_interrupted_stage_leaves_no_corrupt_artifact(run, tmp_path):
    """The features stage is interrupted at a fixed point - exactly 2 outputs published, the third written
    to its temporary file but not renamed (tests/faults/sitecustomize.py holds it there) - and killed
    (SIGKILL, the whole process group); the published files are complete, nothing else carries a final
    name, and `dvc repro` recovers the same bytes."""
    features = run / "out" / "features"
    before = _digest(features)
    assert len(before) >= 4
    sentinel = tmp_path / "fault_reached"
    env = _env()
    env["PYTHONPATH"] = os.pathsep.join(p for p in [str(Path(__file__).parent / "faults"), env.get("PYTHONPATH")] if p)
    env.update(VIDSTYLE_FAULT_DIR=str(features), VIDSTYLE_FAULT_AFTER="2", VIDSTYLE_FAULT_SENTINEL=str(sentinel))
    proc = subprocess.Popen([str(BIN / "dvc"), "repro", "--force", "-s", "features"], cwd=run, env=env,
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
    try:
        deadline = time.time() + 600
        while not sentinel.exists() and proc.poll() is None and time.time() < deadline:
            time.sleep(0.05)
        # the run reached the fault point and is still running (blocked there): it did not finish
        assert sentinel.exists(), f"the fault point was not reached (dvc exit code {proc.poll()})"
        assert proc.poll() is None
    finally:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()
    final = sorted(f.name for f in features.iterdir() if not f.name.startswith("."))
    hidden = [f for f in features.iterdir() if f.name.startswith(".")]
    assert len(final) == 2, final  # exactly the two published outputs ...
    for name in final:  # ... complete, byte for byte what the uninterrupted run wrote
        assert hashlib.sha256((features / name).read_bytes()).hexdigest() == before[name], name
    blocked = sentinel.read_text().split()[1]
    assert Path(blocked).exists() and Path(blocked) in hidden  # the third: only under a temporary name
    assert all(".tmp" in f.name for f in hidden), hidden
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
