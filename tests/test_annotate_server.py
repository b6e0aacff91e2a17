"""The annotation server's API: frame exactness through HTTP, saving (atomic, validated, revision conflict,
tied to the video), overlays."""

from __future__ import annotations

import json

import cv2
import httpx
import numpy as np
import pytest
from annotate_util import CLASSES, numbered_video, running

from vidstyle.formats import FormatError
from vidstyle.formats.annotations import file_sha256, read_annotations, resolve_video_path
from vidstyle.video import VideoReader
from vidstyle.video.numbered import read_number


@pytest.fixture(scope="module")
def videos(tmp_path_factory):
    d = tmp_path_factory.mktemp("videos")
    return [numbered_video(d / "cfr.mp4", 80, 25.0), numbered_video(d / "vfr.mp4", 70, 25.0, vfr=True, seed=3)]


def _client(url):
    return httpx.Client(base_url=url, headers={"Origin": url}, timeout=30)


def _token(c) -> str:
    html = c.get("/").text
    return html.split('name="vidstyle-token" content="')[1].split('"')[0]


def test_frames_by_decoded_index(videos, tmp_path, rng):
    with running(videos, tmp_path / "a.json") as url, _client(url) as c:
        listing = c.get("/api/videos").json()
        assert [v["id"] for v in listing] == ["0", "1"]
        assert [v["frames"] for v in listing] == [80, 70]
        assert listing[1]["constant_rate"] is False and listing[0]["constant_rate"] is True
        for v, path in zip(listing, videos):
            ts = c.get(f"/api/videos/{v['id']}/timestamps").json()
            with VideoReader(path) as r:
                np.testing.assert_allclose(ts, r.timestamps, atol=1e-6)
            # random order, forward steps, back steps: the served image shows its own index
            order = list(rng.integers(0, v["frames"], 12)) + [0, 1, 2, 3, v["frames"] - 1, v["frames"] - 2, 5, 4]
            for i in order:
                for fmt in ("jpeg", "png"):
                    r = c.get(f"/api/videos/{v['id']}/frames/{int(i)}", params={"format": fmt})
                    assert r.status_code == 200 and r.headers["content-type"] == f"image/{fmt}"
                    img = cv2.imdecode(np.frombuffer(r.content, np.uint8), cv2.IMREAD_COLOR)
                    assert read_number(img) == int(i)
                    assert int(r.headers["x-frame-index"]) == int(i)
                    assert float(r.headers["x-frame-time"]) == pytest.approx(ts[int(i)], abs=1e-5)
        assert c.get("/api/videos/0/frames/80").status_code == 404
        assert c.get("/api/videos/0/frames/-1").status_code == 400
        assert c.get("/api/videos/7/frames/0").status_code == 404


def _state(c):
    return c.get("/api/annotations").json()


