"""Training pose tracks from labelled 3D motion seen from any camera (issue 28, item 2).

A :class:`LabelledMotion` is the 15 keypoints of a mocap take in 3D at the recognizer's working rate
with a label per frame (:func:`labelled_motion` reads a BVH and its per-frame labels file; the labels are
at the mocap's rate and are subsampled with the keypoints). :func:`virtual_views` projects each through
cameras drawn by :func:`sample_cameras` — azimuth about the performer's median facing direction,
elevation, distance (in body heights) and vertical field of view, uniform over the given ranges; one
static camera per view, looking at the centre of the take — and corrupts the 2D keypoints with
:class:`KeypointNoise` so that training tracks look like a pose estimator's.

Projection is :meth:`vidstyle.render.camera.Camera.project` (numpy only); a keypoint behind the camera
is missing (NaN).
"""

from __future__ import annotations

import logging
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import InputError, ParameterError
from ..render.camera import Camera, circular_median, intrinsics, look_at_rotation
from .posefeatures import N_KEYPOINTS as N_KP
from .posefeatures import NECK, PELVIS, PoseTrack

log = logging.getLogger(__name__)

UP = np.array([0.0, 1.0, 0.0])


@dataclass
class LabelledMotion:
    """``points`` (F, 15, 3) world keypoints (+Y up) at ``fps``, ``labels`` one class name per frame,
    ``facing`` the performer's median facing angle (radians about +Y, 0 = +Z)."""

    points: np.ndarray
    labels: list[str]
    fps: float
    facing: float = 0.0
    name: str = ""

    def __post_init__(self) -> None:
        self.points = np.asarray(self.points, dtype=np.float64)
        if len(self.labels) != self.points.shape[0]:
            raise InputError(f"{self.name or 'motion'}: {len(self.labels)} labels for {self.points.shape[0]} frames")

    @property
    def height(self) -> float:
        """Body height (world units): the largest vertical extent of the keypoints in a frame."""
        h = self.points[:, :, 1].max(axis=1) - self.points[:, :, 1].min(axis=1)
        return float(np.nanmax(h)) if h.size else 1.0


def labelled_motion(bvh: str | Path, labels: str | Path, fps: float, phase: int = 0) -> LabelledMotion:
    """The keypoints and labels of a BVH take with a per-frame labels file at the mocap's rate
    (``vidstyle.labels``, e.g. the demo's ``mocap/<take>.labels.json``), resampled to ``fps`` by taking
    every ``mocap_fps / fps``-th frame from ``phase``."""
    from ..formats.labels import read_labels
    from ..mocap import read_bvh
    from ..mocap.keypoints import keypoint_positions

    motion = read_bvh(bvh)
    track = read_labels(labels)
    if len(track.labels) != motion.n_frames:
        raise InputError(f"{labels}: {len(track.labels)} labels for the {motion.n_frames} frames of {bvh}")
    src_fps = float(track.fps or motion.fps)
    step = src_fps / float(fps)
    idx = np.round(np.arange(phase, motion.n_frames, step)).astype(int)
    idx = idx[idx < motion.n_frames]
    pts = keypoint_positions(motion)[idx]
    facing = circular_median(motion.facing_angles())
    return LabelledMotion(pts, [track.labels[i] for i in idx], float(fps), facing, Path(bvh).stem)


def sample_cameras(rng: np.random.Generator, n: int, azimuth=(0.0, 360.0), elevation=(-10.0, 45.0),
                   distance=(2.5, 6.0), vfov=(30.0, 60.0)) -> list[dict]:
    """``n`` camera draws: ``azimuth_deg``, ``elevation_deg``, ``distance`` (body heights), ``vfov_deg``,
    each uniform over its range."""
    for name, r in (("azimuth", azimuth), ("elevation", elevation), ("distance", distance), ("vfov", vfov)):
        if len(r) != 2 or r[0] > r[1]:
            raise ParameterError(name, f"must be a (low, high) range, got {r}")
    if not -89 < elevation[0] <= elevation[1] < 89 or distance[0] <= 0:
        raise ParameterError("elevation", "elevations must lie in (-89, 89) degrees and distances be > 0")
    return [{"azimuth_deg": float(rng.uniform(*azimuth)), "elevation_deg": float(rng.uniform(*elevation)),
             "distance": float(rng.uniform(*distance)), "vfov_deg": float(rng.uniform(*vfov))} for _ in range(n)]


