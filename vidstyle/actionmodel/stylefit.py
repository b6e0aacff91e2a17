"""Fit a performer's action-level style from 2D keypoint tracks (issue 30 item 2; Du 2014 models).

Two parts (``docs/actionmodel.md``, "Fitting a performer"):

**Global style** (:class:`GlobalStyleEstimator`, scikit-learn conventions: ``fit`` on the training
performers' videos learns the population's per-view figures, ``estimate`` a performer's style). Input per
video: a (F, 15, 2) track (image pixels, y down; NaN = missing), per-frame action labels (true or
recognised) and the view name (``front``/``left``/``right``: the camera's azimuth relative to the
performer's facing, known from the calibrated camera; the figures are normalised per view by the
training population, so only the view's identity is used, never its angle).

* **lead** (``lead_cue="stance"``, the default): the front foot's image side. Per frame with both ankles and
  hips seen, the lower ankle (nearer a camera that looks down) is the front foot; the sign of its image x
  from the hips' midpoint, times the orthodox sign learned per view from the training population (their
  labelled jab hand), averaged over frames, is the score in [-1, 1]. Label-free: the pose stage's
  left/right swaps do not matter, and every frame counts. With fewer than ``min_stance_frames`` such frames
  (or ``lead_cue="jab"``) the jab rules decide:
  which hand throws the jabs. Per Jab segment, the largest image displacement of each wrist
  from where it was at the segment's start; the wrist that moves more is the jabbing one.
  *Label-free rule* (used when there are ``min_front_jabs`` or more Jab segments in front views): the side
  of the neck (image x) on which the jabbing wrist travels; which side is orthodox is learned from the
  training population (``orthodox_side_``, the sign agreeing with their labelled jab hand); the score is
  ``2 * share of orthodox-side jabs - 1``. It assumes the performer faces the front camera (a single view
  cannot tell an orthodox fighter facing the camera from a southpaw facing away), and does not trust
  the pose stage's left/right labels, which pictorial structures often swap (on the validation
  performers' estimated poses the labelled jab hand was at chance in front views and inverted in one
  side view each). *Labelled rule* (otherwise): the mean of ``(left - right) / (left + right)`` of the
  two wrists' displacements, > 0 the left hand leads (orthodox), viewpoint-free.
* **stance width**: ankle distance over leg length (hip-knee + knee-ankle, the 90th percentile over the
  video) in Guard frames; **guard height**: mean (shoulder - wrist) image height in arm lengths (90th
  percentile of upper + forearm image length); **crouch**: (hip - ankle) height over leg length,
  negated. Each is the performer's median over their videos of (figure - the training population's mean
  at that view), plus 1 for the stance (a ratio to the population's mean, as ``stance_width`` is).
* **tempo**: per action the performer's median segment length (frames) over the population's median: the
  observable duration factor ``tempo[a] / speed`` of :class:`vidstyle.demo.performer.MovementTraits`;
  ``relative_tempo`` divides by its mean over actions (``tempo[a] / mean tempo``). **speed**: the
  population's ``Step`` segment length over the performer's median (a step takes ``BASE_SECONDS["Step"] /
  speed``, whatever the per-action tempo). **action_tempo**: the performer's action-to-step length ratio
  over the population's, which separates the per-action tempo from the overall speed (nan / empty when no
  step was seen). With the performers of the population's videos (``fit(groups=)``) the population's
  step length and ratios are means over performers of their own medians; without, pooled medians (then
  ``action_tempo[a] = tempo[a] * speed``).

  *Recognised labels* (a video given with its per-frame confidence, ``(xy, labels, view, confidence)``):
  the recognizer's ends of a run are often a frame or two off, as much as the performers' tempi differ, so
  with ``run_timing="motion"`` an action run is timed by its motion (:meth:`GlobalStyleEstimator.timed_runs`):
  the keypoints' distance from their place in the video's guard (pelvis-relative, torso lengths), weighted
  per action by how far each moves in the population's instances (left and right alike), median-filtered
  over ``motion_filter`` frames; from the run's peak outward to where it falls below ``motion_level`` of
  the peak, interpolated between frames (:func:`motion_width`). An action leaves and returns to the guard
  and its motion scales in time with its duration, so that width, times the population's run length over
  width of the label, is a sub-frame length in frames. ``Step`` and a run whose motion does not fall back
  near it keep the run's length. ``estimate`` then measures lengths on the runs it can trust: a run whose
  mean confidence is below ``min_run_confidence`` (``step_min_run_confidence`` for ``Step`` runs, which
  time the speed; None: the same) is left out (spurious runs: on the validation performers a false
  ``Step`` run was 7-9 frames, a third shorter than a real one, and pulled the speed up), as is one
  longer than ``max_run_factor`` times the population's length of its label (repeats the recognizer joined
  into one run) or shorter than ``min_run_factor`` times it (None: no floor; false and broken runs are
  short), unless every run of the label is out of those bounds (a performer far faster or slower than the
  population: then all its runs count); a label left with no run keeps its most confident one. Runs
  without a confidence (true labels) are always trusted and keep their lengths. ``scripts/validate_tempo_runs.py`` chose the timing,
  its level and filter, the thresholds and the factor on the validation performers' true and estimated 2D.

**Latent coefficients** (:func:`fit_segment`): for one action segment, the first ``n_fit`` spatial
coefficients of the label's :class:`~vidstyle.actionmodel.ActionModel` (the rest at the prior
component's mean; temporal coefficients at the mean, since a segment's own duration already fixes its
time) and a weak-perspective camera (yaw about the vertical, scale, image translation; the elevation is
assumed known, 10 degrees on the demo) minimise

    sum_{frames, keypoints} rho(|x_proj - x_track| / torso)  +  prior_weight * |L_g^-1 (z - mu_g)|^2

with ``rho`` the Cauchy loss of scale ``loss_scale`` torso lengths (missing keypoints drop out) and
``g`` the GMM component of highest responsibility at the start (the ``log_prior`` of the label's GMM
up to that choice). ``scipy.optimize.least_squares`` (trf) on residuals whose data part is
``sign(r) f sqrt(log(1 + (r/f)^2))`` so the prior terms stay quadratic. The yaw starts from the best of
12 yaws for the model's mean pose (closed-form scale and translation). A southpaw's tracks are mirrored
(image x negated, left/right swapped) before fitting an orthodox model, and the model itself is fitted on
orthodox-mirrored clips (:func:`orthodox_clips`).
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, field

import numpy as np
from sklearn.base import BaseEstimator

from ..errors import ParameterError
from . import defaults as D

log = logging.getLogger(__name__)

# keypoint indices (vidstyle.formats.keypoints.KEYPOINTS order)
HEAD, NECK, PELVIS, LSH, RSH, LEL, REL, LWR, RWR, LHIP, RHIP, LKN, RKN, LAN, RAN = range(15)
NON_ACTIONS = ("Guard", "Step", "unlabelled", "other")
#: what decides the lead (:class:`GlobalStyleEstimator`): ``stance`` (the front foot's image side, every
#: frame) before the jab rules, or the jab rules alone (``jab``)
LEAD_CUES = ("stance", "jab")
VIEW_NAMES = ("front", "left", "right")


# ----------------------------------------------------------------------------- small helpers
def label_runs(labels) -> list[tuple[str, int, int]]:
    out, s = [], 0
    labels = list(labels)
    for t in range(1, len(labels) + 1):
        if t == len(labels) or labels[t] != labels[s]:
            out.append((str(labels[s]), s, t))
            s = t
    return out


def _nanmedian(x) -> float:
    x = np.asarray(x, dtype=np.float64)
    x = x[np.isfinite(x)]
    return float(np.median(x)) if x.size else math.nan


def _torso(xy: np.ndarray) -> float:
    t = np.linalg.norm(xy[:, NECK] - xy[:, PELVIS], axis=-1)
    m = _nanmedian(t)
    return m if np.isfinite(m) and m > 1e-9 else math.nan


def mirror_track(xy: np.ndarray) -> np.ndarray:
    """Left/right mirror image of a track (image x negated, left and right keypoints swapped)."""
    from ..recognition.posefeatures import mirror_track as mt

    return mt(xy)


def video_parts(video) -> tuple[np.ndarray, list, str, np.ndarray | None]:
    """``(xy, labels, view, confidence)`` of a video given as ``(xy, labels, view)`` or ``(xy, labels, view,
    confidence)`` (the per-frame confidence of recognised labels, or None)."""
    if len(video) == 3:
        xy, labels, view = video
        return xy, labels, view, None
    xy, labels, view, conf = video
    return xy, labels, view, None if conf is None else np.asarray(conf, dtype=np.float64)


def video_figures(xy: np.ndarray, labels, confidence=None) -> dict:
    """Raw per-video figures of a track (module text): guard height (arm lengths), stance ratio, leg
    extension, the jab-hand scores; ``runs``: ``(label, length, mean
    confidence)`` of every action and ``Step`` run (NaN confidence when ``confidence`` is None)."""
    xy = np.asarray(xy, dtype=np.float64)
    labels = list(labels)[: len(xy)]
    if len(labels) < len(xy):
        labels += ["unlabelled"] * (len(xy) - len(labels))
    lab = np.array(labels)
    torso = _torso(xy)
    leg = np.concatenate([np.linalg.norm(xy[:, h] - xy[:, k], axis=-1) + np.linalg.norm(xy[:, k] - xy[:, a], axis=-1)
                          for h, k, a in ((LHIP, LKN, LAN), (RHIP, RKN, RAN))])
    arm = np.concatenate([np.linalg.norm(xy[:, s] - xy[:, e], axis=-1) + np.linalg.norm(xy[:, e] - xy[:, w], axis=-1)
                          for s, e, w in ((LSH, LEL, LWR), (RSH, REL, RWR))])
    leg_len = float(np.nanpercentile(leg, 90)) if np.isfinite(leg).any() else math.nan
    arm_len = float(np.nanpercentile(arm, 90)) if np.isfinite(arm).any() else math.nan
    g = lab == "Guard"
    out = {"frames": len(xy), "guard_frames": int(g.sum()), "torso": torso}
    if g.sum() and np.isfinite(leg_len) and np.isfinite(arm_len):
        G = xy[g]
        sh_y = 0.5 * (G[:, LSH, 1] + G[:, RSH, 1])
        wr_y = 0.5 * (G[:, LWR, 1] + G[:, RWR, 1])
        out["guard"] = _nanmedian((sh_y - wr_y) / arm_len)
        out["stance"] = _nanmedian(np.linalg.norm(G[:, LAN] - G[:, RAN], axis=-1) / leg_len)
        hip_y = 0.5 * (G[:, LHIP, 1] + G[:, RHIP, 1])
        an_y = 0.5 * (G[:, LAN, 1] + G[:, RAN, 1])
        out["extension"] = _nanmedian((an_y - hip_y) / leg_len)
    jab, side, runs = [], [], []
    conf = None if confidence is None else np.asarray(confidence, dtype=np.float64)
    for label, s, e in label_runs(labels):
        if _timed(label):
            runs.append((label, e - s, _run_confidence(conf, s, e)))
        if label in NON_ACTIONS:
            continue
        if label == "Jab" and np.isfinite(torso):
            seg = xy[s:e]
            d = [np.nanmax(np.linalg.norm(seg[:, w] - seg[0, w], axis=-1)) if np.isfinite(seg[:, w]).all(-1).any()
                 and np.isfinite(seg[0, w]).all() else math.nan for w in (LWR, RWR)]
            if all(np.isfinite(d)) and sum(d) > 0:
                jab.append((d[0] - d[1]) / (d[0] + d[1]))
                w = (LWR, RWR)[int(np.argmax(d))]
                ok = np.isfinite(seg[:, w]).all(-1) & np.isfinite(seg[:, NECK]).all(-1)
                if ok.any():
                    side.append(float(np.mean(seg[ok, w, 0] - seg[ok, NECK, 0]) / torso))
    out["jab_scores"] = jab
    out["jab_sides"] = side
    out["runs"] = runs
    # the stance: per frame with both ankles and hips seen, the image side (x from the hips' midpoint) of the
    # lower ankle, the front foot for a camera that looks down; label-free, so left/right swaps do not matter
    ok = np.isfinite(xy[:, [LAN, RAN, LHIP, RHIP]]).all(axis=(1, 2))
    if np.isfinite(torso) and ok.any():
        X = xy[ok]
        front_x = np.where(X[:, LAN, 1] > X[:, RAN, 1], X[:, LAN, 0], X[:, RAN, 0])
        out["stance_side"] = float(np.mean(np.sign(front_x - 0.5 * (X[:, LHIP, 0] + X[:, RHIP, 0]))))
    out["stance_frames"] = int(ok.sum()) if "stance_side" in out else 0
    return out


def _timed(label: str) -> bool:
    """Whether runs of ``label`` measure a length (the actions and ``Step``)."""
    return label == "Step" or label not in NON_ACTIONS


def _run_confidence(conf, s: int, e: int) -> float:
    return float(np.mean(conf[s:e])) if conf is not None and e <= len(conf) else math.nan


# ----------------------------------------------------------------------------- timing a run from the motion
#: left/right keypoint pairs (shoulders, elbows, wrists, hips, knees, ankles): the timing weights are
#: symmetric, so a southpaw's mirrored action weighs the same keypoints
LR_PAIRS = ((LSH, RSH), (LEL, REL), (LWR, RWR), (LHIP, RHIP), (LKN, RKN), (LAN, RAN))
RUN_TIMINGS = ("labels", "motion")
MOTION_MARGIN = 0.75  # how far (in run lengths) either side of a run its motion may be timed


def guard_displacement(xy: np.ndarray, labels) -> np.ndarray:
    """``(F, 15)``: each keypoint's image distance, in torso lengths, from its place in the video's guard,
    both relative to the pelvis; the guard is the median over the frames labelled ``Guard`` (over all
    frames when none is). NaN where a keypoint is missing."""
    xy = np.asarray(xy, dtype=np.float64)
    torso = _torso(xy)
    if not np.isfinite(torso):
        return np.full(xy.shape[:2], np.nan)
    rel = (xy - xy[:, PELVIS:PELVIS + 1]) / torso
    lab = np.array((list(labels) + ["unlabelled"] * len(xy))[: len(xy)])
    ref = rel[lab == "Guard"]
    if not np.isfinite(ref).any():
        ref = rel
    with np.errstate(all="ignore"):
        guard = np.nanmedian(ref, axis=0) if np.isfinite(ref).any() else np.full(rel.shape[1:], np.nan)
    return np.linalg.norm(rel - guard, axis=-1)


def displacement_signal(disp: np.ndarray, weights: np.ndarray, filter_frames: int = D.STYLE_MOTION_FILTER) -> np.ndarray:
    """The weighted mean over keypoints of :func:`guard_displacement`'s ``disp`` per frame (NaN where a
    weighted keypoint is missing), median-filtered over ``filter_frames`` frames (a median of 3 removes a
    one-frame spike of the pose stage and leaves a monotone rise or fall unchanged)."""
    from scipy.ndimage import median_filter

    w = np.asarray(weights, dtype=np.float64)
    used = w > 0
    ok = np.isfinite(disp[:, used]).all(axis=1)
    d = np.where(ok, np.nan_to_num(disp[:, used]) @ w[used] / max(float(w[used].sum()), 1e-12), 0.0)
    if filter_frames > 1:
        d = median_filter(d, size=int(filter_frames), mode="nearest")
    d[~ok] = np.nan
    return d


def _crossing(d: np.ndarray, i: int, step: int, level: float, lo: int, hi: int) -> float:
    j = i
    while lo <= j + step < hi:
        if not np.isfinite(d[j + step]):
            return math.nan
        if d[j + step] < level:
            return j + step * (d[j] - level) / (d[j] - d[j + step])
        j += step
    return math.nan


def motion_width(d: np.ndarray, s: int, e: int, level: float = D.STYLE_MOTION_LEVEL,
                 margin: float = MOTION_MARGIN) -> float:
    """The sub-frame duration of the motion of the run ``[s, e)`` of the displacement signal ``d``: from
    the run's peak outward to where ``d`` first falls below ``level`` times the peak on each side,
    linearly interpolated between frames. NaN when a side does not fall below it within ``margin`` run
    lengths of the run or meets a missing frame. An action starts and ends in the guard and its motion
    scales in time with its duration, so the width is proportional to the duration whatever the run's
    recognised ends."""
    seg = d[s:e]
    if e <= s or not np.isfinite(seg).any():
        return math.nan
    pk = s + int(np.nanargmax(seg))
    if d[pk] <= 0:
        return math.nan
    pad = math.ceil(margin * (e - s))
    lo, hi = max(0, s - pad), min(len(d), e + pad)
    thr = level * d[pk]
    left, right = _crossing(d, pk, -1, thr, lo, hi), _crossing(d, pk, +1, thr, lo, hi)
    return right - left if np.isfinite(left) and np.isfinite(right) else math.nan


@dataclass
class GlobalStyle:
    """A performer's estimated global style (module text)."""

    lead: str
    lead_score: float
    guard_height: float
    stance_width: float
    crouch: float
    tempo: dict[str, float] = field(default_factory=dict)  # duration factor tempo/speed per action
    relative_tempo: dict[str, float] = field(default_factory=dict)
    n_videos: int = 0
    n_jabs: int = 0
    speed: float = math.nan  # the population's step length over the performer's (nan: no steps seen)
    action_tempo: dict[str, float] = field(default_factory=dict)  # the per-action tempo, speed removed

    def to_dict(self) -> dict:
        f = lambda x: None if x is None or not np.isfinite(x) else round(float(x), 6)
        return {"lead": self.lead, "lead_score": f(self.lead_score), "guard_height": f(self.guard_height),
                "stance_width": f(self.stance_width), "crouch": f(self.crouch),
                "tempo": {k: f(v) for k, v in self.tempo.items()},
                "relative_tempo": {k: f(v) for k, v in self.relative_tempo.items()},
                "n_videos": int(self.n_videos), "n_jabs": int(self.n_jabs), "speed": f(self.speed),
                "action_tempo": {k: f(v) for k, v in self.action_tempo.items()}}

    @classmethod
    def from_dict(cls, d: dict) -> GlobalStyle:
        n = lambda x: math.nan if x is None else float(x)
        return cls(str(d["lead"]), n(d.get("lead_score")), n(d.get("guard_height")), n(d.get("stance_width")),
                   n(d.get("crouch")), {k: n(v) for k, v in d.get("tempo", {}).items()},
                   {k: n(v) for k, v in d.get("relative_tempo", {}).items()}, int(d.get("n_videos", 0)),
                   int(d.get("n_jabs", 0)), n(d.get("speed")), {k: n(v) for k, v in (d.get("action_tempo") or {}).items()})


