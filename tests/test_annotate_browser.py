"""The annotation page in a real browser (Playwright driving Debian's chromium): keyboard navigation with the
shown frame read back from its own pixels, marking segments and transitions, undo/redo, save, reload,
export and import, accepting library poses, and a screenshot checked by the test; the page's icon (no
console error on load), a header that keeps its layout when the pending-segment message appears, and the
recognised action and confidence of the current frame beside it."""

from __future__ import annotations

import json
import os
import shutil
from pathlib import Path

import cv2
import numpy as np
import pytest
from annotate_util import numbered_video, session

from playwright import sync_api

from vidstyle.annotate.overlays import load_overlays
from vidstyle.annotate.server import Running
from vidstyle.formats.annotations import read_annotations
from vidstyle.formats.matches import Candidate, FrameMatches, Matches, write_matches
from vidstyle.formats.poses import PoseFrame, Poses, write_poses
from vidstyle.video.numbered import read_number

CHROMIUM = shutil.which("chromium") or "/usr/bin/chromium"
ARGS = ["--no-sandbox", "--disable-gpu", "--disable-background-networking", "--disable-component-update",
        "--disable-sync", "--no-first-run"]
N = 120


@pytest.fixture(scope="module")
def browser():
    if not Path(CHROMIUM).exists():
        pytest.fail(f"chromium is not installed at {CHROMIUM} (make test installs it: apt-get install chromium)")
    with sync_api.sync_playwright() as p:
        b = p.chromium.launch(executable_path=CHROMIUM, args=ARGS)
        yield b
        b.close()


@pytest.fixture
def app(tmp_path):
    video = numbered_video(tmp_path / "clip.mp4", N, 25.0, size=(320, 240))
    poses = tmp_path / "poses.json"
    pts = [[160 + 20 * np.sin(k), 60 + 10 * k, 0.9] for k in range(15)]
    write_poses(poses, Poses(str(video), "ps", [PoseFrame(32, "front", pts, {"front": 0.9, "left": 0.1})]))
    matches = tmp_path / "matches.json"
    write_matches(matches, Matches(str(poses), str(video), ["lib/01_01.bvh", "lib/02_03.bvh"], {"k": 2}, [
        FrameMatches(32, 0.0, [Candidate("lib/01_01.bvh", 1.25, 0.1), Candidate("lib/02_03.bvh", 0.5, 0.2)])]))
    ann = tmp_path / "annotations.json"
    s = session([video], ann)
    s.overlays = load_overlays(s.videos, poses=[poses], matches=[matches])
    with Running(s) as url:
        yield url, ann, tmp_path


def shown_number(page) -> int:
    """The frame the page shows, read from the pixels of the displayed image (after it has loaded)."""
    page.wait_for_function("() => { const i = document.getElementById('frame');"
                           " return i.complete && i.dataset.frame === String(window.vidstyle.frame); }")
    png = page.locator("#frame").screenshot()
    img = cv2.imdecode(np.frombuffer(png, np.uint8), cv2.IMREAD_COLOR)
    return read_number(img)


def state(page):
    return page.evaluate("() => JSON.parse(JSON.stringify(window.vidstyle.marks['0']))")


def goto(page, n):
    page.keyboard.press("`")
    page.fill("#goto", str(n))
    page.keyboard.press("Enter")
    assert shown_number(page) == n


def wait_saved(page):
    page.wait_for_function("() => window.vidstyle.changes === window.vidstyle.savedChanges && !window.vidstyle.saving")


