"""The pose model of ``vidstyle train-pose``: viewpoint-specific pictorial structures (front, left,
right, back) plus a generic set, and the thesis' viewpoint classifier (best torso-detector score of
every viewpoint -> one-vs-all + one-vs-one SVMs).

Training (:meth:`PoseModel.fit_specs`) goes through :func:`vidstyle.parallel.parallel_map` three
times: render the frames; extract positive/negative template windows per part (random negatives
plus background-only frames); after a first fit, mine hard negatives (the best-scoring false
detections) and collect the torso scores the viewpoint SVMs learn from.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import cv2
import numpy as np

from ..errors import InputError, ParameterError
from ..formats.poses import PoseFrame
from ..mocap.keypoints import PART_NAMES
from .data import VIEW_NAMES, Sample, Spec, render_samples
from .defaults import DEFAULTS, VIEWPOINT_METHODS
from .features import RotatedFeatures, orientation_bin
from .interfaces import PartDetector, ViewpointClassifier, part_detector
from .model import N_PARTS, PictorialStructures, part_geometry, score_models

log = logging.getLogger(__name__)
GENERIC = "generic"
WORK_HEIGHT = 120


class ViewpointSVM:
    """Thesis viewpoint classifier: one-vs-all and one-vs-one RBF SVMs on the vector of best
    torso scores of every viewpoint's detector. The prediction is the one-vs-one vote winner, ties
    (and disagreements) broken by the one-vs-all decision values; ``scores`` are the one-vs-all
    decision values turned into a softmax."""

    #: the viewpoint features it reads (:meth:`PoseModel.view_features`): the torso columns of "parts"
    NEEDS: tuple[str, ...] = ("torso",)

    def __init__(self, C: float = 3.0, gamma: str | float = "scale", seed: int = 0) -> None:
        self.C = C
        self.gamma = gamma
        self.seed = seed

    def input_of(self, feats: dict):
        """This classifier's input (a batch of one) from one frame's :meth:`PoseModel.view_features`."""
        return feats["parts"][[VIEW_NAMES.index(v) * N_PARTS for v in VIEW_NAMES]][None]

    def fit(self, X: np.ndarray, y: np.ndarray) -> ViewpointSVM:
        from sklearn.multiclass import OneVsRestClassifier  # here: inference needs no scikit-learn (~1.2 s to import)
        from sklearn.preprocessing import StandardScaler
        from sklearn.svm import SVC

        self.scaler_ = StandardScaler().fit(X)
        Z = self.scaler_.transform(X)
        self.classes_ = np.array(VIEW_NAMES)
        yi = np.array([VIEW_NAMES.index(v) for v in y])
        self.ovo_ = SVC(C=self.C, gamma=self.gamma, decision_function_shape="ovo", random_state=self.seed).fit(Z, yi)
        self.ova_ = OneVsRestClassifier(SVC(C=self.C, gamma=self.gamma, random_state=self.seed)).fit(Z, yi)
        return self

    def decision(self, X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        Z = self.scaler_.transform(np.atleast_2d(X))
        ova = np.full((len(Z), len(VIEW_NAMES)), -10.0)
        ova[:, self.ova_.classes_] = self.ova_.decision_function(Z).reshape(len(Z), -1)
        votes = np.zeros((len(Z), len(VIEW_NAMES)))
        pairs = self.ovo_.decision_function(Z).reshape(len(Z), -1)
        cls = self.ovo_.classes_
        n = 0
        for a in range(len(cls)):
            for b in range(a + 1, len(cls)):
                win = np.where(pairs[:, n] > 0, cls[a], cls[b])
                votes[np.arange(len(Z)), win] += 1
                n += 1
        return votes, ova

    def predict(self, X: np.ndarray) -> np.ndarray:
        votes, ova = self.decision(X)
        return self.classes_[np.argmax(votes + 0.01 * np.tanh(ova), axis=1)]

    def scores(self, X: np.ndarray) -> list[dict[str, float]]:
        votes, ova = self.decision(X)
        z = votes + 0.01 * np.tanh(ova)
        p = np.exp(z - z.max(axis=1, keepdims=True))
        p /= p.sum(axis=1, keepdims=True)
        return [{v: float(round(x, 4)) for v, x in zip(VIEW_NAMES, row)} for row in p]


class ViewpointLogistic(ViewpointSVM):
    """Alternative viewpoint classifier: multinomial logistic regression on the best score of every
    part detector of every viewpoint (40 features)."""

    NEEDS = ("parts",)

    def __init__(self, C: float = 1.0, seed: int = 0) -> None:
        self.C = C
        self.seed = seed

    def input_of(self, feats: dict):
        return feats["parts"][None]

    def fit(self, X, y):
        from sklearn.linear_model import LogisticRegression
        from sklearn.preprocessing import StandardScaler

        self.scaler_ = StandardScaler().fit(X)
        self.classes_ = np.array(VIEW_NAMES)
        self.clf_ = LogisticRegression(C=self.C, max_iter=2000).fit(self.scaler_.transform(X),
                                                                     [VIEW_NAMES.index(v) for v in y])
        return self

    def predict(self, X):
        p = self._proba(X)
        return self.classes_[p.argmax(axis=1)]

    def _proba(self, X):
        p = np.zeros((len(np.atleast_2d(X)), len(VIEW_NAMES)))
        p[:, self.clf_.classes_] = self.clf_.predict_proba(self.scaler_.transform(np.atleast_2d(X)))
        return p

    def scores(self, X):
        return [{v: float(round(x, 4)) for v, x in zip(VIEW_NAMES, row)} for row in self._proba(X)]


HOG_WIN = (64, 112)  # whole-person window (w, h) in working pixels (the figure is ~84 px tall at 120)
HOG_DROP = 10  # window centre below the generic torso detection, in working pixels
_MIRROR = {"front": "front", "back": "back", "left": "right", "right": "left"}


def person_crop(gray: np.ndarray, centre_xy) -> np.ndarray:
    """The HOG_WIN window of a working-size gray frame centred ``HOG_DROP`` px below ``centre_xy``
    (replicated border outside the frame)."""
    w, h = HOG_WIN
    cx, cy = float(centre_xy[0]), float(centre_xy[1]) + HOG_DROP
    M = np.array([[1.0, 0.0, w / 2.0 - cx], [0.0, 1.0, h / 2.0 - cy]])
    return cv2.warpAffine(gray, M, (w, h), flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)


_HOG = None


def person_hog(crop: np.ndarray) -> np.ndarray:
    """Dalal-Triggs HOG (16 px blocks of 2x2 8-px cells, 9 bins, stride 8) of a person crop."""
    global _HOG
    if _HOG is None:
        _HOG = cv2.HOGDescriptor(HOG_WIN, (16, 16), (8, 8), (8, 8), 9)
    return _HOG.compute(np.ascontiguousarray(crop)).ravel().astype(np.float32)


class ViewpointHOG(ViewpointLogistic):
    """Alternative viewpoint classifier: a linear SVM (one-vs-rest, squared hinge) on the HOG of a
    whole-person window centred on the generic torso detection. Training frames are used twice,
    as rendered and mirrored (left and right swap, front and back stay). ``scores`` are the
    decision values turned into a softmax."""

    NEEDS = ("hog",)

    def __init__(self, C: float = 0.01, seed: int = 0) -> None:
        self.C = C
        self.seed = seed

    def input_of(self, feats: dict):
        return feats["hog"][None]

    def fit(self, X, y, X_mirror=None):
        from sklearn.svm import LinearSVC

        y = list(y)
        if X_mirror is not None:
            X = np.vstack([X, X_mirror])
            y = y + [_MIRROR[v] for v in y]
        self.classes_ = np.array(VIEW_NAMES)
        self.clf_ = LinearSVC(C=self.C, random_state=self.seed, max_iter=5000).fit(
            np.asarray(X, np.float64), [VIEW_NAMES.index(v) for v in y])
        return self

    def _proba(self, X):
        d = np.full((len(np.atleast_2d(X)), len(VIEW_NAMES)), -10.0)
        d[:, self.clf_.classes_] = self.clf_.decision_function(np.atleast_2d(X).astype(np.float64))
        p = np.exp(3.0 * (d - d.max(axis=1, keepdims=True)))
        return p / p.sum(axis=1, keepdims=True)



class ViewpointProduct:
    """Product of the all-parts logistic's probabilities and the whole-person HOG SVM's softmax
    (both trained as above; nothing else is learned). Input: (parts row, hog) of one frame."""

    NEEDS = ("parts", "hog")

    def __init__(self, logistic: ViewpointLogistic, hog: ViewpointHOG) -> None:
        self.logistic = logistic
        self.hog = hog

    def input_of(self, feats: dict):
        return (feats["parts"], feats["hog"])

    def _proba(self, x):
        p = self.logistic._proba(x[0][None]) * self.hog._proba(x[1][None])
        return p / p.sum(axis=1, keepdims=True)

    def predict(self, x):
        return np.array(VIEW_NAMES)[self._proba(x).argmax(axis=1)]

    def scores(self, x):
        return [{v: float(round(p, 4)) for v, p in zip(VIEW_NAMES, row)} for row in self._proba(x)]


#: the viewpoint classifiers a hog :class:`PoseModel` trains, by name (``viewpoint``): model -> classifier
VIEWPOINT_CLASSIFIERS = {
    "svm": lambda m: m.viewpoint_svm_,
    "logistic": lambda m: m.viewpoint_logistic_,
    "hog": lambda m: m.viewpoint_hog_,
    "combined": lambda m: ViewpointProduct(m.viewpoint_logistic_, m.viewpoint_hog_),
}
assert tuple(VIEWPOINT_CLASSIFIERS) == VIEWPOINT_METHODS


# ---------------------------------------------------------------- parallel training jobs
@dataclass
class _WindowJob:
    samples: list  # (image, keypoints, view)
    sizes: dict  # model name -> list of (h, w)
    n_orient: int
    cell: int
    neg_per_pos: int
    seed: int
    backgrounds: list


def _windows(job: _WindowJob) -> dict:
    """Per model and part: positive and random negative windows of the job's frames."""
    rng = np.random.default_rng(job.seed)
    out = {name: [([], []) for _ in range(N_PARTS)] for name in job.sizes}
    for img, kp, view in job.samples:
        f = RotatedFeatures(img, job.n_orient, job.cell)
        for name in (view, GENERIC):
            probe = PictorialStructures(job.n_orient, job.cell)
            probe.sizes_ = job.sizes[name]
            for j in range(N_PARTS):
                p, n = probe._samples(f, kp, j, rng, job.neg_per_pos)
                if p is not None:
                    out[name][j][0].append(p)
                out[name][j][1].extend(n)
    for bg in job.backgrounds:  # figure-free frames: negatives only
        f = RotatedFeatures(bg, job.n_orient, job.cell)
        for name in job.sizes:
            for j in range(N_PARTS):
                h, w = job.sizes[name][j]
                for _ in range(job.neg_per_pos):
                    xy = rng.uniform([0, 0], [bg.shape[1] - 1, bg.shape[0] - 1])
                    win = f.window(int(rng.integers(job.n_orient)), xy, h, w)
                    if win is not None:
                        out[name][j][1].append(win)
    return {name: [(np.array(p, np.float32), np.array(n, np.float32)) for p, n in parts] for name, parts in out.items()}


