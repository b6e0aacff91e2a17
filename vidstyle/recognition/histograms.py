"""Frame features: word histograms over a frame context, word grouping, normalisation (thesis 4.2).

For frame n the words of frames n-c .. n+c (thesis c = 2) are counted into one histogram ("signature").
Frames near the ends of a video have fewer neighbours; the normalisation makes their histograms
comparable. Histograms are kept sparse (a frame has ~10 points, so ~50 non-zeros of 1000).

Word grouping (Scovanner et al. 2007, thesis 4.2): the *distribution vector* of a word is its count in
every training frame context (``distribution="frames"``, the default: two words that fire in the same
frames of the same actions are "contextually related"), or its total count per training video
(``"videos"``, Scovanner's choice) or per class (``"classes"``). Pairs of words whose distribution vectors
have Pearson correlation above ``threshold`` are related; ``pooling="components"`` merges related words
transitively (connected components, i.e. union-find) into one bin whose count is the sum of its words,
``pooling="pairs"`` keeps one bin per word and adds the counts of each word's related words to it
(h' = h (I + A)). Words that never vary in training (e.g. never occur) are never grouped.
"""

from __future__ import annotations

import logging

import numpy as np
import scipy.sparse as sp
from sklearn.base import BaseEstimator, TransformerMixin

from ..errors import InputError, ParameterError

log = logging.getLogger(__name__)

NORMS = ("l1", "sqrt", "l2", "none")


def frame_word_counts(words: np.ndarray, frame_index: np.ndarray, n_frames: int, n_words: int) -> sp.csr_matrix:
    """(n_frames, n_words) counts of each word in each frame."""
    words = np.asarray(words, np.int64)
    frame_index = np.asarray(frame_index, np.int64)
    data = np.ones(words.size, np.float32)
    m = sp.coo_matrix((data, (frame_index, words)), shape=(n_frames, n_words))
    return m.tocsr()  # duplicates are summed


def context_sum(counts: sp.spmatrix, context: int) -> sp.csr_matrix:
    """Row n of the result = sum of rows n-context .. n+context of ``counts`` (clipped at the ends)."""
    n = counts.shape[0]
    if context <= 0 or n == 0:
        return sp.csr_matrix(counts, dtype=np.float32)
    reach = min(context, n - 1)  # a video shorter than the window
    offsets = list(range(-reach, reach + 1))
    band = sp.diags([np.ones(n - abs(k), np.float32) for k in offsets], offsets, shape=(n, n), format="csr")
    return (band @ counts).tocsr().astype(np.float32)


def normalize_rows(H, norm: str) -> np.ndarray:
    """Dense float64 rows normalised by ``norm``: l1, sqrt (l1 then square root = Hellinger), l2, none.

    Rows without any word stay zero (a frame with no motion has no points)."""
    if norm not in NORMS:
        raise InputError(f"normalize: must be one of {', '.join(NORMS)}, got {norm!r}")
    X = H.toarray() if sp.issparse(H) else np.asarray(H)
    X = X.astype(np.float64, copy=True)
    if norm == "none":
        return X
    if norm in ("l1", "sqrt"):
        s = X.sum(axis=1, keepdims=True)
        X = np.divide(X, s, out=np.zeros_like(X), where=s > 0)
        return np.sqrt(X) if norm == "sqrt" else X
    s = np.sqrt((X * X).sum(axis=1, keepdims=True))
    return np.divide(X, s, out=np.zeros_like(X), where=s > 0)


class FrameFeaturizer(TransformerMixin, BaseEstimator):
    """Word ids of one video -> per-frame context histograms (sparse counts, not yet normalised)."""

    def __init__(self, n_words: int = 1000, context: int = 2):
        self.n_words = n_words
        self.context = context

    def fit(self, X=None, y=None):
        return self

    def transform_video(self, words: np.ndarray, frame_index: np.ndarray, n_frames: int) -> sp.csr_matrix:
        if self.context < 0:
            raise ParameterError("context", f"must be >= 0, got {self.context}")
        counts = frame_word_counts(words, frame_index, n_frames, self.n_words)
        return context_sum(counts, self.context)

    def transform(self, X):
        """``X``: iterable of (words, frame_index, n_frames) -> list of sparse histograms."""
        return [self.transform_video(w, f, n) for (w, f, n) in X]


