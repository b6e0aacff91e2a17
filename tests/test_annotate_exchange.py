"""Export -> import is the identity for every exchange format, on constant and variable frame-rate videos
that show their own number; each format's frame convention checked against its definition."""

from __future__ import annotations

import json
import xml.etree.ElementTree as ET

import httpx
import numpy as np
import pytest
from annotate_util import CLASSES, numbered_video, running

from vidstyle.annotate import exchange
from vidstyle.formats import FormatError
from vidstyle.formats.annotations import CandidateDecision, ActionSpan, Transition, VideoAnnotations, file_sha256
from vidstyle.video import VideoReader


@pytest.fixture(scope="module", params=["cfr", "vfr"])
def target(request, tmp_path_factory):
    p = numbered_video(tmp_path_factory.mktemp("x") / f"{request.param}.mp4", 90, 25.0, vfr=request.param == "vfr", seed=5)
    with VideoReader(p) as r:
        info = r.info
    v = VideoAnnotations(p.name, file_sha256(p), info.frames, info.fps)
    return exchange.Target(v, info.timestamps, info.duration, info.width, info.height)


def random_marks(rng, n, classes):
    cuts = np.sort(rng.choice(np.arange(0, n + 1), size=8, replace=False))
    segs = [ActionSpan(int(a), int(b), str(rng.choice(classes))) for a, b in zip(cuts[::2], cuts[1::2])]
    if cuts[-1] < n:  # a segment running to the last frame (CVAT: no closing "outside" box)
        segs.append(ActionSpan(int(cuts[-1]), n, classes[0]))
    frames = np.sort(rng.choice(n, size=5, replace=False))
    trans = [Transition(int(f), str(rng.choice(classes)), str(rng.choice(classes)),
                        str(rng.choice(["accepted", "discarded"])),
                        [CandidateDecision(f"lib/{k}.bvh", float(np.round(rng.random() * 3, 4)), "accepted" if k % 2 else "discarded")
                         for k in range(int(rng.integers(0, 3)))])
             for f in frames]
    # edge frames: first and last
    trans[0].frame = 0
    trans[-1].frame = n - 1
    return segs, trans


@pytest.mark.parametrize("fmt", exchange.FORMATS)
def test_export_import_identity(fmt, target, rng):
    n = target.video.frames
    for _ in range(4):
        segs, trans = random_marks(rng, n, CLASSES)
        target.video.segments, target.video.transitions = segs, trans
        data = exchange.export(fmt, CLASSES, target)
        got = exchange.import_(fmt, data, list(CLASSES), target)
        assert got.classes == CLASSES
        assert sorted(got.segments, key=lambda s: s.start) == sorted(segs, key=lambda s: s.start)
        assert sorted(got.transitions, key=lambda t: t.frame) == sorted(trans, key=lambda t: t.frame)


def test_conventions(target):
    n = target.video.frames
    ts = target.timestamps
    target.video.segments = [ActionSpan(0, 10, "Jab"), ActionSpan(20, n, "Hook")]
    target.video.transitions = [Transition(15, "Jab", "Hook", "accepted")]
    # Label Studio: 1-based inclusive frame ranges
    ls = json.loads(exchange.export("labelstudio", CLASSES, target))
    ranges = [(r["value"]["ranges"][0]["start"], r["value"]["ranges"][0]["end"], r["value"]["timelinelabels"][0])
              for r in ls[0]["annotations"][0]["result"]]
    assert ranges == [(1, 10, "Jab"), (21, n, "Hook"), (16, 16, "transition")]
    cfg = ET.fromstring(exchange.labelstudio_config(CLASSES))
    names = {t.get("name"): [lab.get("value") for lab in t] for t in cfg.findall("TimelineLabels")}
    assert names == {"actions": CLASSES, "transitions": ["transition"]}
    assert {r["from_name"] for r in ls[0]["annotations"][0]["result"]} <= set(names)
    # CVAT: 0-based frames, keyframe at start, outside box at the exclusive end, tag for the transition
    root = ET.fromstring(exchange.export("cvat", CLASSES, target))
    tracks = [[(int(b.get("frame")), b.get("outside")) for b in t] for t in root.findall("track")]
    assert tracks == [[(0, "0"), (10, "1")], [(20, "0")]]
    assert [int(t.get("frame")) for t in root.findall("tag")] == [15]
    assert root.findtext("meta/task/stop_frame") == str(n - 1)
    # VIA: seconds from the decoded timestamps (not frame / fps)
    via = json.loads(exchange.export("via", CLASSES, target))
    z = [m["z"] for m in via["metadata"].values()]
    assert z[0] == [round(ts[0], 3), round(ts[10], 3)]
    assert z[1] == [round(ts[20], 3), round(target.duration, 3)]
    assert z[2] == [round(ts[15], 3)]


