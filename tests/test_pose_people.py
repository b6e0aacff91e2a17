"""Following one performer among several people (vidstyle.pose.people), with a stand-in backend whose
behaviour is known exactly: like BlazePose it returns the single most prominent person in the image it
is given (here: the largest coloured rectangle), so without the tracker it jumps to whoever is biggest."""

from __future__ import annotations

import numpy as np
import pytest

from vidstyle.errors import ParameterError
from vidstyle.formats.poses import PoseFrame
from vidstyle.pose.people import PerformerTracker, appearance_distance, find_people, iou

BG = (90, 90, 90)
#: 15 keypoints in the unit square of a person's box (head top, neck, pelvis, shoulders, ... ankles)
TEMPLATE = np.array([[0.5, 0.0], [0.5, 0.2], [0.5, 0.55], [0.2, 0.22], [0.8, 0.22], [0.1, 0.4], [0.9, 0.4],
                     [0.05, 0.55], [0.95, 0.55], [0.3, 0.55], [0.7, 0.55], [0.3, 0.78], [0.7, 0.78],
                     [0.3, 1.0], [0.7, 1.0]])


class LargestRectangle:
    """The most prominent (largest) non-background rectangle's keypoints, or nobody."""

    def __init__(self):
        self.calls = 0

    def estimate(self, frame, index=0, background=None):
        self.calls += 1
        packed = frame.astype(np.uint32) @ np.array([1, 256, 65536], np.uint32)
        codes, counts = np.unique(packed, return_counts=True)
        bg = BG[0] + 256 * BG[1] + 65536 * BG[2]
        people = [(n, np.array([c & 255, (c >> 8) & 255, c >> 16], np.uint8)) for c, n in zip(codes, counts) if c != bg]
        if not people:
            pts = np.zeros((15, 3))
            return PoseFrame(index, "unknown", pts, {})
        _, colour = max(people, key=lambda t: t[0])  # the most visible person
        ys, xs = np.nonzero(np.all(frame == colour, axis=-1))
        x, y, w, h = xs.min(), ys.min(), xs.max() - xs.min() + 1, ys.max() - ys.min() + 1
        pts = np.column_stack([x + TEMPLATE[:, 0] * (w - 1), y + TEMPLATE[:, 1] * (h - 1), np.full(15, 0.9)])
        return PoseFrame(index, "front", pts, {"front": 1.0}, azimuth=12.5)


def _scene(people, size=(240, 320)):
    """people: list of (colour, x0, y0, w, h) drawn in order (later ones in front)."""
    img = np.empty((*size, 3), np.uint8)
    img[:] = BG
    for colour, x0, y0, w, h in people:
        img[y0:y0 + h, x0:x0 + w] = colour
    return img


RED, BLUE, GREEN = (30, 30, 220), (220, 40, 30), (40, 200, 40)


def _crossing(frames=40):
    """Red (chosen: the biggest at the start) stands left; blue walks in from the right, passes in front
    of red growing larger (approaching the camera), and leaves to the left; then red is hidden for five
    frames (off screen) and comes back at another place."""
    out, truth = [], []
    for f in range(frames):
        red = (RED, 60, 60, 50, 120)
        bx = 260 - 6 * f
        scale = 1.0 + 0.02 * f
        blue = (BLUE, max(0, bx), 70, int(40 * scale), int(100 * scale))
        people = [red, blue] if bx > -40 else [red]
        if 30 <= f < 35:
            people = [p for p in people if p[0] != RED]
            truth.append(None)
        elif f >= 35:
            people = [(RED, 200, 80, 50, 120)] + [p for p in people if p[0] != RED]
            truth.append((200, 80, 50, 120))
        else:
            truth.append(red[1:])
        out.append(_scene(people))
    return out, truth


def _on(box, rect):
    x0, y0, w, h = rect
    return iou(box, np.array([x0, y0, x0 + w - 1, y0 + h - 1], float)) > 0.5


def test_without_the_tracker_the_backend_jumps_to_the_biggest_person():
    frames, truth = _crossing()
    backend = LargestRectangle()
    on_red = []
    for f, img in enumerate(frames):
        pose = backend.estimate(img, f)
        on_red.append(truth[f] is not None and np.allclose(pose.points[0, 0], truth[f][0] + 0.5 * (truth[f][2] - 1)))
    assert not all(on_red[:30])  # the premise: blue takes over when it is larger


