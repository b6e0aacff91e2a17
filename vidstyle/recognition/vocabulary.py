"""Visual vocabulary: k-means "words" of 3D SIFT descriptors (thesis 4.1).

Three methods, one estimator:

- ``"minibatch"``: :class:`sklearn.cluster.MiniBatchKMeans`; exact nearest-centre assignment.
- ``"hierarchical"``: a vocabulary tree (Nister & Stewenius 2006 style): k-means with ``branching``
  clusters, recursively, until the leaves number ``n_words``. Leaves are shared out among the children
  in proportion to how many descriptors each child holds, so any ``n_words`` (500, 1000, 1500) works, not
  only powers of ``branching``. Assignment descends the tree (``branching`` distances per level instead of
  ``n_words``), which is approximate; ``assign="exact"`` uses the nearest leaf instead.
- ``"kmeans"``: full Lloyd k-means (:class:`sklearn.cluster.KMeans`), the slow reference in benchmarks.

File (``vocab.npz``): ``centres`` (n_words, d) float32, ``method``, ``params`` (JSON), ``dim``,
``descriptor_dtype``, ``training_files`` (JSON list), ``n_descriptors``, ``seed``; for the tree also
``tree_centres`` (nodes, d), ``tree_child_start``, ``tree_child_count``, ``tree_word`` (word id of a leaf
node, -1 for inner nodes); node 0 is the root and the children of a node are contiguous.
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Sequence

import numpy as np
from sklearn.base import BaseEstimator, TransformerMixin

from ..errors import InputError, ParameterError

log = logging.getLogger(__name__)

METHODS = ("minibatch", "hierarchical", "kmeans")


def nearest_centre(x: np.ndarray, centres: np.ndarray, chunk: int = 8192) -> np.ndarray:
    """Index of the nearest centre (squared Euclidean) for every row of ``x``, in chunks (bounded memory)."""
    x = np.asarray(x, dtype=np.float32)
    c = np.asarray(centres, dtype=np.float32)
    c2 = np.einsum("ij,ij->i", c, c)
    out = np.empty(x.shape[0], dtype=np.int32)
    for s in range(0, x.shape[0], chunk):
        xs = x[s : s + chunk]
        # ||x||^2 is constant per row, so it does not change the argmin
        d = c2[None, :] - 2.0 * (xs @ c.T)
        out[s : s + chunk] = np.argmin(d, axis=1)
    return out


class Vocabulary(TransformerMixin, BaseEstimator):
    """k-means words of descriptors; ``transform(descriptors) -> word ids``.

    Parameters
    ----------
    n_words: number of words (cluster centres).
    method: ``"minibatch"``, ``"hierarchical"`` or ``"kmeans"``.
    branching: children per tree node (hierarchical).
    batch_size: MiniBatchKMeans batch size (larger = closer to full k-means, slower).
    max_iter: iterations of each k-means (MiniBatch: epochs over the data).
    max_descriptors: fit on at most this many descriptors, sampled uniformly (None = all).
    assign: ``"tree"`` (descend the tree; hierarchical only) or ``"exact"`` (nearest word).
    """

    def __init__(
        self,
        n_words: int = 1000,
        method: str = "minibatch",
        branching: int = 10,
        batch_size: int = 1024,
        max_iter: int = 10,
        max_descriptors: int | None = 100_000,
        assign: str = "tree",
        random_state: int | None = 0,
    ):
        self.n_words = n_words
        self.method = method
        self.branching = branching
        self.batch_size = batch_size
        self.max_iter = max_iter
        self.max_descriptors = max_descriptors
        self.assign = assign
        self.random_state = random_state

    # ------------------------------------------------------------------ fit
    def fit(self, X, y=None):
        if self.method not in METHODS:
            raise ParameterError("method", f"must be one of {', '.join(METHODS)}, got {self.method!r}")
        if self.assign not in ("tree", "exact"):
            raise ParameterError("assign", f"must be 'tree' or 'exact', got {self.assign!r}")
        X = np.asarray(X)
        if X.ndim != 2 or X.shape[0] == 0:
            raise InputError(f"descriptors: need a non-empty (n, d) array, got shape {X.shape}")
        rng = np.random.default_rng(self.random_state)
        self.descriptor_dtype_ = str(X.dtype)
        if self.max_descriptors is not None and X.shape[0] > self.max_descriptors:
            X = X[np.sort(rng.choice(X.shape[0], self.max_descriptors, replace=False))]
        X = np.ascontiguousarray(X, dtype=np.float32)
        n_words = int(self.n_words)
        if n_words < 2:
            raise ParameterError("n_words", f"need at least 2 words, got {n_words}")
        if X.shape[0] < n_words:
            raise InputError(f"descriptors: {X.shape[0]} descriptors cannot make {n_words} words")
        self.n_fit_descriptors_ = int(X.shape[0])
        seed = int(rng.integers(2**31 - 1))
        if self.method == "minibatch":
            from sklearn.cluster import MiniBatchKMeans

            km = MiniBatchKMeans(
                n_clusters=n_words,
                batch_size=self.batch_size,
                max_iter=self.max_iter,
                n_init=1,
                init="k-means++",
                # k-means++ over 3x the words is enough to seed them and is where MiniBatch spends its time
                init_size=min(X.shape[0], 3 * n_words),
                random_state=seed,
                reassignment_ratio=0.01,
                compute_labels=False,
            ).fit(X)
            self.cluster_centers_ = km.cluster_centers_.astype(np.float32)
            self.tree_ = None
        elif self.method == "kmeans":
            from sklearn.cluster import KMeans

            km = KMeans(n_clusters=n_words, n_init=1, max_iter=self.max_iter, random_state=seed).fit(X)
            self.cluster_centers_ = km.cluster_centers_.astype(np.float32)
            self.tree_ = None
        else:
            if self.branching < 2:
                raise ParameterError("branching", f"must be >= 2, got {self.branching}")
            self.tree_ = _build_tree(X, n_words, self.branching, self.max_iter, np.random.default_rng(seed))
            leaves = self.tree_["word"] >= 0
            centres = np.empty((int(leaves.sum()), X.shape[1]), np.float32)
            centres[self.tree_["word"][leaves]] = self.tree_["centres"][leaves]
            self.cluster_centers_ = centres
        self.n_features_in_ = int(X.shape[1])
        return self

    # ------------------------------------------------------------ transform
    def transform(self, X) -> np.ndarray:
        X = np.asarray(X)
        if X.ndim != 2:
            raise InputError(f"descriptors: must be 2-D, got shape {X.shape}")
        if X.shape[1] != self.n_features_in_:
            raise InputError(
                f"descriptors: dimension {X.shape[1]} does not match the vocabulary's {self.n_features_in_}"
            )
        if X.shape[0] == 0:
            return np.zeros(0, np.int32)
        X = np.ascontiguousarray(X, dtype=np.float32)
        if self.tree_ is not None and self.assign == "tree":
            return _descend(self.tree_, X)
        return nearest_centre(X, self.cluster_centers_)

    def predict(self, X) -> np.ndarray:
        return self.transform(X)

    @property
    def n_words_(self) -> int:
        return int(self.cluster_centers_.shape[0])

    # ------------------------------------------------------------------ I/O
    def save(self, path: str | Path, training_files: Sequence[str] = (), extra: dict | None = None) -> None:
        """Write the fitted vocabulary (:func:`vidstyle.formats.vocabulary.write_vocabulary`)."""
        from ..formats.vocabulary import write_vocabulary

        write_vocabulary(path, self.to_record(training_files, extra))

    def to_record(self, training_files: Sequence[str] = (), extra: dict | None = None):
        """The :class:`~vidstyle.formats.vocabulary.VocabularyRecord` of the fitted vocabulary."""
        from ..formats.vocabulary import VocabularyRecord

        return VocabularyRecord(
            centres=self.cluster_centers_, params=self.get_params(), dim=int(self.n_features_in_),
            descriptor_dtype=self.descriptor_dtype_, n_descriptors=int(self.n_fit_descriptors_),
            training_files=[str(f) for f in training_files], extra=dict(extra or {}), seed=self.random_state,
            tree=self.tree_, method=self.method,
        )

    @classmethod
    def from_record(cls, record, path: str | Path | None = None) -> "Vocabulary":
        """The fitted vocabulary of a :class:`~vidstyle.formats.vocabulary.VocabularyRecord`."""
        from ..errors import FormatError

        try:
            voc = cls(**record.params)
        except TypeError as e:
            raise FormatError(path, "params", f"not the parameters of a vocabulary ({e})") from None
        voc.cluster_centers_ = record.centres.astype(np.float32)
        voc.n_features_in_ = int(record.dim)
        voc.descriptor_dtype_ = str(record.descriptor_dtype)
        voc.n_fit_descriptors_ = int(record.n_descriptors)
        voc.training_files_ = list(record.training_files)
        voc.extra_ = dict(record.extra)
        voc.tree_ = record.tree
        return voc

    @classmethod
    def load(cls, path: str | Path) -> "Vocabulary":
        """Read a vocabulary file (:func:`vidstyle.formats.vocabulary.read_vocabulary`)."""
        from ..formats.vocabulary import read_vocabulary

        return cls.from_record(read_vocabulary(path), path)


# ---------------------------------------------------------------------- tree
def _kmeans(X: np.ndarray, k: int, max_iter: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """Small k-means for one tree node; returns (centres, labels)."""
    from sklearn.cluster import KMeans, MiniBatchKMeans

    seed = int(rng.integers(2**31 - 1))
    if X.shape[0] > 20_000:
        # big upper nodes: mini-batches are enough to place ~10 coarse centres
        km = MiniBatchKMeans(k, batch_size=4096, n_init=3, max_iter=max_iter, random_state=seed).fit(X)
    else:
        km = KMeans(k, n_init=1, max_iter=max_iter, random_state=seed).fit(X)
    return km.cluster_centers_.astype(np.float32), km.labels_.astype(np.int64)


def _share(k: int, sizes: np.ndarray) -> np.ndarray:
    """Split ``k`` leaves among children in proportion to their sizes (each >= 1, never more than its size)."""
    m = len(sizes)
    alloc = np.ones(m, np.int64)
    rest = k - m
    if rest > 0:
        w = sizes.astype(float) - 1
        w = np.maximum(w, 0)
        if w.sum() == 0:
            w = np.ones(m)
        ideal = rest * w / w.sum()
        add = np.floor(ideal).astype(np.int64)
        # largest remainders get the leaves left over
        left = rest - add.sum()
        order = np.argsort(-(ideal - add), kind="stable")
        add[order[:left]] += 1
        alloc += add
    alloc = np.minimum(alloc, np.maximum(sizes, 1))
    # leaves lost to the size cap go to the children with the most room
    short = k - alloc.sum()
    while short > 0:
        room = sizes - alloc
        j = int(np.argmax(room))
        if room[j] <= 0:
            break
        alloc[j] += 1
        short -= 1
    return alloc


def _build_tree(X: np.ndarray, n_words: int, branching: int, max_iter: int, rng: np.random.Generator) -> dict:
    centres: list[np.ndarray] = [X.mean(axis=0)]
    child_start: list[int] = [-1]
    child_count: list[int] = [0]
    word: list[int] = [-1]
    next_word = 0
    # breadth-first so that node ids grow level by level and children stay contiguous
    queue: list[tuple[int, np.ndarray, int]] = [(0, np.arange(X.shape[0]), n_words)]
    while queue:
        node, idx, k = queue.pop(0)
        if k <= 1:
            word[node] = next_word
            next_word += 1
            continue
        kk = min(k, branching)
        c, lab = _kmeans(X[idx], kk, max_iter, rng)
        sizes = np.bincount(lab, minlength=kk)
        keep = np.flatnonzero(sizes > 0)  # k-means can leave a centre empty; drop it
        c, sizes = c[keep], sizes[keep]
        remap = np.full(kk, -1)
        remap[keep] = np.arange(len(keep))
        lab = remap[lab]
        alloc = np.ones(len(keep), np.int64) if k <= branching else _share(k, sizes)
        if alloc.sum() < k and k <= branching:
            alloc = _share(k, sizes)
        first = len(centres)
        child_start[node] = first
        child_count[node] = len(keep)
        for j in range(len(keep)):
            centres.append(c[j])
            child_start.append(-1)
            child_count.append(0)
            word.append(-1)
        for j in range(len(keep)):
            queue.append((first + j, idx[lab == j], int(alloc[j])))
    tree = {
        "centres": np.asarray(centres, np.float32),
        "child_start": np.asarray(child_start, np.int32),
        "child_count": np.asarray(child_count, np.int32),
        "word": np.asarray(word, np.int32),
    }
    if next_word != n_words:
        # only when k-means emptied clusters or nodes ran out of descriptors; keep ids dense
        log.warning("vocabulary tree has %d leaves instead of %d", next_word, n_words)
    return tree


def _descend(tree: dict, X: np.ndarray) -> np.ndarray:
    centres, start, count, word = tree["centres"], tree["child_start"], tree["child_count"], tree["word"]
    node = np.zeros(X.shape[0], np.int64)
    active = np.flatnonzero(word[node] < 0)
    while active.size:
        cur = node[active]
        for n in np.unique(cur):
            sel = active[cur == n]
            s, m = int(start[n]), int(count[n])
            node[sel] = s + nearest_centre(X[sel], centres[s : s + m])
        active = active[word[node[active]] < 0]
    return word[node].astype(np.int32)
