"""scripts/rescore_segments.py adds the segments block to a recognition metrics file only when the labels it
scores are that file's own predictions."""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

SCRIPT = Path(__file__).resolve().parents[1] / "scripts" / "rescore_segments.py"
spec = importlib.util.spec_from_file_location("rescore_segments", SCRIPT)
rs = importlib.util.module_from_spec(spec)
spec.loader.exec_module(rs)


def _doc(smoothed, counts):
    return {"kind": "vidstyle.metrics.recognition", "schema_version": 1, "seed": 0, "recognizer": "pose+sift",
            "frame_accuracy": {"raw": 0.5, "smoothed": smoothed}, "video_accuracy": None, "n_test_videos": 1,
            "n_test_frames": 6, "split": {"kind": "unseen-performer"},
            "confusion": {"classes": ["A", "B"], "counts_smoothed": counts}}


def test_writes_the_block_only_for_the_files_own_predictions(tmp_path, monkeypatch):
    import vidstyle.evaluation.recognition as recognition
    import vidstyle.formats.dataset as dataset

    path = tmp_path / "m.json"
    path.write_text(json.dumps(_doc(0.75, [[3, 1], [0, 2]])))
    segments = {"smoothed": {"boundary_tolerant_accuracy": {"1": 0.9}, "segmental_f1": {"50": 0.5}}}
    scored = {**_doc(0.75, [[3, 1], [0, 2]]), "segments": segments}
    monkeypatch.setattr(dataset, "read_dataset", lambda p: None)
    monkeypatch.setattr(recognition, "score_labels_dir", lambda *a, **k: scored)
    args = ["--metrics", str(path), "--labels-dir", str(tmp_path), "--dataset", "d.json", "--model", "m.joblib"]
    # other predictions (another confusion): refused, the file untouched
    scored["confusion"] = {"classes": ["A", "B"], "counts_smoothed": [[4, 0], [0, 2]]}
    before = path.read_text()
    assert rs.main(args) == 1 and path.read_text() == before
    # the same predictions: the block is added, the rest kept
    scored["confusion"] = {"classes": ["A", "B"], "counts_smoothed": [[3, 1], [0, 2]]}
    assert rs.main(args) == 0
    doc = json.loads(path.read_text())
    assert doc["segments"] == segments and doc["recognizer"] == "pose+sift"
    assert doc["segments_command"].startswith("python scripts/rescore_segments.py --metrics")
