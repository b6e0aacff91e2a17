"""Frame classifiers: the thesis' one-vs-all + one-vs-one RBF SVMs, and a plain SVC baseline.

:class:`OvaOvoSVC` (thesis 4.2): one binary RBF SVM per class against the rest. A frame claimed by
exactly one of them (decision > ``claim_threshold``) gets that class. When several claim it, the classes
that claimed it compete; when none does, the ``n_competitors`` classes with the highest one-vs-all
decision values compete. The competitors play a round robin of one-vs-one SVMs (one per class pair,
trained on the frames of the two classes only); most wins takes the frame, a draw goes to the higher
one-vs-all decision value.

Class scores (for confidence and score smoothing) are the softmax of the one-vs-all decision values;
the confidence of a frame is the score of the class it was given (which, after a one-vs-one decision, need
not be the highest score).

All binary SVMs share one RBF ``gamma`` (``"scale"`` = 1 / (d * Var(X)) of the training frames, as
scikit-learn defines it), so every decision value is ``K(x, SV) @ W + b`` over the union of their support
vectors: one kernel evaluation serves all K + K(K-1)/2 machines, and the same packed form is what the ONNX
export computes (:mod:`vidstyle.recognition.onnx_export`).
"""

from __future__ import annotations

import logging
from itertools import combinations

import numpy as np
from sklearn.base import BaseEstimator, ClassifierMixin

from ..errors import InputError

log = logging.getLogger(__name__)


def softmax(z: np.ndarray) -> np.ndarray:
    z = z - z.max(axis=1, keepdims=True)
    e = np.exp(z)
    return e / e.sum(axis=1, keepdims=True)


def rbf_kernel(X: np.ndarray, Y: np.ndarray, gamma: float, chunk: int = 4096) -> np.ndarray:
    X = np.asarray(X, np.float64)
    Y = np.asarray(Y, np.float64)
    y2 = np.einsum("ij,ij->i", Y, Y)
    out = np.empty((X.shape[0], Y.shape[0]))
    for s in range(0, X.shape[0], chunk):
        xs = X[s : s + chunk]
        d = np.einsum("ij,ij->i", xs, xs)[:, None] - 2.0 * xs @ Y.T + y2[None, :]
        np.maximum(d, 0.0, out=d)
        out[s : s + chunk] = np.exp(-gamma * d)
    return out


def combine_ova_ovo(
    ova: np.ndarray, ovo: np.ndarray, pairs: list[tuple[int, int]], claim_threshold: float = 0.0, n_competitors: int = 2
) -> tuple[np.ndarray, dict]:
    """Resolve one-vs-all claims with one-vs-one duels (see the module docstring).

    ``ova`` (n, K) decision values (> threshold = claim); ``ovo`` (n, P) decision values of the pairs
    ``pairs`` (> 0 = the pair's first class). Returns class indices (n,) and counts of each case.
    """
    n, K = ova.shape
    claims = ova > claim_threshold
    n_claims = claims.sum(axis=1)
    pred = np.argmax(ova, axis=1)
    single = n_claims == 1
    pred[single] = np.argmax(claims[single], axis=1)
    todo = np.flatnonzero(~single)
    stats = {"single_claim": int(single.sum()), "multi_claim": int((n_claims > 1).sum()), "no_claim": int((n_claims == 0).sum())}
    if todo.size == 0 or K < 2:
        return pred, stats
    comp = claims[todo].copy()
    none = n_claims[todo] == 0
    if none.any():
        top = np.argsort(-ova[todo][none], axis=1, kind="stable")[:, : max(2, n_competitors)]
        m = np.zeros((int(none.sum()), K), bool)
        np.put_along_axis(m, top, True, axis=1)
        comp[none] = m
    votes = np.zeros((todo.size, K), np.int64)
    for p, (i, j) in enumerate(pairs):
        both = comp[:, i] & comp[:, j]
        if not both.any():
            continue
        first = ovo[todo, p] > 0
        votes[both & first, i] += 1
        votes[both & ~first, j] += 1
    key = np.where(comp, votes, -1)
    best = key.max(axis=1, keepdims=True)
    tie_ok = comp & (key == best)
    pred[todo] = np.argmax(np.where(tie_ok, ova[todo], -np.inf), axis=1)
    return pred, stats


