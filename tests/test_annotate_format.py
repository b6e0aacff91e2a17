"""The annotations file: round trip, validation naming file and field, fuzzing, the JSON Schema, and the
performer choice (schema version 2; version 1 files still load)."""

from __future__ import annotations

import copy
import json
from pathlib import Path

import jsonschema
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from vidstyle.formats import FormatError
from vidstyle.formats.annotations import (
    JSON_SCHEMA,
    ActionSpan,
    Annotations,
    CandidateDecision,
    PerformerChoice,
    Transition,
    VideoAnnotations,
    check_performer,
    file_sha256,
    frame_labels,
    from_document,
    read_annotations,
    resolve_video_path,
    stored_path,
    to_document,
    write_annotations,
)

ROOT = Path(__file__).resolve().parents[1]
SHA = "ab" * 32


def sample() -> Annotations:
    return Annotations(
        classes=["jab", "cross", "kick"],
        revision=4,
        videos=[VideoAnnotations(
            "clips/a.mp4", SHA, 100, 30.0,
            transitions=[Transition(40, "jab", "kick", "accepted",
                                    [CandidateDecision("lib/x.bvh", 1.5, "accepted"), CandidateDecision("lib/y.bvh", 0.0, "discarded")]),
                         Transition(70, "kick", "cross", "discarded")],
            segments=[ActionSpan(0, 38, "jab"), ActionSpan(42, 68, "kick"), ActionSpan(72, 100, "cross")],
            performer=PerformerChoice(55, 212.0, 97.5))],
    )


@st.composite
def annotations(draw):
    classes = draw(st.lists(st.text(min_size=1, max_size=8), min_size=1, max_size=5, unique=True))
    videos = []
    shas = draw(st.lists(st.from_regex(r"[0-9a-f]{64}", fullmatch=True), max_size=3, unique=True))
    for sha in shas:
        frames = draw(st.integers(1, 500))
        marks = draw(st.lists(st.integers(0, frames - 1), unique=True, max_size=6))
        trans = [Transition(m, draw(st.sampled_from(classes)), draw(st.sampled_from(classes)),
                            draw(st.sampled_from(["accepted", "discarded"])),
                            [CandidateDecision(draw(st.text(min_size=1, max_size=10)),
                                       draw(st.floats(0, 1e4, allow_nan=False)),
                                       draw(st.sampled_from(["accepted", "discarded"])))
                             for _ in range(draw(st.integers(0, 3)))])
                 for m in sorted(marks)]
        cuts = sorted(draw(st.lists(st.integers(0, frames), unique=True, max_size=8)))
        segs = [ActionSpan(a, b, draw(st.sampled_from(classes))) for a, b in zip(cuts[::2], cuts[1::2]) if b > a]
        performer = draw(st.none() | st.builds(PerformerChoice, st.integers(0, frames - 1),
                                               st.floats(0, 1e4, allow_nan=False), st.floats(0, 1e4, allow_nan=False)))
        videos.append(VideoAnnotations(draw(st.text(min_size=1, max_size=20)), sha, frames,
                                       draw(st.floats(0, 240, allow_nan=False)), trans, segs, performer))
    return Annotations(classes, videos, draw(st.integers(0, 10**6)))


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(ann=annotations())
def test_round_trip_and_schema(tmp_path, ann):
    p = tmp_path / "a.json"
    write_annotations(p, ann)
    doc = json.loads(p.read_text())
    jsonschema.validate(doc, JSON_SCHEMA)  # every file written validates against the published schema
    assert read_annotations(p) == ann


def _mutations(doc):
    """Every way to break one field: drop it, or replace it by values of the wrong type or range."""
    bad_values = [None, "x", -1, 1.5, [], {}, True, "", 10**9]

    def walk(node, path):
        if isinstance(node, dict):
            for k in list(node):
                yield path + [k], "drop"
                for v in bad_values:
                    yield path + [k], v
                yield from walk(node[k], path + [k])
        elif isinstance(node, list):
            for i, x in enumerate(node):
                yield from walk(x, path + [i])

    yield from walk(doc, [])


def _apply(doc, path, value):
    d = copy.deepcopy(doc)
    node = d
    for k in path[:-1]:
        node = node[k]
    if value == "drop":
        del node[path[-1]]
    else:
        node[path[-1]] = value
    return d