def camera_for(motion: LabelledMotion, azimuth_deg: float, elevation_deg: float, distance: float,
               vfov_deg: float = 40.0, size: tuple[int, int] = (160, 120)) -> Camera:
    """A static camera at ``azimuth_deg`` about the performer's facing (0 = in front, +90 = their left)
    and ``elevation_deg`` (positive = looking down), ``distance`` body heights from the centre of the
    take's keypoints, looking at it (the conventions of :class:`~vidstyle.render.camera.Camera`)."""
    pts = motion.points.reshape(-1, 3)
    pts = pts[np.all(np.isfinite(pts), axis=1)]
    target = (pts.min(axis=0) + pts.max(axis=0)) / 2.0
    ang = motion.facing + math.radians(azimuth_deg)
    el = math.radians(elevation_deg)
    back = math.cos(el) * np.array([math.sin(ang), 0.0, math.cos(ang)]) + math.sin(el) * UP
    eye = target + distance * motion.height * back
    R = look_at_rotation(eye, target)
    return Camera(intrinsics(size, vfov_deg), R, -R @ eye, azimuth_deg, elevation_deg, size,
                  math.degrees(motion.facing), {"target": target, "distance": distance * motion.height})


def project_keypoints(points: np.ndarray, camera: Camera) -> np.ndarray:
    """(F, 15, 2) pixel coordinates of world keypoints (F, 15, 3); NaN where behind the camera."""
    uv, z = camera.project(points)
    uv = np.array(uv, dtype=np.float64)
    uv[~(z > 1e-6)] = np.nan
    return uv


