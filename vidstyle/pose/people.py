"""One performer, followed through a video, with any single-person pose backend.

Single-person estimators (BlazePose, the pictorial structures) return *a* person per frame: with several
people in view they jump between them. :class:`PerformerTracker` turns such a backend into a tracker:

1. **People in a frame** (:func:`find_people`): run the backend, take the person it finds, paint over
   their box with the frame's median colour, run again, up to ``max_people``; then the same on a grid of
   overlapping tiles (``tiles``), which finds people too small for the detector in the whole frame.
   Every person found is a :class:`Person` (keypoints in frame pixels, box, mean keypoint confidence,
   appearance histogram). Only choosing and re-acquiring the performer search the whole frame.
2. **The performer** is chosen in the first frame where anyone is found: by default the most prominent
   person, i.e. the largest box area times mean keypoint confidence (the person nearest the camera and
   clearly seen); ``person=(x, y)`` picks the person whose box contains that pixel (the nearest box
   centre if none does). A choice made at a known frame (``vidstyle annotate``'s performer: a frame and a
   pixel) is made there instead: :meth:`PerformerTracker.follow` chooses at that frame, then follows
   forward to the later frames and, from the same state, backward to the earlier ones (every gap and
   velocity below is measured in frames either way, so following is symmetric in time).
3. **Following** (:meth:`PerformerTracker.step`): a candidate is the performer when it passes two tests.
   *Motion*: its box centre lies within ``reach`` x the performer's size of where a constant-velocity
   model (damped by ``momentum``) puts the performer, the reach growing with the square root of the frames
   since the performer was last seen, and its size is within a factor 2. *Appearance*: its torso colour
   (HSV histogram, Bhattacharyya distance) is within ``max_appearance`` of the performer's memory **and**
   closer to it by ``margin`` than to every other person remembered who could be standing there (not one
   seen elsewhere in the same frame, nor one last seen beyond the motion gate's reach): two people who
   look alike are told apart by appearance only when the evidence is clear, else by where they stand.
   *Pose* (``max_jump``; only with other people about, where a
   single-person backend may merge two overlapping people into one pose): the median keypoint moved at
   most ``max_jump`` x the performer's size from its last pose (shifted by the predicted motion) per
   square root of the frames since. Each frame the backend first runs on the whole frame; when the
   person it returns passes (the usual case, and always with one person in view) that is the pose, exactly
   the untracked one. Otherwise the backend runs on a crop around the predicted place (``search`` x the
   performer's size), painting over each person found there that fails; then on the whole frame
   (``find_people``), where the performer may be re-acquired anywhere by appearance alone (the same
   two-sided test) after an occlusion of any length, though not as a pose over the expected place that
   failed the tests there (a bad view of the performer, or someone in front of them).
4. **Memories**: the performer's appearance is updated (rate ``LOOK_RATE``) only from frames where nobody
   else was seen overlapping it; everyone else seen (people not passing the motion gate, or not looking
   like the performer) is remembered with their last box and, from views clear of the performer, their
   appearance. These are the "other people" of the appearance test.
5. Frames without the performer are ``None`` with a reason (``missing``), never fake points: ``"performer
   hidden"`` when someone else stands where the performer is expected (a performer passing behind someone
   is missing for those frames, not swapped for the person in front: a missing frame costs accuracy, a
   swap gives the next stage someone else's motion), ``"performer not found"`` otherwise, ``"nobody
   found"`` when the backend finds no one at all.

The backend only needs ``estimate(frame, index) -> PoseFrame`` (:class:`vidstyle.pose.interfaces.PoseBackend`)
and to report nobody found as viewpoint ``"unknown"`` or all scores 0.
"""

from __future__ import annotations

import copy
import logging
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass, field, replace

import numpy as np

from ..errors import ParameterError
from ..formats.poses import UNKNOWN, PoseFrame

log = logging.getLogger(__name__)

#: keypoints with at least this score define a person's box and appearance
MIN_SCORE = 0.3
#: torso keypoints (shoulders and hips) for the appearance histogram: indices in the 15-keypoint order
TORSO = (3, 4, 9, 10)