@pytest.mark.slow
def test_page_end_to_end(browser, app):
    url, ann, tmp = app
    page = browser.new_page(viewport={"width": 1280, "height": 800}, accept_downloads=True)
    errors = []
    page.on("pageerror", lambda e: errors.append(str(e)))
    page.goto(url + "/")
    assert shown_number(page) == 0
    # keyboard navigation: frame shown == frame index
    expect = 0
    for key, step in [("f", 1), ("ArrowRight", 1), ("v", 10), ("v", 10), ("c", -10), ("d", -1), ("ArrowLeft", -1),
                      ("End", None), ("Home", None), ("ArrowLeft", 0)]:
        page.keyboard.press(key)
        expect = {"End": N - 1, "Home": 0}.get(key, max(0, expect + (step or 0)))
        assert shown_number(page) == expect, key
        assert page.evaluate("window.vidstyle.frame") == expect
        assert f"frame {expect} /" in page.inner_text("#info")
    goto(page, 57)
    for _ in range(3):  # quick repeated steps: the last one wins, every frame exact
        page.keyboard.press("f")
    assert shown_number(page) == 60
    # play at the video's rate, then pause: still exact
    page.keyboard.press(" ")
    page.wait_for_function("() => window.vidstyle.frame >= 64")
    page.keyboard.press(" ")
    f = page.evaluate("window.vidstyle.frame")
    assert shown_number(page) == f and not page.evaluate("window.vidstyle.playing")

    # segments: [ ... ] inclusive, action by number key
    goto(page, 10)
    page.keyboard.press("1")
    page.keyboard.press("[")
    goto(page, 29)
    page.keyboard.press("]")
    goto(page, 35)
    page.keyboard.press("2")
    page.keyboard.press("[")
    goto(page, 50)
    page.keyboard.press("]")
    assert state(page)["segments"] == [{"start": 10, "end": 30, "action": "Jab"},
                                       {"start": 35, "end": 51, "action": "Hook"}]
    # a transition between them takes its actions from the neighbouring segments
    goto(page, 32)
    page.keyboard.press("t")
    assert state(page)["transitions"] == [{"frame": 32, "from_action": "Jab", "to_action": "Hook", "status": "accepted"}]
    # undo / redo
    page.keyboard.press("Control+z")
    assert state(page)["transitions"] == []
    page.keyboard.press("Control+z")
    assert len(state(page)["segments"]) == 1
    page.keyboard.press("Control+Shift+z")
    page.keyboard.press("Control+Shift+z")
    assert len(state(page)["segments"]) == 2 and len(state(page)["transitions"]) == 1
    # the pose overlay and the library poses of this frame; accept one, discard the other
    assert page.locator("#candidates li").count() == 2
    page.locator("#candidates li").nth(0).get_by_role("button", name="accept").click()
    page.locator("#candidates li").nth(1).get_by_role("button", name="discard").click()
    overlay = page.locator("#overlay").screenshot()
    ov = cv2.imdecode(np.frombuffer(overlay, np.uint8), cv2.IMREAD_COLOR)
    green = (ov[..., 1] > 180) & (ov[..., 0] < 120) & (ov[..., 2] < 120)
    assert green.sum() > 50  # the skeleton is drawn
    # a digit picks the next segment's action only; Shift+digit relabels the segment under the cursor
    goto(page, 40)
    page.keyboard.press("3")
    assert state(page)["segments"][1]["action"] == "Hook"
    page.keyboard.press("Shift+Digit3")
    assert state(page)["segments"][1]["action"] == "Guard"
    page.keyboard.press("Control+z")
    assert state(page)["segments"][1]["action"] == "Hook"
    # Delete removes the segment here
    goto(page, 12)
    page.keyboard.press("Delete")
    assert [s["start"] for s in state(page)["segments"]] == [35]
    page.keyboard.press("Control+z")
    page.keyboard.press("Control+s")
    wait_saved(page)
    saved = read_annotations(ann)
    v = saved.videos[0]
    assert [(s.start, s.end, s.action) for s in v.segments] == [(10, 30, "Jab"), (35, 51, "Hook")]
    assert [(t.frame, t.from_action, t.to_action, t.status) for t in v.transitions] == [(32, "Jab", "Hook", "accepted")]
    assert [(c.clip, c.time, c.status) for c in v.transitions[0].candidates] == [
        ("lib/01_01.bvh", 1.25, "accepted"), ("lib/02_03.bvh", 0.5, "discarded")]
    assert "saved" in page.inner_text("#status")

    # screenshot, checked: the frame is readable and the timeline shows the segments in their colours
    goto(page, 32)
    shot = tmp / "annotate.png"
    page.screenshot(path=str(shot))
    if os.environ.get("VIDSTYLE_SCREENSHOT"):
        shutil.copy(shot, os.environ["VIDSTYLE_SCREENSHOT"])
    tl = page.locator("#timeline")
    box = tl.bounding_box()
    img = cv2.imread(str(shot))
    y = int(box["y"] + 31)
    seg_px = img[y, int(box["x"] + box["width"] * 20 / N)].astype(int)
    gap_px = img[y, int(box["x"] + box["width"] * 80 / N)].astype(int)
    assert np.ptp(seg_px) > 40 and np.ptp(gap_px) < 10  # coloured over the Jab segment, grey elsewhere
    assert read_number(cv2.imdecode(np.frombuffer(page.locator("#frame").screenshot(), np.uint8), cv2.IMREAD_COLOR)) == 32

    # reload restores everything
    page.reload()
    assert shown_number(page) == 0
    assert state(page)["segments"] == [{"start": 10, "end": 30, "action": "Jab"}, {"start": 35, "end": 51, "action": "Hook"}]
    assert state(page)["transitions"][0]["candidates"][0]["status"] == "accepted"

    # export (CVAT) -> the file imports to the same marks
    page.select_option("#export-format", "cvat")
    with page.expect_download() as dl:
        page.click("#export")
    data = Path(dl.value.path()).read_bytes()
    assert data.startswith(b"<?xml") and b"<track" in data
    # import a Label Studio file into the page: one undoable step, then saved
    page.select_option("#export-format", "labelstudio")
    with page.expect_download() as dl:
        page.click("#export")
    ls = json.loads(Path(dl.value.path()).read_text())
    ls[0]["annotations"][0]["result"] = [r for r in ls[0]["annotations"][0]["result"] if r["from_name"] != "actions"]
    f = tmp / "edited.labelstudio.json"
    f.write_text(json.dumps(ls))
    page.select_option("#import-format", "labelstudio")
    page.set_input_files("#import-file", str(f))
    page.wait_for_function("() => window.vidstyle.marks['0'].segments.length === 0")
    wait_saved(page)
    assert read_annotations(ann).videos[0].segments == []
    page.keyboard.press("Control+z")
    wait_saved(page)
    assert len(read_annotations(ann).videos[0].segments) == 2
    # help overlay on ?
    page.keyboard.press("?")
    assert page.locator("#help").is_visible() and "Ctrl+Shift+Z" in page.inner_text("#help")
    page.keyboard.press("Escape")
    assert not page.locator("#help").is_visible()
    assert errors == []
    page.close()


