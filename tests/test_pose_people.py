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
            # off screen while blue walks over the place red was last seen: hidden, as far as anyone can tell
            assert t.pose is None and t.missing in ("performer not found", "performer hidden")
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
                                           ({"max_appearance": -1.0}, "max_appearance"), ({"margin": -0.1}, "margin"),
                                           ({"reach": 0.0}, "reach"), ({"momentum": 1.5}, "momentum"),
                                           ({"max_gap": 0}, "max_gap")])
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


# ------------------------------------------------------------------ a performer passing behind someone alike
class LargestBody(LargestRectangle):
    """Like :class:`LargestRectangle`, but a person is a body colour (any other colour is clothing detail):
    the one with most visible pixels, its box that colour's pixels' box."""

    def __init__(self, bodies):
        super().__init__()
        self.bodies = [np.array(c, np.uint8) for c in bodies]

    def estimate(self, frame, index=0, background=None):
        self.calls += 1
        masks = [np.all(frame == c, axis=-1) for c in self.bodies]
        counts = [int(m.sum()) for m in masks]
        if max(counts) < 30:
            return PoseFrame(index, "unknown", np.zeros((15, 3)), {})
        ys, xs = np.nonzero(masks[int(np.argmax(counts))])
        x, y, w, h = xs.min(), ys.min(), xs.max() - xs.min() + 1, ys.max() - ys.min() + 1
        pts = np.column_stack([x + TEMPLATE[:, 0] * (w - 1), y + TEMPLATE[:, 1] * (h - 1), np.full(15, 0.9)])
        return PoseFrame(index, "front", pts, {"front": 1.0})

    def working_height(self, native_height):
        return native_height


#: two people in the same red (same hue-saturation bins, told apart by the stand-in backend only by the
#: exact value) with a band of another colour across the chest: their torso histograms differ by ~0.4,
#: within the appearance threshold, so appearance alone cannot say which is which
ALIKE = ((30, 30, 220), (40, 200, 40)), ((30, 30, 200), (220, 40, 30))


def _alike(colours, x0, y0, w, h, rng):
    body, band = colours
    jitter = rng.integers(-1, 2, 2)  # a little unsteadiness, seeded
    return [(body, x0 + int(jitter[0]), y0 + int(jitter[1]), w, h),
            (band, x0 + int(jitter[0]), y0 + int(jitter[1]) + int(0.36 * h), w, max(2, int(0.05 * h)))]


def _passing_behind(seed=0, frames=48):
    """A (the performer, standing) is passed in front by B, who looks alike, is nearer
    (larger) and walks from right to left across the view, hiding A completely for several frames."""
    rng = np.random.default_rng(seed)
    out, truth = [], []
    for f in range(frames):
        a = (100, 70, 50, 120)
        bx = 250 - 5 * f
        b = (bx, 55, 56, 140)
        people = _alike(ALIKE[0], *a, rng) + (_alike(ALIKE[1], *b, rng) if bx > -56 else [])
        out.append(_scene(people))
        truth.append({"A": a, "B": b})
    return out, truth


def _nearest(pose, truth):
    """"A" or "B": whose template keypoints the pose's keypoints lie closest to."""
    def template(rect):
        x0, y0, w, h = rect
        return np.column_stack([x0 + TEMPLATE[:, 0] * (w - 1), y0 + TEMPLATE[:, 1] * (h - 1)])
    d = {k: float(np.linalg.norm(pose.points[:, :2] - template(r), axis=1).mean()) for k, r in truth.items()}
    return min(d, key=d.get)


def test_alike_people_are_alike_by_appearance_alone():
    """The premise: the two torsos are within the appearance threshold of each other."""
    people = find_people(LargestBody([c[0] for c in ALIKE]), _passing_behind()[0][0], max_people=2)
    assert len(people) == 2
    assert 0.2 < appearance_distance(people[0].appearance, people[1].appearance) < 0.45


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_performer_passing_behind_someone_alike_is_missing_not_swapped(seed):
    frames, truth = _passing_behind(seed)
    tracker = PerformerTracker(LargestBody([c[0] for c in ALIKE]), person=(125, 130))  # A (B is larger)
    on, hidden = [], []
    for f, img in enumerate(frames):
        t = tracker.step(img, f)
        a_x0, a_w = truth[f]["A"][0], truth[f]["A"][2]
        b_x0, b_w = truth[f]["B"][0], truth[f]["B"][2]
        covered = b_x0 <= a_x0 and b_x0 + b_w >= a_x0 + a_w
        if t.pose is None:
            hidden.append(f)
            assert t.missing == "performer hidden", f"frame {f}: {t.missing}"
        else:
            on.append(_nearest(t.pose, truth[f]))
            assert on[-1] == "A", f"frame {f}: followed the other person"
        assert not (covered and t.pose is not None), f"frame {f}: A is fully hidden, yet a pose was given"
    fully = [f for f in range(len(frames)) if truth[f]["B"][0] <= 100 and truth[f]["B"][0] + 56 >= 150]
    assert fully and set(fully) <= set(hidden)  # the premise: A was hidden for a while, and missing then
    assert len(hidden) < 12  # and found again once B has passed: the last frames are all on A
    assert on[-10:] == ["A"] * 10