def test_tracker_stays_on_the_performer_and_reacquires_after_occlusion():
    frames, truth = _crossing()
    tracker = PerformerTracker(LargestRectangle())
    switches, missing = 0, []
    for f, img in enumerate(frames):
        t = tracker.step(img, f)
        if truth[f] is None:
            assert t.pose is None and t.missing == "performer not found"
            missing.append(f)
            continue
        assert t.pose is not None, f"frame {f}: lost the performer ({t.missing})"
        assert t.pose.frame == f and t.pose.azimuth == 12.5  # the backend's fields survive the crop search
        # identity: the pose's neck lies on the performer (red) even when blue hides most of them
        x, y = np.round(t.pose.points[1, :2]).astype(int)
        if tuple(img[y, x]) != RED:
            switches += 1
    assert switches == 0
    assert missing == [30, 31, 32, 33, 34]


def test_person_option_picks_the_person_at_a_pixel():
    img = _scene([(RED, 20, 40, 60, 150), (BLUE, 200, 60, 40, 100)])
    tracker = PerformerTracker(LargestRectangle(), person=(220, 100))
    t = tracker.step(img, 0)
    assert _on(t.box, (200, 60, 40, 100)) and t.people == 2
    # default: the most prominent (largest) person
    t = PerformerTracker(LargestRectangle()).step(img, 0)
    assert _on(t.box, (20, 40, 60, 150))


def test_find_people_enumerates_everyone_and_nobody_is_none():
    img = _scene([(RED, 20, 40, 60, 150), (BLUE, 200, 60, 40, 100), (GREEN, 120, 10, 30, 60)])
    people = find_people(LargestRectangle(), img, max_people=4)
    assert len(people) == 3
    assert [round(p.prominence) for p in people] == sorted((round(p.prominence) for p in people), reverse=True)
    assert appearance_distance(people[0].appearance, people[1].appearance) > 0.5
    t = PerformerTracker(LargestRectangle()).step(_scene([]), 0)
    assert t.pose is None and t.missing == "nobody found"


@pytest.mark.parametrize(("kw", "param"), [({"person": (np.nan, 1.0)}, "person"), ({"max_people": 0}, "max_people"),
                                           ({"search": 0.5}, "search"), ({"min_iou": 2.0}, "min_iou"),
                                           ({"max_appearance": -1.0}, "max_appearance")])
def test_parameters_are_checked(kw, param):
    with pytest.raises(ParameterError) as e:
        PerformerTracker(LargestRectangle(), **kw)
    assert e.value.param == param


# ------------------------------------------------------------------ the performer chosen at a frame
class RectangleBackend(LargestRectangle):
    """:class:`LargestRectangle` as a ``vidstyle pose --backend`` (registered by the tests that use it)."""

    uses_background = False

    def working_height(self, native_height):
        return native_height

    def set_inference(self, scales=None):
        return self

    def close(self):
        pass


def _passing(frames=30):
    """Red (the bigger, so the most prominent) walks right along the top, blue walks left along the bottom;
    they never overlap. (130, 175) is on blue at frame 25, and nearest red (the nearest box centre) at the
    start: where the choice is made decides who is followed."""
    return [_scene([(RED, 20 + 6 * f, 10, 60, 100), (BLUE, 260 - 6 * f, 130, 40, 90)]) for f in range(frames)]


def _on_colour(img, pose):
    x, y = np.round(pose.points[1, :2]).astype(int)  # the neck
    return tuple(int(c) for c in img[y, x])


def test_follow_chooses_at_the_start_frame_and_tracks_both_ways():
    frames = _passing()
    pick = [1, 2, 3, 14, 28, 29]  # the choice's frame (25) is not among them
    for start, who in ((25, BLUE), (None, RED)):  # None: the first frame with people, as --person
        ts = PerformerTracker(LargestRectangle(), person=(130, 175)).follow(lambda i: frames[i], pick, start)
        assert [t.index for t in ts] == pick
        assert all(t.pose is not None and _on_colour(frames[t.index], t.pose) == who for t in ts), start
    # nobody at the chosen frame: the choice falls back to the first frame with people (logged)
    frames[25] = _scene([])
    ts = PerformerTracker(LargestRectangle(), person=(130, 175)).follow(lambda i: frames[i], pick, 25)
    assert all(_on_colour(frames[t.index], t.pose) == RED for t in ts)