def test_stale_tab_gets_a_conflict(browser, app):
    url, ann, tmp = app
    a, b = browser.new_page(), browser.new_page()
    for p in (a, b):
        p.goto(url + "/")
        assert shown_number(p) == 0
    a.keyboard.press("t")
    wait_saved(a)
    b.keyboard.press("f")
    b.keyboard.press("t")
    b.wait_for_function("() => window.vidstyle.conflict")
    assert "conflict" in b.inner_text("#status")
    assert [t.frame for t in read_annotations(ann).videos[0].transitions] == [0]
    a.close(), b.close()


def _segments(page):
    return [(s["start"], s["end"], s["action"]) for s in state(page)["segments"]]


def _import(page, fmt, path: Path):
    page.select_option("#import-format", fmt)
    page.set_input_files("#import-file", str(path))


@pytest.mark.slow
def test_page_splits_segments_toggles_transitions_and_imports(browser, app):
    """The controls the end-to-end test does not drive: a segment marked inside another splits it, a
    transition's status toggles by key and by button and its actions change through the selects, and the
    import control reads CVAT and VIA files (and reports a broken one without changing the marks)."""
    from vidstyle.annotate import exchange
    from vidstyle.formats.annotations import ActionSpan, Transition, VideoAnnotations, file_sha256
    from vidstyle.video import VideoReader

    url, ann, tmp = app
    page = browser.new_page(viewport={"width": 1280, "height": 800})
    errors = []
    page.on("pageerror", lambda e: errors.append(str(e)))
    page.goto(url + "/")
    assert shown_number(page) == 0
    # one Jab segment 10..49, then a Hook segment 20..29 marked inside it: the Jab is split around it
    goto(page, 10)
    page.keyboard.press("1")
    page.keyboard.press("[")
    goto(page, 49)
    page.keyboard.press("]")
    assert _segments(page) == [(10, 50, "Jab")]
    goto(page, 29)
    page.keyboard.press("2")
    page.keyboard.press("[")
    goto(page, 20)  # marked backwards: the segment is still 20..29
    page.keyboard.press("]")
    assert _segments(page) == [(10, 20, "Jab"), (20, 30, "Hook"), (30, 50, "Jab")]
    assert page.locator("#segments li").all_inner_texts() == ["10–19 Jab", "20–29 Hook", "30–49 Jab"]  # inner text collapses spaces
    page.keyboard.press("Control+z")
    assert _segments(page) == [(10, 50, "Jab")]
    page.keyboard.press("Control+Shift+z")
    assert _segments(page) == [(10, 20, "Jab"), (20, 30, "Hook"), (30, 50, "Jab")]

    # a transition at the split point: Jab -> Hook from the neighbouring segments; T toggles its status,
    # and so does the status button; the selects change its actions
    goto(page, 20)
    page.keyboard.press("t")
    assert state(page)["transitions"] == [{"frame": 20, "from_action": "Jab", "to_action": "Hook", "status": "accepted"}]
    assert page.locator("#transition-edit").is_visible() and not page.locator("#transition-none").is_visible()
    page.keyboard.press("t")
    assert state(page)["transitions"][0]["status"] == "discarded"
    assert "discarded" in page.inner_text("#t-status")
    assert "discarded" in page.locator("#transitions li").first.get_attribute("class")
    page.click("#t-status")
    assert state(page)["transitions"][0]["status"] == "accepted"
    assert page.inner_text("#t-status").startswith("accepted")
    page.select_option("#t-to", "Guard")
    assert state(page)["transitions"][0]["to_action"] == "Guard"
    page.select_option("#t-from", "Hook")
    assert state(page)["transitions"][0]["from_action"] == "Hook"
    page.keyboard.press("Control+z")
    assert state(page)["transitions"][0]["from_action"] == "Jab"
    assert len(state(page)["transitions"]) == 1 and state(page)["transitions"][0]["to_action"] == "Guard"
    page.keyboard.press("Control+s")
    wait_saved(page)
    v = read_annotations(ann).videos[0]
    assert [(s.start, s.end, s.action) for s in v.segments] == [(10, 20, "Jab"), (20, 30, "Hook"), (30, 50, "Jab")]
    assert [(t.frame, t.from_action, t.to_action, t.status) for t in v.transitions] == [(20, "Jab", "Guard", "accepted")]

    # the import control: a CVAT file and a VIA file made for this video by another tool
    video = tmp / "clip.mp4"
    with VideoReader(video) as r:
        info = r.info
    target = exchange.Target(VideoAnnotations(video.name, file_sha256(video), info.frames, info.fps),
                             info.timestamps, info.duration, info.width, info.height)
    target.video.segments = [ActionSpan(0, 5, "Guard"), ActionSpan(60, 70, "Hook")]
    target.video.transitions = [Transition(65, "Hook", "Guard", "discarded")]
    cvat = tmp / "other.cvat.xml"
    cvat.write_bytes(exchange.export("cvat", ["Jab", "Hook", "Guard"], target))
    _import(page, "cvat", cvat)
    page.wait_for_function("() => window.vidstyle.marks['0'].segments.length === 2")
    assert _segments(page) == [(0, 5, "Guard"), (60, 70, "Hook")]
    assert [(t["frame"], t["status"]) for t in state(page)["transitions"]] == [(65, "discarded")]
    target.video.segments = [ActionSpan(100, N, "Kick")]  # a class the page does not know yet: added
    target.video.transitions = [Transition(99, "Guard", "Kick", "accepted")]
    via = tmp / "other.via.json"
    via.write_bytes(exchange.export("via", ["Jab", "Hook", "Guard", "Kick"], target))
    _import(page, "via", via)
    page.wait_for_function("() => window.vidstyle.marks['0'].segments.length === 1")
    assert _segments(page) == [(100, N, "Kick")]
    assert "Kick" in page.evaluate("window.vidstyle.classes")
    assert "Kick" in page.inner_text("#classes")
    wait_saved(page)
    assert [(s.start, s.end, s.action) for s in read_annotations(ann).videos[0].segments] == [(100, N, "Kick")]
    # a broken file: one error line in the status, the marks unchanged
    broken = tmp / "broken.cvat.xml"
    broken.write_bytes(cvat.read_bytes()[:200])
    _import(page, "cvat", broken)
    page.wait_for_function("() => document.getElementById('status').className === 'error'")
    status = page.inner_text("#status")
    assert "\n" not in status.strip() and "cvat" in status.lower()
    assert _segments(page) == [(100, N, "Kick")]
    # one undo step per import
    page.keyboard.press("Control+z")
    assert _segments(page) == [(0, 5, "Guard"), (60, 70, "Hook")]
    assert errors == []
    page.close()


