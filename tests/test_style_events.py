"""Frame labels -> action events."""

from __future__ import annotations

import json

import numpy as np
import pytest

from vidstyle.errors import InputError
from vidstyle.formats.labels import FrameLabels, read_labels
from vidstyle.style.events import (
    EventParams,
    runs,
    track_to_events,
    tracks_to_events,
)

CLASSES = ("Jab", "Hook", "Uppercut", "Guard", "Step")


def _track(labels, confidence=None, classes=CLASSES, path="t.json"):
    return FrameLabels(list(labels), tuple(classes), 20.0,
                       confidence=None if confidence is None else np.asarray(confidence, float), path=path)


def _events(labels, confidence=None, **kw):
    ev = track_to_events(_track(labels, confidence), EventParams(**kw))
    return ev.names(), ev.durations.tolist(), ev.starts.tolist()


def test_runs_roundtrip():
    x = np.array([1, 1, 2, 2, 2, 1, 3])
    v, s, n = runs(x)
    assert v.tolist() == [1, 2, 1, 3] and s.tolist() == [0, 2, 5, 6] and n.tolist() == [2, 3, 1, 1]
    assert np.array_equal(np.repeat(v, n), x)


def test_filler_separates_and_is_dropped():
    labels = ["Guard"] * 3 + ["Jab"] * 5 + ["Guard"] * 3 + ["Jab"] * 4 + ["Step"] * 4 + ["Hook"] * 6
    names, durs, starts = _events(labels, split_repeats=False)
    assert names == ["Jab", "Jab", "Hook"]
    assert durs == [5, 4, 6] and starts == [3, 11, 19]


def test_short_noise_inside_a_run_is_one_event():
    labels = ["Jab"] * 2 + ["Hook"] + ["Jab"] * 6 + ["Uppercut"] * 2 + ["Jab"] * 5 + ["Guard"] * 4
    names, durs, starts = _events(labels, split_repeats=False)
    assert names == ["Jab"] and durs == [16] and starts == [0]


def test_short_runs_are_dropped_low_confidence_frames_are_unknown():
    labels = ["Jab"] * 6 + ["Guard"] * 3 + ["Hook"] * 2 + ["Guard"] * 3 + ["Uppercut"] * 6
    assert _events(labels, split_repeats=False)[0] == ["Jab", "Uppercut"]
    conf = [0.9] * 6 + [0.9] * 3 + [0.9] * 2 + [0.9] * 3 + [0.2] * 6
    assert _events(labels, conf, split_repeats=False)[0] == ["Jab"]
    assert _events(labels, conf, min_confidence=0.1, split_repeats=False)[0] == ["Jab", "Uppercut"]


def test_a_short_filler_burst_does_not_separate_a_run():
    labels = ["Jab"] * 5 + ["Guard"] + ["Jab"] * 5
    assert _events(labels, split_repeats=False)[0] == ["Jab"]
    assert _events(labels + ["Guard"] * 3 + ["Jab"] * 5, split_repeats=False)[0] == ["Jab", "Jab"]


def test_ignore_parameter_makes_guard_an_action():
    labels = ["Guard"] * 4 + ["Jab"] * 4 + ["Step"] * 4 + ["Guard"] * 4
    ev = track_to_events(_track(labels), EventParams(ignore=("Step",), split_repeats=False))
    assert ev.names() == ["Guard", "Jab", "Guard"]


def test_back_to_back_repeats_are_split():
    rng = np.random.default_rng(0)
    labels = []
    truth = []
    for _ in range(60):
        a = ["Jab", "Hook", "Uppercut"][rng.integers(3)]
        k = 2 if rng.random() < 0.25 else 1
        for _ in range(k):
            truth.append(a)
        labels += [a] * (10 * k) + ["Guard"] * 4
    names = tracks_to_events([_track(labels)], EventParams(split_repeats=True))[0].names()
    assert names == truth
    # without splitting the repeats collapse
    assert len(tracks_to_events([_track(labels)], EventParams(split_repeats=False))[0]) < len(truth)


def _write(tmp_path, doc, name="l.json"):
    p = tmp_path / name
    p.write_text(json.dumps(doc))
    return p


@pytest.mark.parametrize(
    "doc, message",
    [
        ({"classes": ["Jab", "Hook"], "labels": []}, "labels: expected at least 1"),
        ({"classes": ["Jab", "Hook"], "labels": ["Jab", "Kick"]}, r"labels\[1\]: 'Kick' is not one of the classes"),
        ({"classes": ["Jab", "Hook"], "labels": ["Jab"], "confidence": [0.1, 0.2]}, "confidence: expected shape"),
        ({"kind": "vidstyle.labels", "schema_version": 2, "video": "v.mp4", "fps": 20, "labels": ["Jab"]},
         "classes: missing"),
        ({"classes": ["Jab", "Hook"], "labels": ["Jab"], "confidence": [float("nan")]}, "confidence: must be a finite|not valid JSON"),
        ([1, 2], "JSON object"),
    ],
)
def test_bad_label_files(tmp_path, doc, message):
    with pytest.raises(InputError, match=message):
        read_labels(_write(tmp_path, doc))


def test_label_file_roundtrip(tmp_path):
    doc = {"video": "v.mp4", "fps": 25, "classes": list(CLASSES), "labels": ["Jab", "Guard"],
           "confidence": [0.9, 0.4], "performer": "p01"}
    t = read_labels(_write(tmp_path, doc))
    assert t.indices().tolist() == [0, 3] and t.fps == 25 and t.performer == "p01"
    assert t.confidence.tolist() == [0.9, 0.4]