@dataclass
class KeypointNoise:
    """Corruption of projected keypoints, in units of the track's torso length (so it does not depend on
    the image size): Gaussian noise of ``sigma`` per coordinate; ``outlier_rate`` of the keypoints
    displaced by a Gaussian of ``outlier_sigma`` instead (a limb found in the wrong place); frames dropped
    (the performer not found) in runs that start with probability ``dropout_rate / dropout_length`` per
    frame and last a geometric number of frames with mean ``dropout_length``."""

    sigma: float = 0.05
    outlier_rate: float = 0.05
    outlier_sigma: float = 0.5
    dropout_rate: float = 0.02
    dropout_length: float = 4.0
    extra: dict = field(default_factory=dict)

    def apply(self, xy: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        xy = np.array(xy, dtype=np.float64)
        F = xy.shape[0]
        if F == 0:
            return xy
        torso = np.nanmedian(np.linalg.norm(xy[:, NECK] - xy[:, PELVIS], axis=-1))
        if not np.isfinite(torso) or torso <= 0:
            return xy
        noise = rng.normal(0.0, self.sigma, xy.shape)
        out = rng.random(xy.shape[:2]) < self.outlier_rate
        noise[out] = rng.normal(0.0, self.outlier_sigma, (int(out.sum()), 2))
        xy += noise * torso
        if self.dropout_rate > 0:
            p_start = min(1.0, self.dropout_rate / max(self.dropout_length, 1.0))
            starts = np.flatnonzero(rng.random(F) < p_start)
            for s in starts:
                n = int(rng.geometric(1.0 / max(self.dropout_length, 1.0)))
                xy[s:s + n] = np.nan
        return xy

    def to_dict(self) -> dict:
        return {"sigma": self.sigma, "outlier_rate": self.outlier_rate, "outlier_sigma": self.outlier_sigma,
                "dropout_rate": self.dropout_rate, "dropout_length": self.dropout_length, **self.extra}


@dataclass
class ResidualNoise:
    """Corruption by the pose estimator's own errors: each training frame takes the error that the estimator
    made on a calibration frame of a similar 2D pose. The calibration is pairs of tracks of the same frames
    (true keypoints, the estimator's; :meth:`from_tracks`), e.g. held-out renders with their truth. A frame's
    *key* is its true pose root-centred at the pelvis and scaled by the track's median torso length (the
    28 coordinates of the 14 other keypoints); its *residual* is ``(estimated - true) / torso`` (NaN where
    the estimator found nobody). :meth:`apply` finds, for every frame of a track, the ``k`` calibration
    frames whose keys are nearest (Euclidean) and adds the residual of one of them, drawn uniformly, scaled
    by the track's torso. So an arm the estimator misses when it is stretched out, or a limb it puts on the
    wrong side when the legs cross, is missed and swapped in the training tracks in the same poses, which
    Gaussian noise (:class:`KeypointNoise`) cannot imitate. With ``mirror`` the bank also holds the
    left-right mirror image of every calibration frame (its key and residual mirrored), so both stances
    are covered. A frame whose nearest calibration pose is further than ``max_distance`` (key units: torso
    lengths over 28 coordinates) is a pose the calibration never saw; it takes the ``fallback`` noise instead
    (None: no corruption), so the estimator's errors on fighting poses are not pasted onto, say, a walk.
    """

    keys: np.ndarray
    residuals: np.ndarray
    k: int = 3
    max_distance: float | None = None
    fallback: KeypointNoise | None = None
    extra: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        self.keys = np.asarray(self.keys, dtype=np.float64)
        self.residuals = np.asarray(self.residuals, dtype=np.float64)
        if self.keys.ndim != 2 or self.residuals.ndim != 3 or len(self.keys) != len(self.residuals) \
                or len(self.keys) == 0 or self.residuals.shape[1:] != (N_KP, 2) or self.keys.shape[1] != 2 * (N_KP - 1):
            raise ParameterError("residual noise", f"expected keys (N, {2 * (N_KP - 1)}) and residuals (N, {N_KP}, 2) "
                                 f"with N > 0, got {self.keys.shape} and {self.residuals.shape}")
        if not np.all(np.isfinite(self.keys)):
            raise ParameterError("residual noise", "keys must be finite")
        if int(self.k) < 1:
            raise ParameterError("k", f"must be >= 1, got {self.k}")
        self.k = int(min(self.k, len(self.keys)))
        if self.max_distance is not None and not (np.isfinite(self.max_distance) and self.max_distance > 0):
            raise ParameterError("max_distance", f"must be a positive number or None, got {self.max_distance}")
        self._sq = np.einsum("ij,ij->i", self.keys, self.keys)

    def nearest(self, q: np.ndarray, chunk: int = 1024) -> np.ndarray:
        """(Q, k) indices of the ``k`` keys nearest each row of ``q`` (Q, 28), by brute force in chunks (a
        kd-tree is slower than a matrix product in 28 dimensions), in no particular order."""
        out = np.empty((len(q), self.k), dtype=np.int64)
        for s in range(0, len(q), chunk):
            b = q[s:s + chunk]
            d = self._sq[None, :] - 2.0 * (b @ self.keys.T)  # + |b|^2, the same for a row's candidates
            out[s:s + chunk] = np.argpartition(d, self.k - 1, axis=1)[:, :self.k] if self.k < d.shape[1] \
                else np.argsort(d, axis=1)[:, :self.k]
        return out

    @staticmethod
    def _normalise(xy: np.ndarray) -> tuple[np.ndarray, float]:
        """(F, 28) keys of a track's frames (NaN rows where a keypoint is unknown) and its torso length."""
        lengths = np.linalg.norm(xy[:, NECK] - xy[:, PELVIS], axis=-1)
        lengths = lengths[np.isfinite(lengths)]
        torso = float(np.median(lengths)) if lengths.size else np.nan
        q = (xy - xy[:, PELVIS:PELVIS + 1]) / torso
        return np.delete(q, PELVIS, axis=1).reshape(len(xy), -1), torso

    @classmethod
    def from_tracks(cls, trues: Sequence[np.ndarray], ests: Sequence[np.ndarray], k: int = 3, mirror: bool = True,
                    videos: Sequence[str] = (), max_distance: float | None = None,
                    fallback: KeypointNoise | None = None) -> ResidualNoise:
        """The bank of calibration pairs: ``trues[i]`` and ``ests[i]`` (F, 15, 2) pixel keypoints of the same
        frames (an estimated frame with any NaN keypoint is a frame the estimator missed; a true frame with a
        NaN is skipped)."""
        from .posefeatures import mirror_track

        keys, res = [], []
        for true, est in zip(trues, ests, strict=True):
            true, est = np.asarray(true, dtype=np.float64), np.asarray(est, dtype=np.float64)
            if true.shape != est.shape or true.ndim != 3 or true.shape[1:] != (N_KP, 2):
                raise ParameterError("residual noise", f"true and estimated tracks must both be (F, {N_KP}, 2), "
                                     f"got {true.shape} and {est.shape}")
            variants = [(true, est)] + ([(mirror_track(true), mirror_track(est))] if mirror else [])
            for t, e in variants:
                q, torso = cls._normalise(t)
                if not np.isfinite(torso) or torso <= 0:
                    continue
                ok = np.all(np.isfinite(q), axis=1)
                r = (e - t) / torso
                r[~np.all(np.isfinite(e), axis=(1, 2))] = np.nan
                keys.append(q[ok])
                res.append(r[ok])
        if not keys or sum(len(x) for x in keys) == 0:
            raise ParameterError("residual noise", "no calibration frame with a complete true pose")
        n_est = sum(len(x) for x in keys) // (2 if mirror else 1)
        return cls(np.concatenate(keys), np.concatenate(res), k=k, max_distance=max_distance, fallback=fallback,
                   extra={"calibration_frames": int(n_est), "mirror": bool(mirror),
                          "calibrated_on_videos": len(videos) or len(trues)})

    def apply(self, xy: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        xy = np.array(xy, dtype=np.float64)
        if xy.shape[0] == 0:
            return xy
        q, torso = self._normalise(xy)
        if not np.isfinite(torso) or torso <= 0:
            return xy
        ok = np.flatnonzero(np.all(np.isfinite(q), axis=1))
        if ok.size == 0:
            return xy
        idx = self.nearest(q[ok])
        pick = idx[np.arange(len(ok)), rng.integers(0, self.k, len(ok))]
        if self.max_distance is not None:
            far = self._nearest_distance(q[ok], idx) > self.max_distance
            if far.any():
                other = self.fallback.apply(xy, rng) if self.fallback is not None else xy.copy()
                xy[ok[far]] = other[ok[far]]
            ok, pick = ok[~far], pick[~far]
        xy[ok] += self.residuals[pick] * torso
        return xy

    def distances(self, xy: np.ndarray) -> np.ndarray:
        """(F,) distance of each frame's key to its nearest calibration key (NaN where a keypoint is unknown)."""
        q, torso = self._normalise(np.asarray(xy, dtype=np.float64))
        out = np.full(len(q), np.nan)
        ok = np.flatnonzero(np.all(np.isfinite(q), axis=1))
        if ok.size and np.isfinite(torso) and torso > 0:
            out[ok] = self._nearest_distance(q[ok], self.nearest(q[ok]))
        return out

    def _nearest_distance(self, q: np.ndarray, idx: np.ndarray) -> np.ndarray:
        """(Q,) distance of each row of ``q`` to the nearest of its candidate keys ``idx`` (Q, k)."""
        return np.sqrt(((self.keys[idx] - q[:, None, :]) ** 2).sum(-1).min(1))

    def to_dict(self) -> dict:
        d = {"kind": "residuals", "k": self.k, **self.extra}
        if self.max_distance is not None:
            d.update(max_distance=float(self.max_distance),
                     fallback=self.fallback.to_dict() if self.fallback is not None else None)
        return d


def virtual_views(motions: Sequence[LabelledMotion], n_views: int, rng: np.random.Generator | int,
                  noise: KeypointNoise | ResidualNoise | None = None, **camera_ranges) -> tuple[list[PoseTrack], list[list[str]]]:
    """``n_views`` projections of every motion through cameras of :func:`sample_cameras`
    (``camera_ranges``: its ranges), corrupted by ``noise`` (None = exact 2D). Returns tracks and labels."""
    rng = np.random.default_rng(rng) if not isinstance(rng, np.random.Generator) else rng
    tracks, labels = [], []
    for m in motions:
        for cam in sample_cameras(rng, n_views, **camera_ranges):
            c = camera_for(m, **cam)
            xy = project_keypoints(m.points, c)
            if noise is not None:
                xy = noise.apply(xy, rng)
            tracks.append(PoseTrack(xy, m.fps, source=f"{m.name}@az{cam['azimuth_deg']:.0f},el{cam['elevation_deg']:.0f}",
                                    extra=cam))
            labels.append(list(m.labels))
    return tracks, labels


def clip_motions(clips, label_files, fps: float, classes=None, min_frames: int = 10) -> list[LabelledMotion]:
    """Labelled motions from mocap clips (BVH files or directories) labelled by ``label_files`` (a
    :class:`~vidstyle.motiongraph.labels.LabelBook`: label CSV ``file,label[,start,end]``, demo labels
    JSON, or a CMU ``clips.csv``; a ``<clip>.labels.json`` beside a clip is used too), resampled to ``fps``.
    Only labelled frames train: a clip is cut into its runs of frames whose label is one of ``classes``
    (default: any label but ``unlabelled``), runs shorter than ``min_frames`` working frames dropped. A
    clip with no such run is skipped with a warning; none at all is an :class:`InputError`."""
    from ..augmg.index import clip_files
    from ..mocap import read_bvh
    from ..mocap.keypoints import keypoint_positions
    from ..motiongraph.graph import has_tpose_first_frame
    from ..motiongraph.labels import UNLABELLED, LabelBook

    book = LabelBook()
    for f in label_files or []:
        book.load(f)
    keep = None if classes is None else set(map(str, classes))
    out = []
    for path in clip_files(clips):
        side = path.with_name(path.stem + ".labels.json")
        if side.is_file() and not book.has(path):
            book.load(side)
        motion = read_bvh(path)
        labels = np.array(book.frame_labels(path, motion.n_frames), dtype=object)
        if has_tpose_first_frame(motion):  # a CMU conversion's calibration T-pose is no action
            labels[0] = UNLABELLED
        step = float(motion.fps) / float(fps)
        idx = np.round(np.arange(0, motion.n_frames, step)).astype(int)
        idx = idx[idx < motion.n_frames]
        lab = labels[idx].astype(str)
        ok = (lab != UNLABELLED) if keep is None else np.isin(lab, list(keep))
        edges = np.diff(np.concatenate([[0], ok.astype(np.int8), [0]]))
        runs = [(a, b) for a, b in zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)) if b - a >= min_frames]
        if not runs:
            log.warning("%s: no labelled run of %d frames or more (labels %s); skipped", path, min_frames,
                        sorted(set(lab))[:5])
            continue
        pts = keypoint_positions(motion)[idx]
        facing = circular_median(motion.facing_angles())
        for a, b in runs:
            out.append(LabelledMotion(pts[a:b], list(lab[a:b]), float(fps), facing, f"{path.stem}[{idx[a]}:{idx[b - 1] + 1}]"))
    if not out:
        raise InputError(f"{', '.join(map(str, clips))}: no labelled frames to train on (give label files)")
    return out


