"""Strict imports (issue 33, item 6): a frame number or a time that is not exactly what the format says is
refused with the field, never coerced. Label Studio frames must be JSON integers (a float, a string, a
boolean, ``Infinity``, ``1e400`` is refused; no OverflowError); VIA times must be finite seconds inside the
video and segments must end after they start (no clamping); CVAT XML is parsed with no DTD and no entity,
whatever its encoding (a UTF-16 internal entity once injected a class past a byte search).

The property tests (hypothesis, the conftest's "ci" profile) set one frame / time field of a valid export
to any JSON scalar or XML text and check the importer accepts exactly the values the format allows.
"""

from __future__ import annotations

import copy
import json
import math
import re
import xml.etree.ElementTree as ET

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from vidstyle.annotate import exchange
from vidstyle.formats import FormatError
from tests.test_exchange_fuzz import CLASSES, N, TARGET, VALID

DURATION = TARGET.duration


def _import(fmt: str, data: bytes):
    return exchange.import_(fmt, data, list(CLASSES), TARGET, name="upload.json")


def _ls_with(value, key: str = "start", k: int = 0) -> bytes:
    doc = json.loads(VALID["labelstudio"])
    segs = [r for r in doc[0]["annotations"][0]["result"] if r["from_name"] == "actions"]
    segs[k]["value"]["ranges"][0][key] = value
    return json.dumps(doc).encode()


@pytest.mark.parametrize("value, shown", [(1.0, "1.0"), (1.7, "1.7"), ("1", "'1'"), (True, "True"),
                                          (None, "None"), ([1], "[1]")])
def test_labelstudio_frame_must_be_an_integer(value, shown):
    with pytest.raises(FormatError, match=re.escape(f"ranges[0].start: {shown} is not an integer frame number")):
        _import("labelstudio", _ls_with(value))


@pytest.mark.parametrize("literal", ["Infinity", "-Infinity", "NaN", "1e400", "-1e400"])
def test_labelstudio_overflowing_numbers_are_refused(literal):
    data = _ls_with(12345).replace(b"12345", literal.encode())
    with pytest.raises(FormatError, match="upload.json"):
        _import("labelstudio", data)


@pytest.mark.parametrize("start, end", [(0, 10), (5, 4), (1, N + 1), (-3, 2)])
def test_labelstudio_ranges_outside_the_video_or_reversed_are_refused(start, end):
    data = _ls_with(end, "end")
    doc = json.loads(data)
    next(r for r in doc[0]["annotations"][0]["result"] if r["from_name"] == "actions")["value"]["ranges"][0]["start"] = start
    with pytest.raises(FormatError, match=r"ranges\[0\]: frames .* not inside the video"):
        _import("labelstudio", json.dumps(doc).encode())


def _via_with(z) -> bytes:
    doc = json.loads(VALID["via"])
    key = next(k for k, md in doc["metadata"].items() if len(md["z"]) == len(z))
    doc["metadata"][key]["z"] = z
    return json.dumps(doc).encode()


@pytest.mark.parametrize("z, problem", [
    ([-1.0], "outside the video"), ([DURATION + 0.5], "outside the video"), ([1e300], "outside the video"),
    ([-1.0, 0.5], "outside the video"), ([0.2, DURATION + 1], "outside the video"),
    ([0.8, 0.4], "does not end after it starts"), ([0.4, 0.4], "does not end after it starts"),
    (["0.4"], "is not a number of seconds"), ([True], "is not a number of seconds"),
])
def test_via_times_out_of_range_or_reversed_are_refused_not_clamped(z, problem):
    with pytest.raises(FormatError, match=r"upload\.json: metadata\.1_\w+\.z(\[\d\])?: .*" + re.escape(problem)):
        _import("via", _via_with(z))


@pytest.mark.parametrize("literal", ["NaN", "Infinity", "-Infinity", "1e400"])
def test_via_non_finite_times_are_refused(literal):
    data = _via_with([123.25]).replace(b"123.25", literal.encode())
    with pytest.raises(FormatError, match="upload.json"):
        _import("via", data)


_ENTITY_DOC = ('<?xml version="1.0" encoding="{enc}"?>\n<!DOCTYPE annotations [<!ENTITY x "Injected">]>\n'
               '<annotations><version>1.1</version><meta><task><size>40</size><labels><label><name>&x;</name>'
               '<type>rectangle</type></label></labels></task></meta></annotations>')


@pytest.mark.parametrize("enc, problem", [
    ("utf-8", "DOCTYPE: .*not accepted"), ("utf-16", "DOCTYPE: .*not accepted"),
    ("utf-16-le", "multi-byte encodings"), ("utf-16-be", "multi-byte encodings"), ("utf-32", "not well-formed")])
