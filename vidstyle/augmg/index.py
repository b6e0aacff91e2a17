"""k nearest neighbours of a 2D pose over the projected mocap library, and temporal coherence.

:class:`PoseIndex` (scikit-learn style: parameters in ``__init__``, ``fit(clips)`` learns) projects every
library frame (every ``stride``-th mocap frame) at ``n_views`` azimuths around the character (relative
to its facing in that frame) and builds one :class:`scipy.spatial.cKDTree` per azimuth over the
joint-angle features (:mod:`.projection`). A query at viewpoint ``az`` searches the tree of the nearest
azimuth: exact kNN in that view, O(log N) per query. Projection and tree building go through
:func:`vidstyle.parallel.parallel_map` (joblib locally, Dask with a scheduler), one clip / one view
per item.

Temporal coherence (Tautges et al. 2011, online lazy neighbourhood graph): with several consecutive
annotated frames, each frame's kNN candidates are nodes; an edge joins candidates of successive query
frames that lie in the same clip and advance by about the query's frame step. The best path (sum of
pose costs plus ``jump_cost`` for every step that is not such an edge) is found by dynamic
programming, and each frame's candidates are re-ranked by the best path through them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .keypoints import KP
from .projection import angle_features, facing_normalised, facing_of_keypoints, project


@dataclass
class LibraryClip:
    """A library clip's keypoints: ``points`` (F, 15, 3) world positions at ``fps``."""

    path: str
    points: np.ndarray
    fps: float


#: memory per indexed (frame, view): its float32 features (28 x 4 bytes, twice while they are stacked),
#: the kd-tree's float64 copy (28 x 8), its index and nodes, and the float64 temporaries of the projection
#: (peak RSS growth of a fit measured at 634 bytes per point for 100k frames x 12 views and 546 for
#: 200k x 24, single process)
BYTES_PER_INDEXED_POINT = 650


def _project_clip(args) -> list[np.ndarray]:
    points, stride, views, elevation = args
    pts = points[::stride]
    norm = facing_normalised(pts, facing_of_keypoints(pts))
    return [angle_features(project(norm, az, elevation)) for az in views]


def build_tree(features: np.ndarray):
    """A balanced, compact kd-tree (median splits): exact like any kd-tree, and on a projected library
    35x faster per query at 1M frames than sliding-midpoint splits (scripts/bench_augmg.py)."""
    from scipy.spatial import cKDTree

    return cKDTree(features, leafsize=16, balanced_tree=True, compact_nodes=True)


class PcaTree:
    """Exact k nearest neighbours through a kd-tree over a PCA projection, with exact re-ranking.

    The projection onto ``dims`` orthonormal principal axes never lengthens a difference vector, so a
    point's distance in the projection is a lower bound of its true distance. A query takes the
    ``ratio`` x k nearest points of the low-dimensional tree, ranks them by their exact distance, and
    returns them when the k-th exact distance is at most the largest projected distance fetched (no
    unfetched point can then be closer); otherwise it fetches four times more (finally all points).
    The answer is therefore the exact top-k (ties aside) of the full features, found in a tree of far
    fewer dimensions than the 28 the features have. ``features`` (N, D) float32."""

    def __init__(self, features: np.ndarray, dims: int = 8, ratio: int = 8, leafsize: int = 32,
                 sample: int = 20000, seed: int = 0) -> None:
        from scipy.spatial import cKDTree

        f = np.ascontiguousarray(features, dtype=np.float32)
        self.features = f
        rng = np.random.default_rng(seed)
        sub = f[rng.choice(len(f), min(sample, len(f)), replace=False)].astype(np.float64)
        self.mean = sub.mean(axis=0)
        _, _, vt = np.linalg.svd(sub - self.mean, full_matrices=False)
        self.basis = vt[:min(dims, vt.shape[0])].astype(np.float32)  # (m, D), orthonormal rows
        self.ratio = ratio
        proj = (f - self.mean.astype(np.float32)) @ self.basis.T
        self.tree = cKDTree(proj, leafsize=leafsize, balanced_tree=False, compact_nodes=False)

    def query(self, q: np.ndarray, k: int) -> tuple[np.ndarray, np.ndarray]:
        """(distances, indices) of the exact ``k`` nearest features of each query row (Q, D), each (Q, k)."""
        q = np.atleast_2d(np.asarray(q, dtype=np.float32))
        n = len(self.features)
        k = min(k, n)
        qp = (q - self.mean.astype(np.float32)) @ self.basis.T
        out_d = np.empty((len(q), k))
        out_i = np.empty((len(q), k), dtype=np.int64)
        for r in range(len(q)):
            m = min(n, max(k + 1, self.ratio * k))
            while True:
                lo, ii = self.tree.query(qp[r], k=m)
                ii = np.atleast_1d(ii)
                lo = np.atleast_1d(lo)
                diff = self.features[ii] - q[r]
                d = np.sqrt(np.einsum("ij,ij->i", diff, diff, dtype=np.float64))
                order = np.argsort(d, kind="stable")[:k]
                # certificate: nothing unfetched is nearer than the k-th (float32 slack)
                if m >= n or d[order[-1]] <= lo[-1] * (1 - 1e-6) - 1e-6:
                    break
                m = min(n, 4 * m)
            out_d[r], out_i[r] = d[order], ii[order]
        return out_d, out_i


