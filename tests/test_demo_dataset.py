"""Demo behaviour and dataset: chains, labels/transitions/events, files, determinism, CLI."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from vidstyle.cli import main
from vidstyle.demo import ACTIONS, CLASSES, DatasetParams, Performer, label_document, make_dataset
from vidstyle.demo.timeline import build_take, performance_plan
from vidstyle.errors import InputError
from vidstyle.mocap import global_positions, read_bvh


def test_label_document_against_hand_written_truth():
    labels = ["Guard"] * 3 + ["Jab"] * 4 + ["Guard"] * 2 + ["Step"] * 3 + ["Guard"] + ["Jab"] * 2 + ["Hook"] * 2
    doc = label_document(labels, 20.0, ["Jab", "Jab", "Hook"], video="v.mp4")
    assert doc["transitions"] == [3, 7, 9, 12, 13, 15]
    assert doc["events"] == [{"label": "Jab", "start": 3, "end": 7}, {"label": "Jab", "start": 13, "end": 15},
                             {"label": "Hook", "start": 15, "end": 17}]
    assert doc["classes"] == list(CLASSES) and doc["video"] == "v.mp4" and doc["fps"] == 20.0
    assert [s["label"] for s in doc["segments"]] == ["Guard", "Jab", "Guard", "Step", "Guard", "Jab", "Hook"]


def test_performance_follows_the_true_chain():
    """Long performances: the empirical action transitions converge to the performer's matrix."""
    p = Performer.random("p00", np.random.default_rng(4))
    rng = np.random.default_rng(5)
    plan = performance_plan(p, 20 * 60 * 60, rng)  # one hour of plan (no motion needed)
    chain = [ACTIONS.index(s.label) for s in plan if s.label in ACTIONS]
    counts = np.zeros((6, 6))
    np.add.at(counts, (chain[:-1], chain[1:]), 1)
    emp = counts / np.maximum(counts.sum(axis=1, keepdims=True), 1)
    visited = counts.sum(axis=1) > 200
    assert visited.sum() >= 3
    assert np.abs(emp[visited] - p.chain.transition[visited]).max() < 0.08
    # durations follow the chain's duration distributions (video frames)
    for a in ACTIONS:
        d = [s.frames for s in plan if s.label == a]
        if len(d) > 100:
            assert np.mean(d) == pytest.approx(p.chain.duration_frames[a][0], rel=0.05)
    # actions are always separated by a pause, so each one is its own event
    labels = [s.label for s in plan]
    assert all(not (a in ACTIONS and b in ACTIONS) for a, b in zip(labels, labels[1:]))


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_single_action_videos_are_mostly_their_action(seed):
    """Video-level accuracy is the majority label, so a 16 s single-action video must be mostly action."""
    from vidstyle.demo import single_action_plan

    p = Performer.random("p", np.random.default_rng(seed))
    for a in ACTIONS:
        plan = single_action_plan(p, a, 320, np.random.default_rng(seed))
        assert sum(s.frames for s in plan) == 320
        assert sum(s.frames for s in plan if s.label == a) > 0.6 * 320, a
        assert sum(s.label == a for s in plan) >= 8  # many repetitions, each its own event


def test_take_labels_transitions_events_and_chain_agree():
    p = Performer.random("p01", np.random.default_rng(8))
    rng = np.random.default_rng(9)
    take = build_take(p, performance_plan(p, 400, rng), rng)
    assert len(take.labels) == take.motion.n_frames == 3 * 400
    assert take.video_labels == take.labels[::3] and len(take.video_labels) == 400
    doc = label_document(take.video_labels, 20.0, take.chain)
    assert [e["label"] for e in doc["events"]] == take.chain
    changes = [i for i in range(1, 400) if take.video_labels[i] != take.video_labels[i - 1]]
    assert doc["transitions"] == changes
    for e in doc["events"]:
        assert set(take.video_labels[e["start"]:e["end"]]) == {e["label"]}
    # the video resampling keeps exactly one motion frame per video frame
    assert take.motion.resample(20).n_frames == 400


