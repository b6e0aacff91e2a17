"""The CVAT / Label Studio / VIA / native importers read untrusted uploads: fuzzed (seeded by the
conftest's hypothesis profile), nothing but ``FormatError`` / ``InputError`` may escape, and what does
import is checked marks (frames inside the video, known statuses).

Mutations start from a valid export of each format: structural ones (a node of the JSON tree / XML element
replaced, deleted, retyped; attributes and text rewritten) and byte ones (truncation, flipped and inserted
bytes).
"""

from __future__ import annotations

import copy
import json
import xml.etree.ElementTree as ET

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from vidstyle.annotate import exchange
from vidstyle.errors import InputError
from vidstyle.formats.annotations import STATUSES, CandidateDecision, ActionSpan, Transition, VideoAnnotations

CLASSES = ["Jab", "Hook", "Kick"]
N = 40


def _target() -> exchange.Target:
    ts = np.arange(N) / 25.0 + np.r_[0, np.linspace(0.0, 0.012, N - 1)]  # slightly variable rate
    v = VideoAnnotations("clip.mp4", "ab" * 32, N, 25.0)
    v.segments = [ActionSpan(0, 10, "Jab"), ActionSpan(12, 30, "Hook"), ActionSpan(33, N, "Kick")]
    v.transitions = [Transition(0, "Jab", "Hook", "accepted", [CandidateDecision("lib/a.bvh", 1.25, "accepted")]),
                     Transition(11, "Jab", "Hook", "discarded"), Transition(N - 1, "Hook", "Kick", "accepted")]
    return exchange.Target(v, ts, N / 25.0, 64, 48)


TARGET = _target()
VALID = {fmt: exchange.export(fmt, CLASSES, TARGET) for fmt in exchange.FORMATS}
JSON_FORMATS = [f for f in exchange.FORMATS if f != "cvat"]

SCALARS = (st.none() | st.booleans() | st.integers(-3, N + 3) | st.integers(-2**70, 2**70)
           | st.floats(allow_nan=True, allow_infinity=True) | st.text(max_size=6)
           | st.sampled_from(["", "transition", "Jab", "accepted", "1", "-1", "1e400", "[]", "{}", "[{}]"]))
JSON_VALUES = st.recursive(SCALARS, lambda c: st.lists(c, max_size=3) | st.dictionaries(st.text(max_size=4), c, max_size=3),
                           max_leaves=6)


def _check(fmt: str, data: bytes) -> None:
    try:
        marks = exchange.import_(fmt, data, list(CLASSES), TARGET, name="upload")
    except InputError as e:  # FormatError is an InputError
        assert str(e)
        return
    # whatever imports is valid marks of this video
    for s in marks.segments:
        assert 0 <= s.start < s.end <= N and s.action in marks.classes
    for t in marks.transitions:
        assert 0 <= t.frame < N and t.status in STATUSES


def _nodes(obj, path=()):
    yield path
    if isinstance(obj, dict):
        for k, v in obj.items():
            yield from _nodes(v, path + (k,))
    elif isinstance(obj, list):
        for i, v in enumerate(obj):
            yield from _nodes(v, path + (i,))


_json_op = st.tuples(st.sampled_from(["replace", "delete", "listify", "empty"]), st.integers(0, 10**6), JSON_VALUES)


def _mutate_json(doc, ops):
    doc = copy.deepcopy(doc)
    for kind, pick, value in ops:
        paths = [p for p in _nodes(doc) if p]
        if not paths:
            return value
        path = paths[pick % len(paths)]
        parent = doc
        for k in path[:-1]:
            parent = parent[k]
        key = path[-1]
        if kind == "replace":
            parent[key] = value
        elif kind == "delete":
            del parent[key]
        elif kind == "listify":
            parent[key] = [parent[key]]
        else:
            parent[key] = type(parent[key])() if isinstance(parent[key], (dict, list, str)) else None
    return doc


@pytest.mark.parametrize("fmt", JSON_FORMATS)
@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(ops=st.lists(_json_op, min_size=1, max_size=3))
def test_json_structure_fuzz_raises_only_format_errors(fmt, ops):
    doc = _mutate_json(json.loads(VALID[fmt]), ops)
    _check(fmt, json.dumps(doc).encode())


_xml_op = st.tuples(st.sampled_from(["attr", "text", "delete", "duplicate", "retag"]), st.integers(0, 10**6),
                    st.sampled_from(["frame", "outside", "label", "keyframe", "name"]),
                    st.text(max_size=6) | st.integers(-5, N + 5).map(str) | st.sampled_from(["1", "0", "transition", "1e9", "-0"]))


@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(ops=st.lists(_xml_op, min_size=1, max_size=4))
def test_cvat_structure_fuzz_raises_only_format_errors(ops):
    root = ET.fromstring(VALID["cvat"])
    for kind, pick, attr, value in ops:
        elems = list(root.iter())
        parents = {c: p for p in elems for c in p}
        el = elems[pick % len(elems)]
        value = "".join(ch for ch in value if ch.isprintable())
        if kind == "attr":
            el.set(attr, value)
        elif kind == "text":
            el.text = value
        elif kind == "retag" and value.isidentifier():
            el.tag = value
        elif el in parents:
            if kind == "delete":
                parents[el].remove(el)
            else:
                parents[el].append(copy.deepcopy(el))
    _check("cvat", ET.tostring(root))


_bytes_op = st.tuples(st.sampled_from(["truncate", "flip", "insert"]), st.integers(0, 10**6), st.binary(min_size=1, max_size=4))


@pytest.mark.parametrize("fmt", exchange.FORMATS)
@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(ops=st.lists(_bytes_op, min_size=1, max_size=4))
def test_byte_fuzz_raises_only_format_errors(fmt, ops):
    data = bytearray(VALID[fmt])
    for kind, pick, blob in ops:
        i = pick % (len(data) + 1)
        if kind == "truncate":
            del data[i:]
        elif kind == "flip" and i < len(data):
            data[i] ^= blob[0] or 0xFF
        else:
            data[i:i] = blob
    _check(fmt, bytes(data))


@pytest.mark.parametrize("fmt", exchange.FORMATS)
def test_valid_exports_import(fmt):
    """The fuzz starts from files that import (else every mutation would be a trivial error)."""
    got = exchange.import_(fmt, VALID[fmt], list(CLASSES), TARGET)
    assert sorted(got.segments, key=lambda s: s.start) == TARGET.video.segments
    assert [t.frame for t in sorted(got.transitions, key=lambda t: t.frame)] == [0, 11, N - 1]
