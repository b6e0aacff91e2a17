"""The motion graph: clips at one frame rate, an open table of edges between their frames, pruned to its
largest strongly connected component.

Frames of all clips are numbered globally, clip after clip (``N`` frames, ``J`` joints, ``k`` =
``window``). The graph's **nodes are frames**; its **edges** are one table (``E`` rows, all ``(E,)`` unless
noted) with a ``kind`` column:

========================  ==========  =========================================================================
attribute                 shape       meaning
========================  ==========  =========================================================================
``edge_src_``             (E,) int    graph frame shown just before the edge's frames
``edge_dst_``             (E,) int    graph frame the edge arrives at (its last output frame, a pure frame)
``edge_kind_``            (E,) int8   :class:`EdgeKind`: ``PLAYBACK`` 0, ``BLEND`` 1, ``ENHANCEMENT`` 2
``edge_cost_``            (E,) float  cost the planner charges (RMS point-cloud distance, length unit); 0 for
                                      playback
``edge_segment_``         (E,) int    id of the stored motion segment an enhancement passes through, else -1
``edge_align_``           (E, 3)      ``(theta, x0, z0)``: the :class:`~vidstyle.mocap.placement.Placement`
                                      that puts the arriving clip (``dst``'s) into the departing clip's
                                      (``src``'s) coordinates; zeros for playback
``edge_align_segment_``   (E, 3)      for an enhancement, the placement of the segment into ``src``'s
                                      coordinates; NaN for other kinds
``edge_in_scc_``          (E,) bool   both ends in the kept component (only those are walked)
``scc_``                  (N,) bool   frame is in the largest strongly connected component
========================  ==========  =========================================================================

What an edge ``src -> dst`` puts into a walk (the walk has just shown frame ``src``):

- ``PLAYBACK``: ``dst = src + 1`` inside one clip; 1 output frame, ``dst``.
- ``BLEND`` (Kovar): ``k`` output frames ``p = 0..k-1`` blending ``src+1+p`` (departing) with
  ``dst-k+1+p`` (arriving, placed by ``edge_align``) with weight ``1 - alpha(p)`` on the arriving frame
  (:func:`.blend.blend_weight`); the last is exactly ``dst``. Both windows lie inside one clip each.
  (The transition ``i -> j`` of Kovar's paper, blend frames ``i..i+k-1`` against ``j-k+1..j``, is the
  edge ``src = i - 1``, ``dst = j``.) Default cost: RMS distance of those two aligned windows.
- ``ENHANCEMENT`` (AugMG, the thesis' two-half blend through a segment ``W`` centred on ``w_z``): ``2k``
  output frames. ``p = 0..k-1`` blend ``a_{src+1+p}`` with ``w_{z-k+1+p}`` (``W`` placed onto A by
  ``edge_align_segment``), so output frame ``k-1`` is exactly ``w_z``; then ``q = 0..k-1`` blend
  ``w_{z+1+q}`` with ``b_{dst-k+1+q}`` (B placed onto ``W``; ``edge_align`` is the composite B -> A), the
  last being exactly ``dst``. In the thesis' indices (``a_i = src``, ``b_j = dst``): ``a_i..a_{i+k}``
  blended with ``w_{z-k}..w_z``, then ``w_z..w_{z+k}`` with ``b_{j-k}..b_j``, where the end frames of each
  half carry weight 0 or 1. ``W`` therefore needs frames ``w_{z-k+1}..w_{z+k-1}`` (``2k - 1``; ``w_{z+k}``,
  when stored, has weight 0 and only refines the alignment). For labels (planner mismatches, walk
  labels) the first ``k`` frames count as the departing frames ``src+1..src+k``, the last ``k`` as the
  arriving ``dst-k+1..dst``. Default cost: the sum of the RMS distances of the two halves' aligned windows.
  A segment with *anchors* (its enhancement nodes ``a_in < z < a_out``, the library frames that look like
  the departure and the arrival) is aligned by those windows instead (``w_{a_in-k+1..a_in}`` onto A,
  B onto ``w_{a_out..a_out+k-1}``), so the library's own travel from its nodes into ``w_z`` is kept; a
  segment with a *hold* shows ``w_z``'s neighbourhood with full weight over about that fraction of the
  ``2k`` frames (:func:`.blend.blend_frames` ``ramp``/``start``).

A **segment** (:class:`EnhancementSegment`, ``segments_``) is a short motion on the graph's skeleton:
``rotations`` (L, J, 4) local quaternions (x, y, z, w), ``root_positions`` (L, 3), ``centre`` (its ``w_z``,
``k-1 <= centre <= L-k``), a ``source`` string, a ``label``, optional ``anchors`` and a ``hold``.

Open API: :meth:`MotionGraph.add_segment`, :meth:`MotionGraph.add_edges`, :meth:`MotionGraph.remove_edges`,
:meth:`MotionGraph.prune` (the largest-SCC pruning over all edges, re-run after edits; scipy.sparse.csgraph).
Pruning keeps the largest strongly connected component of the frame graph, so every kept frame can reach
every other and has an edge in and out: a walk never dead-ends at the end of a clip. Edges whose ends are
outside the component stay in the table (``edge_in_scc_`` False).

The graph file (``.npz``, schema version 2) is owned by :mod:`vidstyle.formats.motiongraph`.
"""

