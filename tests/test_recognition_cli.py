"""``vidstyle vocabulary / train-recognizer / recognize / evaluate recognition`` end to end."""

from __future__ import annotations

import json

import numpy as np
import pytest

from tests.conftest import SEED
from vidstyle.cli import main
from vidstyle.recognition.synthetic import make_dataset


@pytest.fixture(scope="module")
def ds(tmp_path_factory):
    root = tmp_path_factory.mktemp("cli")
    make_dataset(root, n_performers=4, views=("front", "left"), seed=SEED, dim=24, reps=(2, 3), n_actions=5)
    return root


def test_pipeline_by_dataset(ds, tmp_path):
    common = ["--dataset", str(ds), "--features-dir", str(ds / "features"), "--seed", str(SEED)]
    assert main(["vocabulary", *common, "--words", "60", "--out", str(tmp_path / "v.npz")]) == 0
    assert main(["train-recognizer", *common, "--vocab", str(tmp_path / "v.npz"), "--components", "24",
                 "--out", str(tmp_path / "m.joblib"), "--onnx"]) == 0
    assert (tmp_path / "m.onnx").is_file()
    manifest = json.loads((ds / "dataset.json").read_text())
    vid = manifest["videos"][0]["id"]
    feats = ds / "features" / f"{vid}.npz"
    assert main(["recognize", str(feats), "--model", str(tmp_path / "m.joblib"), "--window", "4",
                 "--out", str(tmp_path / "lab.json")]) == 0
    doc = json.loads((tmp_path / "lab.json").read_text())
    truth = json.loads((ds / "labels" / f"{vid}.json").read_text())
    n = len(truth["labels"])
    assert len(doc["labels"]) == len(doc["raw"]) == len(doc["confidence"]) == n
    assert doc["smoothing_window"] == 4 and doc["model"] == str(tmp_path / "m.joblib")
    assert set(doc["labels"]) <= set(doc["classes"]) and doc["classes"] == truth["classes"]
    assert all(0 <= c <= 1 for c in doc["confidence"])
    # the model records set B, which shares nothing with set A of the vocabulary
    from vidstyle.recognition.recognizer import read_header

    h = read_header(tmp_path / "m.joblib")
    b = {f["features"] for f in h["training_files"]}
    assert b and not b & set(h["vocabulary"]["training_files"])
    assert h["split"]["set"] == "B" and h["seed"] == SEED


def test_explicit_files_and_overlap_guard(ds, tmp_path):
    manifest = json.loads((ds / "dataset.json").read_text())
    ids = [v["id"] for v in manifest["videos"]]
    f = [str(ds / "features" / f"{i}.npz") for i in ids]
    lab = [str(ds / "labels" / f"{i}.json") for i in ids]
    assert main(["vocabulary", *f[:6], "--words", "40", "--method", "hierarchical", "--branching", "4",
                 "--out", str(tmp_path / "v.npz")]) == 0
    labels_args = [x for p in lab[6:14] for x in ("--labels", p)]
    assert main(["train-recognizer", *f[6:14], *labels_args, "--vocab", str(tmp_path / "v.npz"),
                 "--components", "16", "--no-grouping", "--out", str(tmp_path / "m.joblib")]) == 0
    overlap = [x for p in lab[:8] for x in ("--labels", p)]
    assert main(["train-recognizer", *f[:8], *overlap, "--vocab", str(tmp_path / "v.npz"),
                 "--out", str(tmp_path / "m2.joblib")]) == 2
    assert not (tmp_path / "m2.joblib").exists()


def test_evaluate_recognition(ds, tmp_path):
    out = tmp_path / "metrics.json"
    assert main(["evaluate", "recognition", "--dataset", str(ds), "--features-dir", str(ds / "features"),
                 "--words", "60", "--components", "24", "--split", "unseen-view", "--test-view", "left",
                 "--seed", str(SEED), "--out", str(out)]) == 0
    m = json.loads(out.read_text())
    assert m["split"]["kind"] == "unseen-view" and m["split"]["test_views"] == ["left"] and m["seed"] == SEED
    assert m["scored_set"] == "T" and set(m["split"]["test_performers"]).isdisjoint(m["split"]["train_performers"])
    # the synthetic classes are learnable: a recognizer that guesses, or says the most frequent class
    # everywhere, stays at or below the majority share; this one must do far better
    assert m["frame_accuracy"]["smoothed"] >= max(0.8, _majority(ds, m["split"]["test"]) + 0.3)
    assert m["video_accuracy"] >= 0.8
    assert out.with_suffix(".png").stat().st_size > 1000
    import cv2

    img = cv2.imread(str(out.with_suffix(".png")))
    assert img is not None and img.ndim == 3