class GlobalStyleEstimator(BaseEstimator):
    """Population figures per view from training performers (``fit``), a performer's style (``estimate``).

    ``fit(videos)`` / ``estimate(videos)``: ``videos`` a list of ``(xy (F, 15, 2), labels, view)``. Learned:
    ``population_`` (view -> mean guard / stance / extension of the training videos), ``durations_``
    (action -> median segment length, frames)."""

    def __init__(self, lead_threshold: float = 0.0, min_front_jabs: int = 5, lead_cue: str = D.STYLE_LEAD_CUE,
                 min_stance_frames: int = D.STYLE_MIN_STANCE_FRAMES,
                 min_run_confidence: float = D.STYLE_MIN_RUN_CONFIDENCE,
                 step_min_run_confidence: float | None = D.STYLE_STEP_MIN_RUN_CONFIDENCE,
                 max_run_factor: float | None = D.STYLE_MAX_RUN_FACTOR,
                 min_run_factor: float | None = D.STYLE_MIN_RUN_FACTOR, run_timing: str = D.STYLE_RUN_TIMING,
                 motion_level: float = D.STYLE_MOTION_LEVEL, motion_filter: int = D.STYLE_MOTION_FILTER):
        self.lead_threshold = lead_threshold
        self.min_front_jabs = min_front_jabs
        self.lead_cue = lead_cue
        self.min_stance_frames = min_stance_frames
        self.min_run_confidence = min_run_confidence
        self.step_min_run_confidence = step_min_run_confidence
        self.max_run_factor = max_run_factor
        self.min_run_factor = min_run_factor
        self.run_timing = run_timing
        self.motion_level = motion_level
        self.motion_filter = motion_filter

    @classmethod
    def from_model(cls, model, video_fps: float, **kw) -> GlobalStyleEstimator:
        """An estimator without a population: guard / stance / crouch are the raw figures (stance the ankle
        ratio itself), tempo relative to the action model's mean instance length (``mean_frames`` at the
        model's rate, converted to ``video_fps``). Recognised runs are timed by their motion against the
        model's mean instance of each action (:func:`model_videos`) in place of a population's instances."""
        est = cls(**kw)
        est.population_ = {}
        est.orthodox_side_ = 0.0  # unknown without a population: the labelled jab hand decides
        est.stance_side_ = {}
        est.durations_ = {k: lm.mean_frames * float(video_fps) / model.fps_ for k, lm in model.models_.items()}
        est.step_frames_ = math.nan  # no population: the speed is unknown
        est.action_step_ratio_ = {}
        est._fit_motion_timing(model_videos(model, video_fps) if est.run_timing == "motion" else [])
        return est

    def fit(self, videos, y=None, groups=None) -> GlobalStyleEstimator:
        """``groups``: the performer of each video (scikit-learn's ``groups``). With them the tempo reference
        of each action is the mean over performers of their own action-to-step length ratio, so a
        population's mix of speeds does not shift it; without them, pooled medians. The population is
        measured on its labels as given (meant for true labels: a video's confidence, if any, is not used)."""
        if self.lead_cue not in LEAD_CUES:
            raise ParameterError("lead_cue", f"must be one of {', '.join(LEAD_CUES)}, got {self.lead_cue!r}")
        per_view: dict[str, dict[str, list[float]]] = {}
        dur: dict[str, list[int]] = {}
        steps: list[int] = []
        front = []
        stance: dict[str, list[float]] = {}
        videos = list(videos)
        if groups is not None and len(groups) != len(videos):
            raise ParameterError("groups", f"one performer per video: {len(groups)} groups for {len(videos)} videos")
        by_performer: dict = {}
        for i, video in enumerate(videos):
            xy, labels, view, _conf = video_parts(video)
            f = video_figures(xy, labels)
            lengths: dict[str, list[int]] = {}  # the population's labels are all trusted (true labels)
            for label, n, _c in f["runs"]:
                lengths.setdefault(label, []).append(n)
            video_steps = lengths.pop("Step", [])
            steps += video_steps
            if groups is not None:
                mine = by_performer.setdefault(groups[i], ({}, []))
                mine[1].extend(video_steps)
                for a, ds in lengths.items():
                    mine[0].setdefault(a, []).extend(ds)
            if str(view) == "front":
                front.append(f)
            if f["jab_scores"] and f["stance_frames"]:  # the labelled jab hand's lead times the stance side
                stance.setdefault(str(view), []).append(float(np.mean(f["jab_scores"])) * f["stance_side"])
            pv = per_view.setdefault(str(view), {"guard": [], "stance": [], "extension": []})
            for k in pv:
                if k in f and np.isfinite(f[k]):
                    pv[k].append(f[k])
            for a, ds in lengths.items():
                dur.setdefault(a, []).extend(ds)
        if not per_view:
            raise ParameterError("videos", "no training video")
        self.population_ = {v: {k: (float(np.mean(x)) if x else math.nan) for k, x in d.items()} for v, d in per_view.items()}
        # the image side of an orthodox jab in front views, from the labelled jab hand of the population
        prod = [np.mean(f["jab_scores"]) * np.mean(f["jab_sides"]) for f in front if f["jab_scores"] and f["jab_sides"]]
        self.orthodox_side_ = float(np.sign(np.sum(prod))) if prod else 0.0
        # per view, the image side of an orthodox fighter's front foot, learned the same way
        self.stance_side_ = {v: float(np.sign(np.sum(x))) for v, x in stance.items() if np.sum(x) != 0}
        self.durations_ = {a: float(np.median(d)) for a, d in dur.items() if d}
        self.step_frames_ = float(np.median(steps)) if steps else math.nan
        # the per-action tempo reference: action length over step length
        self.action_step_ratio_ = {a: d / self.step_frames_ for a, d in self.durations_.items()} if steps else {}
        if by_performer:
            own = [(d, float(np.median(st))) for d, st in by_performer.values() if st]
            if own:
                self.step_frames_ = float(np.mean([st for _, st in own]))
                self.action_step_ratio_ = {a: float(np.mean(r)) for a in self.durations_
                                           if (r := [float(np.median(d[a])) / st for d, st in own if d.get(a)])}
        self._fit_motion_timing(videos)
        return self

    def _check_timing(self) -> None:
        if self.run_timing not in RUN_TIMINGS:
            raise ParameterError("run_timing", f"must be one of {', '.join(RUN_TIMINGS)}, got {self.run_timing!r}")
        if not 0.0 < self.motion_level < 1.0:
            raise ParameterError("motion_level", f"must be in (0, 1), got {self.motion_level}")
        if int(self.motion_filter) != self.motion_filter or self.motion_filter < 1:
            raise ParameterError("motion_filter", f"must be a whole number of frames >= 1, got {self.motion_filter}")

    def _fit_motion_timing(self, videos) -> None:
        """``motion_weights_`` (action -> per-keypoint weight: the population's mean peak displacement from
        guard in its runs, left and right averaged) and ``motion_ratio_`` (action -> the population's
        median run length over motion width, which turns a width into frames)."""
        self._check_timing()
        self.motion_weights_, self.motion_ratio_ = {}, {}
        if self.run_timing != "motion":
            return
        parts = []
        peaks: dict[str, list[np.ndarray]] = {}
        for video in videos:
            xy, labels, _view, _conf = video_parts(video)
            labels = list(labels)[: len(xy)]
            Dk = guard_displacement(xy, labels)
            parts.append((Dk, labels))
            for label, s, e in label_runs(labels):
                if label not in NON_ACTIONS and np.isfinite(Dk[s:e]).any():
                    with np.errstate(all="ignore"):
                        peaks.setdefault(label, []).append(np.nanmax(Dk[s:e], axis=0))
        for label, pk in peaks.items():
            with np.errstate(all="ignore"):
                w = np.nan_to_num(np.nanmean(np.stack(pk), axis=0))
            for a, b in LR_PAIRS:
                w[a] = w[b] = 0.5 * (w[a] + w[b])
            if w.sum() > 0:
                self.motion_weights_[label] = w
        ratios: dict[str, list[float]] = {}
        for Dk, labels in parts:
            signals: dict[str, np.ndarray] = {}
            for label, s, e in label_runs(labels):
                if label in self.motion_weights_:
                    m = self._run_width(Dk, signals, label, s, e)
                    if np.isfinite(m):
                        ratios.setdefault(label, []).append((e - s) / m)
        self.motion_ratio_ = {a: float(np.median(r)) for a, r in ratios.items()}

    def _run_width(self, disp: np.ndarray, signals: dict, label: str, s: int, e: int) -> float:
        """:func:`motion_width` of the run ``[s, e)`` of ``label`` (NaN when not measurable or not positive);
        ``signals`` caches the video's displacement signal per label."""
        if label not in signals:
            signals[label] = displacement_signal(disp, self.motion_weights_[label], int(self.motion_filter))
        m = motion_width(signals[label], s, e, self.motion_level)
        return m if m > 0 else math.nan

    def timed_runs(self, video) -> list[tuple[str, float, float]]:
        """``(label, length, mean confidence)`` of every action and ``Step`` run of ``video`` (module text).
        With ``run_timing="motion"``, a run of recognised labels (the video has a confidence) of an action
        the population timed is measured from the motion (:func:`motion_width` times ``motion_ratio_``, a
        sub-frame length in frames) where the width is measurable; the recognizer's ends of a run are
        often a frame or two off, as much as the performers' tempi differ. True labels (no confidence),
        ``Step`` and unmeasurable runs keep the run's length."""
        self._check_timing()
        xy, labels, _view, conf = video_parts(video)
        labels = list(labels)[: len(xy)]
        ratio = getattr(self, "motion_ratio_", {}) if self.run_timing == "motion" and conf is not None else {}
        Dk = guard_displacement(xy, labels) if ratio else None
        signals: dict[str, np.ndarray] = {}
        out = []
        for label, s, e in label_runs(labels):
            if not _timed(label):
                continue
            n: float = e - s
            if label in ratio and np.isfinite(m := self._run_width(Dk, signals, label, s, e)):
                n = ratio[label] * m
            out.append((label, n, _run_confidence(conf, s, e)))
        return out

    def trusted_lengths(self, runs) -> dict[str, list[float]]:
        """Label -> the lengths of ``runs`` (``(label, length, mean confidence)``, pooled over a performer's
        videos) that measure it (module text: recognised labels)."""
        if not 0.0 <= self.min_run_confidence <= 1.0:
            raise ParameterError("min_run_confidence", f"must be in [0, 1], got {self.min_run_confidence}")
        step_tau = self.step_min_run_confidence
        if step_tau is None:
            step_tau = self.min_run_confidence
        elif not 0.0 <= step_tau <= 1.0:
            raise ParameterError("step_min_run_confidence",
                                 f"must be in [0, 1] (or None: min_run_confidence), got {step_tau}")
        cap = self.max_run_factor
        if cap is not None and not cap > 1.0:
            raise ParameterError("max_run_factor", f"must be > 1 (or None: no cap), got {cap}")
        floor = self.min_run_factor
        if floor is not None and not 0.0 < floor < 1.0:
            raise ParameterError("min_run_factor", f"must be in (0, 1) (or None: no floor), got {floor}")
        def ref(label: str) -> float:  # the population's length of the label
            return getattr(self, "step_frames_", math.nan) if label == "Step" else getattr(self, "durations_", {}).get(label, math.nan)

        by_label: dict[str, list[tuple[float, float, bool]]] = {}
        for label, n, c in runs:
            # a recognised run much longer than the population's (repeats joined into one) or much shorter
            # (a fragment or a false run) is out of bounds
            out_of_bounds = np.isfinite(c) and ((cap is not None and n > cap * ref(label))
                                                or (floor is not None and n < floor * ref(label)))
            by_label.setdefault(label, []).append((c, n, not out_of_bounds))
        out = {}
        for label, rr in by_label.items():
            # the bounds remove a label's outliers, not the label: one whose every run is out of them (a
            # performer far faster or slower than the population) keeps them all
            rr = [(c, n) for c, n, ok in rr if ok] or [(c, n) for c, n, _ in rr]
            tau = step_tau if label == "Step" else self.min_run_confidence
            keep = [n for c, n in rr if not np.isfinite(c) or c >= tau]
            out[label] = keep or [max(rr)[1]]
        return out

    def estimate(self, videos) -> GlobalStyle:
        if not hasattr(self, "population_"):
            raise ParameterError("estimator", "not fitted")
        g, s, c, jab, sides, runs = [], [], [], [], [], []
        stance_sum, stance_n = 0.0, 0
        stance_side = getattr(self, "stance_side_", {})
        for video in videos:
            xy, labels, view, conf = video_parts(video)
            f = video_figures(xy, labels, conf)
            if str(view) == "front":
                sides += f["jab_sides"]
            if f["stance_frames"] and stance_side.get(str(view)):
                stance_sum += f["stance_frames"] * f["stance_side"] * stance_side[str(view)]
                stance_n += f["stance_frames"]
            pop = self.population_.get(str(view))
            if pop is None and self.population_:  # a view the population lacks: pool over its views
                pop = {k: float(np.nanmean([p[k] for p in self.population_.values()])) for k in ("guard", "stance", "extension")}
            elif pop is None:  # no population: raw figures
                pop = {"guard": 0.0, "stance": 1.0, "extension": 0.0}
            if "guard" in f:
                g.append(f["guard"] - pop["guard"])
                s.append(f["stance"] / pop["stance"])
                c.append(pop["extension"] - f["extension"])
            jab += f["jab_scores"]
            runs += self.timed_runs(video)
        dur = self.trusted_lengths(runs)
        steps = dur.pop("Step", [])
        side = getattr(self, "orthodox_side_", 0.0)
        if self.lead_cue == "stance" and stance_n >= self.min_stance_frames:
            # label-free: the frame-weighted share of frames whose front foot is on the orthodox side, in [-1, 1]
            score = stance_sum / stance_n
        elif side != 0.0 and len(sides) >= self.min_front_jabs:
            # label-free: the share of front-view jabs thrown from the orthodox side of the neck, as a score in [-1, 1]
            score = float(2 * np.mean(np.sign(sides) == side) - 1)
            jab = sides
        else:
            score = float(np.mean(jab)) if jab else 0.0
        tempo = {a: float(np.median(d)) / self.durations_[a] for a, d in dur.items() if a in self.durations_ and d}
        mt = float(np.mean(list(tempo.values()))) if tempo else math.nan
        pop_step = float(getattr(self, "step_frames_", math.nan))
        step = float(np.median(steps)) if steps else math.nan
        speed = pop_step / step if np.isfinite(pop_step) else math.nan
        ratio = getattr(self, "action_step_ratio_", {})
        action_tempo = ({a: float(np.median(d)) / step / ratio[a] for a, d in dur.items() if a in ratio and d}
                        if np.isfinite(speed) else {})
        return GlobalStyle("orthodox" if score >= self.lead_threshold else "southpaw", score, _nanmedian(g),
                           _nanmedian(s), _nanmedian(c), tempo, {a: v / mt for a, v in tempo.items()},
                           len(videos), len(jab), speed, action_tempo)