@dataclass
class _MineJob:
    samples: list
    models: dict  # name -> PictorialStructures
    n_hard: int


def _mine(job: _MineJob) -> dict:
    """Hard negatives (per model, part) and viewpoint features (per frame) with the current models."""
    hard = {name: [[] for _ in range(N_PARTS)] for name in job.models}
    vfeat, hog, hog_m = [], [], []
    for img, kp, view in job.samples:
        f = RotatedFeatures(img, next(iter(job.models.values())).n_orient, next(iter(job.models.values())).cell)
        row = []
        maps = score_models(job.models, f)
        for name in VIEW_NAMES:
            row.extend(maps[name].reshape(N_PARTS, -1).max(axis=1))
        if job.n_hard:
            for name in (view, GENERIC):
                hard[name] = _merge(hard[name], _hard_windows(job.models[name], f, maps[name], kp, job.n_hard))
        else:
            crop = person_crop(img, torso_centre(job.models[GENERIC], maps[GENERIC][0]))
            hog.append(person_hog(crop))
            hog_m.append(person_hog(cv2.flip(crop, 1)))
        vfeat.append(row)
    return {"hard": {k: [np.array(v, np.float32).reshape(len(v), -1) if v else None for v in parts]
                     for k, parts in hard.items()},
            "vfeat": np.array(vfeat, np.float64), "hog": np.array(hog, np.float32),
            "hog_mirror": np.array(hog_m, np.float32)}


