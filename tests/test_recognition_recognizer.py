"""The whole recognizer on synthetic feature files: accuracy on unseen performers, ONNX equality,
model files, input errors."""

from __future__ import annotations

import numpy as np
import pytest

from tests.conftest import SEED
from vidstyle.errors import InputError
from vidstyle.formats.dataset import read_dataset as load_dataset
from vidstyle.formats.labels import read_labels as load_labels
from vidstyle.recognition import ActionRecognizer, Vocabulary, load_features
from vidstyle.evaluation.recognition import evaluate_recognition, score_videos, video_label
from vidstyle.recognition.io import VideoFeatures
from vidstyle.recognition.onnx_export import OnnxRecognizer, export_onnx
from vidstyle.recognition.recognizer import load_model, save_model
from vidstyle.recognition.splits import make_split
from vidstyle.recognition.synthetic import make_dataset


@pytest.fixture(scope="module")
def data(tmp_path_factory):
    root = tmp_path_factory.mktemp("syn")
    make_dataset(root, n_performers=5, views=("front", "left"), seed=SEED, dim=32, reps=(2, 3), n_actions=6)
    ds = load_dataset(root)
    split = make_split(ds, "unseen-performer", seed=SEED)
    f = lambda ids: [root / "features" / f"{i}.npz" for i in ids]  # noqa: E731
    lab = lambda ids: [load_labels(root / "labels" / f"{i}.json").labels for i in ids]  # noqa: E731
    desc = np.concatenate([load_features(p).descriptors for p in f(split.vocab)])
    voc = Vocabulary(n_words=120, random_state=SEED).fit(desc)
    rec = ActionRecognizer(vocabulary=voc, n_components=48, random_state=SEED).fit(
        f(split.train), lab(split.train), classes=ds.classes
    )
    return {"root": root, "ds": ds, "split": split, "voc": voc, "rec": rec,
            "test": f(split.test), "test_labels": lab(split.test)}


def test_unseen_performers_accuracy(data):
    rec = data["rec"]
    idx = {c: i for i, c in enumerate(rec.classes_)}
    raw = sm = n = 0
    for p, lab in zip(data["test"], data["test_labels"]):
        out = rec.predict_video(p)
        y = np.array([idx[c] for c in lab])
        raw += (out["raw"] == y).sum()
        sm += (out["smoothed"] == y).sum()
        n += len(y)
        assert out["scores"].shape == (len(y), len(rec.classes_))
        assert np.all((out["confidence"] > 0) & (out["confidence"] <= 1))
    # the synthetic classes are separable from a frame context; the thesis pipeline must find that
    assert raw / n > 0.85 and sm / n > 0.85


def test_onnx_gives_the_same_labels(data, tmp_path):
    rec = data["rec"]
    export_onnx(rec, tmp_path / "m.onnx")
    onx = OnnxRecognizer(tmp_path / "m.onnx")
    assert list(onx.classes_) == list(rec.classes_)
    for p in data["test"]:
        H = rec.histograms(p)
        a, b = rec.predict_histograms(H), onx.predict_histograms(H)
        assert np.array_equal(a["raw"], b["raw"])
        assert np.array_equal(a["smoothed"], b["smoothed"])
        assert np.allclose(a["confidence"], b["confidence"], atol=1e-9)


def test_baseline_cannot_export(data, tmp_path):
    base = ActionRecognizer(vocabulary=data["voc"], classifier="svc-ovr", n_components=16).fit(
        data["test"][:4], data["test_labels"][:4]
    )
    with pytest.raises(InputError, match="ova-ovo"):
        export_onnx(base, tmp_path / "b.onnx")


def test_model_file_roundtrip(data, tmp_path):
    rec = data["rec"]
    header = save_model(tmp_path / "m.joblib", rec, training_files=[{"features": "x"}])
    rec2, h2 = load_model(tmp_path / "m.joblib")
    assert h2 == header and h2["seed"] == SEED and h2["classes"] == list(rec.classes_)
    assert h2["params"]["context"] == 2 and h2["vocabulary"]["n_words"] == 120
    p = data["test"][0]
    assert np.array_equal(rec.predict(p), rec2.predict(p))
    (tmp_path / "bad.joblib").write_bytes(b"no")
    with pytest.raises(InputError, match="bad.joblib"):
        load_model(tmp_path / "bad.joblib")


def test_frames_without_points_and_empty_video(data):
    rec = data["rec"]
    v = VideoFeatures(np.zeros((0, 32), np.float32), np.zeros(0, np.int64), 5)
    out = rec.predict_video(v)
    assert out["raw"].shape == (5,)
    assert rec.predict_video(VideoFeatures(np.zeros((0, 32), np.float32), np.zeros(0), 0))["raw"].shape == (0,)


