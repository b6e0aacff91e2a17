"""``ActionModel``: Du's (2014) statistical action models (Motion Graphs++), one per action label.

Per label (``docs/actionmodel.md`` has the method and its choices):

1. **Instances** of the most common contact signature (:mod:`.instances`), each segmented into primitives
   at its keyframes (contact changes).
2. **Alignment**: the medoid instance (least summed DTW cost to the others) is the reference; every
   instance is aligned to it primitive by primitive with slope-limited DTW (:mod:`.dtw`), keyframes
   matched to keyframes. The warp ``W`` (aligned frame -> instance frame) is kept.
3. **Functional PCA** on a sample basis (the aligned curves at the reference's frames):
   *spatial* -- per aligned frame the root position (x, z from the start, y the height, in the canonical
   frame) and every joint's rotation as the rotation vector of ``ref^-1 q`` (``ref`` the medoid's rotation
   of that joint at that aligned frame: small, continuous deviations), each scaled by the joint's *reach*
   (the farthest rest-pose descendant from it; a weighting in length units in the spirit of Du's weighted
   PCA: a radian at the hip moves the body more than a radian at the wrist);
   *temporal* -- the warp's log-derivative ``log diff W`` (:mod:`.warp`: any vector is a monotone warp).
   Each PCA keeps ``variance`` of its variance; coefficients are whitened (divided by the component's
   standard deviation).
4. **GMM** over ``[spatial | temporal]`` coefficients, the number of components (1..``max_components``)
   by BIC (scikit-learn ``GaussianMixture``).

``encode`` / ``decode`` / ``log_prior`` are the pieces a later fit to video needs; ``sample`` draws
coefficients from the GMM, decodes them to a BVH-ready :class:`~vidstyle.mocap.Motion` on the source
skeleton and pins the planted feet: each primitive's contact state says which ankle is down, and
:func:`vidstyle.reconstruct.footlock.pin_feet` holds it where it landed, at the planted ankle height
learned from the source clips.
"""

from __future__ import annotations

import logging
import time
from collections import Counter
from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation
from sklearn.base import BaseEstimator

from ..errors import InputError, ParameterError
from ..mocap import Motion
from ..mocap.quat import compose, normalise
from . import defaults as D
from .dtw import dtw, dtw_cost, path_to_warp
from .instances import Instance, InstanceSet, canonical, clip_contacts, cut_instances, segment
from .warp import invert_warp, logderiv_to_warp, warp_to_logderiv

log = logging.getLogger(__name__)


# ----------------------------------------------------------------------------- geometry helpers
def slerp_frames(q: np.ndarray, t: np.ndarray) -> np.ndarray:
    """(len(t), J, 4) rotations of ``q`` (F, J, 4) at fractional frames ``t`` (clamped), by slerp between
    neighbouring frames."""
    F = q.shape[0]
    t = np.clip(np.asarray(t, dtype=np.float64), 0, F - 1)
    i0 = np.floor(t).astype(int)
    i1 = np.minimum(i0 + 1, F - 1)
    a = (t - i0)[:, None, None]
    q0, q1 = q[i0], q[i1]
    dot = np.sum(q0 * q1, -1, keepdims=True)
    q1 = np.where(dot < 0, -q1, q1)
    dot = np.abs(dot)
    theta = np.arccos(np.clip(dot, -1, 1))
    s = np.sin(theta)
    small = s < 1e-8
    w0 = np.where(small, 1 - a, np.sin((1 - a) * theta) / np.where(small, 1, s))
    w1 = np.where(small, a, np.sin(a * theta) / np.where(small, 1, s))
    out = w0 * q0 + w1 * q1
    return out / np.linalg.norm(out, axis=-1, keepdims=True)


def interp_frames(x: np.ndarray, t: np.ndarray) -> np.ndarray:
    """(len(t), ...) linear interpolation of ``x`` (F, ...) at fractional frames ``t`` (clamped)."""
    F = x.shape[0]
    t = np.clip(np.asarray(t, dtype=np.float64), 0, F - 1)
    i0 = np.floor(t).astype(int)
    i1 = np.minimum(i0 + 1, F - 1)
    a = (t - i0).reshape((-1,) + (1,) * (x.ndim - 1))
    return (1 - a) * x[i0] + a * x[i1]