from __future__ import annotations

import hashlib
import logging
import time
from collections.abc import Sequence
from dataclasses import dataclass
from enum import IntEnum
from pathlib import Path

import numpy as np

from ..errors import FormatError, InputError, ParameterError
from ..formats.motiongraph import MotionGraphRecord, read_graph, write_graph
from ..mocap import Motion, Skeleton, global_positions
from . import defaults
from .distance import TILE_GROUP, WindowSet, align_windows, all_pair_candidates, joint_weights, sample_distances
from .labels import UNLABELLED, LabelBook, resample_labels

log = logging.getLogger(__name__)

SCHEMA = "vidstyle.motiongraph/2"


class EdgeKind(IntEnum):
    """The ``kind`` column of the edge table (see the module docstring)."""

    PLAYBACK = 0
    BLEND = 1
    ENHANCEMENT = 2


@dataclass
class EnhancementSegment:
    """A short motion stored in the graph, on the graph's skeleton: ``rotations`` (L, J, 4),
    ``root_positions`` (L, 3), ``centre`` the index of its middle pose ``w_z``. ``anchors``: optional
    ``(a_in, a_out)``, the segment's enhancement nodes: enhancement edges align the departing window onto
    ``w_{a_in-k+1..a_in}`` and the arriving window onto ``w_{a_out..a_out+k-1}`` instead of the windows
    beside ``w_z`` (None). ``hold``: the fraction of an enhancement's ``2k`` frames, about ``w_z``, shown
    with the segment's full weight (0: the two-half blend touches ``w_z`` at one frame)."""

    rotations: np.ndarray
    root_positions: np.ndarray
    centre: int
    source: str = ""
    label: str = ""
    anchors: tuple[int, int] | None = None
    hold: float = 0.0

    @property
    def n_frames(self) -> int:
        return len(self.rotations)


@dataclass
class Clip:
    """One source clip, before resampling."""

    name: str
    motion: Motion
    labels: list[str]  # one per frame of ``motion``
    path: str = ""
    sha256: str = ""


def has_tpose_first_frame(motion: Motion, degrees: float = 10.0) -> bool:
    """True when frame 0 is a calibration pose: the mean joint rotation jumps by more than ``degrees``
    between frames 0 and 1 (CMU files start with a T-pose; real motion moves far less per frame)."""
    if motion.n_frames < 3:
        return False
    q0, q1, q2 = motion.rotations[0], motion.rotations[1], motion.rotations[2]
    step01 = 2 * np.degrees(np.arccos(np.clip(np.abs(np.sum(q0 * q1, -1)), 0, 1))).mean()
    step12 = 2 * np.degrees(np.arccos(np.clip(np.abs(np.sum(q1 * q2, -1)), 0, 1))).mean()
    return step01 > degrees and step01 > 5 * step12


def rest_height(skeleton: Skeleton) -> float:
    """Height of the root above the lowest joint or End Site in the rest pose (the leg length used to
    retarget, :func:`vidstyle.mocap.retarget.leg_length`)."""
    from ..mocap.retarget import leg_length

    return leg_length(skeleton)


def load_clips(paths: Sequence[str | Path], label_files: Sequence[str | Path] = ()) -> list[Clip]:
    """Read BVH clips (files or directories of ``*.bvh``) and their labels (see :mod:`.labels`)."""
    from ..mocap import read_bvh

    files: list[Path] = []
    for p in map(Path, paths):
        if p.is_dir():
            files.extend(sorted(p.glob("*.bvh")))
        elif p.is_file():
            files.append(p)
        else:
            raise InputError(f"{p}: no such clip file or directory")
    if not files:
        raise InputError("clips: no .bvh files given")
    book = LabelBook()
    for lf in label_files:
        book.load(lf)
    clips = []
    for f in files:
        sidecar = f.with_name(f.stem + ".labels.json")
        if not book.has(f) and sidecar.is_file():
            book.load(sidecar)
        data = f.read_bytes()
        motion = read_bvh(f)
        clips.append(Clip(f.stem, motion, book.frame_labels(f, motion.n_frames), str(f), hashlib.sha256(data).hexdigest()))
    return clips


def _as_index_array(x, name: str) -> np.ndarray:
    a = np.atleast_1d(np.asarray(x))
    if a.ndim != 1 or (a.size and a.dtype.kind not in "iu"):
        raise ValueError(f"{name}: expected integer frame indices, got {a.dtype} array of shape {a.shape}")
    return a.astype(np.int64)