def test_input_errors(data, tmp_path):
    voc = data["voc"]
    p = data["test"][0]
    good = load_labels(data["root"] / "labels" / f"{data['split'].test[0]}.json").labels
    with pytest.raises(InputError, match="labels for n_frames"):
        ActionRecognizer(vocabulary=voc).fit([p], [good[:-1]])
    with pytest.raises(InputError, match="not in"):
        ActionRecognizer(vocabulary=voc).fit([p], [good], classes=["Jab"])
    with pytest.raises(InputError, match="fitted vocabulary"):
        ActionRecognizer().fit([p], [good])
    wrong = VideoFeatures(np.ones((3, 16), np.float32), np.array([0, 1, 1]), 4, path="w.npz")
    with pytest.raises(InputError, match="w.npz: descriptors have dimension 16"):
        data["rec"].predict_video(wrong)
    np.savez(tmp_path / "bad.npz", descriptors=np.ones((3, 32)), frame_index=np.array([0, 1, 9]), n_frames=5)
    with pytest.raises(InputError, match="bad.npz: frame_index: frame indices outside"):
        load_features(tmp_path / "bad.npz")
    np.savez(tmp_path / "bad2.npz", descriptors=np.ones((3, 32)), n_frames=5)
    with pytest.raises(InputError, match="bad2.npz: frame_index: missing"):
        load_features(tmp_path / "bad2.npz")
    with pytest.raises(InputError, match="not found"):
        load_features(tmp_path / "none.npz")


def test_video_label_and_scores():
    assert video_label(["Guard", "Jab", "Jab", "Hook", "Step", "Step", "Step"]) == "Jab"
    assert video_label(["Guard", "Step"]) is None
    classes = ["Jab", "Hook", "Guard"]
    out = {"raw": np.array([0, 1, 2, 2]), "smoothed": np.array([0, 0, 2, 2])}
    m = score_videos(classes, [["Jab", "Jab", "Guard", "Hook"]], [out], ["v"], ["Jab"])
    assert m["frame_accuracy"] == {"raw": 0.5, "smoothed": 0.75}
    assert m["video_accuracy"] == 1.0 and m["video_accuracy_raw"] == 0.0  # raw: Jab 1 vs Hook 1 -> "Hook" < "Jab"
    assert m["confusion"]["smoothed"][0] == [1.0, 0.0, 0.0]
    assert m["confusion"]["raw"][0] == [0.5, 0.5, 0.0]


def test_evaluation_run_and_ablation(data):
    m = evaluate_recognition(data["ds"], data["root"] / "features", seed=SEED, n_words=80,
                             recognizer_params={"n_components": 32}, baseline=True)
    assert m["frame_accuracy"]["smoothed"] > 0.85 and m["video_accuracy"] == 1.0
    assert m["seed"] == SEED and "baseline" in m
    assert set(m["split"]["test"]) == set(data["split"].test)
    cm = np.array(m["confusion"]["smoothed"])
    assert np.allclose(cm.sum(1)[cm.sum(1) > 0], 1, atol=1e-3)  # rounded to 4 decimals
    m2 = evaluate_recognition(data["ds"], data["root"] / "features", seed=SEED, n_words=80, ablation="no-grouping",
                              recognizer_params={"n_components": 32}, baseline=False)
    assert m2["model"]["n_groups"] == 80 and m2["params"]["recognizer"]["grouping"] is False


@pytest.fixture(scope="module")
def multiscale(data):
    """The recognizer with a coarse context block and the explicit-duration smoother."""
    split, root = data["split"], data["root"]
    f = [root / "features" / f"{i}.npz" for i in split.train]
    lab = [load_labels(root / "labels" / f"{i}.json").labels for i in split.train]
    return ActionRecognizer(vocabulary=data["voc"], n_components=48, coarse_context=6, smoothing="duration",
                            random_state=SEED).fit(f, lab, classes=data["ds"].classes)


def test_coarse_context_histograms_are_window_counts(data, multiscale):
    """Block 2 of a frame's histogram counts the words of frames n-6..n+6, computed here by hand."""
    v = load_features(data["test"][0])
    words = data["voc"].transform(v.descriptors)
    H = multiscale.histograms(v).toarray()
    W = data["voc"].n_words_
    assert H.shape == (v.n_frames, 2 * W)
    for n in (0, 3, v.n_frames // 2, v.n_frames - 1):
        for block, c in ((0, 2), (1, 6)):
            m = (v.frame_index >= n - c) & (v.frame_index <= n + c)
            np.testing.assert_array_equal(H[n, block * W:(block + 1) * W], np.bincount(words[m], minlength=W))


def test_multiscale_duration_model_accuracy_and_onnx(data, multiscale, tmp_path):
    rec = multiscale
    assert rec.durations_.n_classes == len(rec.classes_)
    idx = {c: i for i, c in enumerate(rec.classes_)}
    sm = n = 0
    export_onnx(rec, tmp_path / "ms.onnx")
    onx = OnnxRecognizer(tmp_path / "ms.onnx")
    for p, lab in zip(data["test"], data["test_labels"]):
        H = rec.histograms(p)
        a, b = rec.predict_histograms(H), onx.predict_histograms(H)
        assert np.array_equal(a["raw"], b["raw"]) and np.array_equal(a["smoothed"], b["smoothed"])
        sm += (a["smoothed"] == np.array([idx[c] for c in lab])).sum()
        n += len(lab)
    assert sm / n > 0.85