def dataset_motions(dataset, performers: list[str], fps: float, phases=(0,)) -> list:
    """The labelled mocap takes of ``performers`` (each take once, whatever its number of videos)."""
    seen, out = set(), []
    for v in sorted(dataset.videos, key=lambda v: v.id):
        bvh = v.raw.get("bvh")
        if v.performer not in performers or not bvh or bvh in seen:
            continue
        seen.add(bvh)
        for ph in phases:
            out.append(labelled_motion(dataset.root / bvh, dataset.root / v.raw["bvh_labels"], fps, phase=ph))
    if not out:
        raise InputError(f"dataset: no mocap takes (bvh + bvh_labels) of the performers {performers}")
    return out


def check_training_memory(rec, n_frames: int) -> None:
    """Refuse (:func:`vidstyle.budget.require`, naming ``--views``) a training set of ``n_frames`` projected
    frames whose tracks and features would not fit in memory: per frame, the keypoints with their scores
    and labels, and the float64 features (mirrored too when ``rec.mirror``) while they are concatenated."""
    from ..budget import require

    copies = 2 if rec.mirror else 1
    per_frame = 15 * 3 * 8 + 64 + copies * rec.featurizer.dimension * 8 * 2
    require(n_frames * per_frame, f"the pose training set ({n_frames} projected frames)", "views",
            "fewer virtual views or training takes")


