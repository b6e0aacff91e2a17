"""The motion graph: clips at one frame rate, transitions at local distance minima, pruned to its
largest strongly connected component.

Frames of all clips are numbered globally, clip after clip. A transition ``(from=i, to=j)`` means:
play the departing clip up to frame ``i - 1``, then ``k`` blended frames (``i .. i+k-1`` against the
aligned ``j-k+1 .. j``), then continue at ``j + 1``. As a graph edge it goes from node ``i - 1`` to node
``j``; playback edges go from every frame to the next of its clip. Pruning keeps the largest strongly
connected component of that frame graph, so every kept frame can reach every other: a walk never
dead-ends at the end of a clip.

Graph file (``.npz``, schema ``vidstyle.motiongraph/1``):

========================  =============  ==========================================================
key                       shape / type   meaning
========================  =============  ==========================================================
schema                    str            ``vidstyle.motiongraph/1``
params_json               str            JSON: every parameter, the seed, the threshold used, stats
fps                       float          frame rate of the graph
clip_names, clip_paths    (C,) str       clip name (file stem) and source BVH path
clip_sha256               (C,) str       SHA-256 of each source BVH
clip_start, clip_frames   (C,) int       first global frame and frame count of each clip
clip_src_first            (C,) int       first source-file frame used (1 when a T-pose frame 0 was dropped)
clip_src_fps, clip_scale  (C,) float     source frame rate; root-translation scale of the retargeting
joint_names, parents      (J,)           hierarchy shared by all clips (that of the first clip)
offsets                   (J, 3)         rest offsets of the first clip (every clip is retargeted onto it)
channels_json             str            BVH channels per joint; end_sites (J, 3), NaN where a joint has none
rotations                 (N, J, 4) f32  local joint rotations (x, y, z, w)
root_positions            (N, 3)         root translation (retargeted)
frame_clip                (N,) int       clip index of every frame
label_names, labels       (L,), (N,)     action names; label index of every frame
joint_weights             (J,)           weights of the frame distance
scc                       (N,) bool      frame is in the largest strongly connected component
trans_from, trans_to      (E,) int       transition i -> j as above (global frames)
trans_cost                (E,)           RMS point-cloud distance of the aligned windows (length unit)
trans_theta, trans_x0,    (E,)           alignment T(q) = R_y(theta) q + (x0, 0, z0) of the arriving
trans_z0                                 window onto the departing one
trans_in_scc              (E,) bool      both ends in the component (only those are walked)
========================  =============  ==========================================================
"""

from __future__ import annotations

import hashlib
import json
import logging
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Sequence

import numpy as np

from ..errors import InputError
from ..mocap import Motion, Skeleton, global_positions
from .distance import WindowSet, all_pair_candidates, joint_weights, sample_distances
from .labels import UNLABELLED, LabelBook, resample_labels

log = logging.getLogger(__name__)

