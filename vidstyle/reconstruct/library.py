"""The mocap library a reconstruction searches: every clip on one skeleton, indexed for 2D kNN.

:class:`ReconstructionLibrary` (scikit-learn style: parameters in ``__init__``, :meth:`fit` learns) reads
mocap clips, puts them on one reference skeleton (:func:`vidstyle.mocap.retarget.retarget`: rotations kept,
root path scaled by the leg-length ratio; the reference is the first clip's skeleton unless one is given),
and keeps, for every ``stride``-th frame (an *indexed frame*, the unit of the kNN search):

- ``rotations_`` (N, J, 4) float32: the local joint rotations (x, y, z, w), the root's with its *yaw
  removed* (rotated by minus the character's facing, so every indexed pose faces +Z),
- ``root_height_`` (N,): the root joint's height above the floor (Y; library units), measured from the
  frame's lower ankle plus the library's planted-ankle height (the median lower-ankle height over its
  planted frames), so a clip recorded on a raised platform or with its floor off Y = 0 stands on the floor
  too (an airborne frame is put down on it: the flight of a jump is not kept),
- ``points_`` (N, 15, 3) float32: the body keypoints facing-normalised (:func:`..augmg.projection.
  facing_normalised`: facing +Z, pelvis above the origin), what a reconstruction is compared with,
- ``contacts_`` (N, 2) bool: left / right ankle planted (:func:`.metrics.foot_contacts` on the clip),
- ``labels_`` (N,) str: the clip's per-frame action label where the clip has a ``.labels.json``
  sidecar (:mod:`vidstyle.formats.labels`), else ``""``,

aligned with the 2D index :attr:`index_` (:class:`vidstyle.augmg.index.PoseIndex`, the one matcher AugMG
uses too: every indexed frame projected at ``n_views`` azimuths, one kd-tree per azimuth).

The stride is chosen so the indexed frames come at about the video's rate (``target_fps``): the lazy
neighbourhood graph's steps (:mod:`.olng`) assume library and video advance at rates within a factor 2.
"""

from __future__ import annotations

import logging
import os
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from ..errors import InputError, ParameterError

#: the left and right ankle keypoints (vidstyle.formats.keypoints.KEYPOINTS order)
KP_ANKLES = (13, 14)

log = logging.getLogger(__name__)


def _clip_labels(path: Path, n_frames: int, fps: float) -> np.ndarray:
    """(F,) per-frame labels of a clip from its ``<stem>.labels.json`` sidecar; ``""`` without one."""
    side = path.with_suffix("").with_suffix(".labels.json")
    out = np.full(n_frames, "", dtype=object)
    if not side.is_file():
        return out
    from ..formats.labels import read_labels

    try:
        labels = read_labels(side)
    except Exception as e:  # a broken sidecar costs the labels, not the reconstruction
        log.warning("%s: labels not used (%s)", side, e)
        return out
    src = np.asarray(labels.labels, dtype=object)
    if len(src):
        at = np.clip(np.round(np.arange(n_frames) / fps * labels.fps).astype(int), 0, len(src) - 1)
        out[:] = src[at]
    return out