@dataclass
class Person:
    points: np.ndarray
    """(15, 3) x, y, score in frame pixels"""
    box: np.ndarray
    """(4,) x0, y0, x1, y1"""
    score: float
    appearance: np.ndarray | None = None
    pose: PoseFrame | None = None

    @property
    def prominence(self) -> float:
        w, h = self.box[2] - self.box[0], self.box[3] - self.box[1]
        return float(max(w, 0) * max(h, 0) * self.score)

    @property
    def centre(self) -> np.ndarray:
        return np.array([(self.box[0] + self.box[2]) / 2, (self.box[1] + self.box[3]) / 2])


@dataclass
class TrackedFrame:
    index: int
    pose: PoseFrame | None
    missing: str | None = None
    """why there is no pose: ``"nobody found"``, ``"performer not found"``, ``"performer hidden"``"""
    people: int = 0
    """how many people were seen when the whole frame was searched (0 if it was not)"""
    box: np.ndarray | None = field(default=None, repr=False)


def box_of(points: np.ndarray, shape: tuple[int, int], margin: float = 0.12) -> np.ndarray | None:
    """Box around the confidently found keypoints, enlarged by ``margin`` of its size, clipped to the frame."""
    ok = points[:, 2] >= MIN_SCORE
    if ok.sum() < 3:
        return None
    xy = points[ok, :2]
    x0, y0 = xy.min(axis=0)
    x1, y1 = xy.max(axis=0)
    mx, my = margin * max(x1 - x0, 1.0), margin * max(y1 - y0, 1.0)
    h, w = shape[:2]
    return np.array([max(0.0, x0 - mx), max(0.0, y0 - my), min(w - 1.0, x1 + mx), min(h - 1.0, y1 + my)])


def iou(a: np.ndarray, b: np.ndarray) -> float:
    ix = max(0.0, min(a[2], b[2]) - max(a[0], b[0]))
    iy = max(0.0, min(a[3], b[3]) - max(a[1], b[1]))
    inter = ix * iy
    union = (a[2] - a[0]) * (a[3] - a[1]) + (b[2] - b[0]) * (b[3] - b[1]) - inter
    return float(inter / union) if union > 0 else 0.0


def appearance(frame: np.ndarray, points: np.ndarray) -> np.ndarray | None:
    """Normalised hue-saturation histogram (8 x 8) of the torso quadrilateral, or None."""
    import cv2

    torso = points[list(TORSO)]
    if np.any(torso[:, 2] < MIN_SCORE) or frame.ndim != 3:
        return None
    quad = torso[[0, 1, 3, 2], :2].round().astype(np.int32)  # ls, rs, rh, lh
    # only the quadrilateral's bounding box is converted (not the whole frame: this runs every frame)
    h, w = frame.shape[:2]
    x0, y0 = np.clip(quad.min(axis=0), 0, [w - 1, h - 1])
    x1, y1 = np.clip(quad.max(axis=0), 0, [w - 1, h - 1])
    mask = np.zeros((y1 - y0 + 1, x1 - x0 + 1), np.uint8)
    cv2.fillConvexPoly(mask, quad - [x0, y0], 255)
    if mask.sum() < 255 * 20:
        return None
    hsv = cv2.cvtColor(np.ascontiguousarray(frame[y0:y1 + 1, x0:x1 + 1]), cv2.COLOR_BGR2HSV)
    hist = cv2.calcHist([hsv], [0, 1], mask, [8, 8], [0, 180, 0, 256]).ravel()
    s = hist.sum()
    return (hist / s).astype(np.float32) if s > 0 else None


def appearance_distance(a: np.ndarray | None, b: np.ndarray | None) -> float:
    """Bhattacharyya distance in [0, 1] (0: identical); 1 when either is unknown."""
    if a is None or b is None:
        return 1.0
    bc = float(np.sum(np.sqrt(a * b)))
    return float(np.sqrt(max(0.0, 1.0 - bc)))


def _found(pose: PoseFrame) -> bool:
    return pose.viewpoint != UNKNOWN and bool(np.any(pose.points[:, 2] > 0))


