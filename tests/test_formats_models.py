"""Recognition's model-file owners (formats/vocabulary.py, formats/recognizer_model.py): round trips, older
vocabulary files without a header still load, and damaged or foreign files are a FormatError naming the
file, never another exception or a hang (seeded hypothesis, replayable)."""

from __future__ import annotations

import io
import zipfile

import joblib
import numpy as np
import pytest
from hypothesis import HealthCheck, given, seed, settings
from hypothesis import strategies as st

from vidstyle.errors import FormatError
from vidstyle.formats.recognizer_model import read_recognizer_model, write_recognizer_model
from vidstyle.formats.vocabulary import read_vocabulary
from vidstyle.recognition import Vocabulary

FUZZ = settings(max_examples=60, deadline=None, derandomize=True,
                suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])


def _vocab(method: str = "hierarchical") -> Vocabulary:
    rng = np.random.default_rng(0)
    X = rng.normal(size=(400, 6)).astype(np.float32)
    return Vocabulary(n_words=12, method=method, branching=3, random_state=0).fit(X)


def _arrays(path) -> dict[str, np.ndarray]:
    with np.load(path, allow_pickle=False) as z:
        return {k: z[k] for k in z.files}


def test_vocabulary_round_trip_with_header(tmp_path):
    voc = _vocab()
    voc.save(tmp_path / "v.npz", training_files=["a.npz"], extra={"split": {"set": "A"}})
    z = _arrays(tmp_path / "v.npz")
    assert str(z["kind"]) == "vidstyle.vocabulary" and int(z["schema_version"]) == 1
    back = Vocabulary.load(tmp_path / "v.npz")
    X = np.random.default_rng(1).normal(size=(50, 6)).astype(np.float32)
    np.testing.assert_array_equal(back.transform(X), voc.transform(X))
    assert back.training_files_ == ["a.npz"] and back.extra_ == {"split": {"set": "A"}}
    assert back.get_params() == voc.get_params()


def test_vocabulary_written_before_the_header_still_loads(tmp_path):
    voc = _vocab()
    voc.save(tmp_path / "v.npz")
    old = {k: v for k, v in _arrays(tmp_path / "v.npz").items() if k not in ("kind", "schema_version")}
    np.savez_compressed(tmp_path / "old.npz", **old)
    rec = read_vocabulary(tmp_path / "old.npz")
    assert rec.schema_version == 1
    np.testing.assert_array_equal(Vocabulary.load(tmp_path / "old.npz").cluster_centers_, voc.cluster_centers_)


def test_a_looping_tree_is_refused(tmp_path):
    voc = _vocab()
    voc.save(tmp_path / "v.npz")
    z = _arrays(tmp_path / "v.npz")
    z["tree_child_start"] = np.zeros_like(z["tree_child_start"])  # root's children: itself -> endless descent
    np.savez_compressed(tmp_path / "loop.npz", **z)
    with pytest.raises(FormatError, match="tree_child_start"):
        read_vocabulary(tmp_path / "loop.npz")


def test_recognizer_model_round_trip_and_wrong_kind(tmp_path):
    header = write_recognizer_model(tmp_path / "m.joblib", {"a": 1}, {"params": {"C": 100.0}})
    assert header["kind"] == "vidstyle.recognizer" and header["schema_version"] == 1
    model, h = read_recognizer_model(tmp_path / "m.joblib", dict)
    assert model == {"a": 1} and h == header
    with pytest.raises(FormatError, match="expected a list"):
        read_recognizer_model(tmp_path / "m.joblib", list)
    joblib.dump({"header": '{"kind": "vidstyle.pose_model", "schema_version": 1}', "model": 1}, tmp_path / "p.joblib")
    with pytest.raises(FormatError, match="kind"):
        read_recognizer_model(tmp_path / "p.joblib")


@pytest.fixture(scope="module")
def vocab_bytes(tmp_path_factory) -> bytes:
    p = tmp_path_factory.mktemp("fuzz") / "v.npz"
    _vocab().save(p, training_files=["a.npz"])
    return p.read_bytes()


@seed(0)
@FUZZ
@given(data=st.data())
def test_damaged_vocabulary_bytes_are_format_errors(vocab_bytes, tmp_path, data):
    b = bytearray(vocab_bytes)
    for _ in range(data.draw(st.integers(1, 8))):
        i = data.draw(st.integers(0, len(b) - 1))
        b[i] = data.draw(st.integers(0, 255))
    cut = data.draw(st.integers(1, len(b)))
    p = tmp_path / "bad.npz"
    p.write_bytes(bytes(b[:cut]))
    try:
        rec = read_vocabulary(p)
    except FormatError as e:
        assert str(p) in str(e)
        return
    Vocabulary.from_record(rec, p).transform(np.zeros((3, rec.dim), np.float32))  # what loads, works


VALUES = st.one_of(
    st.integers(-3, 3).map(np.int64), st.floats(allow_nan=True).map(np.float64), st.text(max_size=5).map(np.array),
    st.lists(st.integers(-2, 40), min_size=0, max_size=8).map(lambda x: np.array(x, np.int64)),
    st.just(np.zeros((2, 2, 2))), st.just(np.array('{"n_words": "x"}')), st.just(np.array("[1, 2]")),
)


@seed(0)
@FUZZ
@given(data=st.data())
def test_wrong_vocabulary_fields_are_format_errors(vocab_bytes, tmp_path, data):
    z = _arrays(io.BytesIO(vocab_bytes))
    for _ in range(data.draw(st.integers(1, 3))):
        key = data.draw(st.sampled_from(sorted(z)))
        if data.draw(st.booleans()):
            z.pop(key)
        else:
            z[key] = data.draw(VALUES)
    p = tmp_path / "bad.npz"
    np.savez(p, **z)
    try:
        rec = read_vocabulary(p)
        voc = Vocabulary.from_record(rec, p)
    except FormatError as e:
        assert str(p) in str(e)
        return
    voc.transform(np.zeros((3, rec.dim), np.float32))


@pytest.fixture(scope="module")
def model_bytes(tmp_path_factory) -> bytes:
    p = tmp_path_factory.mktemp("fuzz") / "m.joblib"
    write_recognizer_model(p, {"a": np.arange(50)}, {"params": {}})
    return p.read_bytes()


@seed(0)
@FUZZ
@given(data=st.data())
def test_truncated_recognizer_models_are_format_errors(model_bytes, tmp_path, data):
    # truncations of a real file (not arbitrary bytes: unpickling untrusted bytes is unsafe by design)
    p = tmp_path / "m.joblib"
    p.write_bytes(model_bytes[: data.draw(st.integers(0, len(model_bytes) - 1))])
    try:
        model, header = read_recognizer_model(p, dict)
    except FormatError as e:
        assert str(p) in str(e)
        return
    # only the stream's trailing checksum was cut: what loads is the whole model
    np.testing.assert_array_equal(model["a"], np.arange(50))
    assert header["kind"] == "vidstyle.recognizer"


def test_a_zip_that_is_not_a_vocabulary(tmp_path):
    p = tmp_path / "x.npz"
    with zipfile.ZipFile(p, "w") as zf:
        zf.writestr("other.txt", "hello")
    with pytest.raises(FormatError, match="centres"):
        read_vocabulary(p)
