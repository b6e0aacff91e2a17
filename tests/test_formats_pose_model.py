"""The pose model file's owner (vidstyle.formats.pose_model): round trip, files written before the owner
existed still load, and a seeded fuzz of the reader (any header or bytes: a model or a one-line FormatError
naming the file, never another exception)."""

from __future__ import annotations

import json

import joblib
import pytest
from hypothesis import HealthCheck, given, seed, settings
from hypothesis import strategies as st

from vidstyle.formats import FormatError
from vidstyle.formats.pose_model import KIND, read_pose_model, write_pose_model
from vidstyle.pose.estimator import PoseModel, load_model, model_header, save_model

HEADER = {"params": {"n_orient": 8}, "seed": 3, "n_train_frames": 0, "parts": ["torso", "head"]}


def test_round_trip_and_header(tmp_path):
    m = PoseModel(n_orient=8, seed=3)
    save_model(tmp_path / "m.joblib", m, {"training": {"demo_performers": 2}})
    got, header = load_model(tmp_path / "m.joblib")
    assert isinstance(got, PoseModel) and got.get_params() == m.get_params()
    assert header["kind"] == KIND == "vidstyle.pose-model" and header["schema_version"] == 1
    assert header["params"] == m.get_params() and header["training"] == {"demo_performers": 2}
    assert header["parts"] == model_header(m)["parts"] and len(header["parts"]) == 10


def test_a_file_written_before_the_owner_still_loads(tmp_path):
    """The pre-owner writer: joblib of {"header": json.dumps(header, default=str), "model": model}, compress 3."""
    m = PoseModel(n_orient=8, seed=3)
    header = {"kind": "vidstyle.pose-model", "schema_version": 1, "params": m.get_params(), "seed": 3,
              "n_train_frames": 0, "parts": model_header(m)["parts"], "training": {"cmu_dir": None}}
    joblib.dump({"header": json.dumps(header, default=str), "model": m}, tmp_path / "old.joblib", compress=3)
    got, h = load_model(tmp_path / "old.joblib")
    assert got.get_params() == m.get_params() and h == header


def test_wrong_kind_class_and_fields_are_named(tmp_path):
    p = tmp_path / "m.joblib"
    write_pose_model(p, {"not": "a model"}, HEADER)
    with pytest.raises(FormatError, match="m.joblib.*PoseModel"):
        read_pose_model(p, PoseModel)
    joblib.dump({"header": json.dumps({**HEADER, "kind": "vidstyle.recognizer", "schema_version": 1}),
                 "model": PoseModel()}, p)
    with pytest.raises(FormatError, match="kind"):
        read_pose_model(p, PoseModel)
    joblib.dump({"header": json.dumps({**HEADER, "kind": KIND, "schema_version": 1, "n_train_frames": -1}),
                 "model": PoseModel()}, p)
    with pytest.raises(FormatError, match="n_train_frames"):
        read_pose_model(p, PoseModel)
    with pytest.raises(FormatError, match="n_train_frames"):  # the writer refuses what the reader would
        write_pose_model(tmp_path / "x.joblib", PoseModel(), {**HEADER, "n_train_frames": -1})
    assert not (tmp_path / "x.joblib").exists()
    with pytest.raises(FormatError, match="not found"):
        read_pose_model(tmp_path / "absent.joblib", PoseModel)


json_values = st.recursive(st.none() | st.booleans() | st.integers(-5, 5) | st.floats(allow_nan=False) | st.text(max_size=4),
                           lambda c: st.lists(c, max_size=3) | st.dictionaries(st.text(max_size=4), c, max_size=3),
                           max_leaves=6)


@seed(26)
@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(edits=st.dictionaries(st.sampled_from(["kind", "schema_version", "params", "seed", "n_train_frames", "parts",
                                              "training"]), json_values, max_size=3),
       drop=st.sets(st.sampled_from(["kind", "schema_version", "params", "seed", "n_train_frames", "parts"]), max_size=2),
       header_text=st.one_of(st.none(), st.text(max_size=20)), raw=st.one_of(st.none(), st.binary(max_size=40)))
def test_fuzzed_pose_model_files_load_or_fail_in_one_line(tmp_path, edits, drop, header_text, raw):
    p = tmp_path / "fuzz.joblib"
    if raw is not None:
        p.write_bytes(raw)
    else:
        doc = {"kind": KIND, "schema_version": 1, **HEADER, **edits}
        for k in drop:
            doc.pop(k, None)
        joblib.dump({"header": json.dumps(doc) if header_text is None else header_text, "model": PoseModel()}, p)
    try:
        model, header = read_pose_model(p, PoseModel)
    except FormatError as e:
        assert "fuzz.joblib" in str(e) and "\n" not in str(e)
        return
    # accepted: the checked fields are what the owner promises
    assert isinstance(model, PoseModel) and header["kind"] == KIND and header["schema_version"] == 1
    assert isinstance(header["params"], dict)
    assert isinstance(header.get("n_train_frames", 0), int) and header.get("n_train_frames", 0) >= 0
    assert isinstance(header.get("parts", []), list)
