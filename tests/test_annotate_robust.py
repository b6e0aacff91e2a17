"""The annotation server answers bad input with a 4xx, never a 500, handles class lists in linear time and
large bodies off the event loop (issue 33 item 5)."""

from __future__ import annotations

import json
import threading

import httpx
import pytest
from annotate_util import numbered_video, running, session

from vidstyle.annotate import exchange
from vidstyle.annotate.launch import class_names
from vidstyle.annotate.server import Running
from vidstyle.annotate.session import Store, open_videos
from vidstyle.formats import FormatError
from vidstyle.formats.annotations import from_document


@pytest.fixture(scope="module")
def video(tmp_path_factory):
    return numbered_video(tmp_path_factory.mktemp("v") / "v.mp4", 12)


@pytest.fixture
def server(video, tmp_path):
    with running([video], tmp_path / "ann.json") as url:
        c = httpx.Client(base_url=url, headers={"Origin": url}, timeout=60)
        token = c.get("/").text.split('name="vidstyle-token" content="')[1].split('"')[0]
        c.headers["X-Vidstyle-Token"] = token
        yield c
        c.close()


@pytest.mark.parametrize("index", ["%C2%B2", "%D9%A3", "%EF%BC%93", "%E0%A5%A9", "1%C2%B2", "+1", "%201", "1e1",
                                   "0x1", "1_0", "1.0", "%00"])
def test_frame_numbers_are_ascii_digits_only(server, index):
    r = server.get(f"/api/videos/0/frames/{index}")
    assert r.status_code == 400, (index, r.status_code)
    assert server.get("/api/videos/0/frames/3").status_code == 200


@pytest.mark.parametrize("vid", [["0"], {"0": 1}, 0, None, True, [], "00"])
def test_a_video_id_that_is_not_a_known_string_is_a_422(server, vid):
    r = server.put("/api/annotations", json={"revision": 0, "videos": [{"id": vid, "segments": []}]})
    assert r.status_code == 422 and "videos[0].id" in r.json()["error"]


def _nested(depth: int, inner: str = "1") -> str:
    return "[" * depth + inner + "]" * depth


@pytest.mark.parametrize("depth", [5_000, 200_000])
def test_deeply_nested_json_is_a_4xx(server, depth):
    bodies = [_nested(depth),
              '{"revision": 0, "videos": [{"id": "0", "segments": ' + _nested(depth) + "}]}",
              '{"revision": 0, "classes": ' + _nested(depth, '"a"') + "}"]
    for body in bodies:
        r = server.put("/api/annotations", content=body.encode(), headers={"Content-Type": "application/json"})
        assert 400 <= r.status_code < 500, r.status_code
    for fmt in ("native", "labelstudio", "via"):
        r = server.post(f"/api/import/{fmt}?video=0", content=_nested(depth).encode())
        assert r.status_code == 422, (fmt, r.status_code)
    assert server.get("/api/annotations").json()["revision"] == 0


def _ls(start, end="3", extra="") -> bytes:
    return ('[{"data": {"video": "v.mp4"' + extra + '}, "annotations": [{"result": [{"type": "timelinelabels", '
            '"from_name": "actions", "to_name": "video", "value": {"ranges": [{"start": ' + start + ', "end": '
            + end + '}], "timelinelabels": ["Jab"]}}]}]}]').encode()


@pytest.mark.parametrize("data", [_ls("Infinity"), _ls("1", "1e400"), _ls("-Infinity"), _ls("NaN"),
                                  _ls("1", extra=', "vidstyle_frames": 1e400'),
                                  _ls("1", extra=', "vidstyle_frames": Infinity'),
                                  _ls("1" + "0" * 5000)])
def test_labelstudio_import_with_numbers_out_of_range_is_a_422(server, data):
    r = server.post("/api/import/labelstudio?video=0", content=data)
    assert r.status_code == 422, r.status_code
    assert server.post("/api/import/labelstudio?video=0", content=_ls("1")).status_code == 200


@pytest.mark.parametrize("body", [b'{"revision": Infinity}', b'{"revision": 1e400}', b'{"revision": -Infinity}',
                                  b'{"revision": NaN}', b'{"revision": 1' + b"0" * 5000 + b"}"])