@pytest.fixture(scope="module")
def mocap_dataset(tmp_path_factory):
    params = DatasetParams(seed=5, performers=2, views=("front", "left"), single_seconds=2.0, performances=1,
                           performance_seconds=5.0, render=False)
    root = tmp_path_factory.mktemp("ds")
    make_dataset(root / "a", params, jobs=1)
    make_dataset(root / "b", params, jobs=2)
    make_dataset(root / "c", DatasetParams(**{**params.__dict__, "seed": 6}), jobs=1)
    return root, params


def test_dataset_manifest_schema(mocap_dataset):
    root, _ = mocap_dataset
    d = json.loads((root / "a" / "dataset.json").read_text())
    assert d["kind"] == "vidstyle.dataset" and d["schema_version"] == 2 and d["seed"] == 5 and d["fps"] == 20 and d["mocap_fps"] == 60
    assert d["size"] == [160, 120] and d["actions"] == list(ACTIONS) and d["classes"] == list(CLASSES)
    assert d["params"]["performers"] == 2 and d["params"]["views"] == ["front", "left"]
    assert [p["id"] for p in d["performers"]] == ["p00", "p01"]
    for p in d["performers"]:
        ch = p["chain"]
        assert ch["actions"] == list(ACTIONS) and len(ch["start"]) == 6 and np.isclose(sum(ch["start"]), 1)
        assert np.allclose(np.sum(ch["transition"], axis=1), 1) and set(ch["duration_frames"]) == set(ACTIONS)
        assert {"height_m", "leg_ratio"} <= set(p["body"]) and p["style"]["lead"] in ("orthodox", "southpaw")
    singles = [v for v in d["videos"] if v["kind"] == "single"]
    perfs = [v for v in d["videos"] if v["kind"] == "performance"]
    assert len(singles) == 2 * 6 * 2 and len(perfs) == 2 * 1 * 2
    keys = {"id", "performer", "kind", "view", "azimuth_deg", "video", "labels", "truth", "bvh", "bvh_labels", "frames"}
    for v in d["videos"]:
        assert keys <= set(v) and (("action" in v) == (v["kind"] == "single"))
        assert v["id"] == Path(v["video"]).stem and v["azimuth_deg"] == {"front": 0.0, "left": 90.0}[v["view"]]
    assert {v["bvh"] for v in singles if v["performer"] == "p00" and v["action"] == "Jab"} == {"mocap/p00_jab.bvh"}


def test_dataset_files_agree_with_each_other(mocap_dataset):
    root, _ = mocap_dataset
    base = root / "a"
    d = json.loads((base / "dataset.json").read_text())
    for v in d["videos"]:
        lab = json.loads((base / v["labels"]).read_text())
        mlab = json.loads((base / v["bvh_labels"]).read_text())
        assert len(lab["labels"]) == v["frames"] and lab["fps"] == 20 and mlab["fps"] == 60
        assert lab["labels"] == mlab["labels"][::3] and lab["chain"] == mlab["chain"]
        assert [e["label"] for e in lab["events"]] == lab["chain"]
        assert lab["transitions"] == [i for i in range(1, len(lab["labels"])) if lab["labels"][i] != lab["labels"][i - 1]]
        if v["kind"] == "single":
            assert set(lab["chain"]) == {v["action"]} and set(lab["labels"]) <= {v["action"], "Guard"}
        motion = read_bvh(base / v["bvh"])
        assert motion.n_frames == len(mlab["labels"]) and motion.fps == pytest.approx(60)
        assert motion.resample(20).n_frames == v["frames"]


def test_dataset_is_deterministic_in_the_seed(mocap_dataset):
    root, _ = mocap_dataset
    files = sorted(p.relative_to(root / "a") for p in (root / "a").rglob("*") if p.is_file())
    assert files == sorted(p.relative_to(root / "b") for p in (root / "b").rglob("*") if p.is_file())
    for f in files:  # one worker or two: byte-identical
        assert (root / "a" / f).read_bytes() == (root / "b" / f).read_bytes(), f
    assert (root / "a" / "mocap" / "p00_perf0.bvh").read_bytes() != (root / "c" / "mocap" / "p00_perf0.bvh").read_bytes()


