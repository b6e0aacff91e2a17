"""``train-recognizer --annotations``: action segments of a user's own videos train the recognizer."""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

import numpy as np
import pytest

from tests.conftest import SEED
from vidstyle.cli import main
from vidstyle.formats.annotations import (
    Annotations,
    ActionSpan,
    VideoAnnotations,
    frame_labels,
    labelled_runs,
    write_annotations,
)
from vidstyle.recognition.io import crop_features, load_features
from vidstyle.recognition.synthetic import make_dataset


@pytest.fixture(scope="module")
def ds(tmp_path_factory):
    root = tmp_path_factory.mktemp("ann_train")
    make_dataset(root, n_performers=4, views=("front", "left"), seed=SEED, dim=24, reps=(2, 3), n_actions=5)
    return root


def segments_of(labels: list[str], gap_every: int = 0) -> list[ActionSpan]:
    """Runs of equal labels as segments; ``gap_every``: leave two frames unlabelled at each change and
    every ``gap_every`` frames (what a person marking only the clear frames would do)."""
    segs, start = [], 0
    for i in range(1, len(labels) + 1):
        if i == len(labels) or labels[i] != labels[start]:
            a, b = start, i
            if gap_every:
                a, b = a + (a > 0), b - (b < len(labels))
            if b > a:
                segs.append(ActionSpan(a, b, labels[start]))
            start = i
    if gap_every:
        out = []
        for s in segs:
            cut = list(range(s.start, s.end, gap_every)) + [s.end]
            out += [ActionSpan(x, y - 1, s.action) for x, y in zip(cut, cut[1:]) if y - 1 > x]
        segs = out
    return segs


def write_ann(ds: Path, ids: list[str], path: Path, gap_every: int = 0) -> None:
    manifest = json.loads((ds / "dataset.json").read_text())
    videos = []
    for i in ids:
        truth = json.loads((ds / "labels" / f"{i}.json").read_text())
        sha = hashlib.sha256(i.encode()).hexdigest()  # the synthetic set has no video files
        videos.append(VideoAnnotations(f"videos/{i}.mp4", sha, len(truth["labels"]), 20.0, [],
                                       segments_of(truth["labels"], gap_every)))
    write_annotations(path, Annotations(list(manifest["classes"]), videos, 0))


def _split(ds):
    manifest = json.loads((ds / "dataset.json").read_text())
    ids = [v["id"] for v in manifest["videos"]]
    perf = {v["id"]: v["performer"] for v in manifest["videos"]}
    voc = [i for i in ids if perf[i] == "p00"]
    train = [i for i in ids if perf[i] in ("p01", "p02")]
    test = [i for i in ids if perf[i] == "p03"]
    return voc, train, test


def _predict(model, feats, out):
    assert main(["recognize", *map(str, feats), "--model", str(model), "--out-dir", str(out)]) == 0
    return {p.stem: json.loads((out / f"{p.stem}.json").read_text())["labels"] for p in feats}


