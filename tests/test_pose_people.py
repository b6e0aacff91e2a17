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