def test_dataset_refuses_a_non_empty_directory_and_overwrites_on_request(tmp_path):
    params = DatasetParams(seed=1, performers=1, views=("front",), single_seconds=1.5, performances=0, render=False)
    (tmp_path / "out").mkdir()
    (tmp_path / "out" / "keep.txt").write_text("x")
    with pytest.raises(InputError, match="not empty"):
        make_dataset(tmp_path / "out", params)
    make_dataset(tmp_path / "out", params, overwrite=True)
    assert not (tmp_path / "out" / "keep.txt").exists() and (tmp_path / "out" / "dataset.json").is_file()
    assert [p.name for p in tmp_path.iterdir()] == ["out"]  # no temporary directory left behind
    with pytest.raises(InputError, match="^views: unknown view"):
        make_dataset(tmp_path / "x", DatasetParams(views=("top",)))


def _video_frames(path: Path) -> np.ndarray:
    from vidstyle.video import VideoReader

    with VideoReader(path) as r:
        return r.read_all()


def test_cli_tiny_rendered_dataset_end_to_end(tmp_path):
    args = ["demo", "make-dataset", "--small", "--performers", "1", "--views", "front,right", "--single-seconds",
            "2", "--performance-seconds", "4", "--seed", "2", "--jobs", "2"]
    assert main(args + ["--out", str(tmp_path / "a")]) == 0
    assert main(args + ["--out", str(tmp_path / "b")]) == 0
    assert main(args + ["--out", str(tmp_path / "b")]) != 0  # refuses to overwrite silently
    from vidstyle.render import load_truth

    d = json.loads((tmp_path / "a" / "dataset.json").read_text())
    assert len(d["videos"]) == 7 * 2
    for v in d["videos"]:
        frames = _video_frames(tmp_path / "a" / v["video"])
        lab = json.loads((tmp_path / "a" / v["labels"]).read_text())
        assert frames.shape == (v["frames"], 120, 160, 3) and len(lab["labels"]) == v["frames"]
        truth = load_truth(tmp_path / "a" / v["truth"])
        assert list(truth["labels"]) == lab["labels"]
        assert np.flatnonzero(truth["transition"]).tolist() == lab["transitions"]
        # the sidecar's 3D joints are the BVH's joints at the video frames
        pos = global_positions(read_bvh(tmp_path / "a" / v["bvh"]))[::3]
        assert np.allclose(truth["joints3d"], pos, atol=1e-3)
        if v["id"] == "p00_perf0_right":
            assert np.array_equal(frames, _video_frames(tmp_path / "b" / v["video"]))


def test_performance_views_render_performances_only_there(tmp_path):
    args = ["demo", "make-dataset", "--small", "--performers", "1", "--views", "front,left", "--single-seconds",
            "2", "--performances", "2", "--performance-seconds", "3", "--seed", "2", "--no-video"]
    assert main(args + ["--performance-views", "left", "--out", str(tmp_path / "a")]) == 0
    d = json.loads((tmp_path / "a" / "dataset.json").read_text())
    perf = sorted(v["id"] for v in d["videos"] if v["kind"] == "performance")
    single_views = {v["view"] for v in d["videos"] if v["kind"] == "single"}
    assert perf == ["p00_perf0_left", "p00_perf1_left"] and single_views == {"front", "left"}
    # the same take and labels as when rendered in every view
    assert main(args + ["--out", str(tmp_path / "b")]) == 0
    for name in ("labels/p00_perf1_left.json", "mocap/p00_perf1.bvh"):
        assert (tmp_path / "a" / name).read_bytes() == (tmp_path / "b" / name).read_bytes()
    assert main(args + ["--performance-views", "left,sideways", "--out", str(tmp_path / "c")]) == 2


def test_cli_performer_writes_a_bvh_clip(tmp_path):
    out = tmp_path / "clip.bvh"
    assert main(["demo", "performer", "--seed", "3", "--action", "roundhousekick", "--seconds", "3", "--out", str(out)]) == 0
    motion = read_bvh(out)
    labels = json.loads((tmp_path / "clip.labels.json").read_text())
    assert motion.n_frames == len(labels["labels"]) == 180 and set(labels["chain"]) == {"RoundhouseKick"}
    assert main(["demo", "performer", "--action", "Punch", "--out", str(out)]) == 2


@pytest.mark.slow
def test_cli_small_dataset(tmp_path):
    assert main(["demo", "make-dataset", "--small", "--out", str(tmp_path / "ds"), "--seed", "0"]) == 0
    d = json.loads((tmp_path / "ds" / "dataset.json").read_text())
    assert len(d["performers"]) == 4 and len(d["videos"]) == 4 * 7 * 2
    for v in d["videos"]:
        assert (tmp_path / "ds" / v["video"]).stat().st_size > 0 and (tmp_path / "ds" / v["truth"]).is_file()