@pytest.mark.slow
def test_full_segments_train_the_same_model_as_labels_files(ds, tmp_path):
    voc, train, test = _split(ds)
    f = lambda ids: [ds / "features" / f"{i}.npz" for i in ids]
    assert main(["vocabulary", *map(str, f(voc)), "--words", "50", "--out", str(tmp_path / "v.npz")]) == 0
    common = ["--vocab", str(tmp_path / "v.npz"), "--components", "16", "--seed", str(SEED), "-j", "1"]
    labels = [x for i in train for x in ("--labels", str(ds / "labels" / f"{i}.json"))]
    assert main(["train-recognizer", *map(str, f(train)), *labels, *common, "--out", str(tmp_path / "a.joblib")]) == 0
    ann = tmp_path / "ann.json"
    write_ann(ds, train, ann)
    assert main(["train-recognizer", "--annotations", str(ann), "--features-dir", str(ds / "features"), *common,
                 "--out", str(tmp_path / "b.joblib")]) == 0
    pa = _predict(tmp_path / "a.joblib", f(test), tmp_path / "pa")
    pb = _predict(tmp_path / "b.joblib", f(test), tmp_path / "pb")
    assert pa == pb  # every frame labelled: exactly the labels-file training
    # FEATURES files instead of --features-dir: matched to the annotated videos by their recorded video
    assert main(["train-recognizer", *map(str, f(train)), "--annotations", str(ann), *common,
                 "--out", str(tmp_path / "c.joblib")]) == 0
    assert _predict(tmp_path / "c.joblib", f(test), tmp_path / "pc") == pa

    # partial marking (frames near changes and every 7th frame left out) still learns the actions
    ann2 = tmp_path / "ann2.json"
    write_ann(ds, train, ann2, gap_every=7)
    assert main(["train-recognizer", "--annotations", str(ann2), "--features-dir", str(ds / "features"), *common,
                 "--out", str(tmp_path / "d.joblib")]) == 0
    pd = _predict(tmp_path / "d.joblib", f(test), tmp_path / "pd")
    truth = {i: json.loads((ds / "labels" / f"{i}.json").read_text())["labels"] for i in test}
    acc = lambda p: np.mean([a == b for i in test for a, b in zip(p[i], truth[i])])
    assert acc(pd) > 0.6 and acc(pd) > acc(pa) - 0.15, (acc(pd), acc(pa))


def test_bad_annotation_inputs_exit_2(ds, tmp_path):
    voc, train, test = _split(ds)
    ann = tmp_path / "ann.json"
    write_ann(ds, train[:2], ann)
    doc = json.loads(ann.read_text())
    doc["videos"][0]["frames"] += 1
    doc["videos"][0]["segments"] = [{"start": 0, "end": 3, "action": doc["classes"][0]}]
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(doc))
    assert main(["vocabulary", *[str(ds / "features" / f"{i}.npz") for i in voc], "--words", "30",
                 "--out", str(tmp_path / "v.npz")]) == 0
    base = ["train-recognizer", "--vocab", str(tmp_path / "v.npz"), "--out", str(tmp_path / "m.joblib")]
    assert main([*base, "--annotations", str(bad), "--features-dir", str(ds / "features")]) == 2
    assert main([*base, "--annotations", str(ann), "--features-dir", str(tmp_path)]) == 2  # no features there
    assert main([*base, "--annotations", str(ann)]) == 2  # neither FEATURES nor --features-dir
    assert main([*base, "--annotations", str(ann), "--dataset", str(ds / "dataset.json"),
                 "--features-dir", str(ds / "features")]) == 2
    assert not (tmp_path / "m.joblib").exists()


def test_labelled_runs_and_crop(ds):
    v = VideoAnnotations("x.mp4", "0" * 64, 20, 20.0, [], [ActionSpan(0, 4, "a"), ActionSpan(4, 6, "b"), ActionSpan(9, 12, "a")])
    assert labelled_runs(v) == [(0, 6), (9, 12)]
    y = frame_labels(v, ["a", "b"])
    assert y.tolist() == [0] * 4 + [1] * 2 + [-1] * 3 + [0] * 3 + [-1] * 8
    f = load_features(next((ds / "features").glob("*.npz")))
    c = crop_features(f, 5, 17)
    keep = (f.frame_index >= 5) & (f.frame_index < 17)
    assert c.n_frames == 12 and np.array_equal(c.frame_index, f.frame_index[keep] - 5)
    assert np.array_equal(c.descriptors, f.descriptors[keep])


def test_context_sum_of_a_run_shorter_than_the_window():
    import scipy.sparse as sp

    from vidstyle.recognition.histograms import context_sum

    for n in (1, 2, 3):
        counts = sp.csr_matrix(np.arange(1, 3 * n + 1, dtype=np.float32).reshape(n, 3))
        brute = np.array([counts.toarray()[max(0, i - 2):i + 3].sum(0) for i in range(n)])
        np.testing.assert_array_equal(context_sum(counts, 2).toarray(), brute)