@pytest.fixture
def passing_video(tmp_path, monkeypatch):
    """The passing scene as a lossless video, its annotations (marks at 3 and 27; the performer: blue,
    clicked at frame 25) and the stand-in backend registered as ``rectangles``."""
    from video_util import write_lossless

    from vidstyle.formats import poses
    from vidstyle.formats.annotations import (
        Annotations,
        PerformerChoice,
        Transition,
        VideoAnnotations,
        file_sha256,
        write_annotations,
    )
    from vidstyle.pose import interfaces

    monkeypatch.setitem(interfaces.BACKENDS, "rectangles", "test_pose_people:RectangleBackend")
    monkeypatch.setattr(poses, "BACKENDS", (*poses.BACKENDS, "rectangles"))  # poses.json may name it
    frames = _passing()
    video = write_lossless(tmp_path / "two.mov", frames)
    ann = tmp_path / "ann.json"
    entry = VideoAnnotations(video.name, file_sha256(video), len(frames), 20.0,
                             [Transition(3, "a", "b"), Transition(27, "b", "a")],
                             performer=PerformerChoice(25, 130.0, 175.0))
    write_annotations(ann, Annotations(["a", "b"], [entry]))
    return frames, video, ann


def test_pose_annotations_follow_the_performer_chosen_in_the_file(passing_video, tmp_path, caplog, capsys):
    from vidstyle.cli import main
    from vidstyle.formats.annotations import read_annotations, write_annotations
    from vidstyle.formats.poses import read_poses
    from vidstyle.pose.run import estimate_marks

    frames, video, ann = passing_video
    marks = [1, 2, 3, 4, 5, 25, 26, 27, 28, 29]
    with caplog.at_level("INFO", logger="vidstyle.pose.run"):
        poses = estimate_marks(video, ann, "rectangles", context=2, jobs=1)
    assert "the person at pixel (130, 175) of frame 25, as chosen in" in caplog.text
    assert [pf.frame for pf in poses.frames] == marks
    assert all(pf.found and _on_colour(frames[pf.frame], pf) == BLUE for pf in poses.frames)
    assert poses.params == {"tracked": True, "person": [130.0, 175.0], "person_frame": 25}
    # the CLI (-j 1: the stand-in backend is registered in this process only): the same poses; --person
    # overrides the file (chosen at the first marked frame: red); --no-track ignores it (the backend alone
    # takes the most prominent, red)
    out = tmp_path / "p.json"
    cli = ["pose", str(video), "-a", str(ann), "--backend", "rectangles", "-j", "1", "-o", str(out)]
    assert main([*cli, "--context", "2"]) == 0
    written = read_poses(out)
    assert written.params == poses.params and [pf.frame for pf in written.frames] == marks
    np.testing.assert_allclose([pf.points for pf in written.frames], [pf.points for pf in poses.frames], atol=0.006)
    for extra in (["--person", "130,175"], ["--no-track"]):
        assert main([*cli, "--context", "2", *extra]) == 0
        assert all(_on_colour(frames[pf.frame], pf) == RED for pf in read_poses(out).frames), extra
    # a choice outside this video's 320x240 frame: one line naming the file, exit 2, no output
    a = read_annotations(ann)
    a.videos[0].performer.x = 320.0
    write_annotations(ann, a)
    out.unlink()
    capsys.readouterr()
    assert main(cli) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and str(ann) in err and "outside" in err and not out.exists()


def test_person_frame_is_checked(passing_video):
    from vidstyle.pose.run import estimate_video

    _, video, _ = passing_video
    for kw in ({"person_frame": 3}, {"person": (1.0, 1.0), "person_frame": 30},
               {"person": (1.0, 1.0), "person_frame": -1}):
        with pytest.raises(ParameterError) as e:
            estimate_video(video, "rectangles", track=True, **kw)
        assert e.value.param == "person_frame"