def model_videos(model, video_fps: float, yaws_deg=(0.0, 45.0, 90.0, -45.0, -90.0),
                 elevation_deg: float = D.STYLE_ELEVATION_DEG) -> list:
    """``(xy, labels, view)`` videos of each label's mean instance (the GMM's heaviest component, decoded at
    its mean length in frames of ``video_fps``) seen from ``yaws_deg`` (weak perspective at
    ``elevation_deg``), with the instance's first and last poses held as guard for as long again before
    and after it: a stand-in population for timing runs from the motion (:meth:`GlobalStyleEstimator.from_model`)."""
    from ..mocap.keypoints import keypoint_positions

    out = []
    for label, lm in model.models_.items():
        n = max(round(lm.mean_frames * float(video_fps) / model.fps_), 2)
        z = np.asarray(lm.gmm_means[int(np.argmax(lm.gmm_weights))], dtype=np.float64)
        P3 = keypoint_positions(model.decode(z, label, n_frames=n))
        P3 = np.concatenate([np.repeat(P3[:1], n, axis=0), P3, np.repeat(P3[-1:], n, axis=0)])
        labels = ["Guard"] * n + [label] * n + ["Guard"] * n
        for yaw in yaws_deg:
            xy = project(P3, math.radians(yaw), 1.0, np.zeros(2), math.radians(elevation_deg))
            out.append((xy, labels, "front"))
    return out


