"""Whole video to 3D motion (Tautges 2012, chapter 3, with the performer's 2D keypoints as the control
signal): :class:`Reconstructor`.

For every video frame ``t`` with a pose (an :class:`Observation`: 15 keypoints, their confidences, and
the camera's azimuth about the performer when the pose stage estimated it):

0. **Viewpoints** (:meth:`Observation.from_poses`): a pose estimator's classified views (the pictorial
   structures') are tracked through the video (:func:`vidstyle.pose.viewtrack.track_views`: no half turn
   between two frames; a frame turned by half a turn has its left and right exchanged), so a run of frames
   read from the back does not turn the body inside out.
1. **kNN** (:meth:`Reconstructor.neighbours`): the frame's bone-direction features
   (:func:`vidstyle.augmg.projection.angle_features`) against the library projected at the views
   nearest the frame's azimuth (``spread`` neighbouring views either side; every view when the azimuth
   is unknown or ``use_azimuth`` is off): the ``k`` nearest indexed library frames over those views,
   each at its best view (the kd-trees of :class:`vidstyle.augmg.index.PoseIndex`, AugMG's matcher).
2. **Temporal coherence** (``method="olng"``): the online lazy neighbourhood graph over a window of
   ``window_s`` seconds (:func:`.olng.olng_costs`); each node's cost becomes the cost of the best
   coherent path ending there. ``method="nn"`` skips this (per-frame nearest neighbours: the baseline).
   ``method="subsequence"`` replaces steps 2 and 3 by Tautges' subsequence graph (chapter 4,
   :func:`.subsequence.subsequence_reconstruct`): windows of ``ssg_window_s`` seconds overlapping by
   ``ssg_overlap`` of a window, each matched by subsequence DTW at the view of its frames' best
   neighbours, the best chain of subsequences cross-faded (its two library frames per video frame are the
   blended nodes, weighted by the cross-fade).
3. **Blend** (Tautges eq. 3.3): the ``n_blend`` nodes of least cost, weighted
   ``w_i = (max C - c_i) / sum_j (max C - c_j)``; the pose is the weighted mean of their local joint
   rotations (quaternions aligned to the best node's hemisphere, normalised), the root's facing-relative
   rotation and height likewise, and the azimuth the weighted circular mean of their views.
4. **Viewpoint refinement**: the projected views come in steps of ``360 / n_views`` degrees; the
   azimuth is refined to the one (within half a step either way of the blended one, 1-degree grid) whose
   orthographic projection of the blended pose fits the observed keypoints best after a
   confidence-weighted scale and translation fit.
5. **Time**: frames without a pose are bridged from their neighbours (quaternions interpolated
   linearly between the nearest frames with a pose, then normalised; before the first and after the
   last, held), and rotations, azimuths and heights are smoothed with a Gaussian of ``smooth_frames``
   frames (quaternions kept in one hemisphere over time first).
6. **Camera and root path** (:mod:`.camera`): a static pinhole camera at the origin, pitched down by
   ``elevation_deg`` (default: the library's projection elevation) with intrinsics from ``focal_px``
   (else :func:`.camera.default_intrinsics`). The world has +Y up and the camera looking along +Z
   (pitched down by the elevation); the character faces ``pi - azimuth`` (radians about +Y, 0 = +Z),
   turned by its angle off the optical axis once its place is known (the azimuth is about the line of
   sight to the performer). The root's
   position in the camera frame is the translation that best reprojects the posed keypoints onto the
   observed ones (:func:`.camera.fit_translations`), smoothed over ``root_smooth_frames``; its height is
   the blended library height (the camera's distance to the performer is the least certain quantity,
   so the height, which the library knows well, does not come from it).
7. **Foot contacts**: a foot is planted where the weighted vote of the blended nodes' contacts
   (:attr:`.library.ReconstructionLibrary.contacts_`) is at least ``contact_threshold``, and across a lift
   of at most ``contact_gap_s`` seconds between two planted runs (:func:`.footlock.bridge_gaps`: a
   vote flickers, a real step takes longer); unset, these and ``pin_drift`` are the validated values for
   the observation's 2D backend (:data:`.defaults.CONTACTS`). With ``foot_lock``, the root
   is moved horizontally so a planted foot stays where it was planted (both planted: the mean of the
   two corrections); the difference between that path and the camera's is low-passed (Gaussian, sigma
   ``relax_s`` seconds) and added back, so a long take does not drift away from what the camera saw.
   What that leaves (two planted feet under a changing stance, the relaxed drift) is taken up by the
   legs: :func:`.footlock.pin_feet` turns hip and knee by two-bone IK so that each planted ankle stays
   where its run of contact began (height: the run's median, not below the floor; with ``pin_drift``, plus
   the relaxed drift added since then, so a foot planted for seconds goes along with the path the camera
   saw instead of stretching the leg after a body that has moved on), the foot keeping
   its world orientation, blended in and out over 3 frames either side; the IK moves an ankle at most
   ``pin_max_offset`` leg lengths (thigh + shin) from where the pose puts it (beyond that the contact or
   the root path is wrong, and bending the leg further would only trade slide for pose error: the foot
   then trails the pose at that distance). The keypoints are those of the pinned motion.
8. **Size** (``height``, when the performer's standing height is known): a single camera cannot tell a
   small performer near it from a tall one further away, so without it the performer has the output
   skeleton's size. With it, the whole result (skeleton, root path, keypoints, camera height) is scaled
   about the floor under the camera so that the skeleton's rest-pose stature
   (:func:`vidstyle.mocap.retarget.stature`, sole to head top) is ``height``: the images it projects to are
   the same, the body and its strides the performer's size. The library's proportions stay.

The result (:class:`Reconstruction`) is a :class:`vidstyle.mocap.motion.Motion` on the library's skeleton
at the video's frame rate (library length units), with per-frame keypoints, labels from the matched library
frames, and the chosen neighbours for inspection.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, field, replace

import numpy as np

from ..errors import InputError, ParameterError
from ..mocap.quat import continuous_quaternions
from . import defaults as D
from .library import ReconstructionLibrary

log = logging.getLogger(__name__)

#: a frame is observed when at least this many keypoints have a finite position and a score above MIN_SCORE
MIN_KEYPOINTS = 8
MIN_SCORE = 0.2
METHODS = ("olng", "nn", "subsequence")
#: a frame whose fitted depth is more than this factor from the take's median is bridged, not believed
DEPTH_RANGE = 2.0


@dataclass
class Observation:
    """A video's 2D poses: ``xy`` (T, 15, 2) pixels (x = column, y = row), NaN where unknown; ``scores``
    (T, 15) confidences in [0, 1]; ``azimuth`` (T,) degrees of the camera about the performer (0 = the
    performer faces the camera, +90 = the camera at their left), NaN where unknown; ``fps``; ``size``
    (width, height) in pixels; ``backend`` the 2D pose estimator's name (``vidstyle pose --backend``; None:
    unknown, e.g. true 2D), which sets how far the foot contacts trust the matched neighbours."""

    xy: np.ndarray
    scores: np.ndarray
    azimuth: np.ndarray
    fps: float
    size: tuple[int, int]
    source: str = ""
    backend: str | None = None

    def __post_init__(self) -> None:
        self.xy = np.asarray(self.xy, dtype=np.float64)
        T = len(self.xy)
        if self.xy.ndim != 3 or self.xy.shape[1:] != (15, 2):
            raise ValueError(f"xy must be (T, 15, 2), got {self.xy.shape}")
        self.scores = np.nan_to_num(np.asarray(self.scores, dtype=np.float64), nan=0.0)
        self.azimuth = np.asarray(self.azimuth, dtype=np.float64)
        if self.scores.shape != (T, 15) or self.azimuth.shape != (T,):
            raise ValueError(f"scores (T, 15) and azimuth (T,) must match xy's {T} frames, got "
                             f"{self.scores.shape} and {self.azimuth.shape}")
        if not (self.fps > 0 and math.isfinite(self.fps)):
            raise ValueError(f"fps must be a finite number > 0, got {self.fps}")
        self.scores = np.where(np.all(np.isfinite(self.xy), axis=-1), np.clip(self.scores, 0.0, 1.0), 0.0)

    @property
    def n_frames(self) -> int:
        return len(self.xy)

    @property
    def valid(self) -> np.ndarray:
        """(T,) frames with enough confident keypoints to match."""
        return (self.scores > MIN_SCORE).sum(axis=1) >= MIN_KEYPOINTS

    @classmethod
    def from_poses(cls, poses, fps: float, size: tuple[int, int], n_frames: int | None = None,
                   view_step_cost: float | None = None, view_dwell_s: float | None = None) -> Observation:
        """From a :class:`vidstyle.formats.poses.Poses` whose frames are decoded frames at ``fps`` (frames
        absent from the file or without a pose are unknown). Classified viewpoints are first tracked
        through the video (:func:`vidstyle.pose.viewtrack.track_views`; ``view_step_cost``: default
        :data:`.defaults.VIEW_STEP_COST`, 0: each frame's own view; ``view_dwell_s``: the least seconds
        between two quarter turns, default :data:`.defaults.VIEW_DWELL_S`, at least one frame)."""
        from ..pose.viewtrack import track_views

        cost = D.VIEW_STEP_COST if view_step_cost is None else float(view_step_cost)
        dwell_s = D.VIEW_DWELL_S if view_dwell_s is None else float(view_dwell_s)
        if not (math.isfinite(dwell_s) and dwell_s >= 0):
            raise ValueError(f"view_dwell_s must be a finite number >= 0, got {view_dwell_s}")
        poses = track_views(poses, cost, max(1, round(dwell_s * float(fps))))
        last = max((f.frame for f in poses.frames), default=-1)
        T = int(n_frames) if n_frames is not None else last + 1
        xy = np.full((T, 15, 2), np.nan)
        scores = np.zeros((T, 15))
        az = np.full(T, np.nan)
        for f in poses.frames:
            if not f.found or f.frame >= T:
                continue
            xy[f.frame] = f.xy
            scores[f.frame] = f.scores
            if f.azimuth is not None:
                az[f.frame] = float(f.azimuth)
            else:
                try:
                    from ..render.camera import parse_view

                    az[f.frame] = parse_view(str(f.viewpoint))
                except ValueError:
                    pass
        return cls(xy, scores, az, float(fps), (int(size[0]), int(size[1])), str(poses.video),
                   str(poses.backend) if poses.backend else None)


@dataclass
class Reconstruction:
    """What :meth:`Reconstructor.reconstruct` found (module docstring): ``motion`` (library skeleton,
    world +Y up, the camera at the origin looking along +Z), ``points`` (T, 15, 3) its keypoints,
    ``observed`` (T,) frames that had a pose, ``azimuth`` (T,) degrees, ``neighbours`` / ``weights``
    (T, n_blend) indexed library frames and their blend weights (-1 / 0 where unused), ``labels`` (T,),
    ``contacts`` (T, 2) planted left / right foot, ``K`` the camera intrinsics, ``elevation_deg`` its pitch
    and ``camera_height`` its height above the floor (the camera is at ``(0, camera_height, 0)``)."""

    motion: object
    points: np.ndarray
    observed: np.ndarray
    azimuth: np.ndarray
    neighbours: np.ndarray
    weights: np.ndarray
    labels: np.ndarray
    contacts: np.ndarray
    K: np.ndarray
    elevation_deg: float
    camera_height: float
    params: dict = field(default_factory=dict)

    def scaled(self, factor: float) -> Reconstruction:
        """The same reconstruction ``factor`` times as large about the floor under the camera (step 8 of the
        module docstring): skeleton, root path, keypoints and camera height; it projects to the same images.
        ``params["scale"]`` records the factor applied in all."""
        from ..mocap.retarget import rescale

        f = float(factor)
        return replace(self, motion=rescale(self.motion, f), points=self.points * f,
                       camera_height=self.camera_height * f,
                       params={**self.params, "scale": self.params.get("scale", 1.0) * f})

    def camera_points(self) -> np.ndarray:
        """(T, 15, 3) the keypoints in camera coordinates (x right, y down, z forward)."""
        return (self.points - np.array([0.0, self.camera_height, 0.0])) @ camera_rotation(self.elevation_deg).T


def _gaussian(x: np.ndarray, sigma: float) -> np.ndarray:
    """Gaussian smoothing along axis 0 (edges: nearest)."""
    if sigma <= 0 or len(x) < 2:
        return x
    from scipy.ndimage import gaussian_filter1d

    return gaussian_filter1d(x, sigma, axis=0, mode="nearest")


def _fill_gaps(x: np.ndarray, ok: np.ndarray) -> np.ndarray:
    """``x`` (T, ...) with rows where ``ok`` is false linearly interpolated from the nearest good rows
    (held before the first and after the last)."""
    if ok.all() or not ok.any():
        return x
    t = np.arange(len(x))
    good = np.flatnonzero(ok)
    flat = x.reshape(len(x), -1)
    out = np.empty_like(flat)
    for c in range(flat.shape[1]):
        out[:, c] = np.interp(t, good, flat[good, c])
    return out.reshape(x.shape)


def _leg_length(skeleton) -> float:
    """Thigh plus shin of the skeleton's left leg: ``|knee - hip| + |ankle - knee|`` in the rest pose."""
    from ..mocap.keypoints import keypoint_joints

    kj = keypoint_joints(skeleton)
    rest = np.zeros((skeleton.n_joints, 3))
    for j, p in enumerate(skeleton.parents):  # parents come first
        rest[j] = (rest[p] if p >= 0 else 0.0) + skeleton.offsets[j]
    hip, knee, ankle = (rest[kj[f"left_{k}"].joint] for k in ("hip", "knee", "ankle"))
    return float(np.linalg.norm(knee - hip) + np.linalg.norm(ankle - knee))


