"""Pose-sequence frame features: the 2D skeleton of every working frame, normalised, with its motion
(issue 28, item 1). The counterpart of the 3D SIFT words for :class:`~vidstyle.recognition.poserecognizer.PoseRecognizer`.

Input: a :class:`PoseTrack`, the 15 keypoints (:data:`vidstyle.formats.keypoints.KEYPOINTS` order) of
consecutive working frames as pixel coordinates, NaN where a keypoint (or the whole frame) is missing.

Per frame ``t`` (:class:`PoseFeaturizer`):

1. **gaps**: each keypoint's NaN runs of at most ``max_gap`` frames are filled by linear interpolation
   between the frames around them (a run at either end of the track is held at the nearest known value);
   a frame still missing a keypoint after that is *missing*;
2. **normalisation**: ``Q(t) = (X(t) - pelvis(t)) / s(t)``, root-centred at the pelvis and scaled by the
   torso length ``s(t)`` = median of ``|neck - pelvis|`` over the known frames within ``scale_window``
   frames of ``t`` (a median over time, so a bent torso or a foreshortened one for a frame or two does
   not change the scale). ``Q`` is invariant to image translation and scale, hence to the camera's
   distance (up to perspective), focal length, principal point and the video's resolution;
3. **motion**: for each ``k`` in ``velocity_steps`` the central difference ``(Q(t+k) - Q(t-k)) / (2k)``
   and of the root ``(pelvis(t+k) - pelvis(t-k)) / (2k s(t))`` (the root's own motion, which ``Q``
   removes: steps); for each ``k`` in ``accel_steps`` the second difference
   ``(Q(t+k) - 2 Q(t) + Q(t-k)) / k^2`` (and the root's); for each ``d`` in ``window_offsets`` the
   displacement ``Q(t+d) - Q(t)`` (and the root's ``(pelvis(t+d) - pelvis(t)) / s(t)``). Frames outside
   the track are clamped to its ends; a missing neighbour is replaced by ``t`` itself (no motion);
4. **missing**: two flags, ``t`` is missing, and the fraction of the frames ``t - margin .. t + margin``
   that are missing. A missing frame's pose and motion features are 0 (the classifier learns from the
   flags and the smoother from the neighbours what it was).

Left and right: :func:`mirror_track` is the left-right mirror image of a track (x -> -x, left and right
keypoints swapped); features of a mirrored track are a fixed signed permutation of the features of the
track (:meth:`PoseFeaturizer.mirror_permutation`). A southpaw is the mirror image of an orthodox fighter,
so the recognizer trains on mirrored copies of its training tracks (``mirror=True``) rather than
guessing a canonical side from a single view, which front and back views make ambiguous.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..errors import ParameterError
from ..formats.keypoints import KEYPOINTS

N_KEYPOINTS = len(KEYPOINTS)
KP = {k: i for i, k in enumerate(KEYPOINTS)}
PELVIS, NECK = KP["pelvis"], KP["neck"]
MIRROR_INDEX = np.array([KP[k.replace("left_", "#").replace("right_", "left_").replace("#", "right_")]
                         for k in KEYPOINTS], dtype=np.int64)
"""(15,) index of each keypoint's left/right counterpart (itself for head_top, neck, pelvis)."""
NON_ROOT = np.array([i for i in range(N_KEYPOINTS) if i != PELVIS], dtype=np.int64)


@dataclass
class PoseTrack:
    """2D keypoints of consecutive working frames: ``xy`` (F, 15, 2) pixels (x = column, y = row), NaN
    where unknown; ``fps`` of the working frames; ``frames`` the source (decoded) frame of each."""

    xy: np.ndarray
    fps: float = 20.0
    frames: np.ndarray | None = None
    source: str = ""
    extra: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        self.xy = np.asarray(self.xy, dtype=np.float64)
        if self.xy.ndim != 3 or self.xy.shape[1:] != (N_KEYPOINTS, 2):
            raise ValueError(f"pose track: expected (frames, {N_KEYPOINTS}, 2) keypoints, got {self.xy.shape}")
        if self.frames is None:
            self.frames = np.arange(self.xy.shape[0])

    @property
    def n_frames(self) -> int:
        return int(self.xy.shape[0])


def mirror_track(xy: np.ndarray) -> np.ndarray:
    """Left-right mirror image of keypoints (..., 15, 2): x negated and left/right keypoints swapped."""
    out = np.asarray(xy, dtype=np.float64)[..., MIRROR_INDEX, :].copy()
    out[..., 0] = -out[..., 0]
    return out