# ----------------------------------------------------------------------------- orthodox clips for the model
def orthodox_clips(clips, southpaw: set[str]):
    """Clips with those of ``southpaw`` performers (name prefix ``pXX_``) mirrored to orthodox."""
    from ..motiongraph.graph import Clip

    out = []
    for c in clips:
        perf = c.name.split("_")[0]
        out.append(Clip(c.name, c.motion.mirror(), c.labels, c.path, c.sha256) if perf in southpaw else c)
    return out


# ----------------------------------------------------------------------------- projection and fitting
def _rot(yaw: float, elevation: float) -> np.ndarray:
    """(2, 3) weak-perspective projection rows: yaw about +Y (the performer turned by ``yaw``), a camera
    looking down by ``elevation``; image x = +X of a performer facing the camera, image y down."""
    cy, sy = math.cos(yaw), math.sin(yaw)
    Ry = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    ce, se = math.cos(elevation), math.sin(elevation)
    # camera: x right, y down; tilt about x
    P = np.array([[1.0, 0, 0], [0, -ce, se]])
    return P @ Ry


def project(points: np.ndarray, yaw: float, scale: float, shift: np.ndarray, elevation: float) -> np.ndarray:
    """(F, K, 2) weak-perspective image of (F, K, 3) points."""
    return scale * points @ _rot(yaw, elevation).T + shift