def test_vfr_via_uses_timestamps_not_fps(tmp_path):
    p = numbered_video(tmp_path / "vfr.mp4", 60, 25.0, vfr=True, seed=9)
    with VideoReader(p) as r:
        info = r.info
    assert not info.constant_rate
    target = exchange.Target(VideoAnnotations(p.name, file_sha256(p), info.frames, info.fps), info.timestamps,
                             info.duration, info.width, info.height)
    # a frame whose time differs from index / fps round-trips exactly; the naive conversion would not
    f = int(np.argmax(np.abs(target.timestamps - np.arange(target.video.frames) / target.video.fps)))
    target.video.transitions = [Transition(f, "Jab", "Hook", "accepted")]
    via = json.loads(exchange.export("via", CLASSES, target))
    t = next(iter(via["metadata"].values()))["z"][0]
    assert round(t * target.video.fps) != f
    assert exchange.import_("via", json.dumps(via).encode(), CLASSES, target).transitions[0].frame == f


def test_import_refuses_other_video_and_bad_files(target):
    target.video.segments, target.video.transitions = [ActionSpan(0, 5, "Jab")], []
    native = json.loads(exchange.export("native", CLASSES, target))
    native["videos"][0]["sha256"] = "0" * 64
    with pytest.raises(FormatError, match="sha256"):
        exchange.import_("native", json.dumps(native).encode(), CLASSES, target)
    cvat = exchange.export("cvat", CLASSES, target).replace(b"<size>90</size>", b"<size>91</size>")
    with pytest.raises(FormatError, match="decodes to 90"):
        exchange.import_("cvat", cvat, CLASSES, target)
    bomb = b'<?xml version="1.0"?><!DOCTYPE a [<!ENTITY x "y">]><annotations>&x;</annotations>'
    with pytest.raises(FormatError, match="DOCTYPE"):
        exchange.import_("cvat", bomb, CLASSES, target)
    for fmt in ("labelstudio", "via", "cvat", "native"):
        with pytest.raises(FormatError):
            exchange.import_(fmt, b"\x00garbage", CLASSES, target)
    # a Label Studio segment past the video's end is refused, naming the field
    ls = json.loads(exchange.export("labelstudio", CLASSES, target))
    ls[0]["annotations"][0]["result"][0]["value"]["ranges"][0]["end"] = 500
    with pytest.raises(FormatError, match="end"):
        exchange.import_("labelstudio", json.dumps(ls).encode(), CLASSES, target)


def test_export_import_through_the_api(tmp_path):
    vids = [numbered_video(tmp_path / "a.mp4", 40, 25.0, vfr=True, seed=2)]
    with running(vids, tmp_path / "ann.json") as url:
        c = httpx.Client(base_url=url, headers={"Origin": url}, timeout=30)
        tok = {"X-Vidstyle-Token": c.get("/").text.split('name="vidstyle-token" content="')[1].split('"')[0]}
        marks = {"id": "0", "transitions": [{"frame": 7, "from_action": "Jab", "to_action": "Guard", "status": "discarded"}],
                 "segments": [{"start": 0, "end": 7, "action": "Jab"}, {"start": 8, "end": 40, "action": "Guard"}]}
        assert c.put("/api/annotations", json={"revision": 0, "videos": [marks]}, headers=tok).status_code == 200
        for fmt in exchange.FORMATS:
            r = c.get(f"/api/export/{fmt}", params={"video": "0"})
            assert r.status_code == 200 and "attachment" in r.headers["content-disposition"]
            back = c.post(f"/api/import/{fmt}", params={"video": "0"}, content=r.content, headers=tok)
            assert back.status_code == 200, back.text
            got = back.json()
            assert got["transitions"] == marks["transitions"] and got["segments"] == marks["segments"], fmt
        assert c.get("/api/export/pdf", params={"video": "0"}).status_code == 400
        r = c.post("/api/import/cvat", params={"video": "0"}, content=b"<nope", headers=tok)
        assert r.status_code == 422 and "cvat" in r.json()["error"]
        assert c.get("/api/annotations").json()["revision"] == 1  # import itself saves nothing