def joint_reach(skeleton, floor: float = 0.05) -> np.ndarray:
    """(J,) farthest rest-pose distance from each joint to a descendant joint or End Site, at least
    ``floor`` times the largest one (a joint that moves nothing still gets a weight)."""
    from ..mocap.retarget import rest_positions

    pos, ends = rest_positions(skeleton)
    parents = skeleton.parents
    J = len(parents)
    reach = np.zeros(J)
    pts = [(j, pos[j]) for j in range(J)] + [(j, e) for j, e in ends.items()]
    for j0, p in pts:
        a = j0
        while a >= 0:
            reach[a] = max(reach[a], float(np.linalg.norm(p - pos[a])))
            a = int(parents[a])
    return np.maximum(reach, floor * reach.max())


def _depth_weights(parents: np.ndarray) -> np.ndarray:
    depth = np.zeros(len(parents))
    for j, p in enumerate(parents):
        if p >= 0:
            depth[j] = depth[p] + 1
    return 1.0 / (1.0 + depth)


# ----------------------------------------------------------------------------- per-label model
@dataclass
class LabelModel:
    """Everything learned for one label (the arrays the model file stores; ``docs/actionmodel.md``)."""

    label: str
    ref_rotations: np.ndarray  # (M, J, 4) the medoid's rotations at the aligned frames
    ref_root: np.ndarray  # (M, 3) the medoid's root positions (canonical frame)
    keyframes: np.ndarray  # (K,) aligned frame where each primitive starts
    states: np.ndarray  # (K, 2) bool, contact state of each primitive (left, right)
    spatial_mean: np.ndarray  # (Ds,)
    spatial_components: np.ndarray  # (ks, Ds) orthonormal rows
    spatial_std: np.ndarray  # (ks,) sqrt of the explained variance (whitening)
    temporal_mean: np.ndarray  # (M-1,)
    temporal_components: np.ndarray  # (kt, M-1)
    temporal_std: np.ndarray  # (kt,)
    gmm_weights: np.ndarray  # (G,)
    gmm_means: np.ndarray  # (G, ks+kt)
    gmm_covariances: np.ndarray  # (G, ks+kt, ks+kt)
    bic: np.ndarray  # (tried,) BIC of 1..tried components
    n_instances: int = 0
    n_other_signature: int = 0
    medoid: str = ""
    fit_seconds: float = 0.0
    spatial_variance_kept: float = 0.0
    temporal_variance_kept: float = 0.0
    mean_frames: float = 0.0
    covariance_type: str = "full"

    @property
    def n_aligned(self) -> int:
        return int(self.ref_rotations.shape[0])

    @property
    def n_spatial(self) -> int:
        return int(self.spatial_components.shape[0])

    @property
    def n_temporal(self) -> int:
        return int(self.temporal_components.shape[0])

    @property
    def n_coefficients(self) -> int:
        return self.n_spatial + self.n_temporal

    @property
    def n_components(self) -> int:
        return int(len(self.gmm_weights))

    @property
    def signature(self) -> list[list[bool]]:
        return [[bool(a), bool(b)] for a, b in self.states]


@dataclass
class Aligned:
    """One instance aligned to its label's reference: aligned rotations (M, J, 4), root (M, 3), warp W (M,)."""

    rotations: np.ndarray
    root: np.ndarray
    warp: np.ndarray
    n_frames: int


def _fit_label_task(item) -> tuple[LabelModel | None, str]:
    """One label's model of :meth:`ActionModel.fit` (``(model, label, instances)``): ``(LabelModel, "")``, or
    ``(None, why)`` when the label is not modelled."""
    model, label, insts = item
    t0 = time.perf_counter()
    try:
        lm = model._fit_label(label, insts)
    except _Skip as e:
        return None, str(e)
    lm.fit_seconds = time.perf_counter() - t0
    return lm, ""