class PoseIndex:
    """kNN over projected library frames. Learned: ``views_`` (azimuths, degrees), ``clip_`` (N,) clip
    number and ``frame_`` (N,) mocap frame of every indexed frame, ``paths_``, ``fps_``, ``trees_``
    (one per view), ``features_`` (views, N, 28) float32."""

    def __init__(self, n_views: int = 12, elevation_deg: float = 10.0, stride: int = 3, jobs: int = 1,
                 scheduler: str | None = None) -> None:
        self.n_views = n_views
        self.elevation_deg = elevation_deg
        self.stride = stride
        self.jobs = jobs
        self.scheduler = scheduler

    def get_params(self) -> dict:
        return {"n_views": self.n_views, "elevation_deg": self.elevation_deg, "stride": self.stride}

    def fit(self, clips: list[LibraryClip]) -> PoseIndex:
        from ..parallel import parallel_map

        if self.n_views < 1 or self.stride < 1:
            raise ValueError(f"n_views and stride must be >= 1, got {self.n_views}, {self.stride}")
        if not clips:
            raise ValueError("fit: no library clips")
        from ..budget import require

        n_points = self.n_views * sum(-(-len(c.points) // self.stride) for c in clips)
        require(n_points * BYTES_PER_INDEXED_POINT, f"projecting {len(clips)} library clips at {self.n_views} views",
                "n_views", "fewer views or library clips, or a larger stride")
        self.views_ = np.arange(self.n_views) * (360.0 / self.n_views)
        per_clip = parallel_map(_project_clip, [(c.points, self.stride, self.views_, self.elevation_deg)
                                                for c in clips], jobs=self.jobs, scheduler=self.scheduler,
                                description="projecting library")
        self.paths_ = [c.path for c in clips]
        self.fps_ = np.array([c.fps for c in clips])
        self.clip_ = np.concatenate([np.full(len(f[0]), i) for i, f in enumerate(per_clip)])
        self.frame_ = np.concatenate([np.arange(len(f[0])) * self.stride for f in per_clip])
        self.features_ = np.stack([np.concatenate([f[v] for f in per_clip]) for v in range(self.n_views)])
        self.trees_ = parallel_map(build_tree, list(self.features_), jobs=self.jobs, scheduler=self.scheduler,
                                   description="indexing views")
        self.bone_ratio_ = bone_length_ratios(np.concatenate([c.points[::self.stride] for c in clips]))
        return self

    @property
    def n_frames(self) -> int:
        return len(self.clip_)

    def view_index(self, azimuth_deg: float) -> int:
        step = 360.0 / self.n_views
        return int(np.round((azimuth_deg % 360.0) / step)) % self.n_views

    def query(self, points2d: np.ndarray, azimuth_deg: float, k: int = 10) -> tuple[np.ndarray, np.ndarray]:
        """Top-``k`` library frames for 2D keypoints (Q, 15, 2) seen at ``azimuth_deg`` relative to the
        character's facing: (indices into ``clip_``/``frame_``, costs) each (Q, k), best first. The cost
        is the feature distance (root of the summed ``2 - 2 cos`` bone-angle differences)."""
        feats = angle_features(np.asarray(points2d, dtype=np.float64))
        k = min(k, self.n_frames)
        d, i = self.trees_[self.view_index(azimuth_deg)].query(feats, k=k)
        return np.asarray(i).reshape(len(feats), k), np.asarray(d).reshape(len(feats), k)

    def time_of(self, idx: np.ndarray) -> np.ndarray:
        """Seconds into its clip of every indexed frame ``idx``."""
        return self.frame_[idx] / self.fps_[self.clip_[idx]]


def coherent_ranking(index: PoseIndex, idx: np.ndarray, cost: np.ndarray, query_frames: np.ndarray,
                     query_fps: float, jump_cost: float = 0.5, tolerance: float = 0.5) -> tuple[np.ndarray, np.ndarray]:
    """Re-rank kNN candidates (Q, k) of consecutive query frames by temporal coherence (module
    docstring). Returns (idx, cost) re-ordered per frame by the best path cost through each candidate
    (``cost`` becomes that path cost). ``tolerance``: allowed deviation of a candidate's time step from
    the query's, as a fraction of the query step (plus one library stride)."""
    Q, k = idx.shape
    if Q < 2:
        return idx, cost
    t = index.time_of(idx)  # (Q, k) seconds
    clip = index.clip_[idx]
    fwd = np.zeros((Q, k))
    back = np.zeros((Q, k))
    fwd[0] = cost[0]
    slack = index.stride / index.fps_[clip]  # (Q, k)

    def trans(q: int) -> np.ndarray:  # (k, k) cost of moving from candidate a at q-1 to b at q
        dt = (query_frames[q] - query_frames[q - 1]) / query_fps
        step = t[q][None, :] - t[q - 1][:, None]
        ok = (clip[q][None, :] == clip[q - 1][:, None]) & (np.abs(step - dt) <= tolerance * abs(dt) + slack[q][None, :])
        return np.where(ok, 0.0, jump_cost)

    for q in range(1, Q):
        fwd[q] = cost[q] + np.min(fwd[q - 1][:, None] + trans(q), axis=0)
    for q in range(Q - 2, -1, -1):
        back[q] = np.min(trans(q + 1) + (cost[q + 1] + back[q + 1])[None, :], axis=1)
    total = fwd + back  # best full path through each candidate
    order = np.argsort(total, axis=1, kind="stable")
    return np.take_along_axis(idx, order, 1), np.take_along_axis(total, order, 1)


def clip_files(paths) -> list:
    """The BVH files of ``paths`` (files, or directories searched recursively, sorted), as Paths;
    :class:`~vidstyle.errors.InputError` for a path that does not exist or no file at all."""
    from pathlib import Path

    from ..errors import InputError

    files = []
    for p in map(Path, paths):
        if p.is_dir():
            files += sorted(p.rglob("*.bvh"))
        elif p.is_file():
            files.append(p)
        else:
            raise InputError(f"{p}: no such clip file or directory")
    if not files:
        raise InputError("--library: no .bvh clips")
    return files


def library_clips(paths, stride_fps: float | None = None) -> list[LibraryClip]:
    """Read BVH clips (files or directories) into keypoints; a CMU calibration T-pose frame is dropped."""

    from ..mocap import read_bvh
    from ..motiongraph.graph import has_tpose_first_frame
    from .keypoints import keypoint_positions

    files = clip_files(paths)
    out = []
    for f in files:
        m = read_bvh(f)
        first = 1 if has_tpose_first_frame(m) else 0
        pts = keypoint_positions(m)
        pts[:first] = pts[first:first + 1]  # keep frame numbers of the file; never match the T-pose
        out.append(LibraryClip(str(f), pts, m.fps))
    return out


__all__ = ["KP", "LibraryClip", "PoseIndex", "clip_files", "coherent_ranking", "girdle_midpoints",
           "library_clips"]


def girdle_midpoints(points: np.ndarray) -> np.ndarray:
    """Copy of keypoints (..., 15, d) with the neck and pelvis at the shoulder and hip midpoints (as
    :func:`.projection.angle_features` compares them, and as BlazePose's mapping defines them: a mocap
    skeleton's root and neck joints sit elsewhere, the CMU root about 10 cm above its hips' midpoint)."""
    p = np.array(points, dtype=np.float64, copy=True)
    p[..., KP["neck"], :] = 0.5 * (p[..., KP["left_shoulder"], :] + p[..., KP["right_shoulder"], :])
    p[..., KP["pelvis"], :] = 0.5 * (p[..., KP["left_hip"], :] + p[..., KP["right_hip"], :])
    return p


def bone_length_ratios(points3d: np.ndarray) -> np.ndarray:
    """(B,) median 3D length of every bone over frames (F, 15, 3), in torso lengths (hip midpoint to
    shoulder midpoint): the unforeshortened 2D length a bone has next to an upright torso."""
    from .keypoints import BONE_INDEX

    p = girdle_midpoints(points3d)
    bones = np.linalg.norm(p[:, BONE_INDEX[:, 1]] - p[:, BONE_INDEX[:, 0]], axis=-1)
    torso = np.linalg.norm(p[:, KP["neck"]] - p[:, KP["pelvis"]], axis=-1)
    return np.median(bones / np.maximum(torso, 1e-9)[:, None], axis=0)


def foreshortening_weights(points2d: np.ndarray, ratios: np.ndarray) -> np.ndarray:
    """(..., B) weight of every bone of 2D keypoints (..., 15, 2): its image length over the length it
    would have seen side-on (``ratios`` x the image torso length), clipped to [0, 1]. A bone pointing
    at the camera is short in the image and its direction is noise (a guard's forearms seen from the
    front); its angle then counts for little. The neck and pelvis are the girdle midpoints."""
    from .keypoints import BONE_INDEX

    p = girdle_midpoints(points2d)
    bones = np.linalg.norm(p[..., BONE_INDEX[:, 1], :] - p[..., BONE_INDEX[:, 0], :], axis=-1)
    torso = np.linalg.norm(p[..., KP["neck"], :] - p[..., KP["pelvis"], :], axis=-1)
    return np.clip(bones / np.maximum(ratios * torso[..., None], 1e-9), 0.0, 1.0)


def bone_weights(scores: np.ndarray | None, points2d: np.ndarray | None = None,
                 ratios: np.ndarray | None = None) -> np.ndarray | None:
    """(..., B) weight of every bone: the smaller confidence score of its two keypoints (scores (..., 15));
    with ``points2d`` and ``ratios`` also times its :func:`foreshortening_weights`. None when neither
    applies (all bones weigh 1)."""
    from .keypoints import BONE_INDEX

    w = None
    if scores is not None:
        s = np.clip(np.asarray(scores, dtype=np.float64), 0.0, 1.0)
        w = np.minimum(s[..., BONE_INDEX[:, 0]], s[..., BONE_INDEX[:, 1]])
    if points2d is not None and ratios is not None:
        f = foreshortening_weights(points2d, ratios)
        w = f if w is None else w * f
    return w


def weighted_feature_distance(q: np.ndarray, f: np.ndarray, w: np.ndarray | None) -> np.ndarray:
    """Distance of query features ``q`` (..., 2B) to library features ``f`` (..., 2B) with bone weights
    ``w`` (..., B) (None: all 1, the plain Euclidean distance the kd-tree uses). Weights are normalised
    to sum to B, so the scale does not depend on how confident the pose is overall."""
    d2 = ((f.astype(np.float64) - q) ** 2).reshape(f.shape[:-1] + (-1, 2)).sum(-1)  # (..., B)
    if w is None:
        return np.sqrt(d2.sum(-1))
    B = d2.shape[-1]
    w = np.broadcast_to(w, d2.shape)
    return np.sqrt(B * (w * d2).sum(-1) / np.maximum(w.sum(-1), 1e-9))


def window_query(index: PoseIndex, points2d: np.ndarray, offsets_s: np.ndarray, azimuth_deg: float, k: int = 10,
                 spread: int = 0, scores: np.ndarray | None = None, per_frame_k: int = 50, tolerance: float = 0.5,
                 foreshortening: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """Top-``k`` library frames for a marked frame seen together with its neighbours (temporal coherence
    over a short window, as in Tautges' lazy neighbourhood graph, but scored exactly).

    ``points2d`` (D, 15, 2): the 2D poses of the marked frame and its neighbours, ``offsets_s`` (D,)
    their time relative to the mark (seconds; 0 = the mark). A candidate is a library frame ``c``; its
    cost is the mean over the D query frames of the (bone-weighted, :func:`weighted_feature_distance`)
    feature distance to the best library frame of the same clip at ``time(c) + offset``, allowed to slip
    by ``tolerance`` x |offset| plus one indexed frame (other speeds). Candidates are the union of the
    kd-tree's ``per_frame_k`` neighbours of every query frame (moved back by its offset) at the view
    nearest ``azimuth_deg`` and ``spread`` neighbouring views either side; each candidate takes its best
    view. With one query frame at offset 0, no scores and no ``foreshortening`` (bones weighted by
    :func:`foreshortening_weights` with the library's ``bone_ratio_``) this is exact kNN at those views.
    Returns (indices into ``clip_``/``frame_``, costs), each (k,), best first."""
    pts = np.asarray(points2d, dtype=np.float64)
    off = np.asarray(offsets_s, dtype=np.float64)
    if pts.ndim != 3 or len(pts) != len(off) or len(pts) == 0:
        raise ValueError(f"points2d (D, 15, 2) and offsets_s (D,) must agree, got {pts.shape} and {off.shape}")
    feats = angle_features(pts).astype(np.float64)  # (D, 2B)
    w = bone_weights(scores, pts if foreshortening else None, index.bone_ratio_ if foreshortening else None)
    step = 360.0 / index.n_views
    views = sorted({index.view_index(azimuth_deg + d * step) for d in range(-spread, spread + 1)})
    N = index.n_frames
    pk = min(per_frame_k, N)
    best_ids, best_cost = [], []
    for v in views:
        _, nn = index.trees_[v].query(feats.astype(np.float32), k=pk)
        nn = np.asarray(nn).reshape(len(feats), pk)
        # shift each query frame's neighbours back to the mark: c = i - offset (indexed frames)
        shift = np.round(off[:, None] * index.fps_[index.clip_[nn]] / index.stride).astype(int)
        c = np.clip(nn - shift, 0, N - 1)
        c = np.where(index.clip_[c] == index.clip_[nn], c, nn)
        cand = np.unique(c)
        cost = _window_cost(index, v, cand, feats, off, w, tolerance)
        best_ids.append(cand)
        best_cost.append(cost)
    ids, cost = np.concatenate(best_ids), np.concatenate(best_cost)
    order = np.lexsort((ids, cost))
    ids, cost = ids[order], cost[order]
    _, first = np.unique(ids, return_index=True)  # each candidate at its best view
    keep = np.sort(first)[:min(k, len(first))]
    return ids[keep], cost[keep]


def _window_cost(index: PoseIndex, view: int, cand: np.ndarray, feats: np.ndarray, off: np.ndarray,
                 w: np.ndarray | None, tolerance: float) -> np.ndarray:
    """(M,) window cost (see :func:`window_query`) of candidates ``cand`` at view ``view``."""
    N = index.n_frames
    F = index.features_[view]
    clip = index.clip_[cand]
    fps = index.fps_[clip]
    total = np.zeros(len(cand))
    for d in range(len(off)):
        centre = cand + np.round(off[d] * fps / index.stride).astype(int)
        slack = 0 if off[d] == 0 else 1 + int(np.ceil(tolerance * abs(off[d]) * float(fps.max()) / index.stride))
        js = centre[:, None] + np.arange(-slack, slack + 1)[None, :]  # (M, S)
        jc = np.clip(js, 0, N - 1)
        ok = index.clip_[jc] == clip[:, None]
        # outside the clip: its nearest frame inside (the clip ends there)
        first = np.searchsorted(index.clip_, clip, side="left")
        last = np.searchsorted(index.clip_, clip, side="right") - 1
        jc = np.where(ok, jc, np.clip(js, first[:, None], last[:, None]))
        dist = weighted_feature_distance(feats[d], F[jc], None if w is None else w[d])
        total += dist.min(axis=1)
    return total / len(off)


def query_views(index, uv: np.ndarray, az: float, k: int, spread: int):
    """kNN of one 2D pose ``uv`` (15, 2) at the view nearest ``az`` (degrees relative to the facing) and,
    with ``spread`` > 0, at that many neighbouring views either side (a named viewpoint is a class), merged
    by cost: ((1, <=k) library frame ids, (1, <=k) costs) of a fitted :class:`PoseIndex`."""
    if spread == 0:
        return index.query(uv[None], az, k)
    step = 360.0 / index.n_views
    ids, costs = [], []
    for d in range(-spread, spread + 1):
        i, c = index.query(uv[None], az + d * step, k)
        ids.append(i[0])
        costs.append(c[0])
    ids, costs = np.concatenate(ids), np.concatenate(costs)
    order = np.argsort(costs, kind="stable")
    ids, costs = ids[order], costs[order]
    _, first = np.unique(ids, return_index=True)
    keep = np.sort(first)[:k]
    return ids[keep][None], costs[keep][None]