class SegmentFitter:
    """Fits coefficients of one label of a fitted :class:`~vidstyle.actionmodel.ActionModel` to 2D tracks
    (module text). ``n_fit`` spatial coefficients are free; ``prior_weight`` scales the GMM prior;
    ``loss_scale`` is the Cauchy scale in torso lengths; ``elevation_deg`` the assumed camera elevation."""

    def __init__(self, model, label: str, n_fit: int = D.STYLE_N_FIT, prior_weight: float = D.STYLE_PRIOR_WEIGHT,
                 loss_scale: float = D.STYLE_LOSS_SCALE, elevation_deg: float = D.STYLE_ELEVATION_DEG,
                 max_nfev: int = D.STYLE_MAX_NFEV):
        self.model = model
        self.label = label
        lm = model._model(label)
        self.lm = lm
        self.n_fit = int(min(n_fit, lm.n_spatial))
        self.prior_weight = float(prior_weight)
        self.loss_scale = float(loss_scale)
        self.elevation = math.radians(float(elevation_deg))
        self.max_nfev = int(max_nfev)
        if self.prior_weight < 0 or self.loss_scale <= 0:
            raise ParameterError("prior_weight/loss_scale", "prior_weight >= 0 and loss_scale > 0 required")

    # the full coefficient vector of the free ones, the others at the component's mean
    def full(self, zf: np.ndarray, g: int | None = None) -> np.ndarray:
        lm = self.lm
        z = np.array(lm.gmm_means[self._g if g is None else g], dtype=np.float64)
        z[: self.n_fit] = zf
        return z

    def keypoints(self, z: np.ndarray, n_frames: int) -> np.ndarray:
        """(n_frames, 15, 3) keypoints of the decoded coefficients, time-normalised to ``n_frames``."""
        from ..mocap.keypoints import keypoint_positions

        return keypoint_positions(self.model.decode(z, self.label, n_frames=n_frames))

    def initial_camera(self, P3: np.ndarray, xy: np.ndarray) -> tuple[float, float, np.ndarray]:
        best = None
        m = np.isfinite(xy).all(-1)
        for yaw in np.linspace(-math.pi, math.pi, 12, endpoint=False):
            q = P3 @ _rot(yaw, self.elevation).T
            qc = q[m] - q[m].mean(0)
            xc = xy[m] - xy[m].mean(0)
            s = max(float((qc * xc).sum() / max((qc * qc).sum(), 1e-12)), 1e-6)
            t = xy[m].mean(0) - s * q[m].mean(0)
            r = float(np.sum((s * q[m] + t - xy[m]) ** 2))
            if best is None or r < best[0]:
                best = (r, yaw, s, t)
        return best[1], best[2], best[3]

    def linearisation(self, zf: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray]:
        """Keypoints (n, 15, 3) of the free coefficients ``zf`` and their Jacobian (n*15*3, n_fit) by forward
        differences (step 0.05 whitened units); cached per (n, zf)."""
        from ..mocap import Motion
        from ..mocap.keypoints import keypoint_positions

        key = (int(n), tuple(np.round(zf, 9)))
        cache = self.__dict__.setdefault("_lin", {})
        if key not in cache:
            h = 0.05
            zs = np.repeat(zf[None], self.n_fit + 1, axis=0)
            zs[1:][np.arange(self.n_fit), np.arange(self.n_fit)] += h
            # the n_fit + 1 decodes' keypoints in one forward-kinematics call (per call, its overhead dominated)
            ms = [self.model.decode(self.full(z), self.label, n_frames=n) for z in zs]
            both = Motion(ms[0].skeleton, np.concatenate([m.rotations for m in ms]), None, ms[0].fps,
                          root_positions=np.concatenate([m.root_positions for m in ms]))
            K = keypoint_positions(both).reshape(self.n_fit + 1, n, -1, 3)
            K0 = K[0]
            J = np.empty((K0.size, self.n_fit))
            for i in range(self.n_fit):
                J[:, i] = (K[i + 1] - K0).ravel() / h
            if len(cache) > 64:
                cache.clear()
            cache[key] = (K0, J)
        return cache[key]

    def fit(self, xy: np.ndarray, z0: np.ndarray | None = None, rounds: int = D.STYLE_ROUNDS) -> dict:
        """Fit one segment's track ``xy`` (n, 15, 2; NaN missing). Returns ``z`` (full coefficients), the
        camera (yaw, scale, shift), the robust data cost per visible keypoint, and ``n_visible``.

        The decoded keypoints are linearised in the free coefficients (:meth:`linearisation`) around the
        start and, for each further round, around the previous solution (Gauss-Newton on the body model;
        the camera stays exact)."""
        from scipy.optimize import least_squares

        xy = np.asarray(xy, dtype=np.float64)
        n = len(xy)
        torso = _torso(xy)
        vis = np.isfinite(xy).all(-1)
        if n < 2 or not np.isfinite(torso) or vis.sum() < 6:
            raise ParameterError("track", f"segment of {n} frames with {int(vis.sum())} visible keypoints: too little to fit")
        lm = self.lm
        if z0 is None:
            self._g = int(np.argmax(lm.gmm_weights))
        else:
            self._g = int(np.argmax([self._comp_logpdf(z0, g) for g in range(lm.n_components)]))
        L = np.linalg.cholesky(lm.gmm_covariances[self._g])
        Linv = np.linalg.inv(L)
        mu = lm.gmm_means[self._g]
        zf = (mu if z0 is None else z0)[: self.n_fit].copy()
        K0, _ = self.linearisation(zf, n)
        yaw, s, t = self.initial_camera(K0, xy)
        target = np.where(vis[..., None], xy, 0.0)
        f = self.loss_scale
        nf = self.n_fit
        p = np.concatenate([zf, [yaw, math.log(s)], t])
        nfev = 0
        for _ in range(max(1, int(rounds))):
            zc = p[:nf].copy()
            K0, J = self.linearisation(zc, n)
            resid, jac = self._residuals(K0, J, zc, target, vis, torso, Linv, mu)
            res = least_squares(resid, p, jac=jac, method="trf", max_nfev=self.max_nfev)
            p = res.x
            nfev += int(res.nfev)
        z = self.full(p[:nf])
        # the exact data cost at the solution
        P3 = self.keypoints(z, n)
        pr = project(P3, p[nf], math.exp(p[nf + 1]), p[nf + 2:nf + 4], self.elevation)
        r = ((pr - target) / torso)[vis].ravel()
        r = f * np.sqrt(np.log1p((r / f) ** 2))
        nv = int(vis.sum())
        return {"z": z, "yaw": float(p[nf]), "scale": float(math.exp(p[nf + 1])), "shift": p[nf + 2:nf + 4].copy(),
                "cost": float(np.sum(r ** 2) / max(nv, 1)), "n_visible": nv, "component": self._g, "nfev": nfev}

    def _residuals(self, K0: np.ndarray, J: np.ndarray, zc: np.ndarray, target: np.ndarray, vis: np.ndarray,
                   torso: float, Linv: np.ndarray, mu: np.ndarray):
        """The robust residuals of one Gauss-Newton round of :meth:`fit` and their exact Jacobian, as
        functions of ``q`` = (free coefficients, yaw, log scale, shift x, y): the data part, keypoints
        ``K0 + J (z - zc)`` projected (:func:`project`) against ``target`` in torso lengths through the
        Cauchy-like ``rho(r) = sign(r) f sqrt(log1p((r / f)^2))``; the prior part ``w Linv (z - mu)``."""
        nf = self.n_fit
        f = self.loss_scale
        w = math.sqrt(self.prior_weight)
        shape = K0.shape
        Jk = J.reshape(*shape, nf)  # (n, 15, 3, nf)
        prior_jac = w * Linv[:, :nf]
        n_data = 2 * int(vis.sum())

        def data(q):
            P3 = K0 + (J @ (q[:nf] - zc)).reshape(shape)
            pr = project(P3, q[nf], math.exp(q[nf + 1]), q[nf + 2:nf + 4], self.elevation)
            return P3, pr, ((pr - target) / torso)[vis].ravel()

        def resid(q):
            _P3, _pr, r = data(q)
            r = np.sign(r) * f * np.sqrt(np.log1p((r / f) ** 2))
            return np.concatenate([r, w * (Linv @ (self.full(q[:nf]) - mu))])

        def jac(q):
            P3, pr, r = data(q)
            yaw, s = q[nf], math.exp(q[nf + 1])
            R = _rot(yaw, self.elevation)
            cy, sy = math.cos(yaw), math.sin(yaw)
            ce, se = math.cos(self.elevation), math.sin(self.elevation)
            dR = np.array([[1.0, 0, 0], [0, -ce, se]]) @ np.array([[-sy, 0, cy], [0, 0, 0], [-cy, 0, -sy]])
            D = np.empty((n_data, nf + 4))
            D[:, :nf] = (s / torso) * np.einsum("nkcf,dc->nkdf", Jk, R)[vis].reshape(n_data, nf)
            D[:, nf] = ((s / torso) * P3 @ dR.T)[vis].ravel()
            D[:, nf + 1] = ((pr - q[nf + 2:nf + 4]) / torso)[vis].ravel()
            D[:, nf + 2:] = 0.0
            D[0::2, nf + 2] = 1.0 / torso
            D[1::2, nf + 3] = 1.0 / torso
            u = np.abs(r) / f
            L = np.log1p(u * u)
            small = u < 1e-6
            drho = np.where(small, 1.0, u / ((1.0 + u * u) * np.sqrt(np.where(small, 1.0, L))))
            out = np.zeros((n_data + len(mu), nf + 4))
            out[:n_data] = drho[:, None] * D
            out[n_data:, :nf] = prior_jac
            return out

        return resid, jac

    def _comp_logpdf(self, z, g) -> float:
        lm = self.lm
        L = np.linalg.cholesky(lm.gmm_covariances[g])
        y = np.linalg.solve(L, z - lm.gmm_means[g])
        return float(np.log(lm.gmm_weights[g]) - 0.5 * y @ y - np.log(np.diag(L)).sum())


