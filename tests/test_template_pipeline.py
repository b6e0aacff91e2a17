"""The template pipeline (pipelines/template) end to end with real DVC on the shared real footage.

The committed example - four pose2sim views of one person (../shared/data/video/real), their annotations
(pipelines/template/example/annotations.json: segments and transition marks) and three CMU clips labelled
with the same classes (example/library.csv) - runs method 1 (features -> recognizer -> style ->
sequence -> motion) and method 2 (poses of the marked frames -> enhancement edges -> motion) to the end.
The template is laid out as in the repository (pipelines/template beside a link to the package), its
paths to ../shared made absolute. Skipped when ../shared (beside the repository) is absent.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import yaml

REPO = Path(__file__).resolve().parents[1]
TEMPLATE = REPO / "pipelines" / "template"
SHARED = REPO.parent / "shared"
VIDEOS = SHARED / "data" / "video" / "real"
CMU = SHARED / "data" / "mocap" / "cmu"
BIN = Path(sys.executable).parent
RELATIVE_SHARED = "../../../shared"  # how the committed params.yaml reaches ../shared from pipelines/template

needs_shared = pytest.mark.skipif(not (VIDEOS.is_dir() and CMU.is_dir()),
                                  reason="../shared (real footage and CMU mocap) is absent")


def _env() -> dict:
    env = dict(os.environ)
    env["PATH"] = f"{BIN}{os.pathsep}{env.get('PATH', '')}"
    env["DVC_NO_ANALYTICS"] = "1"
    return env


def _dvc(cwd: Path, *args: str, timeout: float = 1200) -> subprocess.CompletedProcess:
    res = subprocess.run([str(BIN / "dvc"), *args], cwd=cwd, env=_env(), capture_output=True, text=True,
                         timeout=timeout)
    if res.returncode != 0:
        raise AssertionError(f"dvc {' '.join(args)} failed:\n{res.stdout[-4000:]}\n{res.stderr[-4000:]}")
    return res


def test_params_reach_the_example_from_the_template_folder():
    """As committed, params.yaml points at the example: ../shared from pipelines/template, the annotations
    and the labels CSV in example/, and the classes the annotations use."""
    params = yaml.safe_load((TEMPLATE / "params.yaml").read_text())
    assert params["data"]["videos"].startswith(RELATIVE_SHARED)
    assert (TEMPLATE / RELATIVE_SHARED).resolve() == SHARED.resolve()
    assert (TEMPLATE / params["data"]["annotations"]).is_file()
    assert (TEMPLATE / params["library"]["labels"]).is_file()
    ann = json.loads((TEMPLATE / params["data"]["annotations"]).read_text())
    assert params["library"]["classes"].split(",") == ann["classes"]
    labels = {line.split(",")[1] for line in (TEMPLATE / params["library"]["labels"]).read_text().splitlines()[1:]}
    assert labels == set(ann["classes"])  # every class of the annotations has library frames


@needs_shared
def test_example_annotations_are_of_the_shared_videos():
    """Valid per the schema and the reader, tied to the shared videos by sha256 and decoded frame count."""
    import jsonschema

    from vidstyle.formats.annotations import JSON_SCHEMA, check_video, read_annotations
    from vidstyle.video import VideoReader

    path = TEMPLATE / "example" / "annotations.json"
    jsonschema.validate(json.loads(path.read_text()), JSON_SCHEMA)
    ann = read_annotations(path)
    assert len(ann.videos) == 4
    for v in ann.videos:
        video = VIDEOS / Path(v.path).name
        with VideoReader(video) as r:
            n = r.info.frames
        check_video(ann.video_for(video, path), video, n, path)
        assert v.segments and v.transitions


def _setup(root: Path) -> Path:
    work = root / "pipelines" / "template"
    shutil.copytree(TEMPLATE, work, ignore=shutil.ignore_patterns("out", ".dvc", "dvc.lock"))
    (root / "vidstyle").symlink_to(REPO / "vidstyle", target_is_directory=True)
    params = yaml.safe_load((work / "params.yaml").read_text())
    params["data"]["videos"] = params["data"]["videos"].replace(RELATIVE_SHARED, str(SHARED))
    params["library"]["clips"] = params["library"]["clips"].replace(RELATIVE_SHARED, str(SHARED))
    params["jobs"] = 2
    (work / "params.yaml").write_text(yaml.safe_dump(params))
    _dvc(work, "init", "--no-scm", "-q")
    return work


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    if not (VIDEOS.is_dir() and CMU.is_dir()):
        pytest.skip("../shared (real footage and CMU mocap) is absent")
    work = _setup(tmp_path_factory.mktemp("template"))
    t0 = time.perf_counter()
    res = _dvc(work, "repro")
    print(f"template pipeline: {time.perf_counter() - t0:.1f} s")
    return work, res


@pytest.mark.slow
@needs_shared
def test_template_runs_both_methods_to_a_motion(run):
    from vidstyle.mocap import read_bvh
    from vidstyle.motiongraph import MotionGraph

    work, res = run
    out = work / "out"
    classes = set(json.loads((TEMPLATE / "example" / "annotations.json").read_text())["classes"])
    # method 1: recognised labels of every video, a style, a sequence in it, motion performing it
    assert sorted(p.name for p in (out / "recognized").iterdir()) == [f"pose2sim_single_cam0{i}.json" for i in range(1, 5)]
    seq = json.loads((out / "generated" / "performer.json").read_text())
    assert seq["kind"] == "vidstyle.sequence"
    motion = read_bvh(out / "motion" / "performer.bvh")
    assert motion.n_frames > 30 and np.all(np.isfinite(motion.rotations))
    walk = json.loads((out / "motion" / "performer.labels.json").read_text())
    assert set(walk["labels"]) <= classes | {"unlabelled"} and set(walk["labels"]) & classes
    assert (out / "motion" / "performer.mp4").stat().st_size > 0
    # method 2: the plain graph plus enhancement edges from the marked transitions, and a motion on it
    plain, aug = MotionGraph.load(out / "graph" / "graph.npz"), MotionGraph.load(out / "graph" / "graph_augmg.npz")
    assert not np.any(plain.edge_kind_ == 2) and np.sum(aug.edge_kind_ == 2) > 0
    ann = json.loads((TEMPLATE / "example" / "annotations.json").read_text())
    marked = {f"{t['from_action']}->{t['to_action']}" for v in ann["videos"] for t in v["transitions"]}
    assert aug.segments_ and {s.label for s in aug.segments_} <= marked
    motion2 = read_bvh(out / "motion_augmg" / "performer.bvh")
    assert motion2.n_frames > 30 and np.all(np.isfinite(motion2.rotations))
    assert (out / "report.html").is_file() and (out / "metrics" / "headline.json").is_file()
    # the example's small data is said to be small (warnings that teach), not passed silently
    said = " ".join((res.stdout + res.stderr).split())  # the log's line wrapping undone
    assert "labelled training frames" in said and "needs about 100 per class" in said  # train-recognizer
    assert "learn-style: only" in said and "action-to-action transitions" in said  # learn-style
    # the summary of the run fits a terminal
    text = subprocess.run([str(BIN / "vidstyle"), "report", "out", "--text"], cwd=work, env=_env(),
                          capture_output=True, text=True, check=True).stdout
    assert text.startswith("motion") and max(len(line) for line in text.splitlines()) <= 120


@pytest.mark.slow
@needs_shared
def test_template_repro_is_up_to_date_after_a_run(run):
    work, _ = run
    again = _dvc(work, "repro")
    assert "Running stage" not in again.stdout
