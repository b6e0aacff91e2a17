"""scripts/validate_recognition.py: winners by validation score, ties to the incumbent; only V is scored."""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

import pytest

SCRIPT = Path(__file__).resolve().parents[1] / "scripts" / "validate_recognition.py"
spec = importlib.util.spec_from_file_location("validate_recognition", SCRIPT)
vr = importlib.util.module_from_spec(spec)
spec.loader.exec_module(vr)


def _row(step, sm, video, **cfg):
    return {"step": step, "config": {**vr.START, **cfg}, "frame_accuracy_raw": sm - 0.01,
            "frame_accuracy_smoothed": sm, "video_accuracy": video}


def test_best_prefers_score_then_video_then_the_incumbent():
    inc = _row("start", 0.9, 0.9)
    assert vr.best([inc, _row("C", 0.9, 0.9, C=10.0)]) is inc  # a tie keeps the starting value
    better_video = _row("C", 0.9, 1.0, C=10.0)
    assert vr.best([inc, better_video]) is better_video
    better = _row("C", 0.91, 0.5, C=10.0)
    assert vr.best([inc, better_video, better]) is better


def test_search_scores_only_the_validation_videos(tmp_path, monkeypatch):
    """The Search loads sets A, B and V of the split; T's videos are never read."""
    from vidstyle.formats.dataset import read_dataset as load_dataset
    from vidstyle.recognition.splits import make_split
    from vidstyle.recognition.synthetic import make_dataset

    make_dataset(tmp_path, n_performers=5, views=("front",), seed=0, dim=16, reps=(2, 3), n_actions=4)
    ds = load_dataset(tmp_path)
    split = make_split(ds, seed=0)
    read = []
    real = vr.load_set

    def spy(dataset, fdir, ids, jobs):
        read.extend(ids)
        return real(dataset, fdir, ids, jobs)

    monkeypatch.setattr(vr, "load_set", spy)
    s = vr.Search(ds, {"scovanner2007": str(tmp_path / "features")}, split, 0, 1)
    rows = s.run("start", {**vr.START, "words": 40}, smoothers=[("viterbi", 3.0), ("vote", None)])
    assert set(read) == set(split.vocab + split.train + split.val) and not set(read) & set(split.test)
    assert [r["n_val_frames"] for r in rows] == [sum(len(json.loads((tmp_path / "labels" / f"{i}.json").read_text())["labels"])
                                                      for i in split.val)] * 2
    assert rows[0]["frame_accuracy_raw"] == rows[1]["frame_accuracy_raw"]  # same model, two smoothers


def test_cache_retrains_nothing_and_rescores_smoothers(tmp_path, monkeypatch):
    """A second search over the same cache gives the same rows without fitting anything."""
    from vidstyle.formats.dataset import read_dataset as load_dataset
    from vidstyle.recognition.recognizer import ActionRecognizer
    from vidstyle.recognition.splits import make_split
    from vidstyle.recognition.synthetic import make_dataset

    make_dataset(tmp_path / "d", n_performers=5, views=("front",), seed=0, dim=16, reps=(2, 3), n_actions=4)
    ds = load_dataset(tmp_path / "d")
    split = make_split(ds, seed=0)
    feats = {"scovanner2007": str(tmp_path / "d" / "features")}
    cfg = {**vr.START, "words": 40}
    sm = [("viterbi", 1.0), ("duration", 1.0)]
    first = vr.Search(ds, feats, split, 0, 1, tmp_path / "cache").run("start", cfg, smoothers=sm)
    assert len(list((tmp_path / "cache").glob("*.joblib"))) == 1

    def no_fit(*a, **k):
        raise AssertionError("retrained a cached candidate")

    monkeypatch.setattr(ActionRecognizer, "fit", no_fit)
    again = vr.Search(ds, feats, split, 0, 1, tmp_path / "cache").run("start", cfg, smoothers=sm)
    assert [r["frame_accuracy_smoothed"] for r in again] == [r["frame_accuracy_smoothed"] for r in first]
    with pytest.raises(AssertionError, match="retrained"):  # another C is another candidate
        vr.Search(ds, feats, split, 0, 1, tmp_path / "cache").run("C", {**cfg, "C": 30.0}, smoothers=sm)


def test_factors_not_searched_names_every_factor_left_out():
    assert set(vr.ALL_FACTORS) >= set(vr.FACTORS) | {"variant"}
    assert all(m in ("viterbi", "vote", "duration") for m, _ in vr.SMOOTHERS)