def fill_gaps(xy: np.ndarray, max_gap: int) -> np.ndarray:
    """Fill each keypoint coordinate's NaN runs of at most ``max_gap`` frames: linear interpolation
    between known frames, the nearest known value for a run at either end (see the module docstring)."""
    xy = np.array(xy, dtype=np.float64)
    F = xy.shape[0]
    if F == 0 or max_gap <= 0:
        return xy
    flat = xy.reshape(F, -1)
    t = np.arange(F)
    for c in range(flat.shape[1]):
        col = flat[:, c]
        bad = ~np.isfinite(col)
        if not bad.any() or bad.all():
            continue
        m = np.concatenate([[False], bad, [False]]).astype(np.int8)
        d = np.flatnonzero(np.diff(m))
        good = ~bad
        for a, b in zip(d[::2], d[1::2]):
            if b - a <= max_gap:
                col[a:b] = np.interp(t[a:b], t[good], col[good])
    return flat.reshape(xy.shape)


def torso_scale(xy: np.ndarray, known: np.ndarray, window: int) -> np.ndarray:
    """(F,) torso length per frame: median of ``|neck - pelvis|`` over the known frames within
    ``window`` frames (NaN when none is known)."""
    F = xy.shape[0]
    torso = np.linalg.norm(xy[:, NECK] - xy[:, PELVIS], axis=-1)
    torso = np.where(known & (torso > 0), torso, np.nan)
    if F == 0:
        return torso
    padded = np.concatenate([np.full(window, np.nan), torso, np.full(window, np.nan)])
    windows = np.lib.stride_tricks.sliding_window_view(padded, 2 * window + 1)
    out = np.full(F, np.nan)
    ok = np.isfinite(windows).any(axis=1)
    if ok.any():
        out[ok] = np.nanmedian(windows[ok], axis=1)
    return out


def track_from_poses(poses, fps: float, n_frames: int | None = None) -> PoseTrack:
    """The :class:`PoseTrack` of a :class:`~vidstyle.formats.poses.Poses` (``vidstyle pose`` output) whose
    frames are the decoded frames of a video at ``fps``: one working frame per decoded frame from 0 to
    ``n_frames - 1`` (default: the last frame with a pose); frames without a pose (absent from the file,
    or ``points: null``) are missing (NaN)."""
    last = max((f.frame for f in poses.frames), default=-1)
    n = int(n_frames) if n_frames is not None else last + 1
    xy = np.full((n, N_KEYPOINTS, 2), np.nan)
    for f in poses.frames:
        if f.found and f.frame < n:
            xy[f.frame] = f.xy
    return PoseTrack(xy, float(fps), np.arange(n), source=str(poses.video))