def _shift(pose: PoseFrame, dx: float, dy: float, index: int) -> PoseFrame:
    """``pose`` moved by (dx, dy) pixels (found in a crop, placed in the frame); every other field kept."""
    pts = pose.points.copy()
    pts[:, 0] += dx
    pts[:, 1] += dy
    return replace(pose, frame=index, points=pts, viewpoint_scores=dict(pose.viewpoint_scores))


def _paint(frame: np.ndarray, box: np.ndarray) -> np.ndarray:
    out = frame.copy()
    x0, y0, x1, y1 = (round(float(v)) for v in box)
    fill = np.median(frame.reshape(-1, frame.shape[-1]) if frame.ndim == 3 else frame.ravel(), axis=0)
    out[y0:y1 + 1, x0:x1 + 1] = fill.astype(frame.dtype)
    return out


def find_people(backend, frame: np.ndarray, index: int = 0, max_people: int = 4,
                offset: tuple[float, float] = (0.0, 0.0), full_shape: tuple[int, int] | None = None,
                tiles: int = 1) -> list[Person]:
    """Everyone the backend finds in ``frame``, by repeatedly painting over the person just found.

    ``tiles`` > 1: then also search a ``tiles`` x ``tiles`` grid of overlapping tiles (half a tile of
    overlap) with the people found so far painted over: a single-person detector working on a shrunk
    whole frame (BlazePose's is 224 px wide) misses people who are small in a large frame."""
    people = _find(backend, frame, index, max_people, offset, full_shape)
    if tiles > 1 and len(people) < max_people:
        h, w = frame.shape[:2]
        work = frame
        for p in people:
            work = _paint(work, p.box - np.array([*offset, *offset]))
        th, tw = int(np.ceil(2 * h / (tiles + 1))), int(np.ceil(2 * w / (tiles + 1)))
        for ty in range(tiles):
            for tx in range(tiles):
                y0, x0 = min(h - th, ty * th // 2), min(w - tw, tx * tw // 2)
                found = _find(backend, work[y0:y0 + th, x0:x0 + tw], index, max_people - len(people),
                              (offset[0] + x0, offset[1] + y0), full_shape or frame.shape[:2])
                for p in found:
                    if all(iou(p.box, q.box) < 0.3 for q in people):
                        people.append(p)
                        work = _paint(work, p.box - np.array([*offset, *offset]))
                if len(people) >= max_people:
                    return people
    return people


def _find(backend, frame: np.ndarray, index: int, max_people: int, offset: tuple[float, float],
          full_shape: tuple[int, int] | None) -> list[Person]:
    people: list[Person] = []
    work = frame
    shape = full_shape or frame.shape[:2]
    for _ in range(max_people):
        pose = backend.estimate(work, index)
        if not _found(pose):
            break
        local_box = box_of(pose.points, work.shape)
        if local_box is None:
            break
        if any(iou(local_box, p.box - np.array([*offset, *offset])) > 0.6 for p in people):
            break  # the backend returned someone already painted over (it saw through the paint)
        pts = pose.points.copy()
        pts[:, 0] += offset[0]
        pts[:, 1] += offset[1]
        box = box_of(pts, shape)
        ok = pts[:, 2] >= MIN_SCORE
        people.append(Person(pts, box, float(pts[ok, 2].mean()) if ok.any() else 0.0,
                             appearance(work, pose.points), _shift(pose, *offset, index)))
        work = _paint(work, local_box)
    return people


@dataclass(eq=False)
class _Other:
    """Someone seen who is not the performer: where they were last seen, and how they look (learned only
    when they were seen clear of the performer, so the performer's colours never leak into it)."""

    box: np.ndarray
    index: int
    look: np.ndarray | None = None


#: rate at which a clear, confident view updates an appearance memory (exponential moving average)
LOOK_RATE = 0.1
#: a candidate's size (larger box side) may differ from the performer's expected size by this factor
MAX_SIZE_RATIO = 2.0
#: other people remembered (the least recently seen are forgotten first)
MAX_OTHERS = 8
#: frames an other person's last box still counts as where they are (overlap and occlusion tests)
RECENT = 2


class PerformerTracker:
    """Follow one performer (module docstring). Parameters are checked here (``ParameterError``)."""

    def __init__(self, backend, person: tuple[float, float] | None = None, max_people: int = 4,
                 search: float = 1.6, min_iou: float = 0.2, max_appearance: float = 0.45,
                 max_tries: int = 2, tiles: int = 2, margin: float = 0.1, reach: float = 0.35,
                 momentum: float = 0.5, max_gap: int = 10, max_jump: float | None = 0.3) -> None:
        if person is not None and (len(person) != 2 or not all(np.isfinite(person))):
            raise ParameterError("person", f"expected a finite pixel x,y, got {person!r}")
        if not (isinstance(max_people, int) and 1 <= max_people <= 16):
            raise ParameterError("max_people", f"must be an integer in 1..16, got {max_people!r}")
        if not (np.isfinite(search) and 1.0 <= search <= 10.0):
            raise ParameterError("search", f"must be in [1, 10], got {search!r}")
        if not (np.isfinite(min_iou) and 0.0 <= min_iou <= 1.0):
            raise ParameterError("min_iou", f"must be in [0, 1], got {min_iou!r}")
        if not (np.isfinite(max_appearance) and 0.0 <= max_appearance <= 1.0):
            raise ParameterError("max_appearance", f"must be in [0, 1], got {max_appearance!r}")
        if not (isinstance(tiles, int) and 1 <= tiles <= 4):
            raise ParameterError("tiles", f"must be an integer in 1..4, got {tiles!r}")
        if not (np.isfinite(margin) and 0.0 <= margin <= 1.0):
            raise ParameterError("margin", f"must be in [0, 1], got {margin!r}")
        if not (np.isfinite(reach) and 0.0 < reach <= 10.0):
            raise ParameterError("reach", f"must be in (0, 10], got {reach!r}")
        if not (np.isfinite(momentum) and 0.0 <= momentum <= 1.0):
            raise ParameterError("momentum", f"must be in [0, 1], got {momentum!r}")
        if not (isinstance(max_gap, int) and 1 <= max_gap <= 10_000):
            raise ParameterError("max_gap", f"must be an integer in 1..10000, got {max_gap!r}")
        self.backend = backend
        self.person = None if person is None else (float(person[0]), float(person[1]))
        self.max_people = max_people
        self.search = search
        self.min_iou = min_iou
        self.max_appearance = max_appearance
        self.max_tries = max_tries
        self.tiles = tiles
        self.margin = margin
        self.reach = reach
        self.momentum = momentum
        self.max_gap = max_gap
        if max_jump is not None and not (np.isfinite(max_jump) and max_jump > 0):
            raise ParameterError("max_jump", f"must be positive (or None: off), got {max_jump!r}")
        self.max_jump = max_jump
        self.points: np.ndarray | None = None
        # the performer: last box, when it was seen, its centre's velocity (pixels / frame), its size
        # (larger box side, smoothed) and its appearance memory
        self.box: np.ndarray | None = None
        self.seen: int | None = None
        self.centre: np.ndarray | None = None
        self.velocity = np.zeros(2)
        self.size = 0.0
        self.look: np.ndarray | None = None
        self.others: list[_Other] = []
        self._observed: list[np.ndarray] = []  # boxes of other people seen in the current frame
        self._people: list[Person] = []  # everyone found in the current frame so far

    # ------------------------------------------------------------------ choice
    def choose(self, people: list[Person]) -> Person:
        if self.person is None:
            return max(people, key=lambda p: p.prominence)
        x, y = self.person
        inside = [p for p in people if p.box[0] <= x <= p.box[2] and p.box[1] <= y <= p.box[3]]
        if inside:
            return min(inside, key=lambda p: (p.box[2] - p.box[0]) * (p.box[3] - p.box[1]))
        return min(people, key=lambda p: float(np.hypot(*(p.centre - (x, y)))))

    # ------------------------------------------------------------------ motion
    def gap(self, index: int) -> int:
        """Frames since the performer was last seen, either way in time (0 before it was ever seen)."""
        return 0 if self.seen is None else max(abs(index - self.seen), 1)

    def tracking(self, index: int) -> bool:
        """The motion model still knows where the performer is (seen within ``max_gap`` frames)."""
        return self.seen is not None and self.gap(index) <= self.max_gap

    def predicted(self, index: int) -> np.ndarray:
        """Where the performer's box centre is expected in frame ``index`` (constant velocity, damped by
        ``momentum``, extrapolated over at most ``max_gap`` frames)."""
        return self.centre + self.momentum * self.velocity * min(self.gap(index), self.max_gap)

    def predicted_box(self, index: int) -> np.ndarray:
        (cx, cy), (w, h) = self.predicted(index), self.box[2:] - self.box[:2]
        return np.array([cx - w / 2, cy - h / 2, cx + w / 2, cy + h / 2])

    def near(self, p: Person, index: int) -> bool:
        """Motion gate: ``p``'s box centre within ``reach`` x the performer's size of the predicted centre
        (the reach growing with the square root of the frames since it was seen) and a size within a factor
        ``MAX_SIZE_RATIO`` of the performer's."""
        if not self.tracking(index):
            return False
        size = max(p.box[2] - p.box[0], p.box[3] - p.box[1])
        if not (self.size / MAX_SIZE_RATIO <= size <= self.size * MAX_SIZE_RATIO):
            return False
        d = float(np.hypot(*(p.centre - self.predicted(index))))
        return d <= self.reach * self.size * np.sqrt(self.gap(index))

    # -------------------------------------------------------------- appearance
    def _rivals(self, p: Person, index: int) -> float:
        """The smallest appearance distance from ``p`` to anyone else remembered who could be standing there
        (1 when there is none), so that two people dressed alike are told apart by where they stand: not
        someone seen elsewhere in this frame (a person found apart from ``p``, outside the performer's
        motion gate, who looks like them), nor someone last seen farther from ``p`` than the motion gate
        reaches in the frames since."""
        elsewhere = [q for q in self._people if q is not p and q.appearance is not None
                     and iou(q.box, p.box) < self.min_iou and not self.near(q, index)]
        ds = []
        for o in self.others:
            if o.look is None or any(appearance_distance(q.appearance, o.look) <= self.max_appearance
                                     for q in elsewhere):
                continue
            size = max(o.box[2] - o.box[0], o.box[3] - o.box[1], 1.0)
            centre = (o.box[:2] + o.box[2:]) / 2
            if float(np.hypot(*(p.centre - centre))) > self.reach * size * np.sqrt(max(abs(index - o.index), 1)):
                continue
            ds.append(appearance_distance(p.appearance, o.look))
        return min(ds, default=1.0)

    def looks_like(self, p: Person, index: int) -> bool:
        """Appearance test: ``p``'s torso within ``max_appearance`` of the performer's memory, and closer to
        it by ``margin`` than to anyone else remembered (so a person who looks like the performer but as
        much like someone else is not taken for the performer)."""
        if p.appearance is None or self.look is None:
            return False
        d = appearance_distance(p.appearance, self.look)
        return d <= self.max_appearance and d + self.margin <= self._rivals(p, index)

    def _crowded(self, box: np.ndarray, index: int) -> bool:
        """Someone else was seen (this frame or the last ``RECENT``) overlapping ``box``."""
        return any(iou(box, b) >= self.min_iou for b in self._observed) or any(
            abs(index - o.index) <= RECENT and iou(box, o.box) >= self.min_iou for o in self.others)

    def is_performer(self, p: Person, index: int) -> bool:
        """Near the performer's predicted place and looking like it; with no torso to compare (or none
        remembered yet), overlapping the predicted box by half with nobody else about."""
        if not self.near(p, index):
            return False
        if p.appearance is None or self.look is None:
            return iou(p.box, self.predicted_box(index)) >= 0.5 and not self._crowded(p.box, index)
        return self.looks_like(p, index) and self.steady(p, index)

    def jump(self, p: Person, index: int) -> float:
        """Median distance (performer sizes) of ``p``'s keypoints from the performer's last ones moved by
        the predicted motion, over the keypoints confident in both; 0 when there are fewer than 3."""
        if self.points is None:
            return 0.0
        ok = (p.points[:, 2] >= MIN_SCORE) & (self.points[:, 2] >= MIN_SCORE)
        if ok.sum() < 3:
            return 0.0
        shift = self.predicted(index) - self.centre
        return float(np.median(np.linalg.norm(p.points[ok, :2] - self.points[ok, :2] - shift, axis=1))) / self.size

    def steady(self, p: Person, index: int) -> bool:
        """Keypoint gate (``max_jump``, only with other people about: a single-person backend may then mix
        two people into one pose): the pose moved at most ``max_jump`` x sqrt(frames since)."""
        if self.max_jump is None or not self.others:
            return True
        return self.jump(p, index) <= self.max_jump * np.sqrt(self.gap(index))

    # ------------------------------------------------------------------ memory
    def _accept(self, p: Person, index: int, people: int = 0) -> TrackedFrame:
        ambiguous = self._crowded(p.box, index)
        centre = p.centre
        size = max(float(max(p.box[2] - p.box[0], p.box[3] - p.box[1])), 1.0)
        if self.seen is not None and 0 < abs(index - self.seen) <= 2:  # per frame in the direction of travel
            step = (centre - self.centre) / abs(index - self.seen)
            self.velocity = 0.5 * self.velocity + 0.5 * step
        else:  # first sight, or after a gap: no velocity known
            self.velocity = np.zeros(2)
        self.size = size if self.seen is None else 0.7 * self.size + 0.3 * size
        self.box, self.centre, self.seen, self.points = p.box, centre, index, p.points
        if p.appearance is not None and not ambiguous:  # memory only from clear, unshared views
            self.look = p.appearance if self.look is None else (1 - LOOK_RATE) * self.look + LOOK_RATE * p.appearance
        return TrackedFrame(index, p.pose, None, people, p.box)

    def _observe(self, p: Person, index: int) -> None:
        """``p`` is not the performer. When it is clearly someone else (outside the motion gate while the
        performer is tracked, or not looking like the performer), remember where it is and, seen clear of
        the performer, how it looks. Once the performer is lost (not seen for ``max_gap`` frames) someone
        who looks like them is not remembered as someone else: they are the one to re-acquire."""
        if self.near(p, index) or not self.tracking(index):
            if p.appearance is None or self.look is None:
                return  # could be the performer badly seen: not evidence about anyone else
            d = appearance_distance(p.appearance, self.look)
            if d <= self.max_appearance and self._rivals(p, index) + self.margin > d:
                return  # as likely the performer as anyone else
        if any(iou(p.box, b) > 0.6 for b in self._observed):
            return  # already seen in this frame
        self._observed.append(p.box)
        clear = self.box is None or iou(p.box, self.predicted_box(index) if self.tracking(index) else self.box) < self.min_iou
        match = None
        if p.appearance is not None:
            known = [(appearance_distance(p.appearance, o.look), o) for o in self.others if o.look is not None]
            d, o = min(known, key=lambda t: t[0], default=(1.0, None))
            match = o if d <= self.max_appearance else None
        if match is None:
            recent = [o for o in self.others if abs(index - o.index) <= RECENT and iou(p.box, o.box) >= self.min_iou]
            match = max(recent, key=lambda o: iou(p.box, o.box), default=None)
        if match is None:
            match = _Other(p.box, index)
            self.others.append(match)
            if len(self.others) > MAX_OTHERS:
                self.others.remove(min(self.others, key=lambda o: o.index))
        match.box, match.index = p.box, index
        if clear and p.appearance is not None:
            match.look = p.appearance if match.look is None else (1 - LOOK_RATE) * match.look + LOOK_RATE * p.appearance

    # ------------------------------------------------------------------- steps
    def _search_crop(self, frame: np.ndarray, index: int) -> Person | None:
        h, w = frame.shape[:2]
        cx, cy = self.predicted(index)
        half = self.search * self.size / 2
        x0, y0 = int(max(0, cx - half)), int(max(0, cy - half))
        x1, y1 = int(min(w, cx + half + 1)), int(min(h, cy + half + 1))
        if x1 - x0 < 16 or y1 - y0 < 16:
            return None
        crop = frame[y0:y1, x0:x1]
        people = find_people(self.backend, crop, index, self.max_tries, (float(x0), float(y0)), frame.shape[:2])
        self._people += people
        for p in people:
            if self.is_performer(p, index):
                return p
            self._observe(p, index)
        return None

    def _first(self, frame: np.ndarray, index: int) -> TrackedFrame:
        people = find_people(self.backend, frame, index, self.max_people, tiles=self.tiles)
        if not people:
            return TrackedFrame(index, None, "nobody found", 0)
        self._people = list(people)
        chosen = self.choose(people)
        log.info("frame %d: following the performer at box %s (%d people in view)", index,
                 np.round(chosen.box).astype(int).tolist(), len(people))
        for p in people:  # everyone else, remembered when seen clear of the performer
            if p is not chosen and iou(p.box, chosen.box) < self.min_iou:
                self._observed.append(p.box)
                self.others.append(_Other(p.box, index, p.appearance))
        return self._accept(chosen, index, len(people))

    def step(self, frame: np.ndarray, index: int) -> TrackedFrame:
        self._observed, self._people = [], []
        if self.seen is None:
            return self._first(frame, index)
        # the backend's own choice on the whole frame first: when it is the performer (the usual case,
        # and always with one person in view) the pose is exactly the untracked one
        p = next(iter(_find(self.backend, frame, index, 1, (0.0, 0.0), None)), None)
        if p is not None:
            self._people.append(p)
            if self.is_performer(p, index):
                return self._accept(p, index)
            self._observe(p, index)
        if self.tracking(index):
            p = self._search_crop(frame, index)
            if p is not None:
                return self._accept(p, index)
        # not where it was expected: search the whole frame; near the expected place first, else anyone
        # who looks like the performer clearly more than like anyone else (re-acquisition)
        people = find_people(self.backend, frame, index, self.max_people, tiles=self.tiles)
        if not people:
            return TrackedFrame(index, None, "nobody found", 0)
        self._people += people
        found = [q for q in people if self.is_performer(q, index)]
        if not found:  # elsewhere: a pose over the expected place that failed the tests is a bad view of
            # the performer (or of someone in front of them), not the performer found somewhere else
            expected = self.predicted_box(index) if self.tracking(index) else None
            found = [q for q in people if not self.near(q, index) and self.looks_like(q, index)
                     and (expected is None or iou(q.box, expected) < self.min_iou)]
        if found:
            best = min(found, key=lambda q: appearance_distance(q.appearance, self.look))
            return self._accept(best, index, len(people))
        for q in people:
            self._observe(q, index)
        hidden = False
        if self.tracking(index):  # someone else stands where the performer is expected
            x, y = self.predicted(index)
            hidden = any(b[0] <= x <= b[2] and b[1] <= y <= b[3] for b in self._observed)
        return TrackedFrame(index, None, "performer hidden" if hidden else "performer not found", len(people))

    def track(self, frames: Iterable[tuple[int, np.ndarray]]) -> Iterator[TrackedFrame]:
        for index, frame in frames:
            yield self.step(frame, index)

    def follow(self, read: Callable[[int], np.ndarray], frames: list[int],
               start: int | None = None) -> list[TrackedFrame]:
        """The performer in each of ``frames`` (``read(i)``: frame ``i``), in the order of ``frames``.

        ``start`` None: the frames in their order (:meth:`track`: the choice at the first with people).
        ``start`` = a frame index (one of ``frames`` or not): the choice (``person``) is made at that frame,
        then the performer is followed forward over the later frames and, from the state right after the
        choice (last box, motion, torso appearance, the other people seen), backward over the earlier ones
        in descending order: each frame continues from its neighbour nearer ``start``, which is symmetric in
        time. When nobody is found at
        ``start``, the frames are tracked in order as with ``start`` None (logged)."""
        if start is None:
            return [self.step(read(i), i) for i in frames]
        if self.seen is not None:
            raise ValueError("follow(start=...) needs a tracker that has not chosen yet")
        first = self.step(read(start), start)
        if first.pose is None:
            log.warning("frame %d: nobody found where the performer was chosen; choosing at the first frame "
                        "with people instead", start)
            return [self.step(read(i), i) for i in frames]
        back = copy.copy(self)  # the state after the choice; step() rebinds the arrays, mutates only the others
        back.others = [copy.copy(o) for o in self.others]
        out = {start: first}
        for i in sorted(f for f in frames if f > start):
            out[i] = self.step(read(i), i)
        for i in sorted((f for f in frames if f < start), reverse=True):
            out[i] = back.step(read(i), i)
        return [out[i] for i in frames]