def fit_segment(model, label: str, xy: np.ndarray, **kw) -> dict:
    """:meth:`SegmentFitter.fit` of one segment with the defaults (or ``kw``)."""
    return SegmentFitter(model, label, **kw).fit(xy)


def noisy_track(xy: np.ndarray, rng: np.random.Generator, sigma: float = 0.05, outliers: float = 0.05) -> np.ndarray:
    """A noisy copy of a track: Gaussian noise of ``sigma`` torso lengths on every coordinate, and a share
    ``outliers`` of keypoints moved by a uniform offset of up to 2 torso lengths in x and in y."""
    xy = np.array(xy, dtype=np.float64)
    torso = _torso(xy)
    out = xy + rng.normal(0.0, sigma * torso, xy.shape)
    m = rng.random(xy.shape[:2]) < outliers
    out[m] += rng.uniform(-2 * torso, 2 * torso, (int(m.sum()), 2))
    return out


@dataclass
class ActionStyle:
    """The action-level part of a learned style: global style and per label the mean fitted coefficients
    (in the orthodox frame of the model), their count and spread."""

    global_style: GlobalStyle
    coefficients: dict[str, np.ndarray] = field(default_factory=dict)
    counts: dict[str, int] = field(default_factory=dict)
    spread: dict[str, np.ndarray] = field(default_factory=dict)  # per-coefficient sd of the fitted segments
    model: str = ""  # the action model file it refers to
    params: dict = field(default_factory=dict)

    def to_record(self):
        from ..formats.style import ActionStyleRecord

        g = self.global_style.to_dict()
        return ActionStyleRecord(self.model, dict(self.params), g,
                                 {k: (np.asarray(self.coefficients[k], dtype=np.float64),
                                      np.asarray(self.spread.get(k, np.zeros_like(self.coefficients[k])), dtype=np.float64),
                                      int(self.counts.get(k, 1))) for k in self.coefficients})

    @classmethod
    def from_record(cls, rec) -> ActionStyle:
        gs = GlobalStyle.from_dict(rec.global_style)
        return cls(gs, {k: v[0] for k, v in rec.labels.items()}, {k: v[2] for k, v in rec.labels.items()},
                   {k: v[1] for k, v in rec.labels.items()}, rec.model, dict(rec.params))

    def check_model(self, model, path=None) -> None:
        """Raise ``FormatError`` (naming ``path``) unless every label's coefficients fit ``model``."""
        from ..errors import FormatError

        for k, z in self.coefficients.items():
            if k not in model.models_:
                raise FormatError(path, f"action_style.labels.{k}", "the action model has no such label")
            if len(z) != model.models_[k].n_coefficients:
                raise FormatError(path, f"action_style.labels.{k}.coefficients",
                                  f"{len(z)} coefficients, the action model has {model.models_[k].n_coefficients}")

    def realise(self, model, label: str, n_frames: int | None = None, sample: bool = False, random_state=None,
                pin: bool = False):
        """The performer's way of doing ``label``: the decoded mean coefficients (``sample``: a draw from a
        Gaussian of the fitted segments' spread around it), planted feet held (``pin``, in the orthodox
        frame), mirrored back for a southpaw."""
        z = np.asarray(self.coefficients[label], dtype=np.float64)
        if sample:
            rng = np.random.default_rng(random_state)
            z = z + rng.standard_normal(len(z)) * np.asarray(self.spread.get(label, np.zeros_like(z)))
        m = model.decode(z, label, n_frames=n_frames, pin=pin)
        return m.mirror() if self.global_style.lead == "southpaw" else m