def test_save_reload_conflict_and_validation(videos, tmp_path):
    ann = tmp_path / "ann.json"
    with running(videos, ann) as url, _client(url) as c:
        tok = {"X-Vidstyle-Token": _token(c)}
        st = _state(c)
        assert st["revision"] == 0 and st["classes"] == CLASSES and [v["id"] for v in st["videos"]] == ["0", "1"]
        body = {"revision": 0, "classes": CLASSES, "videos": [
            {"id": "0", "transitions": [{"frame": 30, "from_action": "Jab", "to_action": "Hook", "status": "accepted",
                                         "candidates": [{"clip": "lib/a.bvh", "time": 0.5, "status": "discarded"}]}],
             "segments": [{"start": 0, "end": 29, "action": "Jab"}, {"start": 31, "end": 80, "action": "Hook"}]},
            {"id": "1", "transitions": [], "segments": [{"start": 10, "end": 20, "action": "Guard"}]}]}
        r = c.put("/api/annotations", json=body, headers=tok)
        assert r.status_code == 200 and r.json() == {"revision": 1}
        saved = read_annotations(ann)
        assert saved.revision == 1
        assert saved.videos[0].sha256 == file_sha256(videos[0]) and saved.videos[0].frames == 80
        assert saved.videos[0].transitions[0].candidates[0].status == "discarded"
        assert not saved.videos[0].path.startswith("/")  # stored relative to the annotations file
        assert resolve_video_path(ann, saved.videos[0]) == videos[0].resolve()
        # a stale page (revision 0) is refused, nothing changes
        before = ann.read_bytes()
        r = c.put("/api/annotations", json={**body, "videos": []}, headers=tok)
        assert r.status_code == 409 and r.json()["revision"] == 1
        assert ann.read_bytes() == before
        # invalid content: 422 naming the field, nothing changes
        bad = json.loads(json.dumps(body)); bad["revision"] = 1
        bad["videos"][0]["segments"][0]["end"] = 81
        r = c.put("/api/annotations", json=bad, headers=tok)
        assert r.status_code == 422 and "segments[0].end" in r.json()["error"]
        bad["videos"][0]["segments"][0]["end"] = 29
        bad["videos"][0]["transitions"][0]["to_action"] = "Cartwheel"
        r = c.put("/api/annotations", json=bad, headers=tok)
        assert r.status_code == 422 and "not in classes" in r.json()["error"]
        for junk in (b"{not json", b"[1, 2", b"{\"revision\": NaN}", b"\xff\xfe"):
            r = c.put("/api/annotations", content=junk, headers={**tok, "Content-Type": "application/json"})
            assert r.status_code == 400 and "JSON" in r.json()["error"]
        r = c.put("/api/annotations", json={"revision": 1, "videos": [{"id": "../../etc/passwd"}]}, headers=tok)
        assert r.status_code == 422
        assert ann.read_bytes() == before
        st = _state(c)
        assert st["revision"] == 1 and st["videos"][0]["segments"] == body["videos"][0]["segments"]
    # a new server (a reload, or another day) restores everything
    with running(videos, ann) as url, _client(url) as c:
        st = _state(c)
        assert st["revision"] == 1
        assert st["videos"][0]["transitions"] == body["videos"][0]["transitions"]
        assert st["videos"][1]["segments"] == body["videos"][1]["segments"]
    # only one video this time: the other's marks are kept in the file untouched
    with running(videos[1:], ann) as url, _client(url) as c:
        tok = {"X-Vidstyle-Token": _token(c)}
        st = _state(c)
        r = c.put("/api/annotations", json={"revision": 1, "videos": [{"id": "0", "transitions": [], "segments": []}]},
                  headers=tok)
        assert r.status_code == 200
    saved = read_annotations(ann)
    assert saved.revision == 2 and len(saved.videos[0].transitions) == 1 and saved.videos[1].segments == []


