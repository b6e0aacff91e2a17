"""The owners of the file formats: schema-1 files still load, writers add the header, errors name the file
and the field, and the few queries the stages share (a performer's label files, a chain in another order)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from vidstyle.formats import FormatError
from vidstyle.formats.dataset import read_dataset, write_dataset
from vidstyle.formats.labels import FrameLabels, read_labels, write_labels
from vidstyle.formats.metrics import read_metrics, write_metrics
from vidstyle.formats.recognised import read_recognised
from vidstyle.formats.sequence import (
    ActionSequence,
    format_sequence,
    parse_sequence,
    read_sequence,
    write_sequence,
)
from vidstyle.style.synthetic import write_fake_dataset


def _w(path, doc):
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(doc))
    return path


def test_schema_1_labels_load_and_are_written_as_schema_2(tmp_path):
    old = _w(tmp_path / "old.json", {"video": "v.mp4", "labels": ["Jab", "Guard", "Jab"]})  # no fps, no classes
    t = read_labels(old)
    assert t.classes == ("Guard", "Jab") and t.fps == 20.0 and t.indices().tolist() == [1, 0, 1]
    write_labels(tmp_path / "new.json", t)
    doc = json.loads((tmp_path / "new.json").read_text())
    assert doc["kind"] == "vidstyle.labels" and doc["schema_version"] == 2 and doc["classes"] == ["Guard", "Jab"]
    assert read_labels(tmp_path / "new.json").labels == t.labels
    # schema 2 requires what schema 1 let default
    with pytest.raises(FormatError, match=r"new2.json: fps: missing"):
        read_labels(_w(tmp_path / "new2.json", {k: v for k, v in doc.items() if k != "fps"}))
    with pytest.raises(FormatError, match=r"schema_version: 3 is not supported"):
        read_labels(_w(tmp_path / "v3.json", {**doc, "schema_version": 3}))


def test_labels_length_must_match_the_frames(tmp_path):
    p = _w(tmp_path / "l.json", {"video": "v.mp4", "fps": 20, "classes": ["Jab"], "labels": ["Jab"] * 5})
    assert read_labels(p, n_frames=5).n_frames == 5
    with pytest.raises(FormatError, match=r"l.json: labels: 5 labels but the video has 6 frames"):
        read_labels(p, n_frames=6)


def test_events_must_lie_inside_the_video(tmp_path):
    doc = {"video": "v.mp4", "fps": 20, "classes": ["Jab", "Guard"], "labels": ["Jab"] * 4,
           "events": [{"label": "Jab", "start": 2, "end": 9}]}
    with pytest.raises(FormatError, match=r"events\[0\].end: must be at most 4, got 9"):
        read_labels(_w(tmp_path / "e.json", doc))


def test_recognised_labels_need_raw_and_confidence_in_schema_2(tmp_path):
    base = {"kind": "vidstyle.recognised_labels", "schema_version": 2, "video": "v.mp4", "fps": 20,
            "classes": ["Jab", "Hook"], "labels": ["Jab", "Hook"], "confidence": [0.5, 1.0], "raw": ["Jab", "Jab"],
            "raw_confidence": [0.2, 0.4]}
    r = read_recognised(_w(tmp_path / "r.json", base))
    assert r.raw == ["Jab", "Jab"] and r.confidence.tolist() == [0.5, 1.0]
    assert read_labels(tmp_path / "r.json").raw == ["Jab", "Jab"]  # read_labels reads both kinds
    with pytest.raises(FormatError, match=r"raw: expected at most 2 item"):
        read_recognised(_w(tmp_path / "r2.json", {**base, "raw": ["Jab"] * 3}))
    with pytest.raises(FormatError, match=r"confidence: values must lie in \[0, 1\]"):
        read_recognised(_w(tmp_path / "r3.json", {**base, "confidence": [0.5, 1.5]}))
    legacy = {k: v for k, v in base.items() if k not in ("kind", "schema_version", "raw", "raw_confidence")}
    assert read_recognised(_w(tmp_path / "r4.json", legacy)).raw is None


def test_dataset_schema_1_loads_and_performer_label_files(tmp_path):
    write_fake_dataset(tmp_path / "ds", n_performers=2, n_videos=2, events_per_video=10, seed=0)
    ds = read_dataset(tmp_path / "ds")  # the directory or the file
    assert ds.performer_ids() == ["p00", "p01"] and ds.root == tmp_path / "ds"
    files = ds.performer_label_files("p01")
    assert [v.id for v, _ in files] == ["p01_perf0", "p01_perf1"]
    assert all(p == tmp_path / "ds" / "labels" / f"{v.id}.json" and p.is_file() for v, p in files)
    rec = tmp_path / "rec"
    with pytest.raises(FormatError, match=r"rec/p01_perf0.json: recognised labels of video p01_perf0 \(performer p01\)"):
        ds.performer_label_files("p01", labels_dir=rec)
    assert [p for _, p in ds.performer_label_files("p01", labels_dir=rec, require=False)] == [
        rec / "p01_perf0.json", rec / "p01_perf1.json"]
    assert ds.performer_label_files("p01", views=["left"]) == []
    # a chain in the manifest's order and in any other
    ch = ds.performers[0].chain
    rev = list(reversed(ch.actions))
    start, trans, dur = ch.reordered(rev)
    assert np.allclose(trans, ch.transition[::-1, ::-1]) and np.allclose(start, ch.start[::-1])
    assert np.allclose(dur, [ch.duration_frames[a][0] for a in rev])
    # written back with a header, it reads the same
    write_dataset(tmp_path / "copy" / "dataset.json", ds)
    doc = json.loads((tmp_path / "copy" / "dataset.json").read_text())
    assert doc["kind"] == "vidstyle.dataset" and doc["schema_version"] == 2
    again = read_dataset(tmp_path / "copy")
    assert [v.to_dict() for v in again.videos] == [v.to_dict() for v in ds.videos]


def test_dataset_chain_rows_must_be_stochastic(tmp_path):
    write_fake_dataset(tmp_path / "ds", n_performers=2, n_videos=1, events_per_video=5, seed=0)
    doc = json.loads((tmp_path / "ds" / "dataset.json").read_text())
    doc["performers"][1]["chain"]["transition"][2][0] += 0.5
    with pytest.raises(FormatError, match=r"performers\[1\].chain.transition: must be non-negative with rows summing to 1"):
        read_dataset(_w(tmp_path / "bad" / "dataset.json", doc))


def test_sequence_start_frames_and_formats(tmp_path):
    seq = ActionSequence.from_events([{"action": "Jab", "duration_frames": 4}, {"action": "Hook", "duration_frames": 6},
                                      {"action": "Jab", "duration_frames": 2}], 20.0, style="s.json", model="a", seed=1)
    assert [e.start_frame for e in seq.events] == [0, 4, 10]
    write_sequence(tmp_path / "s.json", seq)
    again = read_sequence(tmp_path / "s.json")
    assert again.actions() == ["Jab", "Hook", "Jab"] and again.seed == 1 and again.fps == 20.0
    assert format_sequence(seq, "text") == "Jab Hook Jab\n"
    assert format_sequence(seq, "csv").splitlines()[2] == "1,Hook,6,4"
    assert json.loads(format_sequence(seq, "json")) == json.loads((tmp_path / "s.json").read_text())
    doc = seq.to_dict()
    doc["events"][1]["start_frame"] = 5
    with pytest.raises(FormatError, match=r"events\[1\].start_frame: expected 4"):
        parse_sequence(doc, "x.json")
    with pytest.raises(FormatError, match=r"length: 2 but there are 3 events"):
        parse_sequence({**seq.to_dict(), "length": 2}, "x.json")


def test_metrics_writer_turns_nan_into_null_and_checks_the_shape(tmp_path):
    doc = {"kind": "vidstyle.metrics.headline", "schema_version": 1, "seed": 0,
           "recognition": {"video_accuracy": float("nan")}, "style": {}, "motion": {"label_fidelity": 0.5}}
    write_metrics(tmp_path / "h.json", doc)
    m = read_metrics(tmp_path / "h.json")
    assert m.get("recognition", "video_accuracy") is None and m.get("motion", "label_fidelity") == 0.5
    with pytest.raises(FormatError, match=r"m.json: kind: expected one of"):
        read_metrics(_w(tmp_path / "m.json", {"seed": 0}))
    # motion metrics of older runs have no header; they load as that kind
    assert read_metrics(_w(tmp_path / "motion.json", {"summary": {}}), "vidstyle.metrics.motion").schema_version == 1


def test_frame_labels_written_in_memory_are_validated(tmp_path):
    t = FrameLabels(["Jab", "Kick"], ("Jab",), 20.0, video="v.mp4")
    with pytest.raises(FormatError, match=r"labels\[1\]: 'Kick' is not one of the classes"):
        write_labels(tmp_path / "x.json", t)
    assert not (tmp_path / "x.json").exists()