def _majority(ds, ids) -> float:
    from collections import Counter

    c = Counter(x for i in ids for x in json.loads((ds / "labels" / f"{i}.json").read_text())["labels"])
    return max(c.values()) / sum(c.values())


def test_evaluate_unseen_camera(ds, tmp_path):
    """Train on the front view, test on the test performers' left-view videos as the 'new camera'."""
    manifest = json.loads((ds / "dataset.json").read_text())
    for name, view in (("main", "front"), ("camera", "left")):
        d = tmp_path / name
        d.mkdir()
        (d / "labels").symlink_to(ds / "labels")
        doc = {**manifest, "videos": [v for v in manifest["videos"] if v["view"] == view]}
        (d / "dataset.json").write_text(json.dumps(doc))
    out = tmp_path / "cam.json"
    args = ["evaluate", "recognition", "--dataset", str(tmp_path / "main"), "--features-dir", str(ds / "features"),
            "--words", "60", "--components", "24", "--split", "unseen-camera", "--no-baseline", "--seed", str(SEED),
            "--out", str(out)]
    assert main(args) == 2 and not out.exists()  # needs the camera dataset
    assert main([*args, "--test-dataset", str(tmp_path / "camera"), "--test-features-dir", str(ds / "features")]) == 0
    m = json.loads(out.read_text())
    s = m["split"]
    assert s["kind"] == "unseen-camera" and s["test_cameras"] == [[90.0, None]]
    assert all(i.endswith("_left") for i in s["test"]) and all(i.endswith("_front") for i in s["train"] + s["vocab"])
    assert {i.split("_")[0] for i in s["test"]} == set(s["test_performers"])
    assert m["frame_accuracy"]["smoothed"] > _majority(ds, s["test"]) + 0.1
    # a camera that training used is refused
    assert main([*args, "--test-dataset", str(tmp_path / "main"), "--test-features-dir", str(ds / "features")]) == 2


def test_bad_inputs_exit_2(ds, tmp_path, capsys):
    assert main(["vocabulary", str(tmp_path / "none.npz"), "--out", str(tmp_path / "v.npz")]) == 2
    assert "none.npz" in capsys.readouterr().err
    assert main(["recognize", str(tmp_path / "none.npz"), "--model", str(tmp_path / "m.joblib"),
                 "--out", str(tmp_path / "l.json")]) == 2
    # labels whose length differs from the features' n_frames
    manifest = json.loads((ds / "dataset.json").read_text())
    vid = manifest["videos"][0]["id"]
    bad = json.loads((ds / "labels" / f"{vid}.json").read_text())
    bad["labels"] = bad["labels"][:-3]
    (tmp_path / "bad.json").write_text(json.dumps(bad))
    assert main(["vocabulary", str(ds / "features" / f"{manifest['videos'][1]['id']}.npz"), "--words", "10",
                 "--out", str(tmp_path / "v.npz")]) == 0
    assert main(["train-recognizer", str(ds / "features" / f"{vid}.npz"), "--labels", str(tmp_path / "bad.json"),
                 "--vocab", str(tmp_path / "v.npz"), "--out", str(tmp_path / "m.joblib")]) == 2
    assert "labels but" in capsys.readouterr().err
    # a features file of another descriptor dimension than the vocabulary
    np.savez(tmp_path / "other.npz", descriptors=np.ones((4, 7), np.float32), frame_index=np.arange(4), n_frames=4)
    (tmp_path / "four.json").write_text(json.dumps({"classes": ["Jab", "Guard"], "labels": ["Jab"] * 2 + ["Guard"] * 2}))
    assert main(["train-recognizer", str(tmp_path / "other.npz"), "--labels", str(tmp_path / "four.json"),
                 "--vocab", str(tmp_path / "v.npz"), "--out", str(tmp_path / "m.joblib")]) == 2
    assert "dimension 7" in capsys.readouterr().err
    (tmp_path / "unknown.json").write_text(json.dumps({"classes": ["Jab"], "labels": ["Jab", "Kick", "Jab", "Jab"]}))
    assert main(["train-recognizer", str(tmp_path / "other.npz"), "--labels", str(tmp_path / "unknown.json"),
                 "--vocab", str(tmp_path / "v.npz"), "--out", str(tmp_path / "m.joblib")]) == 2
    assert "Kick" in capsys.readouterr().err