def test_split_sets_render_only_that_sets_performers(tmp_path):
    """--split-seed S --split-sets B: the classifier's training performers of the split of S, the same takes
    as the full dataset's (train-recognizer --more-views adds them to set B)."""
    from vidstyle.recognition.splits import performer_groups

    args = ["demo", "make-dataset", "--performers", "5", "--views", "45", "--single-seconds", "2",
            "--performances", "0", "--seed", "2", "--no-video"]
    assert main(args + ["--split-seed", "3", "--split-sets", "b,a", "--out", str(tmp_path / "ab")]) == 0
    d = json.loads((tmp_path / "ab" / "dataset.json").read_text())
    groups = performer_groups([f"p{i:02d}" for i in range(5)], 3)
    assert sorted({v["performer"] for v in d["videos"]}) == sorted(groups["A"] + groups["B"])
    assert main(args + ["--out", str(tmp_path / "all")]) == 0
    p = groups["B"][0]
    for name in (f"labels/{p}_jab_az45.json", f"mocap/{p}_jab.bvh"):
        assert (tmp_path / "ab" / name).read_bytes() == (tmp_path / "all" / name).read_bytes()
    assert main(args + ["--split-sets", "B", "--out", str(tmp_path / "x")]) == 2  # no --split-seed
    assert main(args + ["--split-seed", "3", "--split-sets", "B,Q", "--out", str(tmp_path / "y")]) == 2
    assert main(args + ["--split-seed", "3", "--only-performers", "p00", "--out", str(tmp_path / "z")]) == 2


def test_first_performer_renders_new_performers_only(tmp_path):
    """--first-performer K: performers p<K>.. of --performers, the same takes as the full dataset's (the
    performers `vocabulary / train-recognizer --more-performers` add; no split holds them)."""
    args = ["demo", "make-dataset", "--performers", "5", "--views", "front", "--single-seconds", "2",
            "--performances", "0", "--seed", "2", "--no-video"]
    assert main(args + ["--first-performer", "3", "--out", str(tmp_path / "new")]) == 0
    d = json.loads((tmp_path / "new" / "dataset.json").read_text())
    assert sorted({v["performer"] for v in d["videos"]}) == ["p03", "p04"]
    assert main(args + ["--out", str(tmp_path / "all")]) == 0
    for name in ("labels/p04_jab_front.json", "mocap/p03_hook.bvh"):
        assert (tmp_path / "new" / name).read_bytes() == (tmp_path / "all" / name).read_bytes()
    assert main(args + ["--first-performer", "5", "--out", str(tmp_path / "x")]) == 2  # past the last
    assert main(args + ["--first-performer", "1", "--split-seed", "0", "--out", str(tmp_path / "y")]) == 2
    assert not (tmp_path / "x").exists() and not (tmp_path / "y").exists()


def test_footwork_option(tmp_path):
    """--footwork F: the dataset and each performer record it; the punches' mocap differs from the same seed's
    without it, the kicks' does not (footwork is the punches'); out of 0..1 is refused."""
    args = ["demo", "make-dataset", "--performers", "1", "--views", "front", "--single-seconds", "2",
            "--performances", "0", "--seed", "2", "--no-video"]
    assert main(args + ["--footwork", "0.8", "--out", str(tmp_path / "fw")]) == 0
    assert main(args + ["--out", str(tmp_path / "plain")]) == 0
    d = json.loads((tmp_path / "fw" / "dataset.json").read_text())
    assert d["params"]["footwork"] == 0.8
    styles = [p["style"]["footwork"] for p in d["performers"]]
    assert styles and all(0.4 <= f <= 0.8 for f in styles)
    assert "footwork" not in json.loads((tmp_path / "plain" / "dataset.json").read_text())["params"]
    for name, same in (("mocap/p00_jab.bvh", False), ("mocap/p00_lowkick.bvh", True)):
        assert ((tmp_path / "fw" / name).read_bytes() == (tmp_path / "plain" / name).read_bytes()) is same, name
    assert main(args + ["--footwork", "1.5", "--out", str(tmp_path / "bad")]) == 2
    assert not (tmp_path / "bad").exists()