SCHEMA = "vidstyle.motiongraph/1"


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
    """Height of the root above the lowest joint or End Site in the rest pose."""
    pos = np.zeros((skeleton.n_joints, 3))
    for j, p in enumerate(skeleton.parents):
        pos[j] = skeleton.offsets[j] + (pos[p] if p >= 0 else 0.0)
    ends = [pos[j] + off for j, off in skeleton.end_sites.items()]
    ys = np.concatenate([pos[:, 1], [e[1] for e in ends]]) if ends else pos[:, 1]
    return float(pos[0, 1] - ys.min())


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
        raise InputError("CLIPS: no .bvh files given")
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
    """

    def __init__(
        self,
        window: int = 10,
        fps: float = 30.0,
        threshold: float | None = None,
        threshold_quantile: float = 0.05,
        min_gap: int | None = None,
        drop_tpose: bool = True,
        tile: int = 2048,
        dtype: str = "float32",
        n_jobs: int = 1,
        scheduler: str | None = None,
        n_samples: int = 200_000,
        random_state: int = 0,
        mirror: bool = False,
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

    def get_params(self) -> dict:
        keys = ("window", "fps", "threshold", "threshold_quantile", "min_gap", "drop_tpose", "tile", "dtype",
                "n_jobs", "scheduler", "n_samples", "random_state", "mirror")
        return {k: getattr(self, k) for k in keys}

    # ------------------------------------------------------------------------------------------ fit
    def fit(self, clips: Sequence[Clip]) -> "MotionGraph":
        k = int(self.window)
        if k < 2:
            raise InputError(f"--window: must be at least 2 frames, got {k}")
        if not self.fps > 0:
            raise InputError(f"--fps: must be positive, got {self.fps}")
        if not clips:
            raise InputError("CLIPS: no clips")
        t_start = time.perf_counter()
        if self.mirror:
            try:
                clips = list(clips) + [Clip(c.name + "~mirror", c.motion.mirror(), c.labels, c.path, c.sha256) for c in clips]
            except ValueError as e:
                raise InputError(f"--mirror: cannot mirror the skeleton ({e})") from None
        ref = clips[0].motion.skeleton
        h_ref = rest_height(ref)
        rots, roots, frame_clip, labels = [], [], [], []
        meta = {"names": [], "paths": [], "sha": [], "start": [], "frames": [], "first": [], "src_fps": [], "scale": []}
        n = 0
        for c, clip in enumerate(clips):
            m = clip.motion
            if not m.skeleton.same_hierarchy(ref):
                raise InputError(f"{clip.path or clip.name}: skeleton differs from {clips[0].path or clips[0].name}")
            first = 1 if self.drop_tpose and has_tpose_first_frame(m) else 0
            src_fps = m.fps
            m = m[first:]
            h = rest_height(m.skeleton)
            scale = h_ref / h if h > 1e-9 and h_ref > 1e-9 else 1.0
            # retarget onto the first clip's skeleton: keep local rotations, scale the root path
            m = Motion(ref, m.rotations, np.broadcast_to(ref.offsets, m.translations.shape).copy(), m.fps,
                       root_positions=m.root_positions * scale)
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
        min_gap = int(self.min_gap) if self.min_gap is not None else 2 * k

        motion = Motion(ref, self.rotations_, None, self.fps, root_positions=self.root_positions_)
        positions = global_positions(motion)
        ws = WindowSet.from_clips(positions, self.frame_clip_, self.joint_weights_, k)
        W = ws.total_weight
        sample = sample_distances(ws, self.n_samples, min_gap, self.random_state)
        if self.threshold is None:
            if not len(sample):
                raise InputError("CLIPS: too few frames for any window pair")
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
        self._make_transitions(ws, cand)
        self._prune()
        self.stats_ = {
            "frames": int(n),
            "windows": int(ws.n_windows),
            "pairs": int(cand.n_pairs),
            "pairs_below_threshold": int(cand.n_below),
            "fraction_below_threshold": cand.n_below / max(cand.n_pairs, 1),
            "candidates": int(len(cand.a)),
            "transitions": int(len(self.trans_from_)),
            "transitions_in_scc": int(self.trans_in_scc_.sum()),
            "scc_frames": int(self.scc_.sum()),
            "threshold": thr,
            "distance_seconds": self.distance_seconds_,
            "build_seconds": time.perf_counter() - t_start,
        }
        log.info("motion graph: %d frames, %d transitions (%d in the largest SCC of %d frames), threshold %.4g",
                 n, len(self.trans_from_), self.trans_in_scc_.sum(), self.scc_.sum(), thr)
        return self

    def _make_transitions(self, ws: WindowSet, cand) -> None:
        k = ws.k
        W = ws.total_weight
        a_f, b_f = ws.starts[cand.a], ws.starts[cand.b]
        cost = np.sqrt(np.maximum(cand.D, 0) / W)
        # a -> b with T aligning b onto a; b -> a with the inverse transform
        c, s = np.cos(cand.theta), np.sin(cand.theta)
        inv_x0 = -(c * cand.x0 - s * cand.z0)
        inv_z0 = -(s * cand.x0 + c * cand.z0)
        frm = np.concatenate([a_f, b_f])
        to = np.concatenate([b_f, a_f]) + k - 1
        theta = np.concatenate([cand.theta, -cand.theta])
        x0 = np.concatenate([cand.x0, inv_x0])
        z0 = np.concatenate([cand.z0, inv_z0])
        cost = np.concatenate([cost, cost])
        # the departing clip must have a frame before the blend
        ok = (frm > 0) & (self.frame_clip_[np.maximum(frm - 1, 0)] == self.frame_clip_[frm])
        order = np.lexsort((to[ok], frm[ok]))
        self.trans_from_ = frm[ok][order]
        self.trans_to_ = to[ok][order]
        self.trans_cost_ = cost[ok][order]
        self.trans_theta_ = theta[ok][order]
        self.trans_x0_ = x0[ok][order]
        self.trans_z0_ = z0[ok][order]

    def _prune(self) -> None:
        from scipy.sparse import coo_matrix
        from scipy.sparse.csgraph import connected_components

        N = len(self.frame_clip_)
        f = np.arange(N - 1)
        play = self.frame_clip_[f] == self.frame_clip_[f + 1]
        src = np.concatenate([f[play], self.trans_from_ - 1])
        dst = np.concatenate([f[play] + 1, self.trans_to_])
        g = coo_matrix((np.ones(len(src)), (src, dst)), shape=(N, N)).tocsr()
        n_comp, comp = connected_components(g, directed=True, connection="strong")
        sizes = np.bincount(comp, minlength=n_comp)
        big = int(np.argmax(sizes))
        # a component of one frame with no self-loop is not a cycle: no walk can stay in it
        self.scc_ = comp == big if sizes[big] > 1 else np.zeros(N, bool)
        self.trans_in_scc_ = self.scc_[self.trans_from_ - 1] & self.scc_[self.trans_to_] if len(self.trans_from_) else np.zeros(0, bool)

    # ------------------------------------------------------------------------------------------ I/O
    def save(self, path: str | Path) -> None:
        from ..fileio import write_npz

        sk = self.skeleton_
        end_sites = np.full((sk.n_joints, 3), np.nan)
        for j, off in sk.end_sites.items():
            end_sites[j] = off
        params = dict(self.get_params(), threshold_used=self.threshold_, stats=self.stats_)
        write_npz(
            path,
            schema=np.array(SCHEMA),
            params_json=np.array(json.dumps(params, default=str)),
            fps=np.array(float(self.fps)),
            window=np.array(int(self.window)),
            clip_names=np.array(self.clips_["names"], dtype=str),
            clip_paths=np.array(self.clips_["paths"], dtype=str),
            clip_sha256=np.array(self.clips_["sha"], dtype=str),
            clip_start=np.array(self.clips_["start"], dtype=np.int64),
            clip_frames=np.array(self.clips_["frames"], dtype=np.int64),
            clip_src_first=np.array(self.clips_["first"], dtype=np.int64),
            clip_src_fps=np.array(self.clips_["src_fps"], dtype=np.float64),
            clip_scale=np.array(self.clips_["scale"], dtype=np.float64),
            joint_names=np.array(sk.names, dtype=str),
            parents=sk.parents,
            offsets=sk.offsets,
            channels_json=np.array(json.dumps([list(c) for c in sk.channels])),
            end_sites=end_sites,
            rotations=self.rotations_.astype(np.float32),
            root_positions=self.root_positions_,
            frame_clip=self.frame_clip_,
            label_names=np.array(self.label_names_, dtype=str),
            labels=self.labels_,
            joint_weights=self.joint_weights_,
            scc=self.scc_,
            trans_from=self.trans_from_,
            trans_to=self.trans_to_,
            trans_cost=self.trans_cost_,
            trans_theta=self.trans_theta_,
            trans_x0=self.trans_x0_,
            trans_z0=self.trans_z0_,
            trans_in_scc=self.trans_in_scc_,
        )

    @classmethod
    def load(cls, path: str | Path) -> "MotionGraph":
        path = Path(path)
        try:
            z = np.load(path, allow_pickle=False)
        except FileNotFoundError:
            raise InputError(f"{path}: graph file not found") from None
        except (OSError, ValueError) as e:
            raise InputError(f"{path}: not a motion graph .npz ({e})") from None
        with z:
            if "schema" not in z.files or str(z["schema"]) != SCHEMA:
                raise InputError(f"{path}: not a motion graph (schema {SCHEMA} expected)")
            d = {key: z[key] for key in z.files}
        params = json.loads(str(d["params_json"]))
        stats = params.pop("stats", {})
        thr = params.pop("threshold_used", None)
        g = cls(**params)
        end_sites = {j: d["end_sites"][j] for j in range(len(d["parents"])) if not np.isnan(d["end_sites"][j]).any()}
        g.skeleton_ = Skeleton([str(x) for x in d["joint_names"]], d["parents"], d["offsets"],
                               [tuple(c) for c in json.loads(str(d["channels_json"]))], end_sites)
        g.rotations_ = d["rotations"].astype(np.float64)
        g.root_positions_ = d["root_positions"]
        g.frame_clip_ = d["frame_clip"]
        g.label_names_ = [str(x) for x in d["label_names"]]
        g.labels_ = d["labels"]
        g.joint_weights_ = d["joint_weights"]
        g.scc_ = d["scc"]
        for key in ("from", "to", "cost", "theta", "x0", "z0", "in_scc"):
            setattr(g, f"trans_{key}_", d[f"trans_{key}"])
        g.clips_ = {
            "names": [str(x) for x in d["clip_names"]], "paths": [str(x) for x in d["clip_paths"]],
            "sha": [str(x) for x in d["clip_sha256"]], "start": d["clip_start"].tolist(),
            "frames": d["clip_frames"].tolist(), "first": d["clip_src_first"].tolist(),
            "src_fps": d["clip_src_fps"].tolist(), "scale": d["clip_scale"].tolist(),
        }
        g.threshold_ = thr
        g.stats_ = stats
        return g

    # ------------------------------------------------------------------------------------------ helpers
    @property
    def n_frames(self) -> int:
        return len(self.frame_clip_)

    def motion(self, frames: np.ndarray | slice | None = None) -> Motion:
        """Database frames as a Motion (all frames by default)."""
        sel = slice(None) if frames is None else frames
        return Motion(self.skeleton_, self.rotations_[sel], None, self.fps, root_positions=self.root_positions_[sel])