def test_every_broken_field_is_a_format_error_naming_file(tmp_path):
    doc = to_document(sample())
    n_bad = 0
    for path, value in _mutations(doc):
        d = _apply(doc, path, value)
        p = tmp_path / "bad.json"
        p.write_text(json.dumps(d))
        try:
            got = read_annotations(p)
        except FormatError as e:
            assert str(p) in str(e)
            n_bad += 1
            # the JSON Schema agrees that a structurally broken document is invalid, or our rules caught
            # something it cannot express (ranges against frames, classes, overlaps)
            continue
        # what the reader accepts, the published schema accepts too (and it round-trips)
        jsonschema.validate(d, JSON_SCHEMA)
        assert from_document(to_document(got)) == got
    assert n_bad > 100


@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(data=st.recursive(st.none() | st.booleans() | st.integers() | st.floats(allow_nan=False) | st.text(max_size=5),
                         lambda c: st.lists(c, max_size=4) | st.dictionaries(st.text(max_size=8), c, max_size=5),
                         max_leaves=30))
def test_fuzz_any_json_is_read_or_format_error(data):
    docs = [data]
    for version in (1, 2):
        docs.append({"kind": "vidstyle.annotations", "schema_version": version, "revision": 0, "classes": ["a"],
                     "videos": data})
        # any value as the performer of a valid video
        docs.append({"kind": "vidstyle.annotations", "schema_version": version, "revision": 0, "classes": ["a"],
                     "videos": [{"path": "v.mp4", "sha256": SHA, "frames": 10, "fps": 25.0, "transitions": [],
                                 "segments": [], "performer": data}]})
    for d in docs:
        try:
            got = from_document(d, "fuzz.json")
        except FormatError as e:
            assert "fuzz.json" in str(e) and "\n" not in str(e)
            continue
        p = got.videos[0].performer if got.videos else None
        assert p is None or (0 <= p.frame < got.videos[0].frames and np.isfinite([p.x, p.y]).all()
                             and min(p.x, p.y) >= 0)


def test_specific_errors_name_the_field(tmp_path):
    doc = to_document(sample())
    cases = [
        (["videos", 0, "segments", 1, "start"], 30, "videos[0].segments[1]", "overlaps"),
        (["videos", 0, "segments", 0, "end"], 101, "videos[0].segments[0].end", "at most 100"),
        (["videos", 0, "transitions", 0, "frame"], 100, "videos[0].transitions[0].frame", "at most 99"),
        (["videos", 0, "transitions", 1, "frame"], 40, "videos[0].transitions[1].frame", "twice"),
        (["videos", 0, "transitions", 0, "to_action"], "hook", "to_action", "not in classes"),
        (["videos", 0, "sha256"], "XYZ", "videos[0].sha256", "hex"),
        (["videos", 0, "transitions", 0, "candidates", 0, "status"], "maybe", "candidates[0].status", "not one of"),
        (["revision"], -1, "revision", "at least 0"),
        (["videos", 0, "performer", "frame"], 100, "videos[0].performer.frame", "at most 99"),
        (["videos", 0, "performer", "frame"], 2.5, "videos[0].performer.frame", "expected an integer"),
        (["videos", 0, "performer", "x"], -0.5, "videos[0].performer.x", "at least 0"),
        (["videos", 0, "performer", "y"], "12", "videos[0].performer.y", "expected a number"),
        (["videos", 0, "performer", "y"], None, "videos[0].performer.y", "expected a number"),
        (["videos", 0, "performer", "z"], 1, "videos[0].performer", "unknown field"),
        (["videos", 0, "performer"], [55, 1, 2], "videos[0].performer", "expected an object"),
        (["videos", 0, "performer"], None, "videos[0].performer", "expected an object"),
        (["schema_version"], 1, "videos[0]", "unknown field(s) 'performer'"),  # version 1 had none
        (["schema_version"], 3, "schema_version", "not supported"),
    ]
    for path, value, field, problem in cases:
        p = tmp_path / "x.json"
        p.write_text(json.dumps(_apply(doc, path, value)))
        with pytest.raises(FormatError) as e:
            read_annotations(p)
        assert field in str(e.value) and problem in str(e.value), str(e.value)
    (tmp_path / "t.json").write_text("{not json")
    with pytest.raises(FormatError, match="not valid JSON"):
        read_annotations(tmp_path / "t.json")
    # non-finite pixels: not JSON on disk, and refused in a parsed document too
    (tmp_path / "n.json").write_text(json.dumps(doc).replace('"x": 212.0', '"x": NaN'))
    with pytest.raises(FormatError) as e:
        read_annotations(tmp_path / "n.json")
    assert str(tmp_path / "n.json") in str(e.value)
    for bad in (float("nan"), float("inf")):
        with pytest.raises(FormatError, match=r"videos\[0\]\.performer\.x: must be a finite number"):
            from_document(_apply(doc, ["videos", 0, "performer", "x"], bad), "a.json")