def test_cvat_entities_and_doctype_refused_whatever_the_encoding(enc, problem):
    text = _ENTITY_DOC.format(enc=enc)
    data = text.encode(enc)
    if enc in ("utf-16-le", "utf-16-be"):
        data = ("\ufeff" + text).encode(enc)
    with pytest.raises(FormatError, match=r"upload\.json: .*" + problem):
        _import("cvat", data)


@pytest.mark.parametrize("dtd", [
    '<!DOCTYPE annotations SYSTEM "file:///etc/passwd">',
    '<!DOCTYPE annotations [<!ENTITY % p SYSTEM "http://127.0.0.1/x.dtd"> %p;]>',
    '<!DOCTYPE annotations [<!ENTITY a "aa"><!ENTITY b "&a;&a;&a;&a;&a;&a;&a;&a;">]>',
])
def test_cvat_external_entities_and_entity_bombs_refused(dtd):
    data = VALID["cvat"].replace(b"<annotations>", dtd.encode() + b"\n<annotations>", 1)
    with pytest.raises(FormatError, match="DOCTYPE"):
        _import("cvat", data)


def test_cvat_utf16_without_doctype_still_imports():
    text = VALID["cvat"].decode().replace('encoding="utf-8"', 'encoding="utf-16"')
    got = _import("cvat", text.encode("utf-16"))
    assert sorted(got.segments, key=lambda s: s.start) == TARGET.video.segments


@pytest.mark.parametrize("frame", [" 12", "12 ", "1e1", "+12", "-1", "12.0", "\u0661\u0662", "\uff11\uff12", ""])
def test_cvat_frames_must_be_ascii_digits(frame):
    root = ET.fromstring(VALID["cvat"])
    root.find("tag").set("frame", frame)
    with pytest.raises(FormatError, match=r"upload\.json: tag\[0\]\.frame: .* is not a frame number"):
        _import("cvat", ET.tostring(root))


# -------------------------------------------------------------------------------- property tests
SCALARS = (st.none() | st.booleans() | st.integers(-2**70, 2**70) | st.integers(-3, N + 3)
           | st.floats(allow_nan=True, allow_infinity=True) | st.text(max_size=6))


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(value=SCALARS)
def test_labelstudio_transition_frame_accepts_exactly_integers_inside_the_video(value):
    doc = json.loads(VALID["labelstudio"])
    tr = next(r for r in doc[0]["annotations"][0]["result"] if r["from_name"] == "transitions")
    tr["value"]["ranges"][0] = {"start": value, "end": value}
    data = json.dumps(doc).encode()  # NaN / Infinity are written as such: refused too
    ok = isinstance(value, int) and not isinstance(value, bool) and 1 <= value <= N
    try:
        got = _import("labelstudio", data)
    except FormatError:
        assert not ok or value - 1 in {t.frame for t in TARGET.video.transitions if t.frame != 0}  # a duplicate
        return
    assert ok and value - 1 in {t.frame for t in got.transitions}


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(value=SCALARS)
def test_via_transition_time_accepts_exactly_finite_seconds_inside_the_video(value):
    doc = json.loads(VALID["via"])
    key = next(k for k, md in doc["metadata"].items() if len(md["z"]) == 1)
    doc["metadata"][key]["z"] = [value]
    ok = (isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
          and -0.0005 <= value <= DURATION + 0.0005)
    try:
        _import("via", json.dumps(doc).encode())
    except FormatError:
        if ok:  # a valid time may still land on another transition's frame: a duplicate, refused
            return
        return
    assert ok


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(text=st.text(max_size=5) | st.integers(-3, N + 3).map(str))
def test_cvat_tag_frame_accepts_exactly_ascii_digits_inside_the_video(text):
    root = ET.fromstring(VALID["cvat"])
    tags = root.findall("tag")
    tags[-1].set("frame", "".join(ch for ch in text if ch.isprintable()))
    frame = tags[-1].get("frame")
    ok = re.fullmatch(r"[0-9]+", frame) is not None and int(frame) < N
    try:
        _import("cvat", ET.tostring(root))
    except FormatError:
        return
    assert ok


@settings(max_examples=100, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(start=SCALARS, end=SCALARS)
def test_via_segment_times_accept_exactly_ordered_finite_times_inside_the_video(start, end):
    doc = json.loads(VALID["via"])
    key = next(k for k, md in doc["metadata"].items() if len(md["z"]) == 2)
    doc["metadata"][key]["z"] = [start, end]

    def finite(x):
        return isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x) \
            and -0.0005 <= x <= DURATION + 0.0005

    try:
        _import("via", json.dumps(copy.deepcopy(doc)).encode())
    except FormatError:
        return
    assert finite(start) and finite(end) and start < end