def test_recognize_a_video_through_the_features_stage(tmp_path):
    import vidstyle.features.extract  # noqa: F401

    rng = np.random.default_rng(SEED)
    path = tmp_path / "clip.avi"
    from vidstyle.video import VideoWriter

    with VideoWriter(path, 20) as w:
        for t in range(16):  # a bright square moving right over noise: motion for the salient points
            img = (rng.random((120, 160)) * 40).astype(np.uint8)
            img[40:80, 20 + 6 * t : 60 + 6 * t] = 220
            w.write(img)
    assert main(["features", str(path), "--out", str(tmp_path / "f")]) == 0
    feats = tmp_path / "f" / "clip.npz"
    n = int(np.load(feats)["n_frames"])
    (tmp_path / "l.json").write_text(json.dumps({"classes": ["Jab", "Guard"], "labels": ["Guard"] * (n // 2) + ["Jab"] * (n - n // 2)}))
    assert main(["vocabulary", str(feats), "--words", "4", "--out", str(tmp_path / "v.npz")]) == 0
    assert main(["train-recognizer", str(feats), "--labels", str(tmp_path / "l.json"), "--vocab", str(tmp_path / "v.npz"),
                 "--allow-overlap", "--components", "2", "--out", str(tmp_path / "m.joblib")]) == 0
    assert main(["recognize", str(path), "--model", str(tmp_path / "m.joblib"), "--out", str(tmp_path / "a.json")]) == 0
    assert main(["recognize", str(feats), "--model", str(tmp_path / "m.joblib"), "--out", str(tmp_path / "b.json")]) == 0
    a, b = (json.loads((tmp_path / f).read_text()) for f in ("a.json", "b.json"))
    assert a["raw"] == b["raw"] and len(a["labels"]) == n  # same features whether computed now or read


def test_recognize_out_dir_then_score_labels_dir(ds, tmp_path, capsys):
    """The DVC shape: train-recognizer, recognize --out-dir (many inputs, one start-up), then evaluate
    recognition --labels-dir --model, which scores without retraining and matches scoring in memory."""
    common = ["--dataset", str(ds), "--features-dir", str(ds / "features"), "--seed", str(SEED)]
    assert main(["vocabulary", *common, "--words", "60", "--out", str(tmp_path / "v.npz")]) == 0
    assert main(["train-recognizer", *common, "--vocab", str(tmp_path / "v.npz"), "--components", "24",
                 "--smoothing", "viterbi", "--out", str(tmp_path / "m.joblib")]) == 0
    from vidstyle.recognition.recognizer import load_model

    rec, header = load_model(tmp_path / "m.joblib")
    test = header["split"]["test"]
    inputs = [str(ds / "features" / f"{i}.npz") for i in test]
    assert main(["recognize", *inputs, "--model", str(tmp_path / "m.joblib"), "--out-dir", str(tmp_path / "lab")]) == 0
    assert sorted(p.stem for p in (tmp_path / "lab").glob("*.json")) == sorted(test)
    doc = json.loads((tmp_path / "lab" / f"{test[0]}.json").read_text())
    assert doc["smoothing"] == "viterbi"
    out = tmp_path / "metrics.json"
    assert main(["evaluate", "recognition", "--dataset", str(ds), "--labels-dir", str(tmp_path / "lab"),
                 "--model", str(tmp_path / "m.joblib"), "--out", str(out)]) == 0
    m = json.loads(out.read_text())
    assert m["split"]["test"] == test and m["n_test_videos"] == len(test)
    assert m["source"]["model"] == str(tmp_path / "m.joblib") and m["params"]["recognizer"]["smoothing"] == "viterbi"
    # the same numbers as scoring the predictions in memory
    from vidstyle.evaluation.recognition import score_videos
    from vidstyle.formats.dataset import read_dataset as load_dataset
    from vidstyle.formats.labels import read_labels as load_labels

    d = load_dataset(ds)
    by = d.by_id()
    outs = [rec.predict_video(p) for p in inputs]
    truths = [load_labels(d.labels_path(by[i])).labels for i in test]
    acts = [by[i].action if by[i].kind == "single" else None for i in test]
    ref = score_videos(rec.classes_, truths, outs, test, acts)
    assert m["frame_accuracy"] == pytest.approx(ref["frame_accuracy"])
    assert m["video_accuracy"] == pytest.approx(ref["video_accuracy"])
    # errors: both --out and --out-dir, several inputs with --out, a missing test labels file
    assert main(["recognize", *inputs[:2], "--model", str(tmp_path / "m.joblib"), "--out", str(tmp_path / "x.json")]) == 2
    assert main(["recognize", inputs[0], "--model", str(tmp_path / "m.joblib"), "--out", str(tmp_path / "x.json"),
                 "--out-dir", str(tmp_path / "x")]) == 2
    (tmp_path / "lab" / f"{test[0]}.json").unlink()
    assert main(["evaluate", "recognition", "--dataset", str(ds), "--labels-dir", str(tmp_path / "lab"),
                 "--model", str(tmp_path / "m.joblib"), "--out", str(out)]) == 2
    assert f"{test[0]}.json" in capsys.readouterr().err


def test_recognize_reloads_a_model_retrained_at_the_same_path(ds, tmp_path):
    import os
    import shutil

    common = ["--dataset", str(ds), "--features-dir", str(ds / "features"), "--seed", str(SEED)]
    assert main(["vocabulary", *common, "--words", "40", "--out", str(tmp_path / "v.npz")]) == 0
    for w in (3, 7):
        assert main(["train-recognizer", *common, "--vocab", str(tmp_path / "v.npz"), "--components", "16",
                     "--window", str(w), "--out", str(tmp_path / f"m{w}.joblib")]) == 0
    feats = str(next((ds / "features").glob("*.npz")))
    model = tmp_path / "m.joblib"
    for k, w in enumerate((3, 7)):  # same process, same path, new file: the new model is used
        shutil.copy(tmp_path / f"m{w}.joblib", model)
        os.utime(model, ns=(10**18 + k, 10**18 + k))
        assert main(["recognize", feats, "--model", str(model), "--out", str(tmp_path / f"l{w}.json")]) == 0
        assert json.loads((tmp_path / f"l{w}.json").read_text())["smoothing_window"] == w


def test_recognize_with_late_fusion(ds, tmp_path):
    """recognize --pose-model --poses-dir: the labels are the pose recognizer's smoothing of the weighted mean
    of the two recognizers' frame scores, recomputed here; bad combinations exit 2 without output."""
    from vidstyle.formats.poses import PoseFrame, Poses, write_poses
    from vidstyle.recognition.fusion import fuse_scores
    from vidstyle.recognition.io import load_features
    from vidstyle.recognition.posefeatures import PoseTrack, track_from_poses
    from vidstyle.recognition.poserecognizer import PoseRecognizer, save_pose_model
    from vidstyle.recognition.recognizer import load_model

    common = ["--dataset", str(ds), "--features-dir", str(ds / "features"), "--seed", str(SEED)]
    assert main(["vocabulary", *common, "--words", "60", "--out", str(tmp_path / "v.npz")]) == 0
    assert main(["train-recognizer", *common, "--vocab", str(tmp_path / "v.npz"), "--components", "24",
                 "--out", str(tmp_path / "m.joblib")]) == 0
    sift, header = load_model(tmp_path / "m.joblib")
    rng = np.random.default_rng(SEED)
    classes = [str(c) for c in sift.classes_]
    tracks = [PoseTrack(np.cumsum(rng.normal(0, 2, (60, 15, 2)), axis=0) + 80, 20.0) for _ in range(3)]
    labels = [[classes[(i // 12 + v) % len(classes)] for i in range(60)] for v in range(3)]
    pose = PoseRecognizer(max_frames_per_class=None, mirror=False, smoothing="vote", random_state=0)
    save_pose_model(tmp_path / "p.joblib", pose.fit(tracks, labels, classes=classes))
    inputs = [ds / "features" / f"{i}.npz" for i in header["split"]["test"][:2]]
    (tmp_path / "poses").mkdir()
    for p in inputs:
        n = load_features(p).n_frames
        xy = np.cumsum(rng.normal(0, 2, (n, 15, 2)), axis=0) + 80
        frames = [PoseFrame(f, "front", np.c_[xy[f], np.ones(15)]) for f in range(n) if f % 7]
        write_poses(tmp_path / "poses" / f"{p.stem}.poses.json", Poses(p.name, "blazepose", frames))
    args = ["recognize", *map(str, inputs), "--model", str(tmp_path / "m.joblib"), "--pose-model",
            str(tmp_path / "p.joblib"), "--poses-dir", str(tmp_path / "poses"), "--fusion-weight", "0.7"]
    assert main([*args, "--out-dir", str(tmp_path / "lab")]) == 0
    from vidstyle.formats.poses import read_poses

    for p in inputs:
        doc = json.loads((tmp_path / "lab" / f"{p.stem}.json").read_text())
        so = sift.predict_video(load_features(p))
        n = len(so["raw"])
        po = pose.predict_video(track_from_poses(read_poses(tmp_path / "poses" / f"{p.stem}.poses.json"), 20.0, n))
        want = pose.smooth(*fuse_scores([po["scores"], so["scores"]], [pose.classes_, sift.classes_], [0.7, 0.3],
                                        pose.classes_))
        assert doc["labels"] == [str(pose.classes_[i]) for i in want["smoothed"]]
        assert doc["fusion"]["weight_pose"] == 0.7
    # a duration smoother: the fused scores' power (--fusion-emission-weight) is the smoother's for this run,
    # recorded in the labels file, and the model's own power is left as it was
    import copy

    pose_d = PoseRecognizer(max_frames_per_class=None, mirror=False, smoothing="duration", random_state=0)
    save_pose_model(tmp_path / "pd.joblib", pose_d.fit(tracks, labels, classes=classes))
    changed = 0
    for power in (1.0, 4.0):
        out_dir = tmp_path / f"lab_d{power:g}"
        assert main(["recognize", *map(str, inputs), "--model", str(tmp_path / "m.joblib"), "--pose-model",
                     str(tmp_path / "pd.joblib"), "--poses-dir", str(tmp_path / "poses"), "--fusion-weight", "0.7",
                     "--fusion-emission-weight", str(power), "--out-dir", str(out_dir)]) == 0
        for p in inputs:
            doc = json.loads((out_dir / f"{p.stem}.json").read_text())
            so = sift.predict_video(load_features(p))
            po = pose_d.predict_video(track_from_poses(read_poses(tmp_path / "poses" / f"{p.stem}.poses.json"), 20.0,
                                                       len(so["raw"])))
            fused = fuse_scores([po["scores"], so["scores"]], [pose_d.classes_, sift.classes_], [0.7, 0.3], pose_d.classes_)
            ref = copy.deepcopy(pose_d)
            ref.emission_weight = power  # the independent route: the model's own power set to it
            want = ref.smooth(*fused)
            assert doc["labels"] == [str(pose_d.classes_[i]) for i in want["smoothed"]]
            assert doc["emission_weight"] == power and pose_d.emission_weight == 1.0
            changed += power != 1.0 and want["smoothed"].tolist() != pose_d.smooth(*fused)["smoothed"].tolist()
    assert changed  # the power changed some labels: the comparison above can fail
    # --pose-model without --poses-dir; a weight outside [0, 1]; a missing poses file
    assert main([*args[:-4], "--out-dir", str(tmp_path / "x")]) == 2
    assert main([*args[:-1], "1.5", "--out-dir", str(tmp_path / "x")]) == 2
    (tmp_path / "poses" / f"{inputs[0].stem}.poses.json").unlink()
    assert main([*args, "--out-dir", str(tmp_path / "x")]) == 2
    assert not (tmp_path / "x").exists()