def _column_correlation(H: sp.spmatrix | np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Pearson correlation between the columns of H; (corr, valid) where valid = column varies."""
    n = H.shape[0]
    if sp.issparse(H):
        H = H.tocsc().astype(np.float64)
        gram = (H.T @ H).toarray()
        mean = np.asarray(H.mean(axis=0)).ravel()
    else:
        H = np.asarray(H, np.float64)
        gram = H.T @ H
        mean = H.mean(axis=0)
    cov = gram / n - np.outer(mean, mean)
    var = np.diag(cov).copy()
    valid = var > 1e-12 * max(1.0, float(var.max(initial=0.0)))
    sd = np.sqrt(np.where(valid, var, 1.0))
    corr = cov / np.outer(sd, sd)
    corr[~valid, :] = 0.0
    corr[:, ~valid] = 0.0
    return corr, valid


class WordGrouping(TransformerMixin, BaseEstimator):
    """Pool the counts of contextually related words (see the module docstring).

    Learned: ``groups_`` (n_words,) group id of each word (components) and ``matrix_`` (n_words, n_out)
    sparse 0/1 pooling matrix; ``transform(H) = H @ matrix_``.
    """

    def __init__(self, threshold: float = 0.8, distribution: str = "frames", pooling: str = "components"):
        self.threshold = threshold
        self.distribution = distribution
        self.pooling = pooling

    def fit(self, H, y=None, groups=None):
        """``H``: (samples, n_words) training histograms; ``y``: class of each row (``"classes"``);
        ``groups``: video of each row (``"videos"``)."""
        if self.distribution not in ("frames", "videos", "classes"):
            raise InputError(f"distribution: must be frames, videos or classes, got {self.distribution!r}")
        if self.pooling not in ("components", "pairs"):
            raise InputError(f"pooling: must be components or pairs, got {self.pooling!r}")
        n_words = H.shape[1]
        D = H
        if self.distribution in ("videos", "classes"):
            key = groups if self.distribution == "videos" else y
            if key is None:
                raise InputError(f"WordGrouping(distribution={self.distribution!r}) needs per-row keys")
            _, inv = np.unique(np.asarray(key), return_inverse=True)
            agg = sp.csr_matrix((np.ones(len(inv)), (inv, np.arange(len(inv)))), shape=(inv.max() + 1, len(inv)))
            D = agg @ (H if sp.issparse(H) else sp.csr_matrix(H))
        corr, valid = _column_correlation(D)
        adj = (corr > self.threshold) & valid[:, None] & valid[None, :]
        np.fill_diagonal(adj, False)
        self.n_related_pairs_ = int(adj.sum() // 2)
        if self.pooling == "components":
            from scipy.sparse.csgraph import connected_components

            n_groups, labels = connected_components(sp.csr_matrix(adj), directed=False)
            self.groups_ = labels.astype(np.int32)
            self.matrix_ = sp.csr_matrix(
                (np.ones(n_words, np.float32), (np.arange(n_words), labels)), shape=(n_words, n_groups)
            )
        else:
            self.groups_ = np.arange(n_words, dtype=np.int32)
            self.matrix_ = (sp.identity(n_words, np.float32, format="csr") + sp.csr_matrix(adj, dtype=np.float32)).tocsr()
        sizes = np.bincount(self.groups_)
        self.n_groups_ = int(self.matrix_.shape[1])
        self.largest_group_ = int(sizes.max()) if sizes.size else 0
        self.n_features_in_ = n_words
        log.debug(
            "word grouping: %d related pairs, %d bins, largest group %d words",
            self.n_related_pairs_, self.n_groups_, self.largest_group_,
        )
        return self

    def transform(self, H):
        if H.shape[1] != self.n_features_in_:
            raise InputError(f"histograms: {H.shape[1]} words, the grouping was fitted on {self.n_features_in_}")
        out = H @ self.matrix_
        return sp.csr_matrix(out) if sp.issparse(H) else np.asarray(out)


class IdentityGrouping(WordGrouping):
    """No grouping (the ablation): every word is its own bin."""

    def __init__(self):
        super().__init__(threshold=np.inf)

    def fit(self, H, y=None, groups=None):
        n = H.shape[1]
        self.groups_ = np.arange(n, dtype=np.int32)
        self.matrix_ = sp.identity(n, np.float32, format="csr")
        self.n_related_pairs_ = 0
        self.n_groups_ = n
        self.largest_group_ = 1
        self.n_features_in_ = n
        return self