def train_from_dataset(dataset, split: str = "unseen-performer", seed: int = 0, test_view: str | None = None,
                       n_views: int = 8, noise: KeypointNoise | None = None, params: dict | None = None,
                       extra_motions: Sequence[LabelledMotion] = ()):
    """``(PoseRecognizer, header extra)`` trained on the mocap takes of the training performers (sets A
    and B) of ``split`` of a demo ``dataset`` (a :class:`~vidstyle.formats.dataset.Dataset`, or None: the
    ``extra_motions`` alone) and on ``extra_motions`` (:func:`clip_motions`), each seen from ``n_views``
    virtual cameras with ``noise``."""
    from .pipeline import split_header
    from .poserecognizer import PoseRecognizer
    from .splits import make_split

    motions, performers, header = list(extra_motions), [], {"kind": "clips"}
    fps = extra_motions[0].fps if extra_motions else None
    classes = None
    if dataset is not None:
        kind = "unseen-performer" if split == "unseen-camera" else split
        sp = make_split(dataset, kind, seed=seed, test_view=test_view)
        performers = sorted(set(sp.vocab_performers) | set(sp.train_performers))
        motions = dataset_motions(dataset, performers, dataset.fps) + motions
        fps, classes, header = dataset.fps, dataset.classes or None, split_header(sp, "A+B")
    if not motions:
        raise InputError("pose recognizer: nothing to train on")
    rec = PoseRecognizer(**{"random_state": seed, "fps": fps, **(params or {})})
    check_training_memory(rec, sum(len(m.points) for m in motions) * n_views)
    tracks, labels = virtual_views(motions, n_views, seed, noise)
    rec.fit(tracks, labels, classes=classes)
    training = {"performers": performers, "takes": [m.name for m in motions], "n_views": n_views,
                "noise": noise.to_dict() if noise else None}
    return rec, {"training": training, "split": header}