def torso_centre(m: PictorialStructures, torso_maps: np.ndarray) -> np.ndarray:
    """Working-pixel (x, y) of the best torso detection in a (K, Hc, Wc) torso score map."""
    _k, y, x = np.unravel_index(int(np.argmax(torso_maps)), torso_maps.shape)
    return np.array([x * m.cell + (m.cell - 1) / 2.0, y * m.cell + (m.cell - 1) / 2.0])


def _merge(acc, new):
    for j in range(N_PARTS):
        acc[j].extend(new[j])
    return acc


def _hard_windows(m: PictorialStructures, f: RotatedFeatures, S: np.ndarray, kp: np.ndarray, n: int):
    out = [[] for _ in range(N_PARTS)]
    c, th, L = part_geometry(kp[None])
    K, cell = m.n_orient, m.cell
    gy, gx = np.mgrid[0:S.shape[2], 0:S.shape[3]]
    for j in range(N_PARTS):
        kt = int(orientation_bin(th[0, j], K))
        d = np.hypot(gx * cell + (cell - 1) / 2 - c[0, j, 0], gy * cell + (cell - 1) / 2 - c[0, j, 1])
        dk = np.minimum((np.arange(K) - kt) % K, (kt - np.arange(K)) % K)
        near = (d[None] < 0.5 * max(L[0, j], 4)) & (dk[:, None, None] <= 1)
        s = np.where(near, -np.inf, S[j])
        h, w = m.sizes_[j]
        for idx in np.argsort(s.ravel())[::-1][:n]:
            kk, yy, xx = np.unravel_index(idx, s.shape)
            if s[kk, yy, xx] < -1.0:
                break
            win = f.window(int(kk), np.array([xx * cell + (cell - 1) / 2, yy * cell + (cell - 1) / 2]), h, w)
            if win is not None:
                out[j].append(win)
    return out


