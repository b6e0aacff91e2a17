"""Boundary-tolerant accuracy and segmental F1 (vidstyle.evaluation.segments) against hand-computed cases
and a brute-force reference."""

from __future__ import annotations

import numpy as np
import pytest

from vidstyle.evaluation.segments import (
    boundary_scores,
    segment_counts,
    segmental_f1,
    segments,
    tolerant_correct,
)


def test_tolerance_forgives_only_the_labels_that_meet_at_a_nearby_boundary():
    truth = list("AAAABBBB")
    late = list("AAAAABBB")  # the boundary one frame late
    assert tolerant_correct(truth, late, 0).tolist() == [True] * 4 + [False] + [True] * 3
    assert tolerant_correct(truth, late, 1).all()
    third = list("AAAACBBB")  # a third label at the boundary is wrong at any tolerance
    assert not tolerant_correct(truth, third, 3)[4]
    two_late = list("AAAAAABB")
    assert tolerant_correct(truth, two_late, 1).sum() == 7 and tolerant_correct(truth, two_late, 2).all()


def test_tolerant_correct_matches_a_brute_force_reference():
    rng = np.random.default_rng(0)
    for _ in range(50):
        n = int(rng.integers(1, 40))
        truth = rng.integers(0, 3, n)
        pred = rng.integers(0, 3, n)
        for k in range(4):
            ref = [pred[t] in truth[max(0, t - k): t + k + 1] for t in range(n)]
            assert tolerant_correct(truth, pred, k).tolist() == ref
    with pytest.raises(ValueError):
        tolerant_correct([0, 1], [0], 1)
    with pytest.raises(ValueError):
        tolerant_correct([0, 1], [0, 1], -1)


def test_segments_and_counts_by_hand():
    assert segments("AABBBA") == [("A", 0, 2), ("B", 2, 5), ("A", 5, 6)]
    assert segments([]) == []
    truth = "AAAABBBBAAAA"
    # a stray B inside the first A run: the A run is split in two (IoU 2/4 and 1/4 with the true A run)
    pred = "AABABBBBAAAA"
    # predicted segments: A[0,2) IoU 0.5 -> TP at 0.5; B[2,3) IoU with B[4,8) 0 -> FP; A[3,4) best the
    # same true A, already matched -> FP; B[4,8) TP; A[8,12) TP
    assert segment_counts(truth, pred, 0.5) == (3, 2, 0)
    assert segment_counts(truth, pred, 0.6) == (2, 3, 1)  # A[0,2) below 0.6: the first true A unmatched
    assert segment_counts(truth, truth, 1.0) == (3, 0, 0)
    f1 = segmental_f1([truth, truth], [pred, truth], 0.5)  # tp 6, fp 2, fn 0
    assert f1 == pytest.approx(2 * (6 / 8) * 1.0 / (6 / 8 + 1.0))
    assert segmental_f1([], [], 0.5) is None
    with pytest.raises(ValueError):
        segment_counts(truth, pred, 0.0)


def test_boundary_scores_block():
    truth = np.array([0, 0, 0, 1, 1, 1])
    pred = np.array([0, 0, 1, 1, 1, 1])  # the boundary a frame early
    b = boundary_scores([truth, truth], [pred, truth], tolerances=(1,), overlaps=(0.5, 0.75))
    assert b["boundary_tolerant_accuracy"] == {"1": 1.0}
    # segments: pred video has IoU 2/3 and 3/4 with the true runs: TP at 0.5, at 0.75 only the second
    assert b["segmental_f1"]["50"] == pytest.approx(1.0)
    assert b["segmental_f1"]["75"] == pytest.approx(2 * (3 / 4) * (3 / 4) / (3 / 2))


def test_the_recognition_metrics_reader_checks_the_segment_scores(tmp_path):
    import json

    from vidstyle.formats import FormatError
    from vidstyle.formats.metrics import RECOGNITION, read_metrics

    doc = {"kind": RECOGNITION, "schema_version": 1, "seed": 0, "frame_accuracy": {"raw": 0.6, "smoothed": 0.7},
           "video_accuracy": None, "n_test_videos": 1, "n_test_frames": 6, "split": {"kind": "unseen-performer"},
           "confusion": {"classes": ["A", "B"]},
           "segments": {"smoothed": boundary_scores([[0, 0, 1]], [[0, 1, 1]])}}
    path = tmp_path / "m.json"
    path.write_text(json.dumps(doc))
    assert read_metrics(path, RECOGNITION).get("segments", "smoothed", "boundary_tolerant_accuracy", "1") == 1.0
    doc["segments"]["smoothed"]["segmental_f1"]["50"] = 1.5
    path.write_text(json.dumps(doc))
    with pytest.raises(FormatError, match="segmental_f1"):
        read_metrics(path, RECOGNITION)