class Garbling(LargestBody):
    """On the frames ``bad`` the limbs are mirrored left to right in the same box, the torso kept: what a
    single-person backend does when it mixes two overlapping people into one pose, in its simplest form
    (the box and the torso's colours stay: only the keypoint gate can tell)."""

    def __init__(self, bodies, bad):
        super().__init__(bodies)
        self.bad = set(bad)

    def estimate(self, frame, index=0, background=None):
        pose = super().estimate(frame, index, background)
        if index in self.bad and pose.viewpoint != "unknown":
            limbs = [5, 6, 7, 8, 11, 12, 13, 14]
            x0, x1 = pose.points[:, 0].min(), pose.points[:, 0].max()
            pose.points[limbs, 0] = x0 + x1 - pose.points[limbs, 0]
        return pose


@pytest.mark.parametrize("others", [True, False])
def test_keypoint_gate_drops_a_jumping_pose_only_with_other_people_about(others):
    rng = np.random.default_rng(3)
    bad = (10, 11, 20)
    frames = [_scene(_alike(ALIKE[0], 100, 70, 80, 120, rng) + (_alike(ALIKE[1], 230, 55, 56, 140, rng) if others else []))
              for _ in range(30)]
    for max_jump, expect_gated in ((0.1, others), (None, False)):  # mirrored limbs: the median moves by ~0.25
        tracker = PerformerTracker(Garbling([c[0] for c in ALIKE], bad), person=(125, 130), max_jump=max_jump)
        got = [tracker.step(img, f) for f, img in enumerate(frames)]
        assert all(t.pose is not None for f, t in enumerate(got) if f not in bad)
        gated = [f for f, t in enumerate(got) if t.pose is None]
        assert gated == (list(bad) if expect_gated else [])
    # alone in view, the poses are the backend's own, garbled or not
    if not others:
        assert np.allclose(got[10].pose.points, Garbling([ALIKE[0][0]], bad).estimate(frames[10], 10).points)


def test_follow_person_reads_a_video_and_leaves_missing_frames_empty(tmp_path):
    from video_util import write_lossless

    from vidstyle.evaluation.people import follow_person, totals

    frames, _ = _passing_behind(0)
    video = write_lossless(tmp_path / "pass.mov", frames)
    est = follow_person(video, (125, 130), LargestBody([c[0] for c in ALIKE]))
    assert est.shape == (len(frames), 15, 3)
    missing = np.isnan(est[:, 0, 0])
    tracker = PerformerTracker(LargestBody([c[0] for c in ALIKE]), person=(125, 130))
    assert missing.tolist() == [tracker.step(img, f).pose is None for f, img in enumerate(frames)]
    assert 0 < missing.sum() < 12 and np.all(np.isnan(est[missing]))
    t = totals([{"identity_switches": 1, "frames": 50, "pck@0.2": 0.5, "missing": 3},
                {"identity_switches": 0, "frames": 50, "pck@0.2": 0.7, "missing": 0}])
    assert t == {"frames": 100, "identity_switches": 1, "identity_switches_per_100_frames": 1.0,
                 "pck@0.2": pytest.approx(0.6), "missing_frames": 3}


def test_a_stream_of_new_people_is_remembered_up_to_a_limit():
    """Each frame someone new (a colour of their own, the largest in view) walks in far from the performer:
    each is remembered, the least recently seen forgotten first, and the performer is kept throughout."""
    import cv2

    from vidstyle.pose.people import MAX_OTHERS

    tracker = PerformerTracker(LargestRectangle(), person=(40, 100))
    n = MAX_OTHERS + 4
    for f in range(n):
        # a hue-saturation bin of their own, none of them red's
        hsv = np.uint8([[[int(22.5 * (1 + f % 6) + 11), 120 if f < 6 else 220, 220]]])
        colour = tuple(int(v) for v in cv2.cvtColor(hsv, cv2.COLOR_HSV2BGR)[0, 0])
        x = (110, 180, 250)[f % 3]  # not where anyone was seen in the last frames (that would be the same person)
        t = tracker.step(_scene([(RED, 20, 40, 40, 100), (colour, x, 20, 60, 180)]), f)
        assert t.pose is not None and _on(t.box, (20, 40, 40, 100))
    assert len(tracker.others) == MAX_OTHERS
    assert min(o.index for o in tracker.others) == n - MAX_OTHERS


def test_people_dressed_identically_are_told_apart_by_where_they_stand():
    """Same torso colours (same histogram bins): appearance cannot separate them, the motion gate can, as
    long as the other is seen standing elsewhere."""
    a, b = (30, 30, 220), (30, 30, 210)
    backend = LargestBody([a, b])
    rng = np.random.default_rng(5)
    frames = [_scene([(a, 40 + int(rng.integers(-2, 3)), 60, 50, 120), (b, 200 - f, 40, 60, 160)]) for f in range(25)]
    people = find_people(backend, frames[0], max_people=2)
    assert appearance_distance(people[0].appearance, people[1].appearance) < 0.05  # the premise
    tracker = PerformerTracker(backend, person=(65, 120))
    for f, img in enumerate(frames):
        t = tracker.step(img, f)
        assert t.pose is not None and t.box[0] < 120, f"frame {f}: {t.missing or 'the other person'}"


def test_tracker_defaults_are_the_validated_choice():
    """The library defaults are what ``scripts/validate_people.py`` chose on validation crowds."""
    import inspect
    import json
    from pathlib import Path

    table = json.loads((Path(__file__).parents[1] / "pipelines/kickboxing/validation/people.json").read_text())
    defaults = {k: v.default for k, v in inspect.signature(PerformerTracker).parameters.items()}
    assert table["chosen"]["params"] == {k: defaults[k] for k in table["chosen"]["params"]}
    # and the choice kept the previous tracker's PCK with fewer identity switches
    assert table["chosen"]["pck@0.2"] >= table["before"]["pck@0.2"]
    assert table["chosen"]["identity_switches"] < table["before"]["identity_switches"]
