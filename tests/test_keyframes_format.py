"""The keyframes file (``vidstyle.formats.keyframes``): round trip, the errors it names, and a fuzzed
reader (mutated bytes and mutated structure: nothing but FormatError escapes, and whatever is accepted
writes back and reads again to the same keyframes)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from vidstyle.formats import FormatError
from vidstyle.formats.keyframes import (
    KIND,
    Keyframe,
    Keyframes,
    parse_keyframes,
    read_keyframes,
    write_keyframes,
)

DOC = {"keyframes": [{"clip": "a.bvh", "frame": 3, "time": 0.0}, {"clip": "sub/b.bvh", "frame": 40, "time": 1.5}]}


def test_round_trip_and_header(tmp_path):
    k = parse_keyframes(DOC, tmp_path / "k.json")
    assert k.keyframes == [Keyframe("a.bvh", 3, 0.0), Keyframe("sub/b.bvh", 40, 1.5)]
    write_keyframes(tmp_path / "out.json", k)
    doc = json.loads((tmp_path / "out.json").read_text())
    assert doc["kind"] == KIND and doc["schema_version"] == 1
    assert read_keyframes(tmp_path / "out.json").keyframes == k.keyframes


def test_clip_paths_resolve_from_the_file_folder(tmp_path):
    (tmp_path / "d").mkdir()
    p = tmp_path / "d" / "k.json"
    p.write_text(json.dumps(DOC))
    k = read_keyframes(p)
    assert k.clip_path(k.keyframes[1]) == tmp_path / "d" / "sub" / "b.bvh"
    assert Keyframes(k.keyframes).clip_path(k.keyframes[0]) == Path("a.bvh")


@pytest.mark.parametrize("doc, field", [
    ({"keyframes": DOC["keyframes"][:1]}, "keyframes"),
    ({"keyframes": [DOC["keyframes"][0], {**DOC["keyframes"][1], "time": 0.0}]}, "keyframes[1].time"),
    ({"keyframes": [DOC["keyframes"][0], {**DOC["keyframes"][1], "frame": -1}]}, "keyframes[1].frame"),
    ({"keyframes": [DOC["keyframes"][0], {**DOC["keyframes"][1], "frame": 1.5}]}, "keyframes[1].frame"),
    ({"keyframes": [DOC["keyframes"][0], {**DOC["keyframes"][1], "clip": ""}]}, "keyframes[1].clip"),
    ({"keyframes": [DOC["keyframes"][0], {**DOC["keyframes"][1], "tiem": 2}]}, "keyframes[1]"),
    ({"keyframes": [DOC["keyframes"][0], {"clip": "b.bvh", "frame": 1}]}, "keyframes[1].time"),
    ({"keyframes": "a.bvh"}, "keyframes"),
    ({**DOC, "kind": "vidstyle.labels", "schema_version": 1}, "kind"),
    ([], None),
])
def test_errors_name_the_file_and_field(doc, field):
    with pytest.raises(FormatError) as e:
        parse_keyframes(doc, "k.json")
    assert e.value.field == field and str(e.value).startswith("k.json: ")


def test_writer_refuses_what_the_reader_would(tmp_path):
    with pytest.raises(ValueError, match="keyframes"):
        write_keyframes(tmp_path / "k.json", {"keyframes": []})
    assert not (tmp_path / "k.json").exists()


_json = st.recursive(st.none() | st.booleans() | st.integers(-5, 10**6) | st.floats(allow_nan=True) | st.text(max_size=5),
                     lambda c: st.lists(c, max_size=3) | st.dictionaries(st.sampled_from(["clip", "frame", "time", "x"]), c, max_size=4),
                     max_leaves=12)


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(data=st.data())
def test_fuzzed_structure(data, tmp_path):
    doc = json.loads(json.dumps(DOC))
    kind = data.draw(st.sampled_from(["drop", "retype", "item", "extra"]))
    item = doc["keyframes"][data.draw(st.integers(0, 1))]
    if kind == "drop":
        item.pop(data.draw(st.sampled_from(sorted(item))))
    elif kind == "retype":
        item[data.draw(st.sampled_from(sorted(item)))] = data.draw(_json)
    elif kind == "item":
        doc["keyframes"].append(data.draw(_json))
    else:
        doc[data.draw(st.sampled_from(["keyframes", "kind", "schema_version"]))] = data.draw(_json)
    _check(doc, tmp_path)


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(cut=st.integers(0, 200), junk=st.binary(max_size=8))
def test_fuzzed_bytes(cut, junk, tmp_path):
    raw = json.dumps(DOC).encode()
    p = tmp_path / "k.json"
    p.write_bytes(raw[:cut] + junk + raw[cut + len(junk):])
    try:
        k = read_keyframes(p)
    except FormatError as e:
        assert str(p) in str(e) and "\n" not in str(e)
        return
    write_keyframes(tmp_path / "again.json", k)
    assert read_keyframes(tmp_path / "again.json").keyframes == k.keyframes


def _check(doc, tmp_path):
    try:
        k = parse_keyframes(doc, "k.json")
    except FormatError as e:
        assert str(e).startswith("k.json") and "\n" not in str(e)
        return
    write_keyframes(tmp_path / "again.json", k)
    assert read_keyframes(tmp_path / "again.json").keyframes == k.keyframes