def test_points_candidates_read_their_own_features(tmp_path, monkeypatch):
    """A points candidate trains and scores on the features given for that count; the start on --features."""
    import shutil

    from vidstyle.formats.dataset import read_dataset as load_dataset
    from vidstyle.recognition.splits import make_split
    from vidstyle.recognition.synthetic import make_dataset

    make_dataset(tmp_path, n_performers=5, views=("front",), seed=0, dim=16, reps=(2, 3), n_actions=4)
    shutil.copytree(tmp_path / "features", tmp_path / "features20")
    ds = load_dataset(tmp_path)
    split = make_split(ds, seed=0)
    dirs = []
    real = vr.load_set

    def spy(dataset, fdir, ids, jobs):
        dirs.append(Path(fdir).name)
        return real(dataset, fdir, ids, jobs)

    monkeypatch.setattr(vr, "load_set", spy)
    s = vr.Search(ds, {"scovanner2007": str(tmp_path / "features")}, split, 0, 1,
                  points_features={20: str(tmp_path / "features20")})
    s.run("start", {**vr.START, "words": 40}, smoothers=[("viterbi", 1.0)])
    assert set(dirs) == {"features"}
    dirs.clear()
    s.run("points", {**vr.START, "words": 40, "points": 20}, smoothers=[("viterbi", 1.0)])
    assert set(dirs) == {"features20"} and len(dirs) == 3  # sets A, B and V, with their own vocabulary
    assert len(s._vocab) == 2


def test_validation_camera_scores_only_the_validation_performers(tmp_path, monkeypatch):
    """With a validation camera, each row also scores V's performers on their camera videos (never another
    performer's), and the score is the mean of the two smoothed accuracies."""
    from vidstyle.formats.dataset import read_dataset as load_dataset
    from vidstyle.recognition.splits import make_split
    from vidstyle.recognition.synthetic import make_dataset

    make_dataset(tmp_path / "d", n_performers=5, views=("front",), seed=0, dim=16, reps=(2, 3), n_actions=4)
    make_dataset(tmp_path / "c", n_performers=5, views=("front",), seed=7, dim=16, reps=(2, 3), n_actions=4)
    ds, cam = load_dataset(tmp_path / "d"), load_dataset(tmp_path / "c")
    split = make_split(ds, seed=0)
    read = []
    real = vr.load_set

    def spy(dataset, fdir, ids, jobs):
        if Path(fdir).parent.name == "c":
            read.extend(ids)
        return real(dataset, fdir, ids, jobs)

    monkeypatch.setattr(vr, "load_set", spy)
    s = vr.Search(ds, {"scovanner2007": str(tmp_path / "d" / "features")}, split, 0, 1,
                  camera_dataset=cam, camera_features={("scovanner2007", 10): str(tmp_path / "c" / "features")})
    rows = s.run("start", {**vr.START, "words": 40}, smoothers=[("viterbi", 1.0), ("vote", None)])
    by = cam.by_id()
    assert read and {by[i].performer for i in read} == set(split.val_performers)
    for r in rows:
        assert 0.0 <= r["camera_frame_accuracy_smoothed"] <= 1.0 and r["n_camera_frames"] > 0
        assert r["score"] == pytest.approx((r["frame_accuracy_smoothed"] + r["camera_frame_accuracy_smoothed"]) / 2)
    assert vr._key(rows[0]) == (rows[0]["score"], rows[0]["video_accuracy"])


def test_committed_validation_documents_are_rewritten_byte_for_byte_by_their_owner():
    """The scripts write through vidstyle.formats.validation: every committed document of its kinds comes
    back from the owner's writer unchanged, header checked (a layout change would rewrite them all)."""
    import glob
    import json
    from pathlib import Path

    from vidstyle.formats.validation import LAYOUTS, dumps_validation, read_validation

    root = Path(__file__).resolve().parents[1] / "pipelines"
    seen = set()
    for f in sorted(glob.glob(str(root / "**" / "*.json"), recursive=True)):
        text = Path(f).read_text()
        doc = json.loads(text)
        if isinstance(doc, dict) and doc.get("kind") in LAYOUTS:
            assert dumps_validation(doc) == text, f
            assert read_validation(f, doc["kind"]) == doc
            seen.add(doc["kind"])
    assert seen == set(LAYOUTS)
