"""Enhanced distance (thesis eq. 16, figure 15), the reference point, and the two-half transition.

For a candidate reference frame ``w_z`` of clip ``C_w`` and the transition from source action ``C_a``
into target action ``C_b``, with enhancement half-length ``h``:

    D(z) = min_x [ d_k(a_{i0-x-k+1 .. i0-x},  w_{z-h-k+1 .. z-h}) + lam * x / fps ]
         + min_y [ d_k(w_{z+h .. z+h+k-1},    b_{j0+y .. j0+y+k-1}) + lam * y / fps ]

``d_k`` is the windowed Kovar point-cloud distance (:func:`vidstyle.motiongraph.distance.align_windows`,
RMS over the cloud, minimised over a vertical rotation and a floor translation); ``i0`` is the last frame
the source action may leave from and ``j0`` the first frame the target may be entered at; ``x`` and
``y`` are the responsiveness terms (how much earlier the character leaves ``C_a`` / later it enters
``C_b``: the larger, the slower the transition). The candidate with the smallest ``D`` is the
**reference point**; ``a_{i0-x*} -> w_{z-h}`` and ``w_{z+h} -> b_{j0+y*}`` are its **enhancement nodes**.

The transition (thesis 5.2.5): the first half blends ``a_i .. a_{i+k}`` with ``w_{z-k} .. w_z``, the
second half ``w_z .. w_{z+k}`` with ``b_{j-k} .. b_j`` — here with half-length ``h``: the blend weight
moves from the source to the enhancement segment over the first half and from the segment to the target
over the second, so the character passes exactly through ``w_z`` (:func:`two_half_transition`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..mocap.placement import Placement
from ..motiongraph.blend import slerp
from ..motiongraph.distance import align_windows
from .keypoints import KEYPOINTS

#: keypoint weights of the windowed distance: the torso carries the pose (Kovar: hips/spine weigh more)
_WEIGHT = {"pelvis": 3.0, "neck": 2.0, "left_hip": 2.0, "right_hip": 2.0, "left_shoulder": 1.5,
           "right_shoulder": 1.5, "left_knee": 1.5, "right_knee": 1.5}
KEYPOINT_WEIGHTS = np.array([_WEIGHT.get(k, 1.0) for k in KEYPOINTS])


def window_distance(p: np.ndarray, q: np.ndarray) -> np.ndarray:
    """RMS Kovar distance of windows ``p``, ``q`` (..., k, 15, 3), in their length unit."""
    D, *_ = align_windows(p, q, KEYPOINT_WEIGHTS)
    W = KEYPOINT_WEIGHTS.sum() * p.shape[-3]
    return np.sqrt(np.maximum(D, 0.0) / W)


@dataclass
class EnhancedCost:
    cost: float
    into: float  # source -> segment distance at the best x
    out: float  # segment -> target distance at the best y
    x: int
    y: int


def enhanced_distance(src: np.ndarray, i0: int, w: np.ndarray, z: int, dst: np.ndarray, j0: int, h: int,
                      k: int = 5, max_x: int = 0, max_y: int = 0, lam: float = 0.0, fps: float = 60.0
                      ) -> EnhancedCost | None:
    """Eq. 16 for candidate ``z`` of clip ``w`` (module docstring); all clips are keypoint arrays
    (F, 15, 3). None when the windows do not fit in the clips."""
    a_lo, b_hi = z - h - k + 1, z + h + k - 1
    if a_lo < 0 or b_hi >= len(w):
        return None
    xs = np.arange(0, max_x + 1)
    xs = xs[i0 - xs - k + 1 >= 0]
    ys = np.arange(0, max_y + 1)
    ys = ys[j0 + ys + k - 1 < len(dst)]
    if len(xs) == 0 or len(ys) == 0:
        return None
    wa = w[a_lo:z - h + 1]
    wb = w[z + h:b_hi + 1]
    A = np.stack([src[i0 - x - k + 1:i0 - x + 1] for x in xs])
    B = np.stack([dst[j0 + y:j0 + y + k] for y in ys])
    d_in = window_distance(A, np.broadcast_to(wa, A.shape)) + lam * xs / fps
    d_out = window_distance(np.broadcast_to(wb, B.shape), B) + lam * ys / fps
    bx, by = int(np.argmin(d_in)), int(np.argmin(d_out))
    return EnhancedCost(float(d_in[bx] + d_out[by]), float(d_in[bx]), float(d_out[by]), int(xs[bx]), int(ys[by]))


def enhanced_sides(src: np.ndarray, ends: np.ndarray, w: np.ndarray, z: int, dst: np.ndarray, starts: np.ndarray,
                   h: int, k: int = 5, max_x: int = 0, max_y: int = 0, lam: float = 0.0, fps: float = 60.0):
    """The two halves of eq. 16 for many departures and arrivals at once: for every ``i`` in ``ends``, the
    ``into`` term and best ``x`` of ``enhanced_distance(src, i, w, z, src, i, h, k, max_x, 0)``, and for every
    ``j`` in ``starts`` the ``out`` term and best ``y`` of ``enhanced_distance(dst, j, w, z, dst, j, h, k, 0,
    max_y)`` -- what calling it once per run end and start gives (``inf`` and 0 where it gives None), with
    one batched window distance per side instead of two per call. Returns ``(d_in, x, d_out, y)``."""
    ends = np.asarray(ends, dtype=np.int64)
    starts = np.asarray(starts, dtype=np.int64)
    d_in, bx = np.full(len(ends), np.inf), np.zeros(len(ends), np.int64)
    d_out, by = np.full(len(starts), np.inf), np.zeros(len(starts), np.int64)
    a_lo, b_hi = z - h - k + 1, z + h + k - 1
    if a_lo < 0 or b_hi >= len(w):
        return d_in, bx, d_out, by

    def side(anchor, n_frames, steps, sign, seg, first):
        # candidate windows: (anchor, step) pairs whose window fits the clip, and whose call is not None
        # (enhanced_distance also needs its other side's zero step to fit: j0 + k - 1 < len(dst) on the
        # departure side, i0 - k + 1 >= 0 on the arrival side)
        st = np.arange(steps + 1)
        lo = anchor[:, None] + sign * st[None, :] - (k - 1 if sign < 0 else 0)  # first frame of each window
        ok = (lo >= 0) & (lo + k <= n_frames)
        ok &= ((anchor + k - 1 < n_frames) if sign < 0 else (anchor - k + 1 >= 0))[:, None]
        best, arg = np.full(len(anchor), np.inf), np.zeros(len(anchor), np.int64)
        r, c = np.nonzero(ok)
        if len(r) == 0:
            return best, arg
        frames = lo[r, c][:, None] + np.arange(k)[None, :]
        windows = (src if first else dst)[frames]  # (M, k, 15, 3)
        ref = np.broadcast_to(seg, windows.shape)
        dist = window_distance(windows, ref) if first else window_distance(ref, windows)
        cost = np.full(ok.shape, np.inf)
        cost[r, c] = dist + lam * st[c] / fps
        has = ok.any(1)
        arg[has] = np.argmin(cost[has], axis=1)
        best[has] = cost[has, arg[has]]
        return best, arg

    if len(ends):
        d_in, bx = side(ends, len(src), max_x, -1, w[a_lo:z - h + 1], True)
    if len(starts):
        d_out, by = side(starts, len(dst), max_y, 1, w[z + h:b_hi + 1], False)
    return d_in, bx, d_out, by


def adaptive_halves(src: np.ndarray, i0: int, w: np.ndarray, z: int, dst: np.ndarray, j0: int, halves,
                    k: int = 5) -> tuple[int, int, float] | None:
    """Eq. 16 with each side's half-length chosen on its own: ``(h1, h2, cost)`` minimising
    ``d_k(a_{i0-k+1..i0}, w_{z-h1-k+1..z-h1}) + d_k(w_{z+h2..z+h2+k-1}, b_{j0..j0+k-1})`` over
    ``h1, h2`` in ``halves``. The library segment ``w_{z-h1} .. w_{z+h2}`` then starts where the
    library clip looks most like the departure and ends where it looks most like the arrival, so a
    context clip whose motion leaves the transition pose another way (a stance switch after the hop)
    is cut before it does. None when no half-length fits the windows."""
    if i0 - k + 1 < 0 or j0 + k > len(dst):
        return None
    hs = np.array(sorted({int(x) for x in halves}))
    h1s = hs[(z - hs - k + 1 >= 0) & (hs >= 1)]
    h2s = hs[(z + hs + k - 1 < len(w)) & (hs >= 1)]
    if len(h1s) == 0 or len(h2s) == 0:
        return None
    A = src[i0 - k + 1:i0 + 1]
    B = dst[j0:j0 + k]
    WA = np.stack([w[z - t - k + 1:z - t + 1] for t in h1s])
    WB = np.stack([w[z + t:z + t + k] for t in h2s])
    d1 = window_distance(np.broadcast_to(A, WA.shape), WA)
    d2 = window_distance(WB, np.broadcast_to(B, WB.shape))
    a, b = int(np.argmin(d1)), int(np.argmin(d2))
    return int(h1s[a]), int(h2s[b]), float(d1[a] + d2[b])


def enhancement_nodes(src: np.ndarray, i0: int, w: np.ndarray, z: int, dst: np.ndarray, j0: int, k: int = 5,
                      max_span: int = 60, lam: float = 0.0, fps: float = 60.0) -> tuple[int, int, float] | None:
    """The nearest transition points ``(z0, z2, cost)`` around reference point ``z`` (thesis 5.2.4: "the
    nearest transition points w_z0 and w_z2 are the enhancement nodes"): ``z0 < z`` where the source's
    window ending at ``i0`` best joins ``C_w`` (window ``w_{z0-k+1..z0}``), ``z2 > z`` where ``C_w`` best
    joins the target's window starting at ``j0`` (``w_{z2..z2+k-1}``), each within ``max_span`` frames
    and charged ``lam`` per second away from ``z`` (the responsiveness terms). None if nothing fits."""
    if i0 - k + 1 < 0 or j0 + k > len(dst):
        return None
    z0s = np.arange(max(k - 1, z - max_span), z)
    z2s = np.arange(z + 1, min(len(w) - k, z + max_span) + 1)
    if len(z0s) == 0 or len(z2s) == 0:
        return None
    A = src[i0 - k + 1:i0 + 1]
    B = dst[j0:j0 + k]
    WA = np.stack([w[t - k + 1:t + 1] for t in z0s])
    WB = np.stack([w[t:t + k] for t in z2s])
    d0 = window_distance(np.broadcast_to(A, WA.shape), WA) + lam * (z - z0s) / fps
    d2 = window_distance(WB, np.broadcast_to(B, WB.shape)) + lam * (z2s - z) / fps
    a, b = int(np.argmin(d0)), int(np.argmin(d2))
    return int(z0s[a]), int(z2s[b]), float(d0[a] + d2[b])


PLACES = ("first", "both", "drift")
ANCHORS = ("ends", "nodes")


def check_placement(place: str | None = None, anchor: str | None = None, hold: float | None = None) -> None:
    """:class:`~vidstyle.errors.ParameterError` naming the first bad one of the placement options
    (``place`` in :data:`PLACES`, ``anchor`` in :data:`ANCHORS`, ``hold`` in [0, 1)); None = not given.
    One check for the library functions; the commands show it as ``--place: ...``."""
    from ..errors import ParameterError

    if place is not None and place not in PLACES:
        raise ParameterError("place", f"first, both or drift, got {place!r}")
    if anchor is not None and anchor not in ANCHORS:
        raise ParameterError("anchor", f"ends or nodes, got {anchor!r}")
    if hold is not None and not 0.0 <= hold < 1.0:
        raise ParameterError("hold", f"must be in [0, 1), got {hold}")


def _smooth(u: np.ndarray) -> np.ndarray:
    """C^1 ease ``3u^2 - 2u^3`` (``1 - alpha`` of the motion-graph blend weight)."""
    u = np.clip(u, 0.0, 1.0)
    return 3 * u**2 - 2 * u**3


def resample_segment(rot: np.ndarray, root: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray]:
    """A segment (m frames) time-warped to ``n`` frames: rotations by slerp, roots linearly."""
    m = len(rot)
    t = np.linspace(0.0, m - 1, n)
    lo = np.floor(t).astype(int)
    hi = np.minimum(lo + 1, m - 1)
    f = t - lo
    rot_n = slerp(rot[lo], rot[hi], np.broadcast_to(f[:, None], (n, rot.shape[1])))
    return rot_n, root[lo] * (1 - f)[:, None] + root[hi] * f[:, None]


def plain_transition(rot_a: np.ndarray, root_a: np.ndarray, rot_b: np.ndarray, root_b: np.ndarray, n: int
                     ) -> tuple[np.ndarray, np.ndarray]:
    """The plain motion-graph transition of ``n`` frames between departing pose ``a`` and arriving pose
    ``b`` ((J, 4) rotations, (3,) root): one C^1 blend straight from one into the other."""
    t = _smooth((np.arange(n) + 1.0) / (n + 1.0))
    rot = slerp(np.broadcast_to(rot_a, (n,) + rot_a.shape), np.broadcast_to(rot_b, (n,) + rot_b.shape),
                np.broadcast_to(t[:, None], (n, rot_a.shape[0])))
    return rot, root_a[None] * (1 - t)[:, None] + root_b[None] * t[:, None]


def two_half_transition(rot_a, root_a, seg_rot, seg_root, rot_b, root_b, n: int, centre: int | None = None,
                        hold: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """``n`` transition frames from departing pose ``a`` through the (placed) enhancement segment
    ``seg`` (``w_z0 .. w_z .. w_z2``, ``w_z`` at index ``centre``, default the middle) into arriving pose
    ``b``: the first half blends ``a`` into ``w_z0 .. w_z`` (time-warped to the first half), the second
    ``w_z .. w_z2`` into ``b``; the middle output frame is exactly ``w_z``.

    ``hold`` (in [0, 1)): each half's blend weight reaches the segment ``hold`` of the way early (first
    half) and leaves it that late (second half), so the output follows the segment itself, with full
    weight, over the middle ``hold`` fraction of the transition: a performer who *holds* the
    transition pose (a crouch kept for a beat) is not just touched at one frame. 0 is the thesis'
    two-half blend."""
    check_placement(hold=hold)
    c = (len(seg_rot) - 1) // 2 if centre is None else int(centre)
    n1 = n // 2 + 1  # output frames 0 .. n1-1 carry w_z0 .. w_z (the last one is w_z)
    r1, p1 = resample_segment(seg_rot[:c + 1], seg_root[:c + 1], n1)
    r2, p2 = resample_segment(seg_rot[c:], seg_root[c:], n - n1 + 1)
    W_rot, W_root = np.concatenate([r1, r2[1:]]), np.concatenate([p1, p2[1:]])
    mid = float(n1 - 1)
    f = np.arange(n, dtype=np.float64)
    first = f <= mid
    J = rot_a.shape[0]
    rot = np.empty_like(W_rot)
    root = np.empty_like(W_root)
    t1 = _smooth((f[first] + 1.0) / ((mid + 1.0) * (1.0 - hold)))
    rot[first] = slerp(np.broadcast_to(rot_a, (first.sum(), J, 4)), W_rot[first], np.broadcast_to(t1[:, None], (first.sum(), J)))
    root[first] = root_a[None] * (1 - t1)[:, None] + W_root[first] * t1[:, None]
    second = ~first
    t2 = _smooth((f[second] - mid - hold * (n - mid)) / ((1.0 - hold) * (n - mid)))
    rot[second] = slerp(W_rot[second], np.broadcast_to(rot_b, (second.sum(), J, 4)), np.broadcast_to(t2[:, None], (second.sum(), J)))
    root[second] = W_root[second] * (1 - t2)[:, None] + root_b[None] * t2[:, None]
    return rot, root


def place_segment(seg_motion, seg_points: np.ndarray, anchor_points: np.ndarray, scale: float = 1.0,
                  arrival_points: np.ndarray | None = None, drift: bool = False,
                  align_points: tuple[np.ndarray, np.ndarray] | None = None,
                  align_frames: tuple[int, int] | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Rotations (m, J, 4) and roots (m, 3) of a library segment moved onto the performer: roots scaled
    by ``scale`` (body size), then the segment's first frame aligned (vertical rotation + floor
    translation, Kovar) onto ``anchor_points`` (15, 3), the departing pose. With ``arrival_points``
    (the arriving pose) the placement is the mean of that one and the last frame's onto the arrival,
    so the segment drifts from neither end; with ``drift`` too, the placement moves linearly over the
    segment from the first frame's alignment onto the departure to the last frame's onto the arrival
    (the library clip's own travel between its ends is replaced by the performer's, its motion
    around that line is kept).

    ``align_points``: the library poses (15, 3) aligned onto the departure and the arrival instead of
    the segment's own first and last frames, at segment-relative frame indices ``align_frames``
    (default ``(0, m - 1)``; they may lie outside the segment) — the *enhancement nodes*
    (:func:`enhancement_nodes`): the library frames that look like the departure and the arrival.
    A segment cut inside a held pose then keeps the clip's own travel from its node into that pose
    (a step back stays a step back) instead of being pinned onto a pose it does not resemble."""
    from ..motiongraph.distance import align_windows as _align

    m = len(seg_points)
    first, last = (seg_points[0], seg_points[-1]) if align_points is None else align_points
    f0, f2 = (0, m - 1) if align_frames is None else align_frames
    _, theta, x0, z0 = _align(anchor_points[None], first[None] * scale, KEYPOINT_WEIGHTS)
    theta, x0, z0 = float(theta), float(x0), float(z0)
    root = seg_motion.root_positions * scale
    if arrival_points is not None:
        _, t2, x2, z2 = _align(arrival_points[None], last[None] * scale, KEYPOINT_WEIGHTS)
        if drift:
            r1, p1 = Placement(theta, x0, z0).apply_frames(seg_motion.rotations, root)
            r2, p2 = Placement(float(t2), float(x2), float(z2)).apply_frames(seg_motion.rotations, root)
            u = np.clip((np.arange(m) - f0) / (f2 - f0), 0.0, 1.0) if f2 > f0 else np.zeros(m)
            rot = r1.copy()
            rot[:, 0] = slerp(r1[:, 0], r2[:, 0], u)
            return rot, p1 * (1 - u)[:, None] + p2 * u[:, None]
        theta = float(np.angle(np.exp(1j * theta) + np.exp(1j * float(t2))))
        x0, z0 = (x0 + float(x2)) / 2, (z0 + float(z2)) / 2
    return Placement(theta, x0, z0).apply_frames(seg_motion.rotations, root)
