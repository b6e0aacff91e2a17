"""Salient points per frame (thesis section 4.1): the largest optical flow on the moving silhouette.

For frame t of a (frames, height, width) grayscale volume with intensities in [0, 1]:

1. Silhouette: pixels where |f(t+1) - f(t-1)| > ``threshold`` ("a subtraction between the next and the
   previous frames"). The first frame uses |f(1) - f(0)| and the last |f(T-1) - f(T-2)| (the one-sided
   difference); a one-frame video has no silhouette and therefore no points.
2. Dense optical flow magnitude at the pixels of frame t: the flow from t to t+1, and for the last frame
   the flow from T-1 back to T-2 (so every frame, including the last, has a flow field on its own
   pixel grid).
3. The ``n_points`` silhouette pixels of largest flow magnitude that are at least ``min_distance`` pixels
   apart (Euclidean): greedy non-maximum suppression -- take the largest, suppress every pixel closer
   than ``min_distance``, repeat. Ties go to the first pixel in raster order, so the result is
   deterministic. Fewer points are returned when the silhouette runs out (thesis: N = 10).

Flow method: DIS (Kroeger et al. 2016, ``cv2.DISOpticalFlow``) with the "fast" preset by default. At
160x120 it takes about 0.3 ms per frame against about 3 ms for Farneback (measured on this project's
machines, one thread), and the selection only needs the *ranking* of flow magnitudes on a silhouette,
for which DIS' patch-based estimate is plenty. Farneback and the other DIS presets are available
(``flow="farneback"``, ``"dis-ultrafast"``, ``"dis-medium"``). Both are deterministic for a given input.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from functools import cache
from typing import Any

import numpy as np

from ..errors import InputError

FLOW_METHODS = ("dis", "dis-ultrafast", "dis-medium", "farneback")


@dataclass(frozen=True)
class SalientParams:
    n_points: int = 10
    """Points per frame (thesis: 10)."""
    threshold: float = 0.05
    """Silhouette threshold on |f(t+1) - f(t-1)|, intensities in [0, 1] (0.05 ~ 13 grey levels)."""
    min_distance: float = 5.0
    """Minimum Euclidean distance in pixels between the points of one frame."""
    flow: str = "dis"
    min_flow: float = 0.0
    """Silhouette pixels whose flow magnitude (pixels/frame) is not above this are never chosen."""

    def __post_init__(self) -> None:
        problems = []
        if self.n_points < 0:
            problems.append("n_points must be >= 0")
        if not self.threshold >= 0:
            problems.append("threshold must be >= 0")
        if not self.min_distance >= 0:
            problems.append("min_distance must be >= 0")
        if self.flow not in FLOW_METHODS:
            problems.append(f"flow must be one of {', '.join(FLOW_METHODS)}, got {self.flow!r}")
        if not self.min_flow >= 0:
            problems.append("min_flow must be >= 0")
        if problems:
            raise InputError("salient-point parameters: " + "; ".join(problems))

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


def silhouette(frames: np.ndarray, t: int, threshold: float) -> np.ndarray:
    """Boolean mask of frame t: |f(t+1) - f(t-1)| > threshold, one-sided at the first/last frame."""
    T = frames.shape[0]
    if T < 2:
        return np.zeros(frames.shape[1:], dtype=bool)
    prev, nxt = max(t - 1, 0), min(t + 1, T - 1)
    return np.abs(frames[nxt].astype(np.float32) - frames[prev].astype(np.float32)) > threshold


def to_uint8(frame: np.ndarray) -> np.ndarray:
    """[0, 1] float frame -> uint8, as the OpenCV flow methods require 8-bit input."""
    return np.clip(np.rint(np.asarray(frame, dtype=np.float32) * 255), 0, 255).astype(np.uint8)


class FlowMagnitude:
    """Dense optical-flow magnitude between two frames with one OpenCV method; every call depends on its
    two frames only."""

    def __init__(self, method: str = "dis") -> None:
        import cv2

        self.method = method
        if method.startswith("dis"):
            preset = {
                "dis": cv2.DISOPTICAL_FLOW_PRESET_FAST,
                "dis-ultrafast": cv2.DISOPTICAL_FLOW_PRESET_ULTRAFAST,
                "dis-medium": cv2.DISOPTICAL_FLOW_PRESET_MEDIUM,
            }[method]
            self._preset = preset
        elif method != "farneback":
            raise InputError(f"flow: expected one of {', '.join(FLOW_METHODS)}, got {method!r}")

    def __call__(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """|flow| (pixels/frame) at the pixels of ``a`` towards ``b``; both uint8 (h, w)."""
        flow = self.field(a, b)
        return np.sqrt(flow[..., 0] ** 2 + flow[..., 1] ** 2)

    def field(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """The flow (h, w, 2) float32 (pixels/frame) at the pixels of ``a`` towards ``b``."""
        import cv2

        if self.method == "farneback":
            # OpenCV's documented example parameters (pyramid 0.5 x 3, window 15, 3 iterations)
            flow = cv2.calcOpticalFlowFarneback(a, b, None, 0.5, 3, 15, 3, 5, 1.2, 0)
        else:
            # a fresh DIS object per pair (creating one costs ~5 us): a reused one carries state from its
            # previous call into the next (its result on a pair moves by pixels depending on the pair
            # before, and a size change crashes OpenCV 4.x), so the flow of a frame pair would depend on
            # where a video starts or is cut into windows
            flow = cv2.DISOpticalFlow_create(self._preset).calc(a, b, None)
        return flow


def select_points(score: np.ndarray, n_points: int, min_distance: float) -> np.ndarray:
    """Greedy non-maximum suppression: up to ``n_points`` (row, col) of largest finite ``score``.

    Candidates are the pixels with a finite score (mark excluded pixels with -inf). Each chosen pixel
    removes every pixel closer than ``min_distance`` (Euclidean). Ties: first in raster order.
    """
    s = np.array(score, dtype=np.float32, copy=True)
    H, W = s.shape
    rad = math.ceil(min_distance) - 1 if min_distance > 0 else 0
    d = np.arange(-rad, rad + 1)
    disc = (d[:, None] ** 2 + d[None, :] ** 2) < min_distance * min_distance
    flat = s.reshape(-1)
    out = []
    for _ in range(n_points):
        i = int(np.argmax(flat))
        if not np.isfinite(flat[i]):
            break
        r, c = divmod(i, W)
        out.append((r, c))
        r0, r1, c0, c1 = max(r - rad, 0), min(r + rad + 1, H), max(c - rad, 0), min(c + rad + 1, W)
        sub = s[r0:r1, c0:c1]
        sub[disc[r0 - r + rad : r1 - r + rad, c0 - c + rad : c1 - c + rad]] = -np.inf
        s[r, c] = -np.inf  # min_distance == 0: still never pick the same pixel twice
    return np.asarray(out, dtype=np.int64).reshape(-1, 2)


def _disc(min_distance: float) -> tuple[int, np.ndarray]:
    """The suppression radius and disc (offsets closer than ``min_distance``) of :func:`select_points`."""
    rad = math.ceil(min_distance) - 1 if min_distance > 0 else 0
    d = np.arange(-rad, rad + 1)
    return rad, (d[:, None] ** 2 + d[None, :] ** 2) < min_distance * min_distance


def _frame_points_loop(mask, flow, min_flow, n_points, rad, disc, s, cand, out):
    # compiled by numba: the score of frame_points_numpy (|flow| = sqrt(fx * fx + fy * fy) in float32 on
    # the silhouette where it is above min_flow, a float32 compared in float32, else -inf; never NaN), then
    # select_points on it: n_points times the first maximum in raster order, stop at a value that is not
    # finite, suppress the disc around it and the pixel itself. The maximum is searched among the pixels
    # whose score is above -inf (listed in raster order, so the first maximum is the same); when none is
    # left, np.argmax would find -inf, which stops select_points too. Returns the count.
    H, W = mask.shape
    nc = 0
    for r in range(H):
        for c in range(W):
            fx = flow[r, c, 0]
            fy = flow[r, c, 1]
            m = np.sqrt(fx * fx + fy * fy)
            if mask[r, c] and m > min_flow:
                s[r, c] = m
                cand[nc] = r * W + c
                nc += 1
            else:
                s[r, c] = -np.inf
    n = 0
    for _ in range(n_points):
        best = -np.inf
        bi = -1
        for k in range(nc):
            i = cand[k]
            v = s[i // W, i % W]
            if v > best:
                best, bi = v, i
        if bi < 0 or not np.isfinite(best):
            break
        br, bc = bi // W, bi % W
        out[n, 0] = br
        out[n, 1] = bc
        n += 1
        for r in range(max(br - rad, 0), min(br + rad + 1, H)):
            for c in range(max(bc - rad, 0), min(bc + rad + 1, W)):
                if disc[r - br + rad, c - bc + rad]:
                    s[r, c] = -np.inf
        s[br, bc] = -np.inf
    return n


def frame_points_numpy(mask: np.ndarray, flow: np.ndarray, p: SalientParams) -> np.ndarray:
    """Points (k, 2) (row, column) of one frame from its silhouette ``mask`` and its flow field (h, w, 2)
    float32: :func:`select_points` on the flow magnitude where the silhouette is and the magnitude is
    above ``p.min_flow`` (the reference of :func:`frame_points`)."""
    mag = np.sqrt(flow[..., 0] ** 2 + flow[..., 1] ** 2)
    score = np.where(mask & (mag > p.min_flow), mag, -np.inf)
    return select_points(score, p.n_points, p.min_distance)


@cache
def _frame_points_kernel():
    """The compiled :func:`_frame_points_loop`, or None without numba (then :func:`frame_points_numpy`)."""
    from ..compiled import compile_kernel

    return compile_kernel(_frame_points_loop, None)


def frame_points(mask: np.ndarray, flow: np.ndarray, p: SalientParams) -> np.ndarray:
    """:func:`frame_points_numpy` in one compiled pass (score, then the greedy selection), the same
    points: the same float32 magnitudes and comparisons (``min_flow`` as float32, as numpy compares a
    float32 array with a Python float) and the same first-maximum rule."""
    kernel = _frame_points_kernel()
    flow = np.asarray(flow)
    if kernel is None or flow.dtype != np.float32:  # pragma: no cover - numba is a dependency; OpenCV gives float32
        return frame_points_numpy(mask, flow, p)
    rad, disc = _disc(p.min_distance)
    H, W = mask.shape
    s = np.empty((H, W), dtype=np.float32)
    cand = np.empty(H * W, dtype=np.int64)
    out = np.empty((p.n_points, 2), dtype=np.int64)
    n = kernel(np.ascontiguousarray(mask), np.ascontiguousarray(flow), np.float32(p.min_flow), p.n_points,
               rad, disc, s, cand, out)
    return out[:n]


def salient_points(
    frames: np.ndarray, params: SalientParams | None = None, start: int = 0, stop: int | None = None
) -> np.ndarray:
    """Salient points of frames ``start <= t < stop`` of ``frames`` (T, h, w), intensities in [0, 1].

    Frame t reads frames t-1, t and t+1 only, so the points of ``[start, stop)`` computed on a slab that
    holds one more frame on each side (or ends where the video ends) equal those of the whole video.
    Returns an (n, 3) int32 array of (frame, row, column), sorted by frame, then by decreasing flow.
    """
    p = params or SalientParams()
    frames = np.asarray(frames)
    if frames.ndim != 3:
        raise InputError(f"frames: expected (frames, height, width), got shape {frames.shape}")
    T = frames.shape[0]
    stop = T if stop is None else min(stop, T)
    start = max(0, start)
    if T < 2 or p.n_points == 0 or start >= stop:
        return np.zeros((0, 3), dtype=np.int32)
    flow = FlowMagnitude(p.flow)
    u8 = {}

    def byte(t: int) -> np.ndarray:
        if t not in u8:
            u8[t] = to_uint8(frames[t])
        return u8[t]

    out = []
    for t in range(start, stop):
        mask = silhouette(frames, t, p.threshold)
        if not mask.any():
            continue
        field = flow.field(byte(t), byte(t + 1)) if t < T - 1 else flow.field(byte(t), byte(t - 1))
        rc = frame_points(mask, field, p)
        if len(rc):
            out.append(np.column_stack([np.full(len(rc), t), rc]))
    if not out:
        return np.zeros((0, 3), dtype=np.int32)
    return np.concatenate(out).astype(np.int32)