def test_performer_choice_is_stored_kept_and_cleared(videos, tmp_path):
    """The performer choice goes through the same save path as the marks: token, revision, validation
    (frame inside the video, pixel inside its 160x120 frame), atomic write; leaving it out of a PUT keeps it,
    null clears it."""
    ann = tmp_path / "ann.json"
    seg = [{"start": 0, "end": 5, "action": "Jab"}]
    with running(videos, ann) as url, _client(url) as c:
        tok = {"X-Vidstyle-Token": _token(c)}
        assert [v["performer"] for v in _state(c)["videos"]] == [None, None]
        choice = {"frame": 42, "x": 151, "y": 7}
        body = {"revision": 0, "videos": [{"id": "1", "transitions": [], "segments": seg, "performer": choice}]}
        assert c.put("/api/annotations", json=body).status_code == 403  # no token: refused, nothing written
        assert not ann.exists()
        r = c.put("/api/annotations", json=body, headers=tok)
        assert r.status_code == 200 and r.json() == {"revision": 1}
        saved = read_annotations(ann)
        assert saved.videos[0].performer is None
        assert (saved.videos[1].performer.frame, saved.videos[1].performer.x, saved.videos[1].performer.y) == (42, 151, 7)
        assert json.loads(ann.read_text())["videos"][1]["performer"] == {"frame": 42, "x": 151.0, "y": 7.0}
        assert [v["performer"] for v in _state(c)["videos"]] == [None, {"frame": 42, "x": 151.0, "y": 7.0}]
        # invalid choices: 422 naming the problem, the file unchanged
        before = ann.read_bytes()
        for bad, problem in [({"frame": 70, "x": 1, "y": 1}, "performer.frame: must be at most 69"),
                             ({"frame": 3, "x": 160, "y": 1}, "outside"),
                             ({"frame": 3, "x": 1, "y": 119.6}, "outside"),
                             ({"frame": 3, "x": -1, "y": 1}, "performer.x: must be at least 0"),
                             ({"frame": 3, "x": 1}, "performer.y: missing"),
                             ({"frame": 3, "x": 1, "y": 1, "who": "me"}, "unknown field"),
                             ("left one", "expected an object")]:
            r = c.put("/api/annotations", json={"revision": 1, "videos": [{"id": "1", "performer": bad}]}, headers=tok)
            assert r.status_code == 422 and problem in r.json()["error"], (bad, r.json())
        r = c.put("/api/annotations", content=b'{"revision": 1, "videos": [{"id": "1", "performer": '
                  b'{"frame": 3, "x": Infinity, "y": 1}}]}', headers={**tok, "Content-Type": "application/json"})
        assert r.status_code == 400
        assert ann.read_bytes() == before
        # a PUT without the key keeps the choice
        r = c.put("/api/annotations", json={"revision": 1, "videos": [{"id": "1", "segments": []}]}, headers=tok)
        assert r.status_code == 200 and read_annotations(ann).videos[1].performer.frame == 42
    with running(videos, ann) as url, _client(url) as c:  # a restarted server serves it
        tok = {"X-Vidstyle-Token": _token(c)}
        assert _state(c)["videos"][1]["performer"] == {"frame": 42, "x": 151.0, "y": 7.0}
        r = c.put("/api/annotations", json={"revision": 2, "videos": [{"id": "1", "performer": None}]}, headers=tok)
        assert r.status_code == 200
        assert read_annotations(ann).videos[1].performer is None
        assert "performer" not in json.loads(ann.read_text())["videos"][1]
        assert _state(c)["videos"][1]["performer"] is None
    # a file whose choice lies outside the served video's frame is refused at start, as a wrong frame count is
    doc = json.loads(ann.read_text())
    doc["videos"][1]["performer"] = {"frame": 0, "x": 200.0, "y": 1.0}
    ann.write_text(json.dumps(doc))
    with pytest.raises(FormatError, match=r"ann\.json: performer: pixel \(200, 1\) is outside"):
        running(videos, ann)


def test_two_servers_on_one_file_conflict(videos, tmp_path):
    ann = tmp_path / "ann.json"
    with running(videos[:1], ann) as u1, running(videos[:1], ann) as u2, _client(u1) as c1, _client(u2) as c2:
        t1, t2 = {"X-Vidstyle-Token": _token(c1)}, {"X-Vidstyle-Token": _token(c2)}
        body = {"revision": 0, "videos": [{"id": "0", "transitions": [], "segments": [{"start": 0, "end": 5, "action": "Jab"}]}]}
        assert c1.put("/api/annotations", json=body, headers=t1).status_code == 200
        assert c2.put("/api/annotations", json=body, headers=t2).status_code == 409  # the file moved on


def test_annotations_never_land_on_another_video(videos, tmp_path):
    ann = tmp_path / "ann.json"
    with running(videos[:1], ann) as url, _client(url) as c:
        c.put("/api/annotations", json={"revision": 0, "videos": [{"id": "0", "transitions": [],
              "segments": [{"start": 0, "end": 5, "action": "Jab"}]}]}, headers={"X-Vidstyle-Token": _token(c)})
    # the video file at the same path changes content: refuse to open it with those marks
    moved = tmp_path / "copy.mp4"
    moved.write_bytes(videos[0].read_bytes())
    with running([moved], ann) as url, _client(url) as c:  # same content elsewhere: found by sha256
        assert _state(c)["videos"][0]["segments"] == [{"start": 0, "end": 5, "action": "Jab"}]
    numbered_video(moved, 80, 30.0)  # same path, new content (other rate)
    doc = json.loads(ann.read_text())
    doc["videos"][0]["path"] = str(moved)
    ann.write_text(json.dumps(doc))
    with pytest.raises(FormatError, match="another content"):
        running([moved], ann)
    numbered_video(moved, 81, 25.0)
    doc["videos"][0]["sha256"] = file_sha256(moved)
    ann.write_text(json.dumps(doc))
    with pytest.raises(FormatError, match="decodes to 81"):
        running([moved], ann)