class OvaOvoSVC(ClassifierMixin, BaseEstimator):
    """One-vs-all RBF SVMs, one-vs-one SVMs for ties and no-claims (thesis 4.2).

    Parameters
    ----------
    C: SVM soft-margin cost (all machines).
    gamma: RBF gamma, float or ``"scale"``.
    class_weight: of the one-vs-all machines; ``"balanced"`` keeps a class with 1/8 of the frames from
        being out-voted by "the rest" (the one-vs-one machines are unweighted).
    claim_threshold: a one-vs-all decision above this claims the frame.
    n_competitors: classes that compete when no one-vs-all machine claims a frame.
    cache_size: libsvm's kernel cache in MB for each machine; None: the budget
        :data:`~vidstyle.recognition.defaults.SVM_CACHE_MB` divided among the machines trained at once. Speed
        only: the fitted machines do not depend on it.
    n_jobs: machines trained in parallel (joblib).
    """

    def __init__(
        self,
        C: float = 10.0,
        gamma: float | str = "scale",
        class_weight: str | None = "balanced",
        claim_threshold: float = 0.0,
        n_competitors: int = 2,
        cache_size: float | None = None,
        n_jobs: int | None = None,
    ):
        self.C = C
        self.gamma = gamma
        self.class_weight = class_weight
        self.claim_threshold = claim_threshold
        self.n_competitors = n_competitors
        self.cache_size = cache_size
        self.n_jobs = n_jobs

    def fit(self, X, y):
        from joblib import Parallel, delayed

        X = np.asarray(X, np.float64)
        y = np.asarray(y)
        if X.ndim != 2 or X.shape[0] != y.shape[0]:
            raise InputError(f"classifier: X {X.shape} and y {y.shape} do not match")
        self.classes_, yi = np.unique(y, return_inverse=True)
        K = len(self.classes_)
        if K < 2:
            raise InputError(f"classifier: need frames of at least 2 classes, got {list(self.classes_)}")
        self.gamma_ = float(1.0 / (X.shape[1] * X.var())) if self.gamma == "scale" else float(self.gamma)
        self.pairs_ = list(combinations(range(K), 2))
        jobs = [(X, yi == k, self.class_weight, None) for k in range(K)]
        for i, j in self.pairs_:
            rows = np.flatnonzero((yi == i) | (yi == j))
            jobs.append((X[rows], yi[rows] == i, None, rows))
        cache = self.cache_size
        if cache is None:
            from joblib import effective_n_jobs

            from .defaults import SVM_CACHE_MB

            cache = SVM_CACHE_MB / max(1, min(effective_n_jobs(self.n_jobs), len(jobs)))
        if not cache > 0:
            raise InputError(f"classifier: cache_size must be > 0 MB, got {cache}")
        fitted = Parallel(n_jobs=self.n_jobs, prefer="threads")(
            delayed(_fit_binary)(Xs, ys, cw, self.C, self.gamma_, cache) for Xs, ys, cw, _ in jobs
        )
        self.ova_ = fitted[:K]
        self.ovo_ = fitted[K:]
        self._pack(X, [rows for *_, rows in jobs])
        self.n_features_in_ = X.shape[1]
        return self

    def _pack(self, X: np.ndarray, rows: list) -> None:
        """Union of support vectors and the (n_sv, K + P) dual-coefficient matrix over it."""
        sv_global = []
        for svc, r in zip(self.ova_ + self.ovo_, rows):
            idx = svc.support_ if r is None else r[svc.support_]
            sv_global.append(idx)
        union, inv = np.unique(np.concatenate(sv_global), return_inverse=True)
        W = np.zeros((union.size, len(sv_global)))
        at = 0
        for m, (svc, idx) in enumerate(zip(self.ova_ + self.ovo_, sv_global)):
            W[inv[at : at + idx.size], m] = svc.dual_coef_.ravel()
            at += idx.size
        self.support_vectors_ = X[union]
        self.dual_coef_ = W
        self.intercept_ = np.array([float(svc.intercept_[0]) for svc in self.ova_ + self.ovo_])

    def decision_values(self, X) -> tuple[np.ndarray, np.ndarray]:
        """(one-vs-all (n, K), one-vs-one (n, P)) decision values from the packed machines."""
        X = np.asarray(X, np.float64)
        if X.shape[1] != self.n_features_in_:
            raise InputError(f"classifier: {X.shape[1]} features, trained on {self.n_features_in_}")
        D = rbf_kernel(X, self.support_vectors_, self.gamma_) @ self.dual_coef_ + self.intercept_
        K = len(self.classes_)
        return D[:, :K], D[:, K:]

    def predict_with_scores(self, X) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(class indices (n,), class scores (n, K), confidence (n,))."""
        ova, ovo = self.decision_values(X)
        return self.combine(ova, ovo)

    def combine(self, ova: np.ndarray, ovo: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        pred, self.last_stats_ = combine_ova_ovo(ova, ovo, self.pairs_, self.claim_threshold, self.n_competitors)
        scores = softmax(ova)
        return pred, scores, scores[np.arange(len(pred)), pred]

    def predict(self, X) -> np.ndarray:
        return self.classes_[self.predict_with_scores(X)[0]]


def _fit_binary(X, y, class_weight, C, gamma, cache_size):
    from sklearn.svm import SVC

    # sklearn's binary SVC: decision_function = K(x, SV) @ dual_coef_.T + intercept_ > 0 means True
    return SVC(C=C, kernel="rbf", gamma=gamma, class_weight=class_weight, cache_size=cache_size).fit(X, y)


class OvrSVC(ClassifierMixin, BaseEstimator):
    """Baseline: one multi-class :class:`sklearn.svm.SVC` (libsvm one-vs-one voting, ``ovr``-shaped
    decision values). Scores are the softmax of its decision values."""

    def __init__(self, C: float = 10.0, gamma: float | str = "scale", cache_size: float = 500.0):
        self.C = C
        self.gamma = gamma
        self.cache_size = cache_size

    def fit(self, X, y):
        from sklearn.svm import SVC

        X = np.asarray(X, np.float64)
        self.svc_ = SVC(
            C=self.C, kernel="rbf", gamma=self.gamma, decision_function_shape="ovr", cache_size=self.cache_size
        ).fit(X, y)
        self.classes_ = self.svc_.classes_
        self.n_features_in_ = X.shape[1]
        return self

    def predict_with_scores(self, X):
        dec = self.svc_.decision_function(np.asarray(X, np.float64))
        if dec.ndim == 1:
            dec = np.stack([-dec, dec], axis=1)
        pred = np.argmax(dec, axis=1)
        scores = softmax(dec)
        return pred, scores, scores[np.arange(len(pred)), pred]

    def predict(self, X):
        return self.classes_[self.predict_with_scores(X)[0]]
