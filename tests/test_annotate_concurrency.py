"""No lost save when several processes serve one annotations file (issue 33 item 2): a save is a
compare-and-swap on the file (flock beside it), the store re-reads a file changed on disk, and a 409 names the
current revision so a reloaded page can save again."""

from __future__ import annotations

import json
import multiprocessing as mp
import os

import httpx
import pytest
from annotate_util import numbered_video, running

from vidstyle.annotate.session import Conflict, Store, open_videos
from vidstyle.formats.annotations import read_annotations, write_annotations

TRIALS = 100  # the bar: no lost save in 100 concurrent trials


@pytest.fixture(scope="module")
def video(tmp_path_factory):
    return numbered_video(tmp_path_factory.mktemp("v") / "v.mp4", 2 * 2 * TRIALS + 2)


def _segments(store: Store) -> list[dict]:
    return store.state()["videos"][0]["segments"]


def _worker(k: int, video, ann, barrier, out) -> None:
    """Process ``k`` of two: per trial both read the state, then both save from it at once; the loser
    (a Conflict) reads again and saves its change from the new revision."""
    vids = open_videos([video])
    store = Store(ann, vids, ["Jab"])
    got = []
    try:
        for t in range(TRIALS):
            barrier.wait(60)
            st = store.state()
            seg = {"start": 4 * t + 2 * k, "end": 4 * t + 2 * k + 1, "action": "Jab"}
            barrier.wait(60)
            try:
                got.append(("won", st["revision"], store.save({"revision": st["revision"], "videos": [
                    {"id": "0", "segments": st["videos"][0]["segments"] + [seg]}]})))
            except Conflict as e:
                got.append(("lost", st["revision"], e.current))
            barrier.wait(60)
            if got[-1][0] == "lost":  # reload and save again: the change is not lost
                st = store.state()
                got.append(("retried", st["revision"], store.save({"revision": st["revision"], "videos": [
                    {"id": "0", "segments": st["videos"][0]["segments"] + [seg]}]})))
            barrier.wait(60)
    except Exception as e:  # noqa: BLE001 - reported to the test
        got.append(("error", repr(e)))
        barrier.abort()
    finally:
        vids[0].close()
    out.put((k, got))


def test_two_processes_saving_at_once_never_both_win(video, tmp_path):
    ann = tmp_path / "ann.json"
    ctx = mp.get_context("fork")
    barrier, out = ctx.Barrier(2), ctx.Queue()
    procs = [ctx.Process(target=_worker, args=(k, video, ann, barrier, out)) for k in range(2)]
    for p in procs:
        p.start()
    results = dict(out.get(timeout=300) for _ in procs)
    for p in procs:
        p.join(30)
    errors = [r for rs in results.values() for r in rs if r[0] == "error"]
    assert not errors, errors
    for t in range(TRIALS):
        wins = [rs for rs in results.values() if [r for r in rs if r[0] in ("won", "lost")][t][0] == "won"]
        assert len(wins) == 1, f"trial {t}: {len(wins)} saves from one revision succeeded"
    new_revisions = sorted(r[2] for rs in results.values() for r in rs if r[0] in ("won", "retried"))
    assert new_revisions == list(range(1, 2 * TRIALS + 1))  # every revision given out once
    saved = read_annotations(ann)
    assert saved.revision == 2 * TRIALS
    assert sorted(s.start for s in saved.videos[0].segments) == [4 * t + 2 * k for t in range(TRIALS) for k in (0, 1)]


def _client(url):
    return httpx.Client(base_url=url, headers={"Origin": url}, timeout=30)


def _token(c) -> str:
    return c.get("/").text.split('name="vidstyle-token" content="')[1].split('"')[0]


def _put(c, rev, segments):
    return c.put("/api/annotations", json={"revision": rev, "videos": [{"id": "0", "segments": segments}]},
                 headers={"X-Vidstyle-Token": _token(c)})


SEG = [{"start": 0, "end": 3, "action": "Jab"}]


def test_two_servers_on_one_file_the_second_reloads_and_saves(video, tmp_path):
    ann = tmp_path / "ann.json"
    with running([video], ann) as u1, running([video], ann) as u2, _client(u1) as c1, _client(u2) as c2:
        assert _put(c1, 0, SEG).status_code == 200
        r = _put(c2, 0, [{"start": 5, "end": 6, "action": "Hook"}])
        assert r.status_code == 409 and r.json()["revision"] == 1 and "reload" in r.json()["error"]
        st = c2.get("/api/annotations").json()  # the page reloads: the server re-reads the file
        assert st["revision"] == 1 and st["videos"][0]["segments"] == SEG
        r = _put(c2, 1, SEG + [{"start": 5, "end": 6, "action": "Hook"}])
        assert r.status_code == 200 and r.json() == {"revision": 2}
        assert c1.get("/api/annotations").json()["videos"][0]["segments"][1]["start"] == 5
        assert _put(c1, 1, SEG).status_code == 409
    assert [s.start for s in read_annotations(ann).videos[0].segments] == [0, 5]


def test_outside_write_then_a_reloaded_page_saves(video, tmp_path):
    ann = tmp_path / "ann.json"
    with running([video], ann) as url, _client(url) as c:
        assert _put(c, 0, SEG).status_code == 200
        outside = read_annotations(ann)  # another program edits the file (and counts a revision)
        outside.videos[0].segments[0].end = 7
        outside.revision = 5
        write_annotations(ann, outside)
        r = _put(c, 1, SEG)  # the open page did not see it
        assert r.status_code == 409 and r.json()["revision"] == 5
        st = c.get("/api/annotations").json()
        assert st["revision"] == 5 and st["videos"][0]["segments"][0]["end"] == 7
        assert _put(c, 5, SEG + [{"start": 9, "end": 10, "action": "Jab"}]).status_code == 200
        assert read_annotations(ann).revision == 6
        # an edit that keeps the revision number is still a change the page has not seen
        doc = json.loads(ann.read_text())
        doc["videos"][0]["segments"] = []
        ann.write_text(json.dumps(doc))
        assert _put(c, 6, SEG).status_code == 409
        st = c.get("/api/annotations").json()
        assert st["revision"] == 7 and st["videos"][0]["segments"] == []
        assert _put(c, 7, SEG).status_code == 200
        assert read_annotations(ann).revision == 8


def test_a_file_changed_into_junk_is_not_overwritten(video, tmp_path):
    ann = tmp_path / "ann.json"
    with running([video], ann) as url, _client(url) as c:
        assert _put(c, 0, SEG).status_code == 200
        ann.write_text('{"kind": "vidstyle.annotations", "half written')
        r = _put(c, 1, SEG)
        assert r.status_code == 409 and "cannot be used" in r.json()["error"]
        assert ann.read_text().endswith("half written")
        assert c.get("/api/annotations").status_code == 200  # the last good state is still shown


def test_the_lock_file_sits_beside_the_symlink_target(video, tmp_path):
    real = tmp_path / "data" / "ann.json"
    real.parent.mkdir()
    link = tmp_path / "ann.json"
    os.symlink(real, link)
    with running([video], link) as url, _client(url) as c:
        assert _put(c, 0, SEG).status_code == 200
    assert link.is_symlink() and read_annotations(real).revision == 1
    assert (real.parent / ".ann.json.lock").exists() and not (tmp_path / ".ann.json.lock").exists()