def _magenta(png: bytes) -> np.ndarray:
    """Mask of the performer marker's colour (#ff3df2) in a screenshot."""
    img = cv2.imdecode(np.frombuffer(png, np.uint8), cv2.IMREAD_COLOR).astype(int)
    return (img[..., 2] > 200) & (img[..., 1] < 120) & (img[..., 0] > 190)


def _click_video_pixel(page, x: int, y: int, w: int = 320, h: int = 240):
    """Click where the page shows the centre of video pixel (x, y) (the image is scaled to the stage), at the
    nearest whole CSS pixel as a mouse does; returns the image's box and the point clicked."""
    box = page.locator("#frame").bounding_box()
    at = (round(box["x"] + (x + 0.5) * box["width"] / w), round(box["y"] + (y + 0.5) * box["height"] / h))
    page.mouse.click(*at)
    return box, at


def test_choose_performer_stores_the_clicked_video_pixel(browser, app):
    """Choose performer (button or P), then a click on the frame: the file holds that frame and the clicked
    pixel of the 320x240 video, whatever the frame's displayed size; the marker is drawn on that frame
    only; Esc cancels pick mode; Clear and undo go through the same save path."""
    url, ann, _ = app
    errors, scales = [], []
    for viewport, (px, py), frame in [({"width": 1280, "height": 800}, (250, 60), 37),
                                      ({"width": 1000, "height": 560}, (13, 201), 90),
                                      ({"width": 760, "height": 420}, (301, 17), 5)]:
        page = browser.new_page(viewport=viewport)
        page.on("pageerror", lambda e: errors.append(str(e)))
        page.goto(url + "/")
        assert shown_number(page) == 0
        goto(page, frame)
        # a click without pick mode, and one after Esc, choose nobody
        _click_video_pixel(page, px, py)
        page.keyboard.press("p")
        assert "Click the performer" in page.inner_text("#performer-pick")
        page.keyboard.press("Escape")
        _click_video_pixel(page, px, py)
        assert state(page).get("performer") is None and page.evaluate("window.vidstyle.changes") == 0
        before = int(_magenta(page.locator("#stage").screenshot()).sum())
        still = page.locator("#frame").bounding_box()
        page.click("#performer-pick")
        box, at = _click_video_pixel(page, px, py)
        assert box == still  # pick mode does not move the frame under the mouse
        scale = box["width"] / 320
        scales.append(scale)
        got = state(page)["performer"]
        if scale >= 1:  # every video pixel spans a whole CSS pixel: exactly the one aimed at
            assert got == {"frame": frame, "x": px, "y": py}
        else:  # shrunk: the stored pixel is the one under the point clicked
            assert got["frame"] == frame
            for v, c, lo, size, n in ((got["x"], at[0], box["x"], box["width"], 320),
                                      (got["y"], at[1], box["y"], box["height"], 240)):
                assert v * size / n <= c - lo < (v + 1) * size / n
            px, py = got["x"], got["y"]
            assert abs(px - 301) <= 1 and abs(py - 17) <= 1
        wait_saved(page)
        saved = read_annotations(ann)
        assert (saved.videos[0].performer.frame, saved.videos[0].performer.x, saved.videos[0].performer.y) == (frame, px, py)
        assert f"frame {frame}, pixel ({px}, {py})" in page.inner_text("#performer-info")
        # the marker: a ring of radius 10 px about the clicked pixel, on this frame only
        page.wait_for_timeout(100)
        box, stage = page.locator("#frame").bounding_box(), page.locator("#stage").bounding_box()
        if os.environ.get("VIDSTYLE_SCREENSHOT_PERFORMER"):
            page.screenshot(path=os.environ["VIDSTYLE_SCREENSHOT_PERFORMER"])
        shot = page.locator("#stage").screenshot()
        mask = _magenta(shot)
        assert before == 0 and mask.sum() > 40
        cx = box["x"] - stage["x"] + (px + 0.5) * box["width"] / 320
        cy = box["y"] - stage["y"] + (py + 0.5) * box["height"] / 240
        for dx, dy in ((10, 0), (-10, 0), (0, 10), (0, -10)):
            x, y = round(cx + dx), round(cy + dy)
            if 0 <= x < mask.shape[1] and 0 <= y < mask.shape[0]:
                assert mask[max(0, y - 2):y + 3, max(0, x - 2):x + 3].any(), (dx, dy)
        page.keyboard.press("f")
        assert shown_number(page) == frame + 1
        page.wait_for_timeout(100)
        assert int(_magenta(page.locator("#stage").screenshot()).sum()) == 0
        # Clear, then undo: each saved
        page.click("#performer-clear")
        wait_saved(page)
        assert read_annotations(ann).videos[0].performer is None
        assert "none chosen" in page.inner_text("#performer-info")
        page.keyboard.press("Control+z")
        wait_saved(page)
        assert read_annotations(ann).videos[0].performer.frame == frame
        # the side panel's choice goes to its frame
        page.click("#performer-info")
        assert shown_number(page) == frame
        page.keyboard.press("Control+z")  # back to no choice for the next round
        wait_saved(page)
        assert read_annotations(ann).videos[0].performer is None
        page.close()
    assert scales[0] > 1.5 and scales[-1] < 1  # enlarged and shrunk displays
    assert errors == []