def similarity_fit(model: np.ndarray, obs: np.ndarray, w: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Weighted least-squares fit ``obs ~ s * model + c`` per leading index: ``(residuals, centred obs)``,
    each (..., 15, 2). ``model`` (..., 15, 2), ``obs`` (..., 15, 2), ``w`` (..., 15)."""
    sw = np.maximum(w.sum(-1, keepdims=True), 1e-12)
    mm = (w[..., None] * model).sum(-2, keepdims=True) / sw[..., None]
    om = (w[..., None] * obs).sum(-2, keepdims=True) / sw[..., None]
    dm, do = model - mm, obs - om
    s = (w * (dm * do).sum(-1)).sum(-1) / np.maximum((w * (dm * dm).sum(-1)).sum(-1), 1e-12)
    return do - s[..., None, None] * dm, do


def similarity_residual(model: np.ndarray, obs: np.ndarray, w: np.ndarray) -> np.ndarray:
    """The weighted squared residual of :func:`similarity_fit` over the observation's weighted spread."""
    r, do = similarity_fit(model, obs, w)
    return (w * (r * r).sum(-1)).sum(-1) / np.maximum((w * (do * do).sum(-1)).sum(-1), 1e-12)


def view_rotations(azimuth_deg: np.ndarray, elevation_deg: float) -> np.ndarray:
    """(n, 3, 3) :func:`vidstyle.augmg.projection.view_rotation` of every azimuth at one elevation, at once."""
    a = np.radians(np.asarray(azimuth_deg, dtype=np.float64))
    e = math.radians(elevation_deg)
    fwd = -np.stack([math.cos(e) * np.sin(a), np.full(a.shape, math.sin(e)), math.cos(e) * np.cos(a)], axis=-1)
    right = np.cross(fwd, np.array([0.0, 1.0, 0.0]))
    right /= np.linalg.norm(right, axis=-1, keepdims=True)
    down = np.cross(fwd, right)
    return np.stack([right, down, fwd], axis=-2)


#: memory of one block of query-to-library products in :func:`knn_brute` (float32 entries)
KNN_BLOCK_ENTRIES = 1 << 24
#: library rows whose exact distances bound each query's k-th neighbour before the full pass
KNN_SAMPLE = 4096


def augmented_features(features: np.ndarray) -> np.ndarray:
    """(N, D + 1) float32 ``[2 f, -|f|^2]`` of library features (N, D): one product with ``[q, 1]`` gives
    ``2 q.f - |f|^2`` (:func:`knn_brute`)."""
    f = np.asarray(features, dtype=np.float32)
    out = np.empty((len(f), f.shape[1] + 1), dtype=np.float32)
    np.multiply(f, 2.0, out=out[:, :-1])
    out[:, -1] = -np.einsum("ij,ij->i", f.astype(np.float64), f.astype(np.float64))
    return out


def knn_brute(features: np.ndarray, sqnorms: np.ndarray, queries: np.ndarray, k: int,
              augmented: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Exact ``k`` nearest rows of ``features`` (N, D) float32 (``sqnorms`` their squared norms) to each
    query (Q, D): ``(distances, indices)`` each (Q, k), nearest first (ties: smaller index).

    A video's 2D poses sit off the library's manifold (estimation noise, other bodies), where a kd-tree in
    these 28 dimensions visits most of its leaves; this is faster there (scripts/bench_reconstruct.py):
    the k-th smallest exact distance to a fixed sample of :data:`KNN_SAMPLE` library rows bounds the
    query's k-th neighbour from above; one float32 matrix product per block of queries gives
    ``2 q.f - |f|^2``, and only the rows where it reaches ``|q|^2 - bound`` (with a float32 slack) are
    candidates, whose distances are recomputed in float64 and the k smallest kept. Every true neighbour
    is a candidate, so the answer is exact. ``augmented``: :func:`augmented_features` of ``features`` when
    already known (one product then gives the whole left-hand side)."""
    N = len(features)
    k = min(int(k), N)
    q = np.ascontiguousarray(queries, dtype=np.float32)
    out_d = np.empty((len(q), k))
    out_i = np.empty((len(q), k), dtype=np.int64)
    if len(q) == 0:
        return out_d, out_i
    sample = np.arange(N) if N <= KNN_SAMPLE else np.linspace(0, N - 1, KNN_SAMPLE).astype(np.int64)
    fs = features[sample].astype(np.float64)
    q64 = q.astype(np.float64)
    ds = (q64 * q64).sum(1)[:, None] + (fs * fs).sum(1)[None, :] - 2.0 * q64 @ fs.T  # (Q, S)
    bound = np.partition(ds, k - 1, axis=1)[:, k - 1] if k <= len(sample) else np.full(len(q), np.inf)
    qq = (q64 * q64).sum(1)
    scale = np.maximum(qq, 1.0) + float(np.max(sqnorms, initial=0.0))
    thresh = (qq - bound - 1e-5 * scale).astype(np.float32)  # 2 q.f - |f|^2 >= thresh for every candidate
    aug = augmented_features(features) if augmented is None else augmented
    qa = np.concatenate([q, np.ones((len(q), 1), dtype=np.float32)], axis=1)
    step = max(1, KNN_BLOCK_ENTRIES // max(N, 1))
    for s in range(0, len(q), step):
        qb = q[s:s + step]
        g = qa[s:s + step] @ aug.T  # (b, N): 2 q.f - |f|^2
        for j in range(len(qb)):
            cand = np.flatnonzero(g[j] >= thresh[s + j])
            if len(cand) < k:  # cannot happen but for rounding: take them all
                cand = np.arange(N)
            diff = features[cand].astype(np.float64) - q64[s + j]
            dist = np.sqrt(np.einsum("kd,kd->k", diff, diff))
            top = np.lexsort((cand, dist))[:k]
            out_d[s + j], out_i[s + j] = dist[top], cand[top]
    return out_d, out_i


def camera_rotation(elevation_deg: float) -> np.ndarray:
    """(3, 3) world-to-camera rotation of the reconstruction's camera: at the origin, looking along +Z
    pitched down by ``elevation_deg`` (rows: image right, image down, viewing direction)."""
    from ..render.camera import look_at_rotation

    e = math.radians(elevation_deg)
    return look_at_rotation(np.zeros(3), np.array([0.0, -math.sin(e), math.cos(e)]))


class Reconstructor:
    """Video 2D poses -> 3D motion by coherent search of a mocap library (module docstring).

    Parameters (defaults: :mod:`.defaults`, chosen on validation performers): ``k`` neighbours per frame;
    ``window_s`` the OLNG window (Tautges: about half a second);
    ``n_blend`` nodes blended; ``method`` ``"olng"`` or ``"nn"``; ``use_azimuth`` / ``spread`` the views
    searched; ``smooth_frames`` the Gaussian sigma of the pose in time; ``root_smooth_frames`` that of the
    camera's root path; ``contact_threshold`` and ``contact_gap_s`` the foot contacts (None: by the
    observation's 2D backend, :data:`.defaults.CONTACTS`); ``foot_lock`` and ``relax_s`` (the root lock),
    ``pin_drift`` (None: by the backend) and ``pin_max_offset`` (the leg
    IK's reach from the pose, in leg lengths; None: unlimited) of step 7; ``focal_px`` (None: the default
    intrinsics; ``"auto"``: estimated from the keypoints and the blended poses, :func:`.camera.estimate_focal`,
    which keeps the default unless the data clearly prefer another lens); ``elevation_deg`` of the camera (None: the library's); ``n_views``,
    ``library_elevation_deg`` and ``target_fps`` of the library index; ``refine_smooth_frames`` the Gaussian sigma
    (frames) of the refined pose in time (0: none; the refinement bends each frame on its own)
    (:class:`.library.ReconstructionLibrary`); ``height`` the performer's standing height in the library's
    length unit when known (step 8; None: the output skeleton's own size); ``jobs`` / ``scheduler``."""

    def __init__(self, k: int = D.K, window_s: float = D.WINDOW_S, n_blend: int = D.N_BLEND, method: str = D.METHOD,
                 use_azimuth: bool = True, spread: int = 1, smooth_frames: float = D.SMOOTH_FRAMES,
                 root_smooth_frames: float = 3.0, foot_lock: bool = True, relax_s: float = 2.0,
                 focal_px: float | str | None = None, elevation_deg: float | None = None, n_views: int = 12,
                 library_elevation_deg: float = 10.0, target_fps: float = 20.0, ssg_window_s: float = 0.5,
                 ssg_overlap: float = 0.4, ssg_k: int = 16, ssg_transition_weight: float = 1.0,
                 pin_max_offset: float | None = D.PIN_MAX_OFFSET, refine_prior: float | None = D.REFINE_PRIOR,
                 refine_smooth_frames: float = D.REFINE_SMOOTH_FRAMES, contact_threshold: float | None = None,
                 contact_gap_s: float | None = None, pin_drift: bool | None = None, height: float | None = None,
                 jobs: int = 1, scheduler: str | None = None) -> None:
        self.k = k
        self.window_s = window_s
        self.n_blend = n_blend
        self.method = method
        self.use_azimuth = use_azimuth
        self.spread = spread
        self.smooth_frames = smooth_frames
        self.root_smooth_frames = root_smooth_frames
        self.foot_lock = foot_lock
        self.relax_s = relax_s
        self.focal_px = focal_px
        self.elevation_deg = elevation_deg
        self.n_views = n_views
        self.library_elevation_deg = library_elevation_deg
        self.target_fps = target_fps
        self.ssg_window_s = ssg_window_s
        self.ssg_overlap = ssg_overlap
        self.ssg_k = ssg_k
        self.ssg_transition_weight = ssg_transition_weight
        self.pin_max_offset = pin_max_offset
        self.refine_prior = refine_prior
        self.refine_smooth_frames = refine_smooth_frames
        self.contact_threshold = contact_threshold
        self.contact_gap_s = contact_gap_s
        self.pin_drift = pin_drift
        self.height = height
        self.jobs = jobs
        self.scheduler = scheduler

    def get_params(self) -> dict:
        return {k: getattr(self, k) for k in (
            "k", "window_s", "n_blend", "method", "use_azimuth", "spread", "smooth_frames", "root_smooth_frames",
            "foot_lock", "relax_s", "focal_px", "elevation_deg", "n_views", "library_elevation_deg", "target_fps",
            "ssg_window_s", "ssg_overlap", "ssg_k", "ssg_transition_weight", "pin_max_offset",
            "refine_prior", "refine_smooth_frames", "contact_threshold", "contact_gap_s", "pin_drift", "height")}

    def contact_settings(self, backend: str | None) -> dict:
        """``contact_threshold``, ``contact_gap_s`` and ``pin_drift`` for 2D from ``backend``: each parameter
        set here, else the validated value for that backend (:data:`.defaults.CONTACTS`; an unknown one or
        None: its ``"default"`` entry)."""
        chosen = D.CONTACTS.get(backend or "", D.CONTACTS["default"])
        return {k: chosen[k] if getattr(self, k) is None else getattr(self, k)
                for k in ("contact_threshold", "contact_gap_s", "pin_drift")}

    def set_params(self, **params) -> Reconstructor:
        for k, v in params.items():
            if k not in self.get_params() and k not in ("jobs", "scheduler"):
                raise ValueError(f"unknown parameter {k!r}")
            setattr(self, k, v)
        return self

    def check_params(self) -> None:
        """:class:`~vidstyle.errors.ParameterError` for a value a parameter cannot take (before any work)."""
        if not 1 <= int(self.k) <= 1000:
            raise ParameterError("k", f"must be in 1..1000, got {self.k}")
        if not 1 <= int(self.n_blend) <= int(self.k):
            raise ParameterError("n_blend", f"must be in 1..k ({self.k}), got {self.n_blend}")
        if self.method not in METHODS:
            raise ParameterError("method", f"must be one of {', '.join(METHODS)}, got {self.method!r}")
        for name in ("window_s", "smooth_frames", "root_smooth_frames", "relax_s", "refine_smooth_frames"):
            v = float(getattr(self, name))
            if not (v >= 0 and math.isfinite(v)):
                raise ParameterError(name, f"must be a finite number >= 0, got {v}")
        if self.pin_drift is not None and not isinstance(self.pin_drift, (bool, np.bool_)):
            raise ParameterError("pin_drift", f"must be true, false or None, got {self.pin_drift!r}")
        if self.contact_threshold is not None and not 0 < float(self.contact_threshold) <= 1:
            raise ParameterError("contact_threshold", f"must be in (0, 1] or None, got {self.contact_threshold}")
        if self.contact_gap_s is not None and not (float(self.contact_gap_s) >= 0
                                                   and math.isfinite(float(self.contact_gap_s))):
            raise ParameterError("contact_gap_s", f"must be a finite number >= 0 or None, got {self.contact_gap_s}")
        if self.pin_max_offset is not None and not (float(self.pin_max_offset) >= 0
                                                    and math.isfinite(float(self.pin_max_offset))):
            raise ParameterError("pin_max_offset",
                                 f"must be a finite number >= 0 or None, got {self.pin_max_offset}")
        if not 0 <= float(self.ssg_overlap) <= 0.5:
            raise ParameterError("ssg_overlap", f"must be in 0..0.5 (a fraction of the window), got {self.ssg_overlap}")
        if not 1 <= int(self.ssg_k) <= 1000:
            raise ParameterError("ssg_k", f"must be in 1..1000, got {self.ssg_k}")
        for name in ("ssg_window_s", "ssg_transition_weight"):
            v = float(getattr(self, name))
            if not (v >= 0 and math.isfinite(v)):
                raise ParameterError(name, f"must be a finite number >= 0, got {v}")
        if not 0 <= int(self.spread) <= self.n_views // 2:
            raise ParameterError("spread", f"must be in 0..{self.n_views // 2}, got {self.spread}")
        if self.focal_px is not None and self.focal_px != "auto" and not (
                isinstance(self.focal_px, (int, float)) and self.focal_px > 0 and math.isfinite(self.focal_px)):
            raise ParameterError("focal_px", f"must be a finite number > 0 or 'auto', got {self.focal_px}")
        if self.elevation_deg is not None and not -80 <= self.elevation_deg <= 80:
            raise ParameterError("elevation_deg", f"must be in -80..80 degrees, got {self.elevation_deg}")
        if self.height is not None and not (isinstance(self.height, (int, float, np.floating)) and self.height > 0
                                            and math.isfinite(self.height)):
            raise ParameterError("height", f"must be a finite number > 0 (library length units) or None, got {self.height}")

    # ------------------------------------------------------------------ fit
    def fit(self, clips, skeleton=None, cache_dir=None) -> Reconstructor:
        """Index the library clips (BVH files or directories); ``skeleton``: the output skeleton;
        ``cache_dir``: reuse (or store) the index fitted on the same clips and parameters there
        (:func:`~vidstyle.reconstruct.library.cached_library`)."""
        from .library import cached_library

        self.check_params()
        lib = ReconstructionLibrary(self.n_views, self.library_elevation_deg, self.target_fps, self.jobs,
                                    self.scheduler)
        self.library_ = cached_library(lib, clips, skeleton=skeleton, cache_dir=cache_dir)
        return self

    def fit_library(self, library: ReconstructionLibrary) -> Reconstructor:
        """Use an already fitted library (several reconstructions share one index)."""
        self.check_params()
        self.library_ = library
        return self

    # ------------------------------------------------------------------ steps
    def neighbours(self, obs: Observation) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Step 1: ``(ids, costs, views)`` each (T, k): indexed library frames, feature distances and view
        numbers, best first; -1 / inf / -1 where a frame has fewer candidates (no pose: all)."""
        from ..augmg.projection import angle_features

        index = self.library_.index_
        T, V = obs.n_frames, index.n_views
        k = min(int(self.k), index.n_frames)
        valid = obs.valid
        feats = angle_features(np.where(np.isfinite(obs.xy), obs.xy, np.nan)).astype(np.float32)
        feats = np.nan_to_num(feats)
        want = np.zeros((T, V), dtype=bool)
        known = np.isfinite(obs.azimuth) & bool(self.use_azimuth)
        want[~known] = True
        if known.any():
            step = 360.0 / V
            near = np.round((obs.azimuth[known] % 360.0) / step).astype(int)
            rows = np.flatnonzero(known)
            for d in range(-int(self.spread), int(self.spread) + 1):
                want[rows, (near + d) % V] = True
        want &= valid[:, None]
        ids = np.full((T, V * k), -1, dtype=np.int64)
        cost = np.full((T, V * k), np.inf)
        view = np.full((T, V * k), -1, dtype=np.int64)
        for v in range(V):
            rows = np.flatnonzero(want[:, v])
            if rows.size == 0:
                continue
            aug = self._augmented(v)  # [2f, -|f|^2]
            d, i = knn_brute(index.features_[v], -aug[:, -1], feats[rows], k, aug)
            ids[rows, v * k:(v + 1) * k] = i
            cost[rows, v * k:(v + 1) * k] = d
            view[rows, v * k:(v + 1) * k] = v
        # each library frame once per video frame, at its best view
        order = np.argsort(cost, axis=1, kind="stable")
        ids, cost, view = (np.take_along_axis(a, order, 1) for a in (ids, cost, view))
        key = np.where(ids >= 0, np.arange(T)[:, None] * (index.n_frames + 1) + ids, -1).ravel()
        _, first = np.unique(key, return_index=True)
        keep = np.zeros(key.size, dtype=bool)
        keep[first] = True
        keep &= key >= 0
        cost = np.where(keep.reshape(T, -1), cost, np.inf)
        order = np.argsort(cost, axis=1, kind="stable")[:, :k]
        ids, cost, view = (np.take_along_axis(a, order, 1) for a in (ids, cost, view))
        bad = ~np.isfinite(cost)
        ids[bad], view[bad] = -1, -1
        return ids, cost, view

    def _augmented(self, v: int) -> np.ndarray:
        """:func:`augmented_features` of view ``v`` (computed once per library)."""
        lib = self.library_
        cache = lib.__dict__.setdefault("_augmented_cache", {})
        if v not in cache:
            cache[v] = augmented_features(lib.index_.features_[v])
        return cache[v]

    def coherent_costs(self, ids: np.ndarray, cost: np.ndarray, fps: float) -> np.ndarray:
        """Step 2: (T, k) cost of every node (the OLNG best-path cost; the plain cost for ``method="nn"``),
        inf where there is no node."""
        from .olng import olng_costs

        if self.method == "nn":
            return cost.copy()
        T, k = ids.shape
        index = self.library_.index_
        node = ids >= 0
        # stand-ins for missing nodes: a clip of their own (never continued), the row's worst cost
        row_max = np.where(node, cost, -np.inf).max(axis=1)
        row_max = np.where(np.isfinite(row_max), row_max, 0.0)
        fake_clip = -1 - (np.arange(T)[:, None] * k + np.arange(k)[None, :])
        clip = np.where(node, index.clip_[np.maximum(ids, 0)], fake_clip)
        c = np.where(node, cost, row_max[:, None])
        window = max(2, int(round(float(self.window_s) * fps)))
        total, _ = olng_costs(np.where(node, ids, 0), clip, c, window)
        return np.where(node, total, np.inf)

    def blend_weights(self, ids: np.ndarray, total: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Step 3: ``(chosen, weights)`` each (T, n_blend): the nodes of least cost and Tautges' weights
        (eq. 3.3; all equal when their costs are); -1 / 0 where a frame has fewer nodes."""
        n = min(int(self.n_blend), ids.shape[1])
        order = np.argsort(total, axis=1, kind="stable")[:, :n]
        chosen = np.take_along_axis(ids, order, 1)
        c = np.take_along_axis(total, order, 1)
        ok = np.isfinite(c) & (chosen >= 0)
        cmax = np.where(ok, c, -np.inf).max(axis=1, keepdims=True)
        w = np.where(ok, cmax - c, 0.0)
        s = w.sum(axis=1, keepdims=True)
        flat = (s <= 1e-12) & ok.any(axis=1, keepdims=True)
        w = np.where(flat, ok.astype(float), w)
        s = w.sum(axis=1, keepdims=True)
        w = np.where(s > 0, w / np.where(s > 0, s, 1.0), 0.0)
        chosen = np.where(ok, chosen, -1)
        return chosen, w

    def subsequence_nodes(self, obs: Observation, view: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Steps 2-3 of ``method="subsequence"``: ``(chosen, weights, views)`` each (T, 2), the cross-faded
        library frames of the subsequence graph's best chain, their weights and the views they were
        matched at (-1 / 0 / -1 on frames without a pose)."""
        from ..augmg.projection import angle_features
        from .subsequence import subsequence_reconstruct

        lib = self.library_
        index = lib.index_
        T = obs.n_frames
        valid = obs.valid
        feats = np.nan_to_num(angle_features(obs.xy)).astype(np.float64)
        window = max(3, int(round(float(self.ssg_window_s) * obs.fps)))
        overlap = min(window // 2, int(round(float(self.ssg_overlap) * window)))
        pts = lib.points_.astype(np.float64)
        pts = pts - pts[:, 2:3]  # root-relative (the pelvis)
        frame_view = np.where(view[:, 0] >= 0, view[:, 0], 0)
        path = subsequence_reconstruct(feats, valid, frame_view, index.features_, index.clip_, pts, window=window,
                                       overlap=overlap, k=int(self.ssg_k),
                                       transition_weight=float(self.ssg_transition_weight))
        v0 = np.full(T, -1)
        v1 = np.full(T, -1)
        for (s, e), v in zip(path.windows, path.view):
            v0[s:e] = np.where(v0[s:e] < 0, v, v0[s:e])
            v1[s:e] = v
        chosen = np.where(valid[:, None], path.ids, -1)
        w = np.where(valid[:, None], np.column_stack([path.alpha, 1.0 - path.alpha]), 0.0)
        return chosen, w, np.where(valid[:, None], np.column_stack([v0, v1]), -1)

    # ------------------------------------------------------------------ reconstruct
    def reconstruct(self, obs: Observation) -> Reconstruction:
        """The 3D motion of ``obs`` (module docstring)."""
        from ..mocap.motion import Motion
        from ..mocap.placement import yaw_quat
        from ..mocap.quat import qmul
        from . import camera as cam

        if not hasattr(self, "library_"):
            raise RuntimeError("Reconstructor: fit() first")
        self.check_params()
        lib = self.library_
        index = lib.index_
        T = obs.n_frames
        observed = obs.valid
        if not observed.any():
            raise InputError(f"{obs.source or 'poses'}: no frame has a pose to reconstruct from")
        ids, cost, view = self.neighbours(obs)
        if self.method == "subsequence":
            chosen, w, node_view = self.subsequence_nodes(obs, view)
        else:
            total = self.coherent_costs(ids, cost, obs.fps)
            chosen, w = self.blend_weights(ids, total)
            # node views, aligned with the chosen nodes
            pos_in_row = np.argsort(total, axis=1, kind="stable")[:, :chosen.shape[1]]
            node_view = np.take_along_axis(view, pos_in_row, 1)
        use = chosen >= 0
        safe = np.maximum(chosen, 0)

        # blended pose (local rotations, root facing-relative), root height and azimuth
        q = lib.rotations_[safe].astype(np.float64)  # (T, n, J, 4)
        sign = np.where(np.sum(q * q[:, :1], axis=-1, keepdims=True) < 0, -1.0, 1.0)
        qb = np.sum(w[:, :, None, None] * sign * q, axis=1)
        norm = np.linalg.norm(qb, axis=-1, keepdims=True)
        qb = np.where(norm > 1e-9, qb / np.maximum(norm, 1e-12), np.array([0.0, 0.0, 0.0, 1.0]))
        height = np.sum(w * lib.root_height_[safe], axis=1)
        az_nodes = np.radians(index.views_[np.maximum(node_view, 0)])
        az = np.degrees(np.arctan2(np.sum(w * np.sin(az_nodes), 1), np.sum(w * np.cos(az_nodes), 1)))
        contact_vote = np.sum(w[:, :, None] * lib.contacts_[safe], axis=1)
        labels = self._vote_labels(chosen, w)

        # bridge frames without a pose, then smooth in time
        ok = observed & use.any(axis=1)
        qb = continuous_quaternions(_fill_gaps(continuous_quaternions(qb), ok))
        qb = _gaussian(qb, float(self.smooth_frames))
        qb /= np.linalg.norm(qb, axis=-1, keepdims=True)
        height = _gaussian(_fill_gaps(height, ok), float(self.smooth_frames))
        contact_vote = _fill_gaps(contact_vote, ok)

        skeleton = lib.skeleton_
        pose = Motion(skeleton, qb, fps=obs.fps, root_positions=np.column_stack([np.zeros(T), height, np.zeros(T)]))
        local_pts = self._keypoints(pose)  # (T, 15, 3) facing +Z (up to the blended root's residual yaw)

        elevation = float(index.elevation_deg if self.elevation_deg is None else self.elevation_deg)
        az = self._refine_azimuth(local_pts, obs, az, ok, elevation)
        az = np.degrees(np.unwrap(np.radians(_fill_gaps(np.degrees(np.unwrap(np.radians(az))), ok))))
        az = _gaussian(az, float(self.smooth_frames))
        if self.refine_prior is not None:  # the blend bent toward the keypoints (Tautges 3.5; .refine)
            from .refine import refine_poses

            wts0 = np.where(obs.scores > MIN_SCORE, obs.scores, 0.0) * observed[:, None]
            qb = refine_poses(skeleton, qb, q, use & observed[:, None], obs.xy, wts0, az, elevation,
                              prior=float(self.refine_prior))
            if float(self.refine_smooth_frames) > 0:  # each frame is bent on its own: smooth the result in time
                qb = _gaussian(continuous_quaternions(qb), float(self.refine_smooth_frames))
                qb /= np.linalg.norm(qb, axis=-1, keepdims=True)

        # world orientation: the character faces pi - azimuth
        Rc = camera_rotation(elevation)
        W, H = obs.size
        wts = np.where(obs.scores > MIN_SCORE, obs.scores, 0.0)
        if self.focal_px == "auto":  # the lens from the perspective within the poses (camera.estimate_focal)
            qf = qb.copy()
            qf[:, 0] = qmul(yaw_quat(math.pi - np.radians(az)), qb[:, 0])
            rel0 = self._keypoints(Motion(skeleton, qf, fps=obs.fps, root_positions=np.zeros((T, 3))))
            use_w = np.where(ok[:, None], wts, 0.0)
            self.focal_estimated_ = cam.estimate_focal(rel0 @ Rc.T, np.nan_to_num(obs.xy), use_w, W, H)
            K = cam.intrinsics_for_focal(W, H, self.focal_estimated_)
        else:
            K = cam.default_intrinsics(W, H) if self.focal_px is None else cam.intrinsics_for_focal(W, H, self.focal_px)
        off_axis = np.zeros(T)
        for _ in range(2):  # the second pass turns the facing by the performer's angle off the optical axis
            facing = math.pi - np.radians(az) + off_axis
            qw = qb.copy()
            qw[:, 0] = qmul(yaw_quat(facing), qb[:, 0])
            posed = Motion(skeleton, qw, fps=obs.fps, root_positions=np.zeros((T, 3)))
            rel = self._keypoints(posed)  # (T, 15, 3) world axes, relative to the root joint
            t_cam = cam.fit_translations(rel @ Rc.T, obs.xy, wts, K)  # (T, 3) root in camera coordinates
            t_ok = ok & np.all(np.isfinite(t_cam), axis=1)
            if t_ok.any():  # a collapsed 2D pose puts the performer at an absurd depth: bridge it instead
                z = t_cam[:, 2]
                zm = float(np.median(z[t_ok]))
                t_ok &= (z > zm / DEPTH_RANGE) & (z < zm * DEPTH_RANGE)
            if not t_ok.any():
                raise InputError(f"{obs.source or 'poses'}: no frame's keypoints fix the camera")
            root = _fill_gaps(np.where(t_ok[:, None], t_cam, 0.0), t_ok) @ Rc  # camera -> world, camera at 0
            root = _gaussian(root, float(self.root_smooth_frames))
            off_axis = np.angle(np.exp(1j * (np.arctan2(-root[:, 0], -root[:, 2]) - math.pi)))
        # the floor: the library knows the root's height above its floor, so the camera stands at the
        # median of (that height - the root's height relative to the camera) above it
        cam_height = float(np.median((height - root[:, 1])[t_ok]))
        root[:, 1] = height
        cset = self.contact_settings(obs.backend)
        contacts = contact_vote >= float(cset["contact_threshold"])
        gap = int(round(float(cset["contact_gap_s"]) * obs.fps))
        if gap > 0:
            from .footlock import bridge_gaps

            contacts = bridge_gaps(contacts, gap)
        if self.foot_lock:
            root, drift = self._lock_feet(root, rel, contacts, obs.fps)
        motion = Motion(skeleton, qw, fps=obs.fps, root_positions=root)
        if self.foot_lock:
            from .footlock import pin_feet

            reach = None
            if self.pin_max_offset is not None:
                reach = float(self.pin_max_offset) * _leg_length(skeleton)
            # with pin_drift a planted foot moves with the slow (horizontal) drift the root lock added back
            motion = pin_feet(motion, contacts, floor=0.0, max_offset=reach,  # the library's floor: height 0
                              creep=drift if cset["pin_drift"] else None)
            points = self._keypoints(motion)
        else:
            points = rel + root[:, None, :]
        out = Reconstruction(motion, points, observed, az, chosen, w, labels, contacts, K, elevation, cam_height,
                             {**self.get_params(), **cset, "stride": int(lib.stride_),
                              "library_frames": lib.n_frames, "scale": 1.0})
        if self.height is not None:  # step 8: the whole scene scaled about the floor under the camera
            from ..mocap.retarget import stature

            out = out.scaled(float(self.height) / stature(skeleton))
        return out

    # ------------------------------------------------------------------ helpers
    def _keypoints(self, motion) -> np.ndarray:
        from ..mocap.keypoints import keypoint_positions

        return keypoint_positions(motion)

    def _vote_labels(self, chosen: np.ndarray, w: np.ndarray) -> np.ndarray:
        lab = self.library_.labels_[np.maximum(chosen, 0)]
        out = np.full(len(chosen), "", dtype=object)
        for t in range(len(chosen)):
            score: dict[str, float] = {}
            for name, wt, c in zip(lab[t], w[t], chosen[t]):
                if c >= 0 and name:
                    score[name] = score.get(name, 0.0) + float(wt)
            if score:
                out[t] = max(score, key=score.get)
        return out

    def _refine_azimuth(self, pts: np.ndarray, obs: Observation, az: np.ndarray, ok: np.ndarray,
                        elevation: float) -> np.ndarray:
        """Step 4: per observed frame the azimuth (1-degree grid within half a view step of ``az``) whose
        orthographic projection of the facing-normalised pose ``pts`` fits the keypoints best."""
        from ..augmg.projection import facing_normalised, facing_of_keypoints

        half = 180.0 / self.library_.index_.n_views
        grid = np.arange(-math.floor(half), math.floor(half) + 1, 1.0)
        norm = facing_normalised(pts, facing_of_keypoints(pts))
        out = az.copy()
        rows = np.flatnonzero(ok)
        if rows.size == 0 or grid.size < 2:
            return out
        wts = np.where(obs.scores > MIN_SCORE, obs.scores, 0.0)
        best_res = np.full(rows.size, np.inf)
        best = az[rows].copy()
        for g in grid:
            cand = az[rows] + g
            R = view_rotations(cand, elevation)  # (n, 3, 3)
            proj = np.einsum("nij,nkj->nki", R, norm[rows])[..., :2]
            res = similarity_residual(proj, obs.xy[rows], wts[rows])
            better = res < best_res
            best_res = np.where(better, res, best_res)
            best = np.where(better, cand, best)
        out[rows] = best
        return out

    def _lock_feet(self, root: np.ndarray, rel: np.ndarray, contacts: np.ndarray, fps: float) -> np.ndarray:
        """Step 7: the root moved horizontally so planted ankles stay put; the difference to the camera's
        root path ``root`` is then low-passed (Gaussian, sigma ``relax_s`` seconds) and added back, so the
        path follows the camera in the long run and the feet in the short. Returns the path and that
        low-passed difference (T, 3; zero in height)."""
        from ..augmg.keypoints import KP

        ankles = rel[:, [KP["left_ankle"], KP["right_ankle"]]][:, :, [0, 2]]  # (T, 2, 2) horizontal
        locked = root.copy()
        offset = np.zeros(2)
        anchor = np.full((2, 2), np.nan)
        for t in range(len(root)):
            base = root[t, [0, 2]]
            corr = []
            for f in range(2):
                if not contacts[t, f]:
                    anchor[f] = np.nan
                    continue
                here = base + offset + ankles[t, f]
                if np.isnan(anchor[f, 0]):
                    anchor[f] = here
                corr.append(anchor[f] - here)
            if corr:
                offset = offset + np.mean(corr, axis=0)
            locked[t, [0, 2]] = base + offset
        drift = _gaussian(root - locked, float(self.relax_s) * fps)
        out = locked + drift
        out[:, 1] = root[:, 1]
        return out, drift