class MotionGraph:
    """Motion graph estimator (scikit-learn style: parameters in ``__init__``, ``fit`` learns the graph).

    Parameters
    ----------
    window : blend / comparison window ``k`` in frames at ``fps``.
    fps : frame rate every clip is resampled to.
    threshold : RMS point-cloud distance (length unit of the clips) below which local minima become
        transitions; ``None`` takes the ``threshold_quantile`` of the distance over random window pairs.
    threshold_quantile : see ``threshold``.
    min_gap : within one clip, pairs of windows closer than this many frames are not transitions
        (default ``2 * window``).
    drop_tpose : drop frame 0 of clips whose first frame is a calibration pose (CMU).
    tile, dtype : tile size and GEMM precision of the all-pairs pass (float32 GEMM; candidates are
        re-evaluated in float64).
    n_jobs, scheduler : run tiles in this process (1), on joblib workers, or on a Dask scheduler.
    n_samples : random pairs for the threshold quantile.
    random_state : seed of that sample.
    mirror : also add the left/right mirror image of every clip (named ``<clip>~mirror``), which doubles
        the data and the transitions between rare actions.

    Learned attributes: the frame database (``skeleton_``, ``rotations_`` (N, J, 4), ``root_positions_``
    (N, 3), ``frame_clip_`` (N,), ``labels_`` (N,) into ``label_names_``, ``clips_``), the edge table and
    ``scc_`` (module docstring), ``segments_``, ``joint_weights_`` (J,), ``threshold_``, ``stats_``.
    """

    def __init__(
        self,
        window: int = defaults.WINDOW,
        fps: float = defaults.FPS,
        threshold: float | None = None,
        threshold_quantile: float = defaults.THRESHOLD_QUANTILE,
        min_gap: int | None = None,
        drop_tpose: bool = defaults.DROP_TPOSE,
        tile: int = defaults.TILE,
        dtype: str = defaults.DTYPE,
        n_jobs: int = defaults.N_JOBS,
        scheduler: str | None = None,
        n_samples: int = defaults.N_SAMPLES,
        random_state: int = defaults.RANDOM_STATE,
        mirror: bool = defaults.MIRROR,
    ) -> None:
        self.window = window
        self.fps = fps
        self.threshold = threshold
        self.threshold_quantile = threshold_quantile
        self.min_gap = min_gap
        self.drop_tpose = drop_tpose
        self.tile = tile
        self.dtype = dtype
        self.n_jobs = n_jobs
        self.scheduler = scheduler
        self.n_samples = n_samples
        self.random_state = random_state
        self.mirror = mirror

    PARAMS = ("window", "fps", "threshold", "threshold_quantile", "min_gap", "drop_tpose", "tile", "dtype",
              "n_jobs", "scheduler", "n_samples", "random_state", "mirror")

    def get_params(self) -> dict:
        return {k: getattr(self, k) for k in self.PARAMS}

    def check_params(self) -> None:
        """Raise :class:`ParameterError` naming the first parameter out of range (``fit`` calls this)."""
        if self.dtype not in defaults.DTYPES:
            raise ParameterError("dtype", f"float32 or float64, got {self.dtype!r}")
        if not 0 < self.threshold_quantile < 1:
            raise ParameterError("threshold_quantile", f"must be in (0, 1), got {self.threshold_quantile}")
        if self.threshold is not None and not self.threshold > 0:
            raise ParameterError("threshold", f"must be positive, got {self.threshold}")
        if self.tile < defaults.MIN_TILE:
            raise ParameterError("tile", f"must be at least {defaults.MIN_TILE}, got {self.tile}")

    def memory_estimate(self, n_frames: int, n_joints: int, window: int | None = None) -> int:
        """Bytes a fit over ``n_frames`` frames of ``n_joints`` joints needs at these settings, upper side:
        per frame, the rotations, forward kinematics, window features, candidate pairs and edges (calibrated
        on CMU clips: peak RSS growth 305 MB for 15k frames and 643 MB for 29.5k frames, 31 joints, tile
        2048, two threads, about 700 bytes per joint-frame at the margin); per tile worker, the distance
        tile and its in-place buffers (``tile^2``) and the features of a row and a column block (``tile x 3
        x window x joints``); in-process, the block features the tile threads share (``TILE_GROUP +
        threads + 1`` blocks of ``tile x 5 x window x joints`` GEMM operands, about 90 MB at tile 2048 and
        31 joints; the 29.5k build then measured 797 MB of peak RSS growth). This gives 595 and 884 MB for
        those two builds."""
        import os

        k = int(self.window if window is None else window)
        cores = os.cpu_count() or 1  # n_jobs 1: one thread per core; -1: one worker per core
        workers = 1 if self.scheduler else cores if self.n_jobs in (1, -1) else int(self.n_jobs)
        tile = int(self.tile)
        per_frame = n_joints * 640 + 1024
        per_worker = tile * tile * 4 * 3 + 2 * 2 * tile * 3 * k * n_joints * 8
        shared = 0 if self.scheduler or self.n_jobs != 1 else (TILE_GROUP + workers + 1) * tile * 5 * k * n_joints * 4
        return int(n_frames * per_frame + workers * per_worker + shared)

    def _check_memory(self, n_frames: int, n_joints: int, k: int) -> None:
        from ..budget import require

        total, tiles = self.memory_estimate(n_frames, n_joints, k), self.memory_estimate(0, n_joints, k)
        require(total, f"the motion graph over {n_frames} frames ({n_joints} joints, tile {self.tile})",
                "tile" if tiles > total / 2 else None,  # the tiles' buffers are the bigger part: --tile's to fix
                "fewer or shorter clips, a lower --fps, a smaller --tile or fewer --jobs")

    # ------------------------------------------------------------------------------------------ fit
    def fit(self, clips: Sequence[Clip]) -> MotionGraph:
        from ..mocap.retarget import retarget_clips

        self.check_params()
        k = int(self.window)
        if k < 2:
            raise InputError(f"window: must be at least 2 frames, got {k}")
        if not self.fps > 0:
            raise InputError(f"fps: must be positive, got {self.fps}")
        if not clips:
            raise InputError("clips: no clips")
        t_start = time.perf_counter()
        if self.mirror:
            try:
                clips = list(clips) + [Clip(c.name + "~mirror", c.motion.mirror(), c.labels, c.path, c.sha256) for c in clips]
            except ValueError as e:
                raise InputError(f"mirror: cannot mirror the skeleton ({e})") from None
        ref = clips[0].motion.skeleton
        rots, roots, frame_clip, labels = [], [], [], []
        meta = {"names": [], "paths": [], "sha": [], "start": [], "frames": [], "first": [], "src_fps": [], "scale": []}
        n = 0
        # retarget onto the first clip's skeleton: keep local rotations, scale the root path by leg length
        targeted = retarget_clips([c.motion for c in clips], ref, [c.path or c.name for c in clips])
        for c, (clip, (m, scale)) in enumerate(zip(clips, targeted)):
            first = 1 if self.drop_tpose and has_tpose_first_frame(m) else 0
            src_fps = m.fps
            m = m[first:]
            if abs(m.fps - self.fps) > 1e-9:
                m = m.resample(self.fps)
            lab = resample_labels(clip.labels, src_fps, self.fps, m.n_frames, first=first) if clip.labels else [UNLABELLED] * m.n_frames
            rots.append(m.rotations)
            roots.append(m.root_positions)
            frame_clip.append(np.full(m.n_frames, c))
            labels.extend(lab)
            for key, val in zip(meta, (clip.name, clip.path, clip.sha256, n, m.n_frames, first, src_fps, scale)):
                meta[key].append(val)
            n += m.n_frames
        self.skeleton_ = ref
        self.rotations_ = np.concatenate(rots)
        self.root_positions_ = np.concatenate(roots)
        self.frame_clip_ = np.concatenate(frame_clip)
        self.label_names_ = sorted(set(labels))
        lookup = {name: i for i, name in enumerate(self.label_names_)}
        self.labels_ = np.array([lookup[x] for x in labels], dtype=np.int64)
        self.clips_ = meta
        self.joint_weights_ = joint_weights(ref.parents)
        self.segments_: list[EnhancementSegment] = []
        min_gap = int(self.min_gap) if self.min_gap is not None else 2 * k

        self._check_memory(n, len(ref.parents), k)
        positions = global_positions(self.motion())
        ws = WindowSet.from_clips(positions, self.frame_clip_, self.joint_weights_, k)
        W = ws.total_weight
        sample = sample_distances(ws, self.n_samples, min_gap, self.random_state)
        if self.threshold is None:
            if not len(sample):
                raise InputError("clips: too few frames for any window pair")
            thr = float(np.sqrt(np.quantile(sample, self.threshold_quantile) / W))
        else:
            thr = float(self.threshold)
        self.threshold_ = thr
        t_dist = time.perf_counter()
        cand = all_pair_candidates(
            ws, thr * thr * W, min_gap, tile=self.tile, dtype=np.dtype(self.dtype).type, n_jobs=self.n_jobs,
            scheduler=self.scheduler,
        )
        self.distance_seconds_ = time.perf_counter() - t_dist
        self._init_edges(ws, cand)
        self.prune()
        n_blend = int((self.edge_kind_ == EdgeKind.BLEND).sum())
        self.stats_ = {
            "frames": int(n),
            "windows": int(ws.n_windows),
            "pairs": int(cand.n_pairs),
            "pairs_below_threshold": int(cand.n_below),
            "fraction_below_threshold": cand.n_below / max(cand.n_pairs, 1),
            "candidates": len(cand.a),
            "transitions": n_blend,
            "transitions_in_scc": int((self.edge_in_scc_ & (self.edge_kind_ == EdgeKind.BLEND)).sum()),
            "scc_frames": int(self.scc_.sum()),
            "threshold": thr,
            "distance_seconds": self.distance_seconds_,
            "build_seconds": time.perf_counter() - t_start,
        }
        log.info("motion graph: %d frames, %d transitions (%d in the largest SCC of %d frames), threshold %.4g",
                 n, n_blend, self.stats_["transitions_in_scc"], self.scc_.sum(), thr)
        return self

    def _init_edges(self, ws: WindowSet, cand) -> None:
        """Playback edges and the Kovar blends of the candidate window pairs (both directions)."""
        from ..mocap.placement import inverse_placements

        k = ws.k
        W = ws.total_weight
        a_f, b_f = ws.starts[cand.a], ws.starts[cand.b]
        cost = np.sqrt(np.maximum(cand.D, 0) / W)
        inv = inverse_placements(cand.theta, cand.x0, cand.z0)
        # window a (frames a_f..a_f+k-1) blends into window b (b_f..b_f+k-1) and vice versa
        src = np.concatenate([a_f, b_f]) - 1
        dst = np.concatenate([b_f, a_f]) + k - 1
        align = np.concatenate([np.stack([cand.theta, cand.x0, cand.z0], 1).reshape(-1, 3), inv])
        cost = np.concatenate([cost, cost])
        # the departing clip must have a frame before the blend
        ok = (src >= 0) & (self.frame_clip_[np.maximum(src, 0)] == self.frame_clip_[src + 1])
        order = np.lexsort((dst[ok], src[ok]))
        f = np.arange(self.n_frames - 1)
        play = f[self.frame_clip_[f] == self.frame_clip_[f + 1]]
        P = len(play)
        self.edge_src_ = np.concatenate([play, src[ok][order]]).astype(np.int64)
        self.edge_dst_ = np.concatenate([play + 1, dst[ok][order]]).astype(np.int64)
        kinds = np.full(len(self.edge_src_), EdgeKind.BLEND, np.int8)
        kinds[:P] = EdgeKind.PLAYBACK
        self.edge_kind_ = kinds
        self.edge_cost_ = np.concatenate([np.zeros(P), cost[ok][order]])
        self.edge_segment_ = np.full(len(self.edge_src_), -1, np.int64)
        self.edge_align_ = np.concatenate([np.zeros((P, 3)), align[ok][order]])
        self.edge_align_segment_ = np.full((len(self.edge_src_), 3), np.nan)
        self.edge_in_scc_ = np.zeros(len(self.edge_src_), bool)

    # ------------------------------------------------------------------------------------------ open API
    def add_segment(self, rotations: np.ndarray, root_positions: np.ndarray, centre: int | None = None,
                    source: str = "", label: str = "", anchors: tuple[int, int] | None = None,
                    hold: float = 0.0) -> int:
        """Store a short motion ``W`` on the graph's skeleton and return its id (for ``add_edges``).

        ``rotations`` (L, J, 4) local joint quaternions (x, y, z, w; normalised here), ``root_positions``
        (L, 3) in the graph's length unit, ``centre`` the index of the middle pose ``w_z`` (default
        ``L // 2``); an enhancement needs ``window - 1`` frames on each side of it
        (``w_{z-k+1}..w_{z+k-1}``). ``source`` (e.g. ``"clip.bvh@3.25s"``) and ``label`` are kept as metadata.
        ``anchors`` ``(a_in, a_out)``: the enhancement nodes (see :class:`EnhancementSegment`), with
        ``k - 1 <= a_in <= centre <= a_out <= L - k``; ``hold`` in [0, 1).
        """
        k = int(self.window)
        J = self.skeleton_.n_joints
        rot = np.array(rotations, dtype=np.float64)
        root = np.array(root_positions, dtype=np.float64)
        if rot.ndim != 3 or rot.shape[1:] != (J, 4):
            raise ValueError(f"rotations: expected shape (L, {J}, 4) on the graph's skeleton, got {rot.shape}")
        L = len(rot)
        if root.shape != (L, 3):
            raise ValueError(f"root_positions: expected shape ({L}, 3), got {root.shape}")
        if not (np.isfinite(rot).all() and np.isfinite(root).all()):
            raise ValueError("rotations / root_positions: contain NaN or inf")
        norm = np.linalg.norm(rot, axis=-1, keepdims=True)
        if not (norm > 1e-9).all():
            raise ValueError("rotations: contain a zero quaternion")
        c = L // 2 if centre is None else int(centre)
        if not (k - 1 <= c <= L - k):
            raise ValueError(f"centre: {c} leaves fewer than window - 1 = {k - 1} frames on one side of a "
                             f"{L}-frame segment (needs {k - 1} <= centre <= {L - k})")
        if anchors is not None:
            a_in, a_out = (int(x) for x in anchors)
            if not (k - 1 <= a_in <= c <= a_out <= L - k):
                raise ValueError(f"anchors: ({a_in}, {a_out}) must satisfy window - 1 = {k - 1} <= a_in <= centre = {c} "
                                 f"<= a_out <= {L - k} (L - window)")
            anchors = (a_in, a_out)
        if not 0.0 <= float(hold) < 1.0:
            raise ValueError(f"hold: must be in [0, 1), got {hold}")
        self.segments_.append(EnhancementSegment(rot / norm, root, c, str(source), str(label), anchors, float(hold)))
        return len(self.segments_) - 1

    def add_segment_from(self, motion: Motion, time: float, source: str = "", label: str = "") -> int:
        """Store the window of a library ``motion`` around ``time`` (seconds) as a segment: the motion is
        retargeted onto the graph's skeleton (:func:`vidstyle.mocap.retarget.retarget`; same joint
        layout required), resampled to the graph's ``fps``, and frames ``w_{z-k+1}..w_{z+k}`` around the
        frame ``z`` nearest ``time`` are kept (fewer at a clip end; ``ValueError`` when fewer than
        ``k - 1`` remain on a side). Returns the segment id."""
        from ..mocap.retarget import retarget

        k = int(self.window)
        m, _ = retarget(motion, self.skeleton_, source or "motion")
        if abs(m.fps - self.fps) > 1e-9:
            m = m.resample(self.fps)
        z = int(round(float(time) * self.fps))
        if not 0 <= z < m.n_frames:
            raise ValueError(f"time: {time} s is outside the motion (0 .. {m.duration:.3f} s)")
        lo, hi = z - k + 1, min(z + k + 1, m.n_frames)
        if lo < 0 or hi - z < k:
            raise ValueError(f"time: {time} s is closer than window - 1 = {k - 1} frames to an end of the motion")
        return self.add_segment(m.rotations[lo:hi], m.root_positions[lo:hi], centre=z - lo, source=source, label=label)

    def add_edges(self, src, dst, kind: EdgeKind | int, cost=None, segment=None) -> np.ndarray:
        """Append edges ``src -> dst`` (graph frames, scalars or (n,) arrays) of one ``kind`` and return
        their row indices in the edge table.

        ``cost`` (scalar or (n,)): the planner's cost; ``None`` computes the default (the Kovar window
        distance, see the module docstring; 0 for playback). ``segment``: the segment id(s) of
        ``ENHANCEMENT`` edges (required for them, not allowed for the others). Alignments are computed
        here. New edges count as walkable when both ends are in the current component; call
        :meth:`prune` to recompute the component itself.
        """
        kind = EdgeKind(int(kind))
        src = _as_index_array(src, "src")
        dst = _as_index_array(dst, "dst")
        n = max(len(src), len(dst))
        src, dst = np.broadcast_to(src, (n,)).copy(), np.broadcast_to(dst, (n,)).copy()
        N, k = self.n_frames, int(self.window)
        if n and (src.min() < 0 or dst.min() < 0 or src.max() >= N or dst.max() >= N):
            raise ValueError(f"src/dst: frame indices must be in [0, {N})")
        clip = self.frame_clip_
        seg = np.full(n, -1, np.int64)
        if kind == EdgeKind.ENHANCEMENT:
            if segment is None:
                raise ValueError("segment: required for ENHANCEMENT edges")
            seg = np.broadcast_to(_as_index_array(segment, "segment"), (n,)).copy()
            if n and (seg.min() < 0 or seg.max() >= len(self.segments_)):
                raise ValueError(f"segment: ids must be in [0, {len(self.segments_)}) (add_segment first)")
        elif segment is not None and np.any(np.asarray(segment) >= 0):
            raise ValueError(f"segment: only ENHANCEMENT edges pass through a segment, not {kind.name}")
        if kind == EdgeKind.PLAYBACK:
            bad = (dst != src + 1) | (clip[src] != clip[np.minimum(src + 1, N - 1)]) | (src + 1 >= N)
            if bad.any():
                i = int(np.flatnonzero(bad)[0])
                raise ValueError(f"PLAYBACK edge {src[i]} -> {dst[i]}: must go to the next frame of the same clip")
        else:
            hi = np.minimum(src + k, N - 1)
            lo = np.maximum(dst - k + 1, 0)
            bad = (src + k >= N) | (clip[hi] != clip[src]) | (dst - k + 1 < 0) | (clip[lo] != clip[dst])
            if bad.any():
                i = int(np.flatnonzero(bad)[0])
                raise ValueError(f"{kind.name} edge {src[i]} -> {dst[i]}: frames src+1..src+{k} and dst-{k - 1}..dst "
                                 "must each lie inside one clip")
        align = np.zeros((n, 3))
        align_seg = np.full((n, 3), np.nan)
        dist = np.zeros(n)
        if kind != EdgeKind.PLAYBACK and n:
            if kind == EdgeKind.BLEND:
                dist, align = self._blend_alignment(src, dst)
            else:
                dist, align, align_seg = self._enhancement_alignment(src, dst, seg)
        if cost is None:
            c = dist
        else:
            c = np.broadcast_to(np.asarray(cost, dtype=np.float64), (n,)).copy()
            if not np.isfinite(c).all() or (c < 0).any():
                raise ValueError("cost: must be finite and non-negative")
        self.edge_src_ = np.concatenate([self.edge_src_, src])
        self.edge_dst_ = np.concatenate([self.edge_dst_, dst])
        self.edge_kind_ = np.concatenate([self.edge_kind_, np.full(n, int(kind), np.int8)])
        self.edge_cost_ = np.concatenate([self.edge_cost_, c])
        self.edge_segment_ = np.concatenate([self.edge_segment_, seg])
        self.edge_align_ = np.concatenate([self.edge_align_, align])
        self.edge_align_segment_ = np.concatenate([self.edge_align_segment_, align_seg])
        self.edge_in_scc_ = np.concatenate([self.edge_in_scc_, self.scc_[src] & self.scc_[dst]])
        return np.arange(len(self.edge_src_) - n, len(self.edge_src_))

    def remove_edges(self, edges) -> None:
        """Delete rows ``edges`` (indices or a (E,) bool mask) of the edge table; later rows move up.
        Call :meth:`prune` afterwards to recompute the component."""
        e = np.asarray(edges)
        keep = np.ones(self.n_edges, bool)
        keep[e] = False
        for name in ("src", "dst", "kind", "cost", "segment", "align", "align_segment", "in_scc"):
            setattr(self, f"edge_{name}_", getattr(self, f"edge_{name}_")[keep])

    def prune(self) -> MotionGraph:
        """Recompute ``scc_`` (the largest strongly connected component over every edge of the table,
        scipy.sparse.csgraph) and ``edge_in_scc_``."""
        from scipy.sparse import coo_matrix
        from scipy.sparse.csgraph import connected_components

        N = self.n_frames
        g = coo_matrix((np.ones(self.n_edges), (self.edge_src_, self.edge_dst_)), shape=(N, N)).tocsr()
        n_comp, comp = connected_components(g, directed=True, connection="strong")
        sizes = np.bincount(comp, minlength=n_comp)
        big = int(np.argmax(sizes))
        # a component of one frame with no self-loop is not a cycle: no walk can stay in it
        self.scc_ = comp == big if sizes[big] > 1 else np.zeros(N, bool)
        self.edge_in_scc_ = self.scc_[self.edge_src_] & self.scc_[self.edge_dst_]
        return self

    # ------------------------------------------------------------------------------------------ alignment
    def _positions(self, rotations: np.ndarray, root_positions: np.ndarray) -> np.ndarray:
        sh = rotations.shape
        m = Motion(self.skeleton_, rotations.reshape(-1, *sh[-2:]), None, self.fps,
                   root_positions=root_positions.reshape(-1, 3))
        return global_positions(m).reshape(*sh[:-2], self.skeleton_.n_joints, 3)

    def _frame_positions(self, frames: np.ndarray) -> np.ndarray:
        return self._positions(self.rotations_[frames], self.root_positions_[frames])

    def _rms(self, D: np.ndarray, k: int) -> np.ndarray:
        return np.sqrt(np.maximum(D, 0) / (self.joint_weights_.sum() * k))

    def _blend_alignment(self, src: np.ndarray, dst: np.ndarray):
        k = int(self.window)
        p = np.arange(k)
        pa = self._frame_positions(src[:, None] + 1 + p)
        pb = self._frame_positions(dst[:, None] - k + 1 + p)
        D, th, x0, z0 = align_windows(pa, pb, self.joint_weights_)
        return self._rms(D, k), np.stack([th, x0, z0], 1)

    def _enhancement_alignment(self, src: np.ndarray, dst: np.ndarray, seg: np.ndarray):
        from ..mocap.placement import Placement

        k = int(self.window)
        p = np.arange(k)
        n = len(src)
        dist = np.zeros(n)
        align = np.zeros((n, 3))
        align_seg = np.zeros((n, 3))
        for s in np.unique(seg):
            sel = np.flatnonzero(seg == s)
            S = self.segments_[int(s)]
            c = S.centre
            wpos = self._positions(S.rotations, S.root_positions)
            # first half: W (w_{z-k+1}..w_z, or the departure node's window) onto A (src+1..src+k)
            a_in = c if S.anchors is None else S.anchors[0]
            pa = self._frame_positions(src[sel, None] + 1 + p)
            D1, t1, x1, z1 = align_windows(pa, np.broadcast_to(wpos[a_in - k + 1 : a_in + 1], pa.shape), self.joint_weights_)
            # second half: B (dst-k+1..) onto W (w_{z+1}.., over the frames W has (k or k-1); or the
            # arrival node's window w_{a_out..a_out+k-1})
            if S.anchors is None:
                lo, m = c + 1, min(k, S.n_frames - 1 - c)
            else:
                lo, m = S.anchors[1], k
            pb = self._frame_positions(dst[sel, None] - k + 1 + np.arange(m))
            D2, t2, x2, z2 = align_windows(np.broadcast_to(wpos[lo : lo + m], pb.shape), pb, self.joint_weights_)
            dist[sel] = self._rms(D1, k) + self._rms(D2, m)
            for r, i in enumerate(sel):
                ws = Placement(t1[r], x1[r], z1[r])
                align_seg[i] = ws.as_array()
                align[i] = ws.then(Placement(t2[r], x2[r], z2[r])).as_array()
        return dist, align, align_seg

    # ------------------------------------------------------------------------------------------ I/O
    def to_record(self) -> MotionGraphRecord:
        """The fitted graph as the file's record (:class:`vidstyle.formats.motiongraph.MotionGraphRecord`)."""
        sk = self.skeleton_
        end_sites = np.full((sk.n_joints, 3), np.nan)
        for j, off in sk.end_sites.items():
            end_sites[j] = off
        segs = self.segments_
        J = sk.n_joints
        frames = [s.n_frames for s in segs]
        c = self.clips_
        return MotionGraphRecord(
            params=self.get_params(), threshold_used=self.threshold_, stats=self.stats_,
            fps=self.fps, window=self.window,
            clip_names=c["names"], clip_paths=c["paths"], clip_sha256=c["sha"], clip_start=c["start"],
            clip_frames=c["frames"], clip_src_first=c["first"], clip_src_fps=c["src_fps"], clip_scale=c["scale"],
            joint_names=sk.names, parents=sk.parents, offsets=sk.offsets, channels=[list(x) for x in sk.channels],
            end_sites=end_sites,
            rotations=self.rotations_, root_positions=self.root_positions_, frame_clip=self.frame_clip_,
            label_names=self.label_names_, labels=self.labels_, joint_weights=self.joint_weights_, scc=self.scc_,
            edge_src=self.edge_src_, edge_dst=self.edge_dst_, edge_kind=self.edge_kind_, edge_cost=self.edge_cost_,
            edge_segment=self.edge_segment_, edge_align=self.edge_align_, edge_align_segment=self.edge_align_segment_,
            edge_in_scc=self.edge_in_scc_,
            segment_rotations=np.concatenate([s.rotations for s in segs]) if segs else np.zeros((0, J, 4)),
            segment_root_positions=np.concatenate([s.root_positions for s in segs]) if segs else np.zeros((0, 3)),
            segment_start=(np.concatenate([[0], np.cumsum(frames)[:-1]]).astype(np.int64) if segs
                           else np.zeros(0, np.int64)),
            segment_frames=np.array(frames, dtype=np.int64),
            segment_centre=np.array([s.centre for s in segs], dtype=np.int64),
            segment_source=np.array([s.source for s in segs], dtype=str),
            segment_label=np.array([s.label for s in segs], dtype=str),
            segment_anchor=np.array([s.anchors if s.anchors is not None else (-1, -1) for s in segs],
                                    dtype=np.int64).reshape(len(segs), 2),
            segment_hold=np.array([s.hold for s in segs], dtype=np.float64),
        )

    @classmethod
    def from_record(cls, rec: MotionGraphRecord) -> MotionGraph:
        """A fitted graph from a record (as :func:`vidstyle.formats.motiongraph.read_graph` returns it).
        Unknown parameters (of newer or older versions) are ignored."""
        known = {k: v for k, v in rec.params.items() if k in cls.PARAMS}
        g = cls(**known)
        g.window, g.fps = int(rec.window), float(rec.fps)
        end_sites = np.asarray(rec.end_sites, dtype=np.float64)
        parents = np.asarray(rec.parents)
        ends = {j: end_sites[j] for j in range(len(parents)) if np.isfinite(end_sites[j]).all()}
        g.skeleton_ = Skeleton([str(x) for x in rec.joint_names], parents, np.asarray(rec.offsets),
                               [tuple(x) for x in rec.channels], ends)
        g.rotations_ = np.asarray(rec.rotations)
        g.root_positions_ = np.asarray(rec.root_positions)
        g.frame_clip_ = np.asarray(rec.frame_clip)
        g.label_names_ = [str(x) for x in rec.label_names]
        g.labels_ = np.asarray(rec.labels)
        g.joint_weights_ = np.asarray(rec.joint_weights)
        g.scc_ = np.asarray(rec.scc).astype(bool)
        for key in ("src", "dst", "cost", "segment", "align", "align_segment"):
            setattr(g, f"edge_{key}_", np.asarray(getattr(rec, f"edge_{key}")))
        g.edge_kind_ = np.asarray(rec.edge_kind).astype(np.int8)
        g.edge_in_scc_ = g.scc_[g.edge_src_] & g.scc_[g.edge_dst_]
        g.segments_ = [
            EnhancementSegment(rec.segment_rotations[s : s + n], rec.segment_root_positions[s : s + n], int(z), str(src),
                    str(lab), None if a[0] == -1 else (int(a[0]), int(a[1])), float(h))
            for s, n, z, src, lab, a, h in zip(rec.segment_start, rec.segment_frames, rec.segment_centre,
                                               rec.segment_source, rec.segment_label, rec.segment_anchor,
                                               rec.segment_hold)
        ]
        g.clips_ = {
            "names": [str(x) for x in rec.clip_names], "paths": [str(x) for x in rec.clip_paths],
            "sha": [str(x) for x in rec.clip_sha256], "start": np.asarray(rec.clip_start).tolist(),
            "frames": np.asarray(rec.clip_frames).tolist(), "first": np.asarray(rec.clip_src_first).tolist(),
            "src_fps": np.asarray(rec.clip_src_fps).tolist(), "scale": np.asarray(rec.clip_scale).tolist(),
        }
        g.threshold_ = rec.threshold_used
        g.stats_ = rec.stats
        return g

    def save(self, path: str | Path) -> None:
        """Write the graph file (:mod:`vidstyle.formats.motiongraph`, schema version 2)."""
        write_graph(path, self.to_record())

    @classmethod
    def load(cls, path: str | Path) -> MotionGraph:
        """Read a graph file (schema version 1 or 2); malformed files raise ``FormatError``."""
        rec = read_graph(path)
        try:
            return cls.from_record(rec)
        except (ValueError, TypeError, IndexError, KeyError) as e:  # what the reader's checks could not foresee
            raise FormatError(path, None, f"not a consistent motion graph ({e})") from None

    # ------------------------------------------------------------------------------------------ helpers
    @property
    def n_frames(self) -> int:
        return len(self.frame_clip_)

    @property
    def n_edges(self) -> int:
        return len(self.edge_src_)

    def edges(self, kind: EdgeKind | int | None = None, in_scc: bool | None = None) -> np.ndarray:
        """Row indices of the edge table, optionally of one ``kind`` and/or by ``edge_in_scc_``."""
        m = np.ones(self.n_edges, bool)
        if kind is not None:
            m &= self.edge_kind_ == int(kind)
        if in_scc is not None:
            m &= self.edge_in_scc_ == in_scc
        return np.flatnonzero(m)

    def motion(self, frames: np.ndarray | slice | None = None) -> Motion:
        """Database frames as a Motion (all frames by default)."""
        sel = slice(None) if frames is None else frames
        return Motion(self.skeleton_, self.rotations_[sel], None, self.fps, root_positions=self.root_positions_[sel])
