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
   forward to the later frames and, from the same state, backward to the earlier ones.
3. **Following**: each frame, the backend first runs on the whole frame; when the person it returns
   overlaps the performer's last box (IoU >= ``min_iou``) with a matching appearance (torso colour
   within ``max_appearance``), that is the pose (so with one person in view the poses are exactly the
   untracked ones). Otherwise the backend runs on a crop around the last box (enlarged by ``search``),
   where other people outside it are not seen at all; a person found there is accepted by the same
   test, else painted over and the crop searched again. A performer hidden behind someone else is
   missing for those frames rather than swapped for the other person. When the crop has no accepted person, the whole frame is
   searched and the performer re-acquired by appearance (HSV histogram of the torso, Bhattacharyya
   distance <= ``max_appearance``) after an occlusion of any length.
4. Frames without the performer are ``None`` with a reason (``missing``), never fake points.

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
    """why there is no pose: ``"nobody found"``, ``"performer not found"``"""
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
    x0, y0, x1, y1 = (int(round(v)) for v in box)
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


class PerformerTracker:
    """Follow one performer (module docstring). Parameters are checked here (``ParameterError``)."""

    def __init__(self, backend, person: tuple[float, float] | None = None, max_people: int = 4,
                 search: float = 1.6, min_iou: float = 0.2, max_appearance: float = 0.45,
                 max_tries: int = 2, tiles: int = 2) -> None:
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
        self.backend = backend
        self.person = None if person is None else (float(person[0]), float(person[1]))
        self.max_people = max_people
        self.search = search
        self.min_iou = min_iou
        self.max_appearance = max_appearance
        self.max_tries = max_tries
        if not (isinstance(tiles, int) and 1 <= tiles <= 4):
            raise ParameterError("tiles", f"must be an integer in 1..4, got {tiles!r}")
        self.tiles = tiles
        self.box: np.ndarray | None = None
        self.look: np.ndarray | None = None

    # ------------------------------------------------------------------ choice
    def choose(self, people: list[Person]) -> Person:
        if self.person is None:
            return max(people, key=lambda p: p.prominence)
        x, y = self.person
        inside = [p for p in people if p.box[0] <= x <= p.box[2] and p.box[1] <= y <= p.box[3]]
        if inside:
            return min(inside, key=lambda p: (p.box[2] - p.box[0]) * (p.box[3] - p.box[1]))
        return min(people, key=lambda p: float(np.hypot(*(p.centre - (x, y)))))

    def _accept(self, p: Person) -> bool:
        """A person found in the crop or the whole frame is the performer: near the last box and alike
        (:meth:`_same_person`), or, once lost, alike by appearance alone."""
        if self.box is not None and iou(p.box, self.box) >= self.min_iou:
            return self._same_person(p)
        return appearance_distance(p.appearance, self.look) <= self.max_appearance

    def _same_person(self, p: Person) -> bool:
        """Strict test for the backend's whole-frame choice: it overlaps the last box and looks like the
        performer (or, with no appearance to compare, overlaps it by half)."""
        if self.box is None or iou(p.box, self.box) < self.min_iou:
            return False
        if p.appearance is None or self.look is None:
            return iou(p.box, self.box) >= 0.5
        return appearance_distance(p.appearance, self.look) <= self.max_appearance

    def _remember(self, p: Person) -> None:
        self.box = p.box
        if p.appearance is not None:
            self.look = p.appearance if self.look is None else (0.9 * self.look + 0.1 * p.appearance)

    # ------------------------------------------------------------------- steps
    def _search_crop(self, frame: np.ndarray, index: int) -> Person | None:
        h, w = frame.shape[:2]
        cx, cy = (self.box[0] + self.box[2]) / 2, (self.box[1] + self.box[3]) / 2
        half = self.search * max(self.box[2] - self.box[0], self.box[3] - self.box[1]) / 2
        x0, y0 = int(max(0, cx - half)), int(max(0, cy - half))
        x1, y1 = int(min(w, cx + half + 1)), int(min(h, cy + half + 1))
        if x1 - x0 < 16 or y1 - y0 < 16:
            return None
        crop = frame[y0:y1, x0:x1]
        for p in find_people(self.backend, crop, index, self.max_tries, (float(x0), float(y0)), frame.shape[:2]):
            if self._accept(p):
                return p
        return None

    def step(self, frame: np.ndarray, index: int) -> TrackedFrame:
        if self.box is not None:
            # the backend's own choice on the whole frame first: when it is the performer (the usual case,
            # and always with one person in view) the pose is exactly the untracked one
            p = next(iter(_find(self.backend, frame, index, 1, (0.0, 0.0), None)), None)
            if p is not None and self._same_person(p):
                self._remember(p)
                return TrackedFrame(index, p.pose, None, 0, p.box)
            p = self._search_crop(frame, index)
            if p is not None:
                self._remember(p)
                return TrackedFrame(index, p.pose, None, 0, p.box)
        people = find_people(self.backend, frame, index, self.max_people, tiles=self.tiles)
        if not people:
            return TrackedFrame(index, None, "nobody found", 0)
        if self.box is None and self.look is None:
            chosen = self.choose(people)
            log.info("frame %d: following the performer at box %s (%d people in view)", index,
                     np.round(chosen.box).astype(int).tolist(), len(people))
            self._remember(chosen)
            return TrackedFrame(index, chosen.pose, None, len(people), chosen.box)
        matches = [p for p in people if self._accept(p)]
        if not matches:
            self.box = None  # lost: re-acquire by appearance only
            return TrackedFrame(index, None, "performer not found", len(people))
        best = min(matches, key=lambda p: appearance_distance(p.appearance, self.look))
        self._remember(best)
        return TrackedFrame(index, best.pose, None, len(people), best.box)

    def track(self, frames: Iterable[tuple[int, np.ndarray]]) -> Iterator[TrackedFrame]:
        for index, frame in frames:
            yield self.step(frame, index)

    def follow(self, read: Callable[[int], np.ndarray], frames: list[int],
               start: int | None = None) -> list[TrackedFrame]:
        """The performer in each of ``frames`` (``read(i)``: frame ``i``), in the order of ``frames``.

        ``start`` None: the frames in their order (:meth:`track`: the choice at the first with people).
        ``start`` = a frame index (one of ``frames`` or not): the choice (``person``) is made at that frame,
        then the performer is followed forward over the later frames and, from the state right after the
        choice (last box, torso appearance), backward over the earlier ones in descending order: each frame
        continues from its neighbour nearer ``start``, which is symmetric in time. When nobody is found at
        ``start``, the frames are tracked in order as with ``start`` None (logged)."""
        if start is None:
            return [self.step(read(i), i) for i in frames]
        if self.box is not None or self.look is not None:
            raise ValueError("follow(start=...) needs a tracker that has not chosen yet")
        first = self.step(read(start), start)
        if first.pose is None:
            log.warning("frame %d: nobody found where the performer was chosen; choosing at the first frame "
                        "with people instead", start)
            return [self.step(read(i), i) for i in frames]
        back = copy.copy(self)  # the state after the choice; step() rebinds box and look, never mutates them
        out = {start: first}
        for i in sorted(f for f in frames if f > start):
            out[i] = self.step(read(i), i)
        for i in sorted((f for f in frames if f < start), reverse=True):
            out[i] = back.step(read(i), i)
        return [out[i] for i in frames]