def _background_frames(n: int, seed: int, size=(160, 120)) -> list[np.ndarray]:
    from ..render.background import make_background

    rng = np.random.default_rng(seed)
    out = []
    for i in range(n):
        spec = ["texture", "texture:brick", "texture:grass", "texture:gravel", "plain"][i % 5]
        bg, _ = make_background(spec, size, rng)
        g = cv2.cvtColor(np.clip(bg + rng.normal(0, 2, bg.shape), 0, 255).astype(np.uint8), cv2.COLOR_BGR2GRAY)
        out.append(g)
    return out


def _chunks(seq, n):
    n = max(1, n)
    size = max(1, math.ceil(len(seq) / n))
    return [seq[i:i + size] for i in range(0, len(seq), size)]


# ---------------------------------------------------------------- the model

def check_scales(scales) -> tuple[float, ...]:
    """Zoom factors of multi-scale inference: finite, within 0.25-4, 1 first (the pose at scale 1
    gives the centre the others zoom about); ValueError otherwise."""
    out = [float(z) for z in scales]
    if not out or not all(np.isfinite(z) and 0.25 <= z <= 4.0 for z in out):
        raise ValueError(f"scales must be zoom factors between 0.25 and 4, got {list(scales)}")
    return tuple(dict.fromkeys([1.0] + out))


def zoom_about(centre: np.ndarray, z: float, size: tuple[int, int]) -> np.ndarray:
    """2x3 affine map (for ``cv2.warpAffine``, pixel centres at integers) that zooms by ``z`` about
    ``centre`` (x, y) and moves it to the middle of a frame of ``size`` (W, H): ``q = z p + t``."""
    W, H = size
    return np.array([[z, 0.0, (W - 1) / 2.0 - z * float(centre[0])],
                     [0.0, z, (H - 1) / 2.0 - z * float(centre[1])]])