def test_performer_choice_versions_and_frame_size(tmp_path):
    """Version 1 files (written before the performer choice) load unchanged and are written back as version
    2; the choice round-trips exactly; its pixel is checked against the frame of the video it is used on."""
    v1 = to_document(sample())
    v1["schema_version"] = 1
    del v1["videos"][0]["performer"]
    p = tmp_path / "v1.json"
    p.write_text(json.dumps(v1))
    jsonschema.validate(v1, JSON_SCHEMA)
    old = read_annotations(p)
    assert old.videos[0].performer is None and old.videos[0].segments == sample().videos[0].segments
    write_annotations(p, old)
    doc = json.loads(p.read_text())
    assert doc["schema_version"] == 2 and "performer" not in doc["videos"][0]
    assert read_annotations(p) == old
    # the published schema refuses a performer in a version-1 file, as the reader does
    with pytest.raises(jsonschema.ValidationError):
        jsonschema.validate({**to_document(sample()), "schema_version": 1}, JSON_SCHEMA)
    write_annotations(p, sample())
    doc = json.loads(p.read_text())
    assert doc["videos"][0]["performer"] == {"frame": 55, "x": 212.0, "y": 97.5}
    v = read_annotations(p).videos[0]
    assert v.performer == PerformerChoice(55, 212.0, 97.5)
    # pixel centres at integers: a W x H frame holds x <= W - 0.5, y <= H - 0.5
    assert check_performer(v, 213, 98) == v.performer
    for w, h in ((212, 98), (213, 97)):
        with pytest.raises(FormatError, match=r"a\.json: performer: pixel \(212, 97\.5\) is outside"):
            check_performer(v, w, h, "a.json")
    v.performer = None
    assert check_performer(v, 1, 1) is None


def test_writer_refuses_invalid_object_and_leaves_file(tmp_path):
    p = tmp_path / "a.json"
    write_annotations(p, sample())
    before = p.read_bytes()
    bad = sample()
    bad.videos[0].segments.append(ActionSpan(10, 20, "jab"))  # overlaps 0..38
    with pytest.raises(FormatError, match="overlaps"):
        write_annotations(p, bad)
    assert p.read_bytes() == before
    assert sorted(x.name for x in tmp_path.iterdir()) == ["a.json"]


def test_schema_file_is_the_module_schema():
    on_disk = json.loads((ROOT / "annotations" / "schema.json").read_text())
    assert on_disk == JSON_SCHEMA
    jsonschema.Draft202012Validator.check_schema(on_disk)
    # the schema itself rejects the structural breaks
    doc = to_document(sample())
    with pytest.raises(jsonschema.ValidationError):
        jsonschema.validate(_apply(doc, ["videos", 0, "transitions", 0, "status"], "maybe"), on_disk)
    with pytest.raises(jsonschema.ValidationError):
        jsonschema.validate(_apply(doc, ["videos", 0, "frames"], "drop"), on_disk)


def test_every_annotations_file_in_repo_validates():
    for p in sorted((ROOT / "annotations").glob("*.json")):
        if p.name == "schema.json":
            continue
        jsonschema.validate(json.loads(p.read_text()), JSON_SCHEMA)
        read_annotations(p)


def test_frame_labels_and_paths(tmp_path):
    ann = sample()
    y = frame_labels(ann.videos[0], ann.classes)
    want = np.full(100, -1)
    want[0:38] = 0
    want[42:68] = 2
    want[72:100] = 1
    np.testing.assert_array_equal(y, want)
    vid = tmp_path / "clips" / "a.mp4"
    vid.parent.mkdir()
    vid.write_bytes(b"hello")
    a = tmp_path / "ann.json"
    assert stored_path(a, vid) == "clips/a.mp4"
    assert resolve_video_path(a, ann.videos[0]) == vid.resolve()
    import hashlib
    assert file_sha256(vid) == hashlib.sha256(b"hello").hexdigest()


def test_lookup_helpers(tmp_path):
    ann = sample()
    t = ann.videos[0].transitions[0]
    assert t.decision("lib/x.bvh", 1.5) == "accepted" and t.decision("lib/y.bvh", 0.0) == "discarded"
    assert t.decision("lib/x.bvh", 1.25) is None
    vid = tmp_path / "v.bin"
    vid.write_bytes(b"video bytes")
    ann.videos[0].sha256 = file_sha256(vid)
    assert ann.video_for(vid) is ann.videos[0]
    vid.write_bytes(b"other bytes")
    with pytest.raises(FormatError, match="no annotations of"):
        ann.video_for(vid, "a.json")
