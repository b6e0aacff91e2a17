"""CMU recognition dataset (``vidstyle demo make-cmu-dataset``): planning, manifest schema, labels vs video
frames, determinism, subject = performer. Rendering tests skip without ../shared."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np
import pytest

from vidstyle.cli import main
from vidstyle.demo.cmu import CMUParams, CmuClip, clip_windows, make_cmu_dataset, parse_actions, plan_segments, video_frames
from vidstyle.errors import InputError
from vidstyle.mocap import read_bvh
from vidstyle.video import VideoReader


def read_video(path):
    with VideoReader(path) as r:
        return r.read_all()

# two actions of distinct subjects, one view, 1.5 s windows, two windows per subject: ~20 short videos
SMALL = dict(classes=parse_actions("walk,basketball"), views=("left",), segment_seconds=1.5, max_per_subject=2)


# --------------------------------------------------------------------------- pure planning (no data needed)
def test_parse_actions_merges_aliases_and_rejects_unknown():
    assert parse_actions("walk, jog ,nonwalk=jump+dribble") == (
        ("walk", ("walk",)), ("jog", ("run",)), ("nonwalk", ("jump", "basketball")))
    with pytest.raises(InputError, match="unknown action 'skate'"):
        parse_actions("walk,skate")
    with pytest.raises(InputError, match="given twice"):
        parse_actions("walk,moving=walk+run")
    with pytest.raises(InputError, match="at least one"):
        parse_actions(" , ")


def test_clip_windows_against_hand_computed_cases():
    assert clip_windows(170, 80, 20) == [(5, 85), (85, 165)]  # 2 windows, 10 spare frames split 5/5
    assert clip_windows(80, 80, 20) == [(0, 80)]
    assert clip_windows(50, 80, 20) == [(0, 50)]  # shorter than a window: the whole clip
    assert clip_windows(19, 80, 20) == []


def test_video_frames_matches_resample():
    # 174 BVH frames at 120 fps, T-pose dropped -> 173 frames = 172/120 s -> 29 frames at 20 fps
    clip = CmuClip("x.bvh", "02", "03", "run/jog", 174, 120.0, "run")
    assert video_frames(clip, 20) == 1 + int(np.floor(172 / 120 * 20))


def test_cap_is_independent_of_class_grouping():
    """The per-subject cap draws by subject and source action, so merging classes keeps the same windows
    (features of one grouping then serve the other)."""
    clips = [CmuClip(f"05_{t:02d}.bvh", "05", f"{t:02d}", "dance", 1000, 120.0, "dance") for t in range(1, 6)]
    clips += [CmuClip("05_09.bvh", "05", "09", "walk", 600, 120.0, "walk")]
    a, _ = plan_segments(clips, CMUParams(classes=parse_actions("walk,dance"), max_per_subject=4, seed=3))
    b, _ = plan_segments(clips, CMUParams(classes=parse_actions("walk,other=dance+jump"), max_per_subject=4, seed=3))
    assert [s.stem for s in a] == [s.stem for s in b]
    assert sum(s.clip.source_action == "dance" for s in a) == 4
    assert {s.label for s in b} == {"walk", "other"}


def test_subjects_and_class_case():
    """--subjects keeps only those subjects' clips (the windows are the ones the full plan gives them);
    a class keeps its case (Step=walk: the demo's class), so another dataset's labels can name it."""
    clips = [CmuClip(f"{s}_{t:02d}.bvh", s, f"{t:02d}", "walk", 600, 120.0, "walk") for s in ("03", "07") for t in (1, 2)]
    full, _ = plan_segments(clips, CMUParams(classes=parse_actions("Step=walk"), segment_seconds=1.5, seed=3))
    only, _ = plan_segments(clips, CMUParams(classes=parse_actions("Step=walk"), segment_seconds=1.5, seed=3,
                                             subjects=("03",)))
    assert {s.performer for s in full} == {"s03", "s07"}
    assert [s.stem for s in only] == [s.stem for s in full if s.clip.subject == "03"] and only
    assert {s.label for s in only} == {"Step"}
    assert parse_actions("Walk,Other=run+jump") == (("Walk", ("walk",)), ("Other", ("run", "jump")))
    assert "subjects" not in CMUParams(classes=parse_actions("walk")).to_dict()
    assert CMUParams(classes=parse_actions("walk"), subjects=("03",)).to_dict()["subjects"] == ["03"]
    with pytest.raises(InputError, match="two digits"):
        CMUParams(classes=parse_actions("walk"), subjects=("3a",)).validate()


def test_unknown_subject_is_refused(cmu_dir, tmp_path):
    with pytest.raises(InputError, match="no clip of subject.*99"):
        make_cmu_dataset(cmu_dir, tmp_path / "x", CMUParams(classes=parse_actions("walk"), subjects=("99",)), jobs=1)
    assert not (tmp_path / "x").exists()


# --------------------------------------------------------------------------- rendered datasets
@pytest.fixture(scope="module")
def cmu_small(cmu_dir, tmp_path_factory):
    root = tmp_path_factory.mktemp("cmu")
    params = CMUParams(seed=5, **SMALL)
    m1 = make_cmu_dataset(cmu_dir, root / "a", params, jobs=1)
    m2 = make_cmu_dataset(cmu_dir, root / "b", params, jobs=2)  # other worker count, same files
    return m1, m2


@pytest.mark.shared
def test_manifest_schema(cmu_small):
    doc = json.loads(cmu_small[0].read_text())
    assert doc["kind"] == "vidstyle.dataset" and doc["schema_version"] == 2 and doc["seed"] == 5 and doc["fps"] == 20 and doc["size"] == [160, 120]
    assert doc["actions"] == doc["classes"] == ["walk", "basketball"]
    assert doc["params"]["segment_seconds"] == 1.5 and doc["params"]["views"] == ["left"]
    keys = {"id", "performer", "kind", "action", "view", "azimuth_deg", "video", "labels", "truth", "bvh", "frames"}
    for v in doc["videos"]:
        assert keys <= set(v) and v["kind"] == "single" and v["view"] == "left" and v["azimuth_deg"] == 90.0
        assert v["action"] in doc["classes"]
        for k in ("video", "labels", "truth"):
            assert (cmu_small[0].parent / v[k]).is_file(), v[k]
    assert {p["id"] for p in doc["performers"]} == {v["performer"] for v in doc["videos"]}
    # the cap: at most 2 windows per subject and action
    per = {}
    for v in doc["videos"]:
        per[(v["performer"], v["action"])] = per.get((v["performer"], v["action"]), 0) + 1
    assert max(per.values()) <= 2
    # the loader of the recognition stage accepts it
    from vidstyle.formats.dataset import read_dataset as load_dataset

    ds = load_dataset(cmu_small[0])
    assert len(ds.videos) == len(doc["videos"]) and ds.classes == ["walk", "basketball"]


@pytest.mark.shared
def test_labels_match_video_frames_and_source(cmu_small, cmu_dir):
    root = cmu_small[0].parent
    doc = json.loads(cmu_small[0].read_text())
    for v in doc["videos"]:
        lab = json.loads((root / v["labels"]).read_text())
        frames = read_video(root / v["video"])
        assert len(lab["labels"]) == len(frames) == v["frames"]
        assert set(lab["labels"]) == {v["action"]} and lab["transitions"] == []
        assert lab["events"] == [{"label": v["action"], "start": 0, "end": v["frames"]}]
        assert lab["classes"] == doc["classes"] and lab["performer"] == v["performer"] and lab["fps"] == 20
        # 1.5 s windows, or a whole clip when shorter; never the T-pose (frame 0 of the BVH)
        assert v["frames"] <= 30 and v["bvh_start"] >= 1
    # the sidecar's 3D joints are the BVH's own frames (independent truth: forward kinematics of the file)
    from vidstyle.mocap import global_positions
    from vidstyle.render import load_truth

    v = doc["videos"][0]
    truth = load_truth(root / v["truth"])
    m = read_bvh(Path(v["bvh"]))
    ref = global_positions(m[v["bvh_start"]:v["bvh_start"] + 1])[0]
    assert np.allclose(truth["joints3d"][0], ref, atol=1e-3)


@pytest.mark.shared
def test_deterministic(cmu_small):
    a, b = (m.parent for m in cmu_small)
    assert (a / "dataset.json").read_text() == (b / "dataset.json").read_text().replace(str(b), str(a))
    for f in sorted((a / "videos").glob("*.mp4")):
        fa = read_video(f)
        fb = read_video(b / "videos" / f.name)
        assert np.array_equal(fa, fb), f.name
    for f in sorted((a / "labels").glob("*.json")):
        assert f.read_text() == (b / "labels" / f.name).read_text()


@pytest.mark.shared
def test_every_performer_is_its_cmu_subject(cmu_small, cmu_dir):
    """Independent truth: clips.csv says which subject recorded each clip; the performer must be that
    subject, so a split by performer is a split by subject."""
    with open(cmu_dir / "clips.csv", newline="") as f:
        subject_of = {r["file"]: r["subject"] for r in csv.DictReader(f)}
    doc = json.loads(cmu_small[0].read_text())
    for v in doc["videos"]:
        assert v["performer"] == f"s{subject_of[Path(v['bvh']).name]}"
        assert v["id"].startswith(v["performer"] + "_")
    # walking was recorded by several subjects, basketball by subject 06 only
    subjects = {a: {v["performer"] for v in doc["videos"] if v["action"] == a} for a in doc["classes"]}
    assert len(subjects["walk"]) >= 3 and subjects["basketball"] == {"s06"}


@pytest.mark.shared
def test_cli_errors_are_one_line(cmu_dir, tmp_path, capsys):
    assert main(["demo", "make-cmu-dataset", "--cmu", str(tmp_path / "nope"), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert "CMU directory not found" in err
    assert main(["demo", "make-cmu-dataset", "--cmu", str(cmu_dir), "--out", str(tmp_path / "o"),
                 "--actions", "walk,skate"]) == 2
    assert "unknown action 'skate'" in capsys.readouterr().err
    assert not (tmp_path / "o").exists()


def test_follow_offset_removes_drift_but_keeps_sway_and_height():
    """A root moving at constant speed with a 2 Hz lateral sway and a vertical bob: the follow camera
    removes the straight-line drift (exactly, away from the ends) and keeps sway and bob."""
    from vidstyle.demo.cmu import follow_offset

    t = np.arange(80) / 20.0
    sway = 0.1 * np.sin(2 * np.pi * 2 * t)  # whole periods in a 1 s window: its moving average is 0
    root = np.stack([sway, 1.0 + 0.05 * np.cos(2 * np.pi * 2 * t), 1.4 * t], axis=1)
    rest = root - follow_offset(root, 20.0)
    inner = slice(10, 70)
    assert np.allclose(rest[inner, 2], rest[inner, 2].mean(), atol=0.04)  # forward drift gone (1-frame lag max)
    assert np.allclose(rest[inner, 0], sway[inner], atol=1e-9)
    assert np.array_equal(rest[:, 1], root[:, 1])