def test_overlays_map_onto_decoded_frames(videos, tmp_path):
    from vidstyle.annotate.overlays import load_overlays
    from vidstyle.annotate.session import open_videos
    from vidstyle.video import working_indices

    vids = open_videos(videos)
    try:
        # recognize labels at a working rate of 12.5 fps on the 25 fps video: each label covers 2 frames
        src = working_indices(vids[0].reader.info.timestamps, 12.5)
        labels = ["Jab"] * 10 + ["Hook"] * (len(src) - 10)
        lab = tmp_path / "lab.json"
        lab.write_text(json.dumps({"video": str(videos[0]), "fps": 12.5, "classes": CLASSES, "labels": labels}))
        from vidstyle.formats.poses import PoseFrame, Poses, write_poses
        from vidstyle.mocap.keypoints import KEYPOINTS

        poses = tmp_path / "p.json"
        pts = np.arange(45, dtype=float).reshape(15, 3) / 50
        write_poses(poses, Poses(videos[1].name, "ps", [PoseFrame(3, "left", pts, {"left": 1.0})]))
        ov = load_overlays(vids, labels=[lab], poses=[poses])
        spans = ov["0"]["recognized"]["spans"]
        assert spans == [{"start": 0, "end": int(src[10]), "action": "Jab"}, {"start": int(src[10]), "end": 80, "action": "Hook"}]
        assert int(src[10]) == 20
        assert ov["1"]["poses"]["frames"]["3"]["points"] == np.round(pts, 2).tolist()
        assert ov["1"]["poses"]["keypoints"] == list(KEYPOINTS) and len(ov["1"]["poses"]["edges"]) == 14
        # wrong label count, frame outside the video, a video not in the session: errors naming the file
        lab.write_text(json.dumps({"video": str(videos[0]), "fps": 12.5, "labels": labels[:-1]}))
        with pytest.raises(FormatError, match="lab.json"):
            load_overlays(vids, labels=[lab])
        write_poses(poses, Poses(videos[1].name, "ps", [PoseFrame(70, "left", pts, {"left": 1.0})]))
        with pytest.raises(FormatError, match=r"frames\[0\].frame"):
            load_overlays(vids, poses=[poses])
        m = tmp_path / "m.json"
        m.write_text(json.dumps({"kind": "vidstyle.matches", "schema_version": 1, "poses": "p.json",
                                 "video": "other.mp4", "library": [], "params": {}, "frames": []}))
        with pytest.raises(FormatError, match="none of the videos"):
            load_overlays(vids, matches=[m])
    finally:
        for v in vids:
            v.close()


def test_cli_bad_inputs_exit_2(videos, tmp_path, capsys):
    from vidstyle.cli import main

    assert main(["annotate", str(tmp_path / "missing.mp4"), "--no-browser"]) == 2
    bad = tmp_path / "bad.json"
    bad.write_text('{"kind": "vidstyle.annotations", "schema_version": 1, "revision": -3, "classes": [], "videos": []}')
    assert main(["annotate", str(videos[0]), "-a", str(bad), "--no-browser"]) == 2
    assert main(["annotate", str(videos[0]), str(videos[0]), "-a", str(tmp_path / "a.json"), "--no-browser"]) == 2
    assert main(["annotate", str(videos[0]), "--port", "70000", "--no-browser"]) == 2
    err = capsys.readouterr().err
    assert "missing.mp4" in err and "bad.json: revision" in err and "identical content" in err


def test_concurrent_requests_stay_frame_exact(videos, tmp_path, rng):
    from concurrent.futures import ThreadPoolExecutor

    idx = [int(i) for i in rng.integers(0, 70, 20)] + list(range(20, 30))
    with running(videos[1:], tmp_path / "a.json") as url:
        def fetch(i):
            with httpx.Client(base_url=url, timeout=60) as c:
                r = c.get(f"/api/videos/0/frames/{i}")
                return read_number(cv2.imdecode(np.frombuffer(r.content, np.uint8), cv2.IMREAD_COLOR))

        with ThreadPoolExecutor(6) as ex:
            assert list(ex.map(fetch, idx)) == idx