@pytest.fixture
def two_videos(tmp_path):
    vids = [numbered_video(tmp_path / "a.mp4", 40, 25.0, size=(160, 120)),
            numbered_video(tmp_path / "b.mp4", 30, 25.0, size=(160, 120), vfr=True, seed=2)]
    ann = tmp_path / "annotations.json"
    yield vids, ann


def _select(page, vid):
    page.select_option("#video", vid)
    page.wait_for_function(f"() => window.vidstyle.vid.id === '{vid}'")
    assert shown_number(page) == 0


def test_a_409_merges_changes_to_other_videos_and_an_outside_write_is_seen_after_reload(browser, two_videos):
    vids, ann = two_videos
    with Running(session(vids, ann)) as url, Running(session(vids, ann)) as url2:  # two processes' servers
        a, b = browser.new_page(), browser.new_page()
        a.goto(url + "/")
        b.goto(url2 + "/")
        for p in (a, b):
            assert shown_number(p) == 0
        a.keyboard.press("t")                       # a: a transition on video 0
        wait_saved(a)
        _select(b, "1")                             # b (other server, stale): a transition on video 1
        b.keyboard.press("f")
        b.keyboard.press("t")
        wait_saved(b)                               # 409, merged (other video), saved again
        assert not b.evaluate("window.vidstyle.conflict")
        saved = read_annotations(ann)
        assert saved.revision == 2
        assert [t.frame for t in saved.videos[0].transitions] == [0]
        assert [t.frame for t in saved.videos[1].transitions] == [1]
        assert b.evaluate("window.vidstyle.marks['0'].transitions.length") == 1  # b now shows a's mark
        # both change the same video: a real conflict, nothing overwritten
        a.keyboard.press("f")
        a.keyboard.press("t")
        wait_saved(a)
        _select(b, "0")
        b.keyboard.press("End")
        b.keyboard.press("t")
        b.wait_for_function("() => window.vidstyle.conflict")
        assert "conflict" in b.inner_text("#status")
        assert [t.frame for t in read_annotations(ann).videos[0].transitions] == [0, 1]
        # an outside write, then a reload of the page: the page sees it and saves from it
        outside = read_annotations(ann)
        outside.videos[1].transitions = []
        outside.revision += 5
        from vidstyle.formats.annotations import write_annotations

        write_annotations(ann, outside)
        b.reload()
        assert shown_number(b) == 0
        assert b.evaluate("window.vidstyle.revision") == outside.revision
        b.keyboard.press("v")
        b.keyboard.press("t")
        wait_saved(b)
        saved = read_annotations(ann)
        assert saved.revision == outside.revision + 1 and saved.videos[1].transitions == []
        assert [t.frame for t in saved.videos[0].transitions] == [0, 1, 10]
        a.close(), b.close()