def plan_action_style(model, estimator: GlobalStyleEstimator, videos, max_segments: int = D.STYLE_MAX_SEGMENTS,
                      random_state: int = 0) -> tuple[GlobalStyle, dict[str, list[np.ndarray]]]:
    """The first half of :func:`fit_action_style`: the global style of ``videos`` and, per modelled label,
    the segments to fit (a southpaw's tracks mirrored; up to ``max_segments``, a seeded even spread)."""
    gs = estimator.estimate(videos)
    segs: dict[str, list[np.ndarray]] = {}
    for video in videos:
        xy, labels, _view, _conf = video_parts(video)
        xy = np.asarray(xy, dtype=np.float64)
        if gs.lead == "southpaw":
            xy = mirror_track(xy)
        for label, s, e in label_runs(list(labels)[: len(xy)]):
            if label in model.models_ and e - s >= 3:
                segs.setdefault(label, []).append(xy[s:e])
    rng = np.random.default_rng(random_state)
    chosen = {}
    for label, lst in sorted(segs.items()):
        if len(lst) > max_segments:
            idx = sorted(rng.choice(len(lst), max_segments, replace=False))
            lst = [lst[i] for i in idx]
        chosen[label] = lst
    return gs, chosen


def fit_label_segments(model, label: str, segments, params: dict | None = None) -> tuple[np.ndarray, np.ndarray, int] | None:
    """The second half of :func:`fit_action_style` for one label: every segment fitted with one
    :class:`SegmentFitter`; (mean, per-coefficient sd, count) of the fitted coefficients, or None when no
    segment could be fitted."""
    fitter = SegmentFitter(model, label, **dict(params or {}))
    Z = []
    for xy in segments:
        try:
            Z.append(fitter.fit(xy)["z"])
        except ParameterError as e:
            log.info("style fit: %s segment skipped: %s", label, e)
    if not Z:
        return None
    Z = np.array(Z)
    return Z.mean(0), Z.std(0), len(Z)