class ActionModel(BaseEstimator):
    """Statistical models of actions learned from labelled mocap (module text).

    >>> model = ActionModel(variance=0.95, random_state=0).fit(clips)        # doctest: +SKIP
    >>> motions = model.sample("Jab", 5, random_state=0)                     # doctest: +SKIP
    >>> z = model.encode(instance_motion, "Jab"); model.log_prior(z, "Jab")  # doctest: +SKIP

    ``fit`` takes :class:`vidstyle.motiongraph.graph.Clip` s (:func:`.instances.load_labelled`) or an
    :class:`~.instances.InstanceSet`. Learned attributes end in ``_``: ``skeleton_``, ``fps_``,
    ``labels_``, ``models_`` (label -> :class:`LabelModel`), ``contact_height_`` (planted ankle height,
    source units), ``reach_`` (J,), ``skipped_`` (label -> why it has no model).

    ``n_jobs``: the labels' models fitted on that many workers (:func:`vidstyle.parallel.parallel_map`;
    None or 1: in this process). Each label's fit is seeded by ``random_state`` and the label alone, so the
    model is the same for every ``n_jobs``; a run setting, not a model parameter (not in the model file).
    """

    def __init__(self, variance: float = D.VARIANCE, slope_limit: int = D.SLOPE_LIMIT,
                 max_components: int = D.MAX_COMPONENTS, covariance_type: str = D.COVARIANCE_TYPE,
                 min_frames: int = D.MIN_FRAMES, min_run: int = D.MIN_RUN, min_primitive: int = D.MIN_PRIMITIVE,
                 min_instances: int = D.MIN_INSTANCES, medoid_candidates: int = D.MEDOID_CANDIDATES,
                 blend_frames: int = D.BLEND_FRAMES, warp_smoothing: float = D.WARP_SMOOTHING, labels: tuple[str, ...] | None = None,
                 random_state: int | None = D.RANDOM_STATE, n_jobs: int | None = None) -> None:
        self.variance = variance
        self.slope_limit = slope_limit
        self.max_components = max_components
        self.covariance_type = covariance_type
        self.min_frames = min_frames
        self.min_run = min_run
        self.min_primitive = min_primitive
        self.min_instances = min_instances
        self.medoid_candidates = medoid_candidates
        self.blend_frames = blend_frames
        self.warp_smoothing = warp_smoothing
        self.labels = labels
        self.random_state = random_state
        self.n_jobs = n_jobs

    # ------------------------------------------------------------------ parameters
    def check_params(self) -> None:
        v = self.variance
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not 0 < float(v) <= 1:
            raise ParameterError("variance", f"must be in (0, 1], got {v!r}")
        for name, lo in (("slope_limit", 1), ("max_components", 1), ("min_frames", 2), ("min_run", 1),
                         ("min_primitive", 2), ("min_instances", 2), ("medoid_candidates", 2), ("blend_frames", 0)):
            x = getattr(self, name)
            if isinstance(x, bool) or not isinstance(x, (int, np.integer)) or x < lo:
                raise ParameterError(name, f"must be an integer >= {lo}, got {x!r}")
        ws = self.warp_smoothing
        if isinstance(ws, bool) or not isinstance(ws, (int, float)) or not 0 <= float(ws) < 1e3:
            raise ParameterError("warp_smoothing", f"must be a number >= 0 (reference frames), got {ws!r}")
        if self.covariance_type not in ("full", "diag"):
            raise ParameterError("covariance_type", f"must be full or diag, got {self.covariance_type!r}")

    # ------------------------------------------------------------------ features
    def _positions(self, rotations: np.ndarray, root: np.ndarray) -> np.ndarray:
        from ..mocap.kinematics import forward_kinematics

        m = Motion(self.skeleton_, rotations, None, self.fps_, root_positions=root)
        return forward_kinematics(m, return_matrices=False)[0]

    def _frame_features(self, pos: np.ndarray) -> np.ndarray:
        """(F, 3J) DTW frame features: joint positions weighted by 1/(1+depth) (Du 3.2.1: deeper joints,
        noisier and less important, weigh less)."""
        return (pos * np.sqrt(self._dtw_w)[None, :, None]).reshape(len(pos), -1)

    def _spatial(self, rot: np.ndarray, root: np.ndarray, ref: np.ndarray) -> np.ndarray:
        """(M*(3+3J),) spatial feature vector of aligned rotations / root against reference rotations."""
        M, J = rot.shape[:2]
        rel = (Rotation.from_quat(ref.reshape(-1, 4)).inv() * Rotation.from_quat(rot.reshape(-1, 4))).as_rotvec()
        rel = rel.reshape(M, J, 3) * self.reach_[None, :, None]
        return np.concatenate([root, rel.reshape(M, -1)], axis=1).ravel()

    def _unspatial(self, x: np.ndarray, ref: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        M, J = ref.shape[:2]
        x = x.reshape(M, 3 + 3 * J)
        root = x[:, :3]
        rel = x[:, 3:].reshape(M, J, 3) / self.reach_[None, :, None]
        # (Rotation.from_quat(ref) * Rotation.from_rotvec(rel)).as_quat(), to the last bit, without scipy's
        # slow product (a third of a style fit's decodes)
        rot = compose(normalise(ref.reshape(-1, 4)), Rotation.from_rotvec(rel.reshape(-1, 3)).as_quat())
        return rot.reshape(M, J, 4), root

    # ------------------------------------------------------------------ alignment
    def _segments(self, inst: Instance, ref_keys: np.ndarray | None, M: int | None) -> list[tuple[int, int]]:
        return inst.bounds()

    def _align(self, inst: Instance, ref_feat: np.ndarray, ref_keys: np.ndarray,
               cost_only: bool = False) -> tuple[float, np.ndarray | None]:
        """DTW cost and warp (M,) of ``inst`` onto a reference with features ``ref_feat`` (M, D) and
        primitive starts ``ref_keys``: primitive by primitive when the instance has as many primitives,
        else as one segment."""
        feat = self._inst_feat(inst)
        M = len(ref_feat)
        rb = list(ref_keys) + [M - 1]
        ib = [a for a, _ in inst.bounds()] + [inst.n_frames - 1]
        if len(ib) != len(rb):
            rb, ib = [0, M - 1], [0, inst.n_frames - 1]
        total = 0.0
        W = np.zeros(M)
        for k in range(len(rb) - 1):
            r0, r1, i0, i1 = rb[k], rb[k + 1], ib[k], ib[k + 1]
            C = _sqdist(ref_feat[r0:r1 + 1], feat[i0:i1 + 1])
            if cost_only:
                total += dtw_cost(C, self.slope_limit)
                continue
            cost, path = dtw(C, self.slope_limit)
            total += cost
            W[r0:r1 + 1] = i0 + path_to_warp(path, r1 - r0 + 1, i1 - i0 + 1, smooth=self.warp_smoothing)
        return total, (None if cost_only else W)

    def _inst_feat(self, inst: Instance) -> np.ndarray:
        f = getattr(inst, "_feat", None)
        if f is None:
            f = self._frame_features(self._positions(inst.motion.rotations, inst.motion.root_positions))
            inst._feat = f
        return f

    def _resample(self, inst: Instance, W: np.ndarray) -> Aligned:
        rot = slerp_frames(inst.motion.rotations, W)
        root = interp_frames(inst.motion.root_positions, W)
        return Aligned(rot, root, W, inst.n_frames)

    # ------------------------------------------------------------------ fit
    def fit(self, X, y=None) -> ActionModel:
        """Fit one model per label of ``X`` (clips or an :class:`InstanceSet`); ``y`` is ignored."""
        self.check_params()
        if isinstance(X, InstanceSet):
            iset = X
        else:
            iset = cut_instances(X, self.min_frames, self.min_run, self.min_primitive)
        self.skeleton_ = iset.skeleton
        self.fps_ = float(iset.fps)
        self.reach_ = joint_reach(self.skeleton_)
        self._dtw_w = _depth_weights(self.skeleton_.parents)
        self.n_joints_ = self.skeleton_.n_joints
        self.sources_ = list(iset.sources)
        # planted ankle height: median over the planted frames of every instance
        heights = []
        from ..reconstruct.footlock import leg_chains

        try:
            self.ankles_ = [c[2] for c in leg_chains(self.skeleton_)]
        except ValueError as e:
            raise InputError(f"clips: the skeleton has no two leg chains to plant ({e})") from None
        for inst in iset.instances:
            pos = self._positions(inst.motion.rotations, inst.motion.root_positions)
            for f, a in enumerate(self.ankles_):
                heights.append(pos[inst.contacts[:, f], a, 1])
        h = np.concatenate(heights) if heights else np.zeros(0)
        self.contact_height_ = float(np.median(h)) if len(h) else 0.0
        self.models_: dict[str, LabelModel] = {}
        self.skipped_: dict[str, str] = {}
        wanted = iset.labels() if self.labels is None else list(self.labels)
        tasks = []
        for label in wanted:
            insts = iset.of(label)
            if not insts:
                self.skipped_[label] = "no instance"
                continue
            tasks.append((self, label, insts))
        if self.n_jobs in (None, 1) or len(tasks) < 2:
            done = [_fit_label_task(t) for t in tasks]
        else:
            from ..parallel import parallel_map

            # the largest labels first (each worker takes the next when done)
            order = sorted(range(len(tasks)), key=lambda k: -sum(i.n_frames for i in tasks[k][2]))
            out = parallel_map(_fit_label_task, [tasks[k] for k in order], jobs=self.n_jobs, description="action models")
            done = [None] * len(tasks)
            for k, r in zip(order, out):
                done[k] = r
        for (_, label, _), (lm, skipped) in zip(tasks, done):
            if lm is None:
                self.skipped_[label] = skipped
                log.warning("action model: %s not modelled: %s", label, skipped)
                continue
            self.models_[label] = lm
        if not self.models_:
            raise InputError("clips: no action has enough instances to model "
                             f"({'; '.join(f'{k}: {v}' for k, v in self.skipped_.items()) or 'no labelled action'})")
        self.labels_ = sorted(self.models_)
        return self

    def _rng(self, salt: str) -> np.random.Generator:
        base = 0 if self.random_state is None else int(self.random_state)
        return np.random.default_rng([base, *salt.encode()])

    def _fit_label(self, label: str, insts: list[Instance]) -> LabelModel:
        sigs = Counter(i.signature for i in insts)
        sig, _count = sigs.most_common(1)[0]
        keep = [i for i in insts if i.signature == sig]
        if len(keep) < self.min_instances:
            raise _Skip(f"{len(keep)} instance(s) of its most common contact signature (need {self.min_instances})")
        rng = self._rng(label)
        cand = keep if len(keep) <= self.medoid_candidates else [keep[k] for k in sorted(
            rng.choice(len(keep), self.medoid_candidates, replace=False))]
        # medoid: least summed DTW cost to the other candidates
        n = len(cand)
        cost = np.zeros((n, n))
        for a in range(n):
            fa = self._inst_feat(cand[a])
            ka = np.array([s for s, _ in cand[a].bounds()])
            for b in range(a + 1, n):
                c, _ = self._align(cand[b], fa, ka, cost_only=True)
                cost[a, b] = cost[b, a] = c
        med = cand[int(np.argmin(cost.sum(1)))]
        ref_feat = self._inst_feat(med)
        ref_keys = np.array([s for s, _ in med.bounds()], dtype=np.int64)
        ref_rot, ref_root = med.motion.rotations.copy(), med.motion.root_positions.copy()
        S, T = [], []
        for inst in keep:
            _, W = self._align(inst, ref_feat, ref_keys)
            al = self._resample(inst, W)
            S.append(self._spatial(al.rotations, al.root, ref_rot))
            T.append(warp_to_logderiv(W))
        S, T = np.array(S), np.array(T)
        sp = _pca(S, self.variance)
        tp = _pca(T, self.variance)
        Z = np.concatenate([_project(S, *sp), _project(T, *tp)], axis=1)
        gw, gm, gc, bic = self._gmm(Z, rng)
        lm = LabelModel(label, ref_rot, ref_root, ref_keys, np.array(sig, dtype=bool).reshape(-1, 2),
                        sp[0], sp[1], sp[2], tp[0], tp[1], tp[2], gw, gm, gc, bic,
                        n_instances=len(keep), n_other_signature=len(insts) - len(keep),
                        medoid=f"{med.source}@{med.start}", spatial_variance_kept=sp[3], temporal_variance_kept=tp[3],
                        mean_frames=float(np.mean([i.n_frames for i in keep])), covariance_type=self._last_cov_type)
        return lm

    def _gmm(self, Z: np.ndarray, rng: np.random.Generator):
        w, mu, cov, bics, kind = fit_gmm_bic(Z, self.max_components, self.covariance_type,
                                             int(rng.integers(2**31 - 1)))
        self._last_cov_type = kind
        return w, mu, cov, bics

    # ------------------------------------------------------------------ public API for later fitting
    def _model(self, label: str) -> LabelModel:
        if not hasattr(self, "models_"):
            raise InputError("action model: not fitted")
        if label not in self.models_:
            raise ParameterError("label", f"no model for {label!r} (labels: {', '.join(self.labels_)})")
        return self.models_[label]

    def instance(self, motion: Motion, label: str) -> Instance:
        """``motion`` (one action instance on the model's skeleton layout) as an :class:`Instance`: canonical
        frame, contacts, primitives."""
        from ..mocap.retarget import retarget

        m, _ = retarget(motion, self.skeleton_, "instance")
        contacts = clip_contacts(m, self.min_run)
        keys, states = segment(contacts, self.min_primitive)
        return Instance(label, canonical(m), contacts, keys, states)

    def align(self, inst: Instance | Motion, label: str) -> Aligned:
        """``inst`` aligned to ``label``'s reference (rotations and root at the aligned frames, warp)."""
        lm = self._model(label)
        if isinstance(inst, Motion):
            inst = self.instance(inst, label)
        if inst.n_frames < 2:
            raise ParameterError("instance", f"needs at least 2 frames, got {inst.n_frames}")
        ref_feat = self._frame_features(self._positions(lm.ref_rotations, lm.ref_root))
        _, W = self._align(inst, ref_feat, lm.keyframes)
        return self._resample(inst, W)

    def encode(self, inst: Instance | Motion, label: str) -> np.ndarray:
        """Coefficients ``[spatial | temporal]`` (whitened PCA scores) of one instance of ``label``."""
        self._model(label)
        al = self.align(inst, label)
        return self.encode_aligned(al, label)

    def encode_aligned(self, al: Aligned, label: str) -> np.ndarray:
        lm = self._model(label)
        s = self._spatial(al.rotations, al.root, lm.ref_rotations)
        t = warp_to_logderiv(al.warp)
        return np.concatenate([_project(s[None], lm.spatial_mean, lm.spatial_components, lm.spatial_std)[0],
                               _project(t[None], lm.temporal_mean, lm.temporal_components, lm.temporal_std)[0]])

    def decode_aligned(self, z: np.ndarray, label: str) -> Aligned:
        """Aligned rotations, root and warp of coefficients ``z``."""
        lm = self._model(label)
        z = np.asarray(z, dtype=np.float64)
        if z.shape != (lm.n_coefficients,):
            raise ValueError(f"{label}: expected {lm.n_coefficients} coefficients, got shape {z.shape}")
        s = lm.spatial_mean + (z[:lm.n_spatial] * lm.spatial_std) @ lm.spatial_components
        d = lm.temporal_mean + (z[lm.n_spatial:] * lm.temporal_std) @ lm.temporal_components
        rot, root = self._unspatial(s, lm.ref_rotations)
        W = logderiv_to_warp(d)
        return Aligned(rot, root, W, int(round(W[-1])) + 1)

    def decode(self, z: np.ndarray, label: str, n_frames: int | None = None, pin: bool = False) -> Motion:
        """The motion of coefficients ``z`` in its own time (``n_frames``: default the warp's length),
        canonical frame; ``pin``: hold planted feet (as :meth:`sample` does)."""
        al = self.decode_aligned(z, label)
        n = al.n_frames if n_frames is None else int(n_frames)
        u = invert_warp(al.warp, max(n, 1))
        rot = slerp_frames(al.rotations, u)
        root = interp_frames(al.root, u)
        m = Motion(self.skeleton_, rot, None, self.fps_, root_positions=root)
        if pin:
            m = self.pin(m, self.contacts_at(label, u))
        return m

    def contacts_at(self, label: str, u: np.ndarray) -> np.ndarray:
        """(len(u), 2) contact state of the primitive at each aligned time ``u``."""
        lm = self._model(label)
        k = np.searchsorted(lm.keyframes, np.floor(np.asarray(u) + 1e-9), side="right") - 1
        return lm.states[np.clip(k, 0, len(lm.states) - 1)]

    def pin(self, motion: Motion, contacts: np.ndarray) -> Motion:
        """Planted ankles held where they land, at the learned planted height
        (:func:`vidstyle.reconstruct.footlock.pin_feet`)."""
        from ..reconstruct.footlock import pin_feet

        return pin_feet(motion, contacts, blend_frames=self.blend_frames, height=self.contact_height_)

    def log_prior(self, z: np.ndarray, label: str) -> np.ndarray | float:
        """Log density of coefficients ``z`` ((k,) or (n, k)) under ``label``'s GMM."""
        from scipy.special import logsumexp

        lm = self._model(label)
        z = np.asarray(z, dtype=np.float64)
        single = z.ndim == 1
        Z = np.atleast_2d(z)
        k = lm.n_coefficients
        out = []
        for w, mu, cov in zip(lm.gmm_weights, lm.gmm_means, lm.gmm_covariances):
            L = np.linalg.cholesky(cov)
            y = np.linalg.solve(L, (Z - mu).T)
            out.append(np.log(w) - 0.5 * np.sum(y * y, 0) - np.log(np.diag(L)).sum() - 0.5 * k * np.log(2 * np.pi))
        r = logsumexp(np.array(out), axis=0)
        return float(r[0]) if single else r

    def sample_coefficients(self, label: str, n: int, random_state=None) -> np.ndarray:
        """(n, k) coefficients drawn from ``label``'s GMM with ``random_state`` (default the model's)."""
        lm = self._model(label)
        rs = self.random_state if random_state is None else random_state
        rng = rs if isinstance(rs, np.random.Generator) else np.random.default_rng(rs)
        comp = rng.choice(lm.n_components, size=int(n), p=lm.gmm_weights / lm.gmm_weights.sum())
        Zs = rng.standard_normal((int(n), lm.n_coefficients))
        out = np.empty_like(Zs)
        for g in range(lm.n_components):
            L = np.linalg.cholesky(lm.gmm_covariances[g])
            idx = comp == g
            out[idx] = lm.gmm_means[g] + Zs[idx] @ L.T
        return out

    def sample(self, label: str, n: int = 1, random_state=None, pin: bool = True) -> list[Motion]:
        """``n`` new instances of ``label`` as motions on the source skeleton (canonical frame: facing +Z,
        starting above the origin), planted feet pinned (``pin``)."""
        if isinstance(n, bool) or int(n) != n or n < 0:
            raise ParameterError("n", f"must be an integer >= 0, got {n!r}")
        Z = self.sample_coefficients(label, int(n), random_state)
        return [self.decode(z, label, pin=pin) for z in Z]

    # ------------------------------------------------------------------ persistence
    def to_record(self):
        """The fitted model as an :class:`~vidstyle.formats.actionmodel.ActionModelRecord`."""
        from dataclasses import fields as dc_fields

        from ..formats.actionmodel import LABEL_ARRAYS, ActionModelRecord

        sk = self.skeleton_
        models = {}
        for label in self.labels_:
            lm = self.models_[label]
            arrays = {k: getattr(lm, k) for k in LABEL_ARRAYS}
            meta = {f.name: getattr(lm, f.name) for f in dc_fields(lm) if f.name not in LABEL_ARRAYS and f.name != "label"}
            models[label] = {**arrays, "meta": meta}
        params = {k: (list(v) if isinstance(v, tuple) else v) for k, v in self.get_params().items() if k != "n_jobs"}
        return ActionModelRecord(params, self.fps_, self.contact_height_,
                                 {"names": list(sk.names), "parents": sk.parents, "offsets": sk.offsets,
                                  "channels": list(sk.channels), "end_sites": dict(sk.end_sites)},
                                 self.reach_, list(self.labels_), models, list(self.sources_), dict(self.skipped_))

    @classmethod
    def from_record(cls, rec, path=None) -> ActionModel:
        """The fitted model of a record read by :func:`vidstyle.formats.actionmodel.read_actionmodel`
        (FormatError naming ``path`` when its skeleton has no two legs)."""
        from ..errors import FormatError
        from ..mocap.skeleton import Skeleton
        from ..reconstruct.footlock import leg_chains

        model = cls(**rec.params)
        sk = rec.skeleton
        try:
            model.skeleton_ = Skeleton(sk["names"], sk["parents"], sk["offsets"], sk["channels"], sk["end_sites"])
            model.ankles_ = [c[2] for c in leg_chains(model.skeleton_)]
        except (ValueError, InputError) as e:
            raise FormatError(path, "skeleton_names", f"not a skeleton with two legs ({e})") from None
        model.fps_ = rec.fps
        model.contact_height_ = rec.contact_height
        model.reach_ = np.asarray(rec.reach, dtype=np.float64)
        model._dtw_w = _depth_weights(model.skeleton_.parents)
        model.n_joints_ = model.skeleton_.n_joints
        model.sources_ = list(rec.sources)
        model.skipped_ = dict(rec.skipped)
        model.models_ = {}
        for label in rec.labels:
            d = rec.models[label]
            model.models_[label] = LabelModel(label, **{k: v for k, v in d.items() if k != "meta"}, **d["meta"])
        model.labels_ = list(rec.labels)
        return model

    def save(self, path) -> None:
        """Write the model file (:mod:`vidstyle.formats.actionmodel`), atomically."""
        from ..formats.actionmodel import write_actionmodel

        write_actionmodel(path, self.to_record())

    @classmethod
    def load(cls, path) -> ActionModel:
        """Read a model file (every field checked: FormatError naming the file and field)."""
        from ..formats.actionmodel import read_actionmodel

        return cls.from_record(read_actionmodel(path), path)


class _Skip(Exception):
    pass


def fit_gmm_bic(Z: np.ndarray, max_components: int = D.MAX_COMPONENTS, covariance_type: str = "full",
                random_state: int = 0, reg_covar: float = 1e-3):
    """GMMs of 1, 2, ... components on ``Z`` (N, d) (scikit-learn ``GaussianMixture``, 3 restarts each);
    the one of least BIC. Returns ``(weights (G,), means (G, d), covariances (G, d, d), BIC of each
    number tried, covariance type used)``.

    A mixture is tried only while it has no more free parameters than there are rows (beyond that EM
    collapses components onto single rows and the likelihood, and BIC, mean nothing); with too few rows
    for one full covariance, diagonal covariances are used (on whitened PCA scores, one diagonal
    Gaussian is the PCA model itself)."""
    from sklearn.mixture import GaussianMixture

    Z = np.asarray(Z, dtype=np.float64)
    N, d = Z.shape

    def n_params(g: int, kind: str) -> int:
        return g * d + g * (d * (d + 1) // 2 if kind == "full" else d) + g - 1

    kind = covariance_type
    if kind == "full" and n_params(1, "full") > N:
        kind = "diag"
    best, bics = None, []
    for g in range(1, int(max_components) + 1):
        if g > 1 and (n_params(g, kind) > N or g > N):
            break
        gm = GaussianMixture(g, covariance_type=kind, random_state=random_state, n_init=3, reg_covar=reg_covar).fit(Z)
        b = float(gm.bic(Z))
        bics.append(b)
        if best is None or b < best[1]:
            best = (gm, b)
    gm = best[0]
    cov = gm.covariances_
    if kind == "diag":
        cov = np.stack([np.diag(c) for c in cov])
    return gm.weights_.copy(), gm.means_.copy(), np.asarray(cov, dtype=np.float64), np.array(bics), kind


def _sqdist(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    d = (a * a).sum(1)[:, None] + (b * b).sum(1)[None, :] - 2 * a @ b.T
    return np.maximum(d, 0.0)


def _pca(X: np.ndarray, variance: float):
    """(mean, components (k, D), std (k,), variance kept) of ``X`` (N, D): the fewest components keeping
    ``variance`` of the total (all with nonzero variance for 1.0). SVD of the centred data."""
    mean = X.mean(0)
    Xc = X - mean
    N = len(X)
    _, s, Vt = np.linalg.svd(Xc, full_matrices=False)
    ev = s**2 / max(N - 1, 1)
    total = ev.sum()
    tol = 1e-12 * max(total, 1e-300)
    nz = int(np.sum(ev > tol))
    if total <= 0 or nz == 0:
        return mean, np.zeros((0, X.shape[1])), np.zeros(0), 1.0
    if variance >= 1.0:
        k = nz
    else:
        k = int(np.searchsorted(np.cumsum(ev) / total, variance) + 1)
        k = min(max(k, 1), nz)
    # a deterministic sign: the largest-magnitude entry of each component positive
    comps = Vt[:k]
    sign = np.sign(comps[np.arange(k), np.argmax(np.abs(comps), axis=1)])
    comps = comps * sign[:, None]
    return mean, comps, np.sqrt(ev[:k]), float(ev[:k].sum() / total)


def _project(X: np.ndarray, mean: np.ndarray, comps: np.ndarray, std: np.ndarray, *_):
    return ((X - mean) @ comps.T) / np.where(std > 0, std, 1.0)