def test_beyond_loopback_the_page_takes_the_key_from_the_fragment_or_asks(browser, tmp_path):
    vid = numbered_video(tmp_path / "k.mp4", 20, 25.0)
    s = session([vid], tmp_path / "keyed.json")
    s.secret = "the-secret-" + "k" * 24
    with Running(s) as kurl:
        page = browser.new_page()
        page.goto(f"{kurl}/#key={s.secret}")
        assert shown_number(page) == 0
        page.keyboard.press("f")
        page.keyboard.press("t")
        wait_saved(page)
        assert [t.frame for t in read_annotations(tmp_path / "keyed.json").videos[0].transitions] == [1]
        page.close()
        page = browser.new_page()             # no key in the URL: the page asks for it
        asked = []
        page.on("dialog", lambda d: (asked.append(d.message), d.accept(f"{kurl}/#key={s.secret}")))
        page.goto(f"{kurl}/")
        assert shown_number(page) == 0 and len(asked) == 1 and "key" in asked[0]
        page.keyboard.press("t")
        wait_saved(page)
        assert [t.frame for t in read_annotations(tmp_path / "keyed.json").videos[0].transitions] == [0, 1]
        page.close()


@pytest.fixture
def recognised_app(tmp_path):
    """A session with recognised labels at half the video's rate (each label covers two decoded frames),
    with a confidence per label."""
    video = numbered_video(tmp_path / "rec.mp4", 60, 25.0, size=(320, 240))
    n = 30
    labels = ["Jab"] * 20 + ["Hook"] * (n - 20)
    confidence = [round(0.05 + (k % 10) / 10, 2) for k in range(n)]
    rec = tmp_path / "rec.json"
    rec.write_text(json.dumps({"video": str(video), "fps": 12.5, "classes": ["Jab", "Hook", "Guard"],
                               "labels": labels, "confidence": confidence}))
    s = session([video], tmp_path / "annotations.json")
    s.overlays = load_overlays(s.videos, labels=[rec])
    with Running(s) as url:
        yield url