def fit_action_style(model, estimator: GlobalStyleEstimator, videos, params: dict | None = None,
                     max_segments: int = D.STYLE_MAX_SEGMENTS, random_state: int = 0) -> ActionStyle:
    """A performer's :class:`ActionStyle` from ``videos`` (``(xy, labels, view)``): global style, then per
    modelled label up to ``max_segments`` segments (a seeded even spread over all) fitted with
    :class:`SegmentFitter` after mirroring a southpaw's tracks (:func:`plan_action_style`, then
    :func:`fit_label_segments` per label: the labels are independent, so they may run in parallel)."""
    params = dict(params or {})
    gs, segs = plan_action_style(model, estimator, videos, max_segments, random_state)
    fits = {label: fit_label_segments(model, label, lst, params) for label, lst in segs.items()}
    return assemble_action_style(gs, fits, params)


def assemble_action_style(gs: GlobalStyle, fits: dict, params: dict | None = None) -> ActionStyle:
    """:class:`ActionStyle` of a global style and ``label -> fit_label_segments(...)`` results."""
    coeffs, counts, spread = {}, {}, {}
    for label, fit in sorted(fits.items()):
        if fit is not None:
            coeffs[label], spread[label], counts[label] = fit
    return ActionStyle(gs, coeffs, counts, spread, params=dict(params or {}))


def learn_action_style(label_paths, poses_dir, model_path, estimator: GlobalStyleEstimator | None = None,
                       seed: int = 0) -> ActionStyle:
    """``learn-style --poses-dir``: the action-level style of one performer from label files (true or
    recognised; their ``video`` names the pose file ``<poses_dir>/<video stem>.poses.json``, their ``view``
    the view, default ``front``) and an action model file. ``estimator``: a fitted
    :class:`GlobalStyleEstimator` (default: :meth:`GlobalStyleEstimator.from_model`). Bad input raises a
    one-line error naming the file (missing pose file, damaged model, a label file without a video)."""
    from pathlib import Path

    from ..errors import InputError
    from ..formats.labels import read_labels
    from ..formats.poses import read_poses
    from ..recognition.posefeatures import track_from_poses
    from .model import ActionModel

    model = ActionModel.load(model_path)
    videos = []
    fps = 20.0
    for p in label_paths:
        fl = read_labels(p)
        fps = fl.fps
        if not fl.video:
            raise InputError(f"{p}: the label file names no video, so no pose file can be found for it")
        pf = Path(poses_dir) / f"{Path(fl.video).stem}.poses.json"
        if not pf.is_file():
            raise InputError(f"{pf}: pose file not found (for {p})")
        xy = track_from_poses(read_poses(pf), fl.fps, fl.n_frames).xy
        videos.append((xy, fl.labels, fl.view or "front", fl.confidence))
    est = estimator if estimator is not None else GlobalStyleEstimator.from_model(model, fps)
    style = fit_action_style(model, est, videos, random_state=seed)
    style.model = str(model_path)
    style.check_model(model, model_path)
    log.info("action style: %s, guard %.3f, stance %.3f; coefficients of %s", style.global_style.lead,
             style.global_style.guard_height, style.global_style.stance_width, ", ".join(sorted(style.coefficients)))
    return style


def restyle_motion(motion, labels, action_style: ActionStyle, model, blend: int = D.STYLE_BLEND_FRAMES,
                   min_fraction: float = D.STYLE_MIN_FRACTION):
    """``motion`` (e.g. ``synthesize``'s graph walk) with every run of frames labelled with an action the
    style has coefficients for replaced by this performer's way of doing it (:meth:`ActionStyle.realise`,
    decoded at the run's length, feet pinned, mirrored for a southpaw), retargeted onto ``motion``'s
    skeleton (rotations kept, root path scaled by leg length), turned to the facing and moved to the root
    position of the run's first frame, and cross-faded with the original over ``blend`` frames at either
    end (rotations by normalised quaternion interpolation, root linearly). Returns ``(motion, replaced
    runs [(label, start, end)])``. A run shorter than ``min_fraction`` of the label's mean instance length
    (in ``motion``'s frame rate) keeps the graph's frames: squeezing a whole kick into a few frames would
    move far faster than any source."""
    from ..mocap import Motion
    from ..mocap.retarget import retarget

    labels = list(labels)
    if len(labels) != motion.n_frames:
        raise ParameterError("labels", f"{len(labels)} labels for {motion.n_frames} frames")
    rot = motion.rotations.copy()
    root = motion.root_positions.copy()
    angles = motion.facing_angles()
    done = []
    for label, s, e in label_runs(labels):
        n = e - s
        if label not in action_style.coefficients or n < 3:
            continue
        if n < min_fraction * model.models_[label].mean_frames * motion.fps / model.fps_:
            log.info("restyle: %s at frames %d-%d kept (%d frames, under %.0f %% of its mean length)", label, s, e, n,
                     100 * min_fraction)
            continue
        inst = action_style.realise(model, label, n_frames=n, pin=True)
        inst, _ = retarget(inst, motion.skeleton, f"{label} of the style")
        inst = inst.normalize_facing(0, float(angles[s]), origin=True)
        r = inst.root_positions.copy()
        r[:, 0] += root[s, 0]
        r[:, 2] += root[s, 2]
        b = int(min(blend, n // 2))
        w = np.ones(n)
        if b > 0:
            ramp = np.arange(1, b + 1) / (b + 1)
            w[:b] = ramp
            w[n - b:] = ramp[::-1]
        q0, q1 = rot[s:e], inst.rotations
        q1 = np.where(np.sum(q0 * q1, -1, keepdims=True) < 0, -q1, q1)
        q = (1 - w)[:, None, None] * q0 + w[:, None, None] * q1
        rot[s:e] = q / np.linalg.norm(q, axis=-1, keepdims=True)
        root[s:e] = (1 - w)[:, None] * root[s:e] + w[:, None] * r
        done.append((label, s, e))
    return Motion(motion.skeleton, rot, None, motion.fps, root_positions=root), done