class ReconstructionLibrary:
    """Library clips on one skeleton with their 2D index (module docstring). Parameters: ``n_views``
    azimuths and ``elevation_deg`` of the projection, ``target_fps`` (the indexed frames' approximate rate),
    ``jobs`` / ``scheduler`` for the projection."""

    def __init__(self, n_views: int = 12, elevation_deg: float = 10.0, target_fps: float = 20.0, jobs: int = 1,
                 scheduler: str | None = None) -> None:
        self.n_views = n_views
        self.elevation_deg = elevation_deg
        self.target_fps = target_fps
        self.jobs = jobs
        self.scheduler = scheduler

    def get_params(self) -> dict:
        return {"n_views": self.n_views, "elevation_deg": self.elevation_deg, "target_fps": self.target_fps}

    def fit(self, clips: Sequence[str | os.PathLike], skeleton=None) -> ReconstructionLibrary:
        """Read BVH ``clips`` (files or directories) and index them; ``skeleton`` (a
        :class:`vidstyle.mocap.skeleton.Skeleton`) is the output skeleton (default: the first clip's)."""
        from ..augmg.index import clip_files
        from ..mocap import read_bvh

        files = clip_files(clips)
        motions = [read_bvh(f) for f in files]
        return self.fit_motions(motions, [str(f) for f in files], skeleton=skeleton)

    def fit_motions(self, motions, paths: Sequence[str], skeleton=None) -> ReconstructionLibrary:
        """:meth:`fit` from motions already read (``paths`` name them)."""
        from ..augmg.index import LibraryClip, PoseIndex
        from ..augmg.projection import facing_normalised, facing_of_keypoints
        from ..mocap.keypoints import keypoint_positions
        from ..mocap.kinematics import forward_kinematics
        from ..mocap.placement import yaw_quat
        from ..mocap.quat import qmul
        from ..mocap.retarget import retarget
        from ..motiongraph.graph import has_tpose_first_frame
        from .metrics import foot_contacts

        if not 1 <= self.n_views <= 360:
            raise ParameterError("n_views", f"must be in 1..360, got {self.n_views}")
        if not (self.target_fps > 0 and np.isfinite(self.target_fps)):
            raise ParameterError("target_fps", f"must be a finite number > 0, got {self.target_fps}")
        if not motions:
            raise InputError("--library: no clips")
        reference = skeleton if skeleton is not None else motions[0].skeleton
        fps = np.array([m.fps for m in motions])
        self.stride_ = max(1, int(round(float(np.median(fps)) / self.target_fps)))
        self.skeleton_ = reference
        rots, heights, points, contacts, labels, lib_clips, lowers = [], [], [], [], [], [], []
        for path, motion in zip(paths, motions):
            m, _ = retarget(motion, reference, source=path)
            first = 1 if has_tpose_first_frame(m) else 0
            pos, mats = forward_kinematics(m)
            pts = keypoint_positions(m, positions=pos, matrices=mats)
            pts[:first] = pts[first:first + 1]  # never match a calibration T-pose
            facing = facing_of_keypoints(pts)
            q = m.rotations.copy()
            q[:, 0] = qmul(yaw_quat(-facing), q[:, 0])
            q[:first] = q[first:first + 1]
            sel = slice(None, None, self.stride_)
            rots.append(q[sel].astype(np.float32))
            lower = np.minimum(pts[:, KP_ANKLES[0], 1], pts[:, KP_ANKLES[1], 1])
            heights.append((m.root_positions[:, 1] - lower)[sel])
            lowers.append(lower[sel])
            points.append(facing_normalised(pts, facing)[sel].astype(np.float32))
            contacts.append(foot_contacts(pts, m.fps)[sel])
            labels.append(_clip_labels(Path(path), m.n_frames, m.fps)[sel])
            lib_clips.append(LibraryClip(path, pts, m.fps))
        self.index_ = PoseIndex(n_views=self.n_views, elevation_deg=self.elevation_deg, stride=self.stride_,
                                jobs=self.jobs, scheduler=self.scheduler).fit(lib_clips)
        self.rotations_ = np.concatenate(rots)
        contacts_all = np.concatenate(contacts)
        lower_all = np.concatenate(lowers)
        planted = contacts_all.any(axis=1)
        self.ankle_height_ = float(np.median(lower_all[planted] if planted.any() else lower_all))
        self.root_height_ = np.concatenate(heights) + self.ankle_height_
        self.points_ = np.concatenate(points)
        self.contacts_ = np.concatenate(contacts)
        self.labels_ = np.concatenate(labels)
        self.paths_ = list(paths)
        if len(self.rotations_) != self.index_.n_frames:  # both take every stride-th frame of every clip
            raise AssertionError("library arrays and index disagree")
        log.info("library: %d clips, %d indexed frames (every %d-th), %d views", len(paths), len(self.rotations_),
                 self.stride_, self.n_views)
        return self

    @property
    def n_frames(self) -> int:
        return len(self.rotations_)

    def __getstate__(self) -> dict:
        state = dict(self.__dict__)
        state.pop("_augmented_cache", None)  # query-time caches are rebuilt on demand
        return state


#: bump when what a cached library holds changes (old cache files are then ignored, not misread)
CACHE_VERSION = 1


def library_cache_key(files: Sequence[str | os.PathLike], params: dict, skeleton=None) -> str:
    """sha256 naming a fitted library: the bytes of every clip (and its ``.labels.json`` when there is one),
    in order, the library parameters, the output skeleton (names, parents, offsets; None: the first clip's)
    and :data:`CACHE_VERSION` with the package version."""
    import hashlib
    import json

    from .. import __version__
    from ..formats.annotations import file_sha256

    h = hashlib.sha256()
    h.update(json.dumps({"cache": CACHE_VERSION, "vidstyle": __version__, "params": params}, sort_keys=True).encode())
    for f in files:
        f = Path(f)
        h.update(file_sha256(f).encode())
        lab = f.with_suffix(".labels.json")
        h.update(file_sha256(lab).encode() if lab.is_file() else b"-")
    if skeleton is not None:
        h.update(json.dumps([list(skeleton.names), skeleton.parents.tolist()]).encode())
        h.update(np.ascontiguousarray(skeleton.offsets, dtype=np.float64).tobytes())
    return h.hexdigest()


def cached_library(library: ReconstructionLibrary, clips, skeleton=None,
                   cache_dir: str | os.PathLike | None = None) -> ReconstructionLibrary:
    """``library.fit(clips, skeleton)``, or, with ``cache_dir``, the library fitted before on the same clip
    bytes, parameters and skeleton (``<cache_dir>/library-<key>.joblib``, :func:`library_cache_key`),
    written there atomically after a fit. A cache file that cannot be read is refitted over (and says so)."""
    if cache_dir is None:
        return library.fit(clips, skeleton=skeleton)
    import joblib

    from ..augmg.index import clip_files
    from ..fileio import atomic_path, make_dir

    files = clip_files(clips)
    key = library_cache_key(files, library.get_params(), skeleton)
    path = Path(cache_dir) / f"library-{key[:32]}.joblib"
    if path.is_file():
        try:
            cached = joblib.load(path)
            if isinstance(cached, ReconstructionLibrary) and getattr(cached, "cache_key_", None) == key:
                cached.jobs, cached.scheduler = library.jobs, library.scheduler
                log.info("library: %d indexed frames from the cache %s", cached.n_frames, path)
                return cached
            log.warning("%s: not a cached library of these clips; refitting", path)
        except Exception as e:  # a truncated or foreign file: refit and overwrite
            log.warning("%s: unreadable cache (%s); refitting", path, e.__class__.__name__)
    library.fit(files, skeleton=skeleton)
    library.cache_key_ = key
    make_dir(path.parent)
    with atomic_path(path) as tmp:
        joblib.dump(library, tmp)
    log.info("library: cached in %s", path)
    return library