def _header_layout(page) -> dict:
    return page.evaluate("""() => {
        const box = (id) => { const r = document.getElementById(id).getBoundingClientRect();
                              return [Math.round(r.left), Math.round(r.top), Math.round(r.width), Math.round(r.height)]; };
        return {header: Math.round(document.querySelector('header').getBoundingClientRect().height),
                status: box('status'), save: box('save'), video: box('video')};
    }""")


@pytest.mark.parametrize("width", [1280, 1100, 900])
def test_page_icon_stable_header_and_recognised_label_of_the_frame(browser, recognised_app, width):
    """No console error on load (the icon is declared and served, no /favicon.ico 404); the header keeps its
    height and layout when the pending-segment message appears; the recognised action and its confidence
    of the current frame are shown beside it and follow frame steps."""
    url = recognised_app
    page = browser.new_page(viewport={"width": width, "height": 800})
    problems = []
    page.on("console", lambda m: problems.append(m.text) if m.type == "error" else None)
    page.on("pageerror", lambda e: problems.append(str(e)))
    page.on("response", lambda r: problems.append(f"{r.status} {r.url}") if r.status >= 400 else None)
    page.goto(url + "/")
    assert shown_number(page) == 0
    icon = page.evaluate("() => { const l = document.querySelector('link[rel~=\"icon\"]'); return l && l.href; }")
    assert icon, "the page declares no icon: the browser asks for /favicon.ico"
    for where in (icon, url + "/favicon.ico"):
        got = page.request.get(where)
        assert got.status == 200 and got.headers["content-type"].startswith("image/svg+xml"), where
    page.wait_for_timeout(300)
    assert problems == []

    # the header: the same height and the same places with and without the pending-segment message
    before = _header_layout(page)
    page.keyboard.press("[")
    page.wait_for_function("() => document.getElementById('pending').textContent.includes('segment from 0')")
    assert _header_layout(page) == before
    page.keyboard.press("Escape")
    goto(page, 57)
    page.keyboard.press("[")
    page.wait_for_function("() => document.getElementById('pending').textContent.includes('segment from 57')")
    assert _header_layout(page) == before

    # the recognised action of the current frame, beside it: frames 2k and 2k+1 are working frame k
    def recognised():
        return page.inner_text("#recognised")

    assert page.is_visible("#recognised")
    goto(page, 0)
    assert "Jab" in recognised() and "confidence 0.05" in recognised()
    page.keyboard.press("f")
    assert shown_number(page) == 1 and "Jab" in recognised() and "confidence 0.05" in recognised()
    page.keyboard.press("f")
    assert shown_number(page) == 2 and "Jab" in recognised() and "confidence 0.15" in recognised()
    goto(page, 41)  # working frame 20: the first Hook
    assert "Hook" in recognised() and "confidence 0.05" in recognised()
    page.keyboard.press("d")
    page.keyboard.press("d")
    assert shown_number(page) == 39 and "Jab" in recognised() and "confidence 0.95" in recognised()
    assert problems == []
    page.close()