def test_put_with_non_finite_or_huge_numbers_is_a_4xx(server, body):
    r = server.put("/api/annotations", content=body, headers={"Content-Type": "application/json"})
    assert 400 <= r.status_code < 500, r.status_code


class Counted(str):
    """A class name that counts how often it is compared for equality: a list search per name compares it
    with every other name (quadratic); a set or dict compares it only on a hash match."""

    calls = 0

    def __eq__(self, other):
        Counted.calls += 1
        return str.__eq__(self, other)

    __hash__ = str.__hash__


N = 3000


def _names(prefix="c"):
    return [Counted(f"{prefix}{i}") for i in range(N)]


def test_class_lists_are_merged_without_a_list_search_per_name(video, tmp_path):
    vids = open_videos([video])
    try:
        Counted.calls = 0
        store = Store(tmp_path / "a.json", vids, _names())
        assert store.ann.classes == [f"c{i}" for i in range(N)]
        assert Counted.calls < 10 * N, Counted.calls  # a list search per name: ~N*N/2
        Counted.calls = 0
        store.save({"revision": 0, "classes": _names()})
        store2 = Store(tmp_path / "a.json", vids, _names("d") + _names())  # the file's classes, then new ones
        assert store2.ann.classes[:2] == ["c0", "c1"] and store2.ann.classes[N] == "d0"
        assert len(store2.ann.classes) == 2 * N
        assert Counted.calls < 20 * N, Counted.calls
    finally:
        vids[0].close()


def test_class_names_and_duplicates_in_linear_time():
    Counted.calls = 0
    names = class_names(None, NoFile(), {"0": {"recognized": {"classes": _names()}},
                                               "1": {"recognized": {"classes": _names()}}})
    assert names == [f"c{i}" for i in range(N)] and Counted.calls < 10 * N
    Counted.calls = 0
    assert class_names(_names() + _names(), NoFile(), {}) == [f"c{i}" for i in range(N)]
    assert Counted.calls < 10 * N
    doc = {"kind": "vidstyle.annotations", "schema_version": 2, "revision": 0,
           "classes": _names() + [Counted(f"c{N - 1}")], "videos": []}
    Counted.calls = 0
    with pytest.raises(FormatError, match=f"'c{N - 1}' appears more than once"):
        from_document(doc, "x.json")
    assert Counted.calls < 10 * N, Counted.calls


class NoFile:  # an annotations path that does not exist
    def exists(self):
        return False


def test_an_import_adds_classes_without_a_list_search_per_name(video, tmp_path):
    vids = open_videos([video])
    try:
        store = Store(tmp_path / "a.json", vids, ["Jab"])
        target = exchange.Target(store.entry("0"), vids[0].timestamps, float(vids[0].reader.info.duration),
                                 vids[0].reader.width, vids[0].reader.height)
        data = json.dumps([{"data": {"video": "v.mp4", "vidstyle_classes": [f"c{i}" for i in range(N)]},
                            "annotations": [{"result": []}]}]).encode()
        Counted.calls = 0
        marks = exchange.import_("labelstudio", data, _names("k"), target)
        assert len(marks.classes) == 2 * N and marks.classes[N] == "c0"
        assert Counted.calls < 10 * N, Counted.calls
    finally:
        vids[0].close()


def test_saves_and_imports_run_off_the_event_loop(video, tmp_path):
    s = session([video], tmp_path / "ann.json")
    threads = {}
    save, import_ = s.store.save, exchange.import_

    def spy_save(body):
        threads["save"] = threading.current_thread()
        return save(body)

    def spy_import(*a, **kw):
        threads["import"] = threading.current_thread()
        return import_(*a, **kw)

    s.store.save = spy_save
    run = Running(s)
    exchange.import_ = spy_import
    try:
        with run as url, httpx.Client(base_url=url, headers={"Origin": url}, timeout=30) as c:
            c.headers["X-Vidstyle-Token"] = s.token
            assert c.put("/api/annotations", json={"revision": 0, "videos": []}).status_code == 200
            assert c.post("/api/import/labelstudio?video=0", content=_ls("1")).status_code == 200
    finally:
        exchange.import_ = import_
    # the server's event loop runs in run.thread; a handler that blocks there stalls every other request
    assert threads["save"] is not run.thread and threads["import"] is not run.thread