class PoseFeaturizer:
    """Frame features of a :class:`PoseTrack` (see the module docstring). A descriptor-like object:
    :meth:`transform`, :attr:`dimension`, :attr:`temporal_margin`, :meth:`parameters`,
    :meth:`mirror_permutation`."""

    name = "pose"

    def __init__(self, velocity_steps=(1, 2, 4), accel_steps=(2, 4), window_offsets=(-8, -4, 4, 8),
                 max_gap: int = 5, scale_window: int = 10):
        self.velocity_steps = tuple(int(k) for k in velocity_steps)
        self.accel_steps = tuple(int(k) for k in accel_steps)
        self.window_offsets = tuple(int(d) for d in window_offsets)
        self.max_gap = int(max_gap)
        self.scale_window = int(scale_window)
        if any(k < 1 for k in self.velocity_steps + self.accel_steps):
            raise ParameterError("velocity_steps", "steps must be >= 1 frame")
        if any(d == 0 for d in self.window_offsets):
            raise ParameterError("window_offsets", "offsets must be non-zero")
        if self.max_gap < 0 or self.scale_window < 0:
            raise ParameterError("max_gap", "max_gap and scale_window must be >= 0")

    # ------------------------------------------------------------ descriptor-like interface
    def parameters(self) -> dict[str, Any]:
        return {"variant": self.name, "velocity_steps": list(self.velocity_steps),
                "accel_steps": list(self.accel_steps), "window_offsets": list(self.window_offsets),
                "max_gap": self.max_gap, "scale_window": self.scale_window}

    @property
    def temporal_margin(self) -> int:
        return max([0, *self.velocity_steps, *self.accel_steps, *(abs(d) for d in self.window_offsets)])

    @property
    def n_blocks(self) -> int:
        """Motion blocks (each 14 keypoints + the root, x and y) after the pose block."""
        return len(self.velocity_steps) + len(self.accel_steps) + len(self.window_offsets)

    @property
    def dimension(self) -> int:
        return 2 * len(NON_ROOT) + self.n_blocks * 2 * N_KEYPOINTS + 2

    def mirror_permutation(self) -> tuple[np.ndarray, np.ndarray]:
        """``(perm, sign)``: features of :func:`mirror_track` of a track are ``F[:, perm] * sign``."""
        # a block of 14 (or 15) keypoints x (x, y): keypoint i's mirror image is MIRROR_INDEX[i], x negated
        def block(kps: np.ndarray, offset: int):
            pos = {int(k): j for j, k in enumerate(kps)}
            perm = np.array([offset + 2 * pos[int(MIRROR_INDEX[k])] + c for k in kps for c in (0, 1)])
            sign = np.tile([-1.0, 1.0], len(kps))
            return perm, sign

        perms = [block(NON_ROOT, 0)]
        off = 2 * len(NON_ROOT)
        allk = np.concatenate([NON_ROOT, [PELVIS]])  # keypoints, then the root
        for _ in range(self.n_blocks):
            perms.append(block(allk, off))
            off += 2 * N_KEYPOINTS
        perm = np.concatenate([p for p, _ in perms] + [np.array([off, off + 1])])
        sign = np.concatenate([s for _, s in perms] + [np.ones(2)])
        return perm, sign

    # ------------------------------------------------------------ features
    def normalised(self, xy: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """``(Q, root, scale, missing)``: root-centred, torso-scaled keypoints (F, 15, 2) (NaN where
        missing), the pelvis (F, 2) in pixels, the torso length (F,) and the missing flags (F,), after
        :func:`fill_gaps`."""
        xy = fill_gaps(np.asarray(xy, dtype=np.float64), self.max_gap)
        known = np.all(np.isfinite(xy), axis=(1, 2))
        scale = torso_scale(xy, known, self.scale_window)
        missing = ~known | ~np.isfinite(scale)
        root = xy[:, PELVIS].copy()
        with np.errstate(invalid="ignore", divide="ignore"):
            Q = (xy - root[:, None, :]) / scale[:, None, None]
        Q[missing] = np.nan
        root[missing] = np.nan
        return Q, root, scale, missing

    def transform(self, track: PoseTrack | np.ndarray) -> np.ndarray:
        """(F, :attr:`dimension`) frame features of a track (or of its (F, 15, 2) keypoints)."""
        xy = track.xy if isinstance(track, PoseTrack) else np.asarray(track, dtype=np.float64)
        F = xy.shape[0]
        if F == 0:
            return np.zeros((0, self.dimension))
        Q, root, scale, missing = self.normalised(xy)
        t = np.arange(F)

        def at(d: int):
            """(Q, root) at t + d, clamped to the track, with t itself where that frame is missing."""
            j = np.clip(t + d, 0, F - 1)
            j = np.where(missing[j], t, j)
            return Q[j], root[j]

        # pose block: 14 non-root keypoints (the pelvis is 0 by construction)
        s = scale[:, None]
        blocks = [Q[:, NON_ROOT].reshape(F, -1)]

        def motion(q, r):  # (F, 15, 2): 14 keypoints then the root
            return np.concatenate([q[:, NON_ROOT], r[:, None, :]], axis=1).reshape(F, -1)

        for k in self.velocity_steps:
            (qa, ra), (qb, rb) = at(k), at(-k)
            blocks.append(motion((qa - qb) / (2 * k), (ra - rb) / (2 * k) / s))
        for k in self.accel_steps:
            (qa, ra), (qb, rb) = at(k), at(-k)
            blocks.append(motion((qa - 2 * Q + qb) / k**2, (ra - 2 * root + rb) / k**2 / s))
        for d in self.window_offsets:
            qa, ra = at(d)
            blocks.append(motion(qa - Q, (ra - root) / s))
        m = self.temporal_margin
        c = np.concatenate([[0], np.cumsum(missing)])
        lo, hi = np.clip(t - m, 0, F), np.clip(t + m + 1, 0, F)
        frac = (c[hi] - c[lo]) / (hi - lo)
        X = np.concatenate(blocks, axis=1)
        X[missing] = 0.0
        X = np.nan_to_num(X, nan=0.0, posinf=0.0, neginf=0.0)
        return np.concatenate([X, missing[:, None].astype(float), frac[:, None]], axis=1)