class HogParts:
    """Part detector strategy of :class:`PoseModel` (``detector="hog"``): HOG cells of rotated copies of the
    gray frame scored by each tree's linear part templates (the learned templates live in the trees,
    ``model.models_``), the person prior from a video's background, and the viewpoint features the hog
    model's classifiers read. Stateless: every method takes the model it serves."""

    #: trains on colour renders (``render_samples(keep_bgr=...)``)
    needs_colour = False
    #: adds the person prior of a video's background (``fg_weight``)
    uses_foreground = True

    def fit(self, model, samples: list[Sample], jobs: int = -1, scheduler: str | None = None) -> PoseModel:
        from ..parallel import parallel_map

        views = {s.view for s in samples}
        missing = [v for v in VIEW_NAMES if v not in views]
        if missing:
            raise InputError(f"training frames have no {', '.join(missing)} view")
        kp = {name: np.stack([s.keypoints for s in samples if name in (s.view, GENERIC)])
              for name in VIEW_NAMES + (GENERIC,)}
        model.models_ = {}
        for name in VIEW_NAMES + (GENERIC,):
            m = PictorialStructures(model.n_orient, model.cell, model.C, model.neg_per_pos, model.hard_rounds, model.seed,
                                    model.dt, model.unary_weight)
            model.models_[name] = m.fit_geometry(kp[name])
        for m in model.models_.values():  # one template size per part: window gathers are shared
            m.sizes_ = list(model.models_[GENERIC].sizes_)
        sizes = {n: m.sizes_ for n, m in model.models_.items()}
        triples = [(s.image, s.keypoints, s.view) for s in samples]
        n_chunks = max(2, min(32, len(triples) // 20))
        bgs = _chunks(_background_frames(max(10, len(triples) // 20), model.seed + 1), n_chunks)
        chunks = _chunks(triples, n_chunks)
        jobs_ = [_WindowJob(c, sizes, model.n_orient, model.cell, model.neg_per_pos, model.seed * 1000 + i,
                            bgs[i] if i < len(bgs) else []) for i, c in enumerate(chunks)]
        res = parallel_map(_windows, jobs_, jobs=jobs, scheduler=scheduler, description="part windows")
        data = {name: [(np.vstack([r[name][j][0] for r in res if len(r[name][j][0])]),
                        np.vstack([r[name][j][1] for r in res if len(r[name][j][1])]))
                       for j in range(N_PARTS)] for name in model.models_}
        for name, m in model.models_.items():
            self._fit_templates(model, m, data[name])
        if model.hard_rounds:
            mined = parallel_map(_mine, [_MineJob(c, model.models_, 3) for c in chunks], jobs=jobs,
                                 scheduler=scheduler, description="hard negatives")
            for name, m in model.models_.items():
                extra = [[r["hard"][name][j] for r in mined if r["hard"][name][j] is not None] for j in range(N_PARTS)]
                data[name] = [(P, np.vstack([Nn] + e)) for (P, Nn), e in zip(data[name], extra)]
                self._fit_templates(model, m, data[name])
        # viewpoint features with the final detectors
        vf = parallel_map(_mine, [_MineJob(c, model.models_, 0) for c in chunks], jobs=jobs, scheduler=scheduler,
                          description="viewpoint features")
        X = np.vstack([r["vfeat"] for r in vf])
        y = np.array([t[2] for t in triples])
        self._fit_viewpoint(model, X, y, np.vstack([r["hog"] for r in vf]), np.vstack([r["hog_mirror"] for r in vf]))
        model.n_train_frames_ = len(samples)
        return model

    def _fit_templates(self, model, m: PictorialStructures, data) -> None:
        m.templates_, m.bias_ = [], np.zeros(N_PARTS)
        for j, (P, Nn) in enumerate(data):
            X = np.vstack([P, Nn])
            y = np.r_[np.ones(len(P)), np.zeros(len(Nn))]
            from sklearn.linear_model import LogisticRegression

            clf = LogisticRegression(C=model.C, max_iter=300, class_weight="balanced").fit(X, y)
            h, w = m.sizes_[j]
            m.templates_.append(clf.coef_[0].reshape(h, w, -1).astype(np.float32))
            m.bias_[j] = float(clf.intercept_[0])

    def _fit_viewpoint(self, model, X: np.ndarray, y: np.ndarray, hog: np.ndarray, hog_mirror: np.ndarray) -> None:
        torso = X[:, [VIEW_NAMES.index(v) * N_PARTS for v in VIEW_NAMES]]
        model.viewpoint_svm_ = ViewpointSVM(seed=model.seed).fit(torso, y)
        model.viewpoint_logistic_ = ViewpointLogistic(seed=model.seed).fit(X, y)
        model.viewpoint_hog_ = ViewpointHOG(C=model.hog_C, seed=model.seed).fit(hog, y, hog_mirror)
        model.viewpoint_ = model._classifier(model.viewpoint)

    def prepare(self, model, frame: np.ndarray) -> tuple[RotatedFeatures, float]:
        g, s = model.to_work_size(frame if frame.ndim == 2 else cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY))
        f = RotatedFeatures(g, model.n_orient, model.cell)
        f.gray = g
        return f, s

    def view_features(self, model, f: RotatedFeatures, full: bool | None = None,
                      which: str | None = None) -> tuple[dict, dict]:
        """Viewpoint features of a frame (``f`` from :meth:`prepare`): ``"parts"``, the best score of
        every part detector of every viewpoint (40 values, view-major; NaN where not run), and
        ``"hog"``, the whole-person HOG (None when not needed). ``full`` runs every detector of every
        viewpoint (default: only what ``which``, default the model's classifier, needs). Also
        returns the score maps computed (model name -> maps; only complete maps)."""
        needs = model._classifier(which or model.viewpoint).NEEDS
        views_full = bool(full) or "parts" in needs
        row = np.full(len(VIEW_NAMES) * N_PARTS, np.nan)
        out = {"parts": row, "hog": None}
        maps: dict = {}
        if views_full or "torso" in needs:
            views = {v: model.models_[v] for v in VIEW_NAMES}
            got = score_models(views, f, None if views_full else [0])
            for n, name in enumerate(VIEW_NAMES):
                best = got[name].reshape(got[name].shape[0], -1).max(axis=1)
                row[n * N_PARTS: n * N_PARTS + len(best)] = best
            if views_full:
                maps.update(got)
        if full or "hog" in needs:
            g = score_models({GENERIC: model.models_[GENERIC]}, f, None if full else [0])[GENERIC]
            if full:
                maps[GENERIC] = g
            out["hog"] = person_hog(person_crop(f.gray, torso_centre(model.models_[GENERIC], g[0])))
        return out, maps

    def foreground_map(self, model, frame: np.ndarray, background: np.ndarray | None, f: RotatedFeatures):
        """The frame's foreground at the working size (None without a background or a prior)."""
        if background is None or not getattr(model, "fg_weight", 0.0):
            return None
        from .foreground import foreground

        if background.shape != frame.shape:
            raise ValueError(f"background shape {background.shape} is not the frame's {frame.shape}")
        fg = foreground(frame, background)
        if fg.shape != (f.H, f.W):
            fg = cv2.resize(fg, (f.W, f.H), interpolation=cv2.INTER_AREA)
        return fg

    def solve(self, model, model_name: str, S: np.ndarray, scale: float, fg: np.ndarray | None = None,
              f: RotatedFeatures | None = None, fg_weight: float | None = None) -> np.ndarray:
        """(15, 3) keypoints of the best configuration of one detector set given its score maps,
        with the person prior when ``fg`` is given."""
        m = model.models_[model_name]
        w = getattr(model, "fg_weight", 0.0) if fg_weight is None else fg_weight
        if fg is not None and w:
            from .foreground import part_coverage

            S = S + np.float32(w) * part_coverage(m, f, fg)
        r = m.infer(S)
        return m.keypoints(r["states"], r["unary"], scale=scale)


def check_common_params(model) -> None:
    """The parameter checks every pose model shares (``n_orient``, ``unary_weight``)."""
    if not 4 <= model.n_orient <= 36:
        raise ParameterError("n_orient", "must be between 4 and 36")
    if not model.unary_weight > 0:
        raise ParameterError("unary_weight", "must be positive")


class PoseModel:
    """Viewpoint-specific + generic pictorial structures and a viewpoint classifier.

    Parameters (stored as given): ``n_orient``, ``cell``, ``C`` (part logistic regressions),
    ``neg_per_pos``, ``hard_rounds`` (0 or 1), ``viewpoint`` ("svm" = the thesis' torso-score SVMs,
    "logistic" = logistic regression on every part's best score, "hog" = linear SVM on a
    whole-person HOG), ``dt`` ("envelope" or "brute"), ``unary_weight`` (detectors vs tree prior),
    ``hog_C``, ``fg_weight`` (person prior from a video's background, 0 = off), ``seed``.
    Defaults: :mod:`vidstyle.pose.defaults` (chosen by ``scripts/validate_pose.py``).
    Learned: ``models_`` (view name or "generic" -> :class:`PictorialStructures`),
    ``viewpoint_`` (the chosen classifier), ``viewpoint_svm_``, ``viewpoint_logistic_``,
    ``viewpoint_hog_``, ``n_train_frames_``.
    """

    def __init__(self, n_orient: int = DEFAULTS["n_orient"], cell: int = 4, C: float = 0.05, neg_per_pos: int = 12,
                 hard_rounds: int = DEFAULTS["hard_rounds"], viewpoint: str = DEFAULTS["viewpoint"],
                 dt: str = "envelope", unary_weight: float = DEFAULTS["unary_weight"], hog_C: float = 0.01,
                 fg_weight: float = DEFAULTS["fg_weight"], seed: int = 0) -> None:
        self.n_orient = n_orient
        self.cell = cell
        self.C = C
        self.neg_per_pos = neg_per_pos
        self.hard_rounds = hard_rounds
        self.viewpoint = viewpoint
        self.dt = dt
        self.unary_weight = unary_weight
        self.hog_C = hog_C
        self.fg_weight = fg_weight
        self.seed = seed

    PARAMS = ("n_orient", "cell", "C", "neg_per_pos", "hard_rounds", "viewpoint", "dt", "unary_weight", "hog_C",
              "fg_weight", "seed")
    #: the viewpoint classifiers this model trains (``set_inference(viewpoint=...)``, ``evaluate pose``)
    VIEWPOINTS = VIEWPOINT_METHODS
    #: name -> (fitted model -> its viewpoint classifier, a :class:`~vidstyle.pose.interfaces.ViewpointClassifier`)
    VIEWPOINT_CLASSIFIERS = VIEWPOINT_CLASSIFIERS
    #: the part detectors (:data:`vidstyle.pose.interfaces.PART_DETECTORS`): a name, so that the strategy is
    #: not pickled and model files stay loadable whatever the strategy classes become
    detector = "hog"

    @property
    def parts_(self) -> PartDetector:
        """The part detector strategy (:class:`HogParts`, :class:`~vidstyle.pose.cnn.CnnParts`) of :attr:`detector`."""
        return part_detector(self.detector)

    def get_params(self) -> dict:
        return {k: getattr(self, k) for k in self.PARAMS}

    def check_params(self) -> PoseModel:
        """:class:`ParameterError` naming the first parameter this model cannot train with (run by
        :meth:`fit` and :meth:`fit_specs` before any work, as scikit-learn estimators check in ``fit``)."""
        check_common_params(self)
        if self.viewpoint not in VIEWPOINT_METHODS:
            raise ParameterError("viewpoint", f"{self.viewpoint!r} is not one of {', '.join(VIEWPOINT_METHODS)}")
        if not self.fg_weight >= 0:
            raise ParameterError("fg_weight", "must be 0 or positive")
        if self.hard_rounds not in (0, 1):
            raise ParameterError("hard_rounds", "must be 0 or 1")
        return self

    def set_inference(self, viewpoint: str | None = None, unary_weight: float | None = None,
                      fg_weight: float | None = None, scales=None) -> PoseModel:
        """Change what needs no retraining: the viewpoint classifier used, the unary weight, the
        person prior's weight, the zoom factors of multi-scale inference (:meth:`estimate`)."""
        if scales is not None:
            self.scales = check_scales(scales)
        if fg_weight is not None and self.parts_.uses_foreground:
            self.fg_weight = float(fg_weight)
        if viewpoint is not None:
            if viewpoint not in self.VIEWPOINT_CLASSIFIERS:
                raise ValueError(f"viewpoint must be one of {tuple(self.VIEWPOINT_CLASSIFIERS)}, got {viewpoint!r}")
            self.viewpoint = viewpoint
            self.viewpoint_ = self._classifier(viewpoint)
        if unary_weight is not None:
            self.unary_weight = float(unary_weight)
            for m in self.models_.values():
                m.unary_weight = float(unary_weight)
        return self

    # ---------------------------------------------------------- training
    def fit_specs(self, specs: list[Spec], jobs: int = -1, scheduler: str | None = None) -> PoseModel:
        self.check_params()
        samples = render_samples(specs, jobs=jobs, scheduler=scheduler, keep_bgr=self.parts_.needs_colour)
        return self.fit(samples, jobs=jobs, scheduler=scheduler)

    def fit(self, samples: list[Sample], jobs: int = -1, scheduler: str | None = None) -> PoseModel:
        """Fit the trees, the part detectors and the viewpoint classifier(s) on labelled frames."""
        self.check_params()
        self.parts_.fit(self, samples, jobs=jobs, scheduler=scheduler)
        return self


    def _classifier(self, which: str) -> ViewpointClassifier:
        """The trained viewpoint classifier called ``which`` (:attr:`VIEWPOINT_CLASSIFIERS`)."""
        if which not in self.VIEWPOINT_CLASSIFIERS:
            raise ParameterError("viewpoint", f"{which!r} is not one of {', '.join(self.VIEWPOINT_CLASSIFIERS)}")
        return self.VIEWPOINT_CLASSIFIERS[which](self)

    # ---------------------------------------------------------- inference
    def work_scale(self, frame_shape) -> float:
        return WORK_HEIGHT / float(frame_shape[0])

    def to_work_size(self, img: np.ndarray) -> tuple[np.ndarray, float]:
        """``img`` (gray or colour) resized to the working height (aspect kept), and the scale."""
        s = self.work_scale(img.shape)
        if abs(s - 1.0) > 1e-6:
            img = cv2.resize(img, (max(8, round(img.shape[1] * s)), WORK_HEIGHT), interpolation=cv2.INTER_AREA)
        return img, s

    def prepare(self, frame: np.ndarray):
        """The frame prepared for the part detectors (:attr:`parts_`) and its working scale."""
        return self.parts_.prepare(self, frame)

    def view_features(self, f, full: bool | None = None, which: str | None = None) -> tuple[dict, Any]:
        """Viewpoint features of a prepared frame and the score maps computed (:attr:`parts_`)."""
        return self.parts_.view_features(self, f, full, which)


    def classify_view(self, feats: dict, which: str | None = None) -> tuple[str, dict]:
        clf = self._classifier(which or self.viewpoint)
        x = clf.input_of(feats)
        return str(clf.predict(x)[0]), clf.scores(x)[0]

    #: zoom factors tried about the person (``set_inference(scales=...)``; (1.0,): the frame as given)
    scales: tuple[float, ...] = (1.0,)

    def estimate(self, frame: np.ndarray, index: int = 0, view: str | None = None,
                 detectors: str | None = None, background: np.ndarray | None = None) -> PoseFrame:
        """Pose of one frame (BGR or gray, any size: it is resized to the working height). ``view``
        forces a viewpoint (else the classifier decides); ``detectors="generic"`` uses the generic
        set. ``background`` (same size and channels as ``frame``: the median of frames of a
        static-camera video, :func:`vidstyle.pose.foreground.background_model`) adds the person
        prior, weighted by ``fg_weight``.

        With ``scales`` other than 1 (multi-scale inference, for people smaller or larger in the frame
        than the training renders' figures): the frame is also zoomed by each factor about the centre
        of the pose found at scale 1 (kept at the frame's size, borders replicated), and the pose whose
        keypoints score highest on average is returned, mapped back to the frame's pixels."""
        zooms = tuple(float(z) for z in self.scales if float(z) != 1.0)
        return max(self.zoom_candidates(frame, zooms, index, view, detectors, background),
                   key=lambda c: float(c.points[:, 2].mean()))  # the first of equals: scale 1 wins ties

    def zoom_candidates(self, frame: np.ndarray, zooms: tuple[float, ...], index: int = 0, view: str | None = None,
                        detectors: str | None = None, background: np.ndarray | None = None) -> list[PoseFrame]:
        """The pose of the frame as given, then one per zoom factor of ``zooms``: the frame zoomed by it
        about the centre of the first pose (kept at the frame's size, borders replicated), each pose mapped
        back to the frame's pixels. :meth:`estimate` returns the one whose keypoints score highest on
        average; ``scripts/validate_pose_scales.py`` scores every zoom of a frame from one call."""
        pf = self._estimate_once(frame, index, view, detectors, background)
        out = [pf]
        H, W = frame.shape[:2]
        centre = pf.points[:, :2].mean(axis=0)
        for z in zooms:
            A = zoom_about(centre, z, (W, H))
            fz = cv2.warpAffine(frame, A, (W, H), flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
            bz = None if background is None else cv2.warpAffine(background, A, (W, H), flags=cv2.INTER_LINEAR,
                                                                  borderMode=cv2.BORDER_REPLICATE)
            cand = self._estimate_once(fz, index, view, detectors, bz)
            cand.points[:, :2] = (cand.points[:, :2] - A[:, 2]) / z
            out.append(cand)
        return out

    def _estimate_once(self, frame: np.ndarray, index: int, view: str | None, detectors: str | None,
                       background: np.ndarray | None) -> PoseFrame:
        f, s = self.prepare(frame)
        feats, maps = self.view_features(f)
        vname, vscores = self.classify_view(feats)
        if view is not None:
            vname = view
        model_name = GENERIC if detectors == GENERIC else vname
        S = maps[model_name] if model_name in maps else score_models({model_name: self.models_[model_name]},
                                                                      f)[model_name]
        fg = self.foreground_map(frame, background, f)
        pts = self.solve(model_name, S, s, fg, f)
        return PoseFrame(index, vname, pts, vscores)

    @property
    def uses_background(self) -> bool:
        """Whether :meth:`estimate` reads a video's background (the person prior is on)."""
        return bool(getattr(self, "fg_weight", 0.0))

    def working_height(self, native_height: int) -> int:
        """Videos are read at :data:`WORK_HEIGHT` rows (the training renders' figure scale)."""
        return WORK_HEIGHT

    def close(self) -> None:
        """Nothing to release (the :class:`~vidstyle.pose.interfaces.PoseBackend` interface)."""

    def foreground_map(self, frame: np.ndarray, background: np.ndarray | None, f):
        """The frame's foreground at the working size (None without a background, a prior, or for
        detectors that use none)."""
        return self.parts_.foreground_map(self, frame, background, f)

    def solve(self, model_name: str, S: np.ndarray, scale: float, fg: np.ndarray | None = None,
              f=None, fg_weight: float | None = None) -> np.ndarray:
        """(15, 3) keypoints of the best configuration of one tree given its score maps (:attr:`parts_`)."""
        return self.parts_.solve(self, model_name, S, scale, fg, f, fg_weight)



# ---------------------------------------------------------------- files
def model_header(model: PoseModel, extra: dict | None = None) -> dict:
    """What a pose model file records about ``model`` (:mod:`vidstyle.formats.pose_model`)."""
    return {"params": model.get_params(), "seed": model.seed, "n_train_frames": int(getattr(model, "n_train_frames_", 0)),
            "parts": list(PART_NAMES), **(extra or {})}


def save_model(path: str | Path, model: PoseModel, extra: dict | None = None) -> dict:
    """Write a fitted pose model file (``vidstyle train-pose``); ``extra``: more header fields. Returns the header."""
    from ..formats.pose_model import write_pose_model

    return write_pose_model(path, model, model_header(model, extra))


def load_backend(model_path: str | Path) -> PoseModel:
    """The ``ps`` pose backend: the pose model of a file (:data:`vidstyle.pose.interfaces.BACKENDS`)."""
    return load_model(model_path)[0]


def load_model(path: str | Path) -> tuple[PoseModel, dict]:
    """``(model, header)`` of a pose model file (:class:`PoseModel` or :class:`~vidstyle.pose.cnn.CnnPoseModel`)."""
    from ..formats.pose_model import read_pose_model

    return read_pose_model(path, PoseModel)
