"""Vocabulary: MiniBatch, hierarchical tree and full k-means words of descriptors."""

from __future__ import annotations

import numpy as np
import pytest

from vidstyle.errors import InputError
from vidstyle.recognition.vocabulary import Vocabulary, _share, nearest_centre


def blobs(rng, k=12, d=16, n_per=80, spread=0.05):
    # 3 well-apart groups of k/3 blobs: a tree with branching 3 shares its leaves evenly among them
    centres = np.repeat(rng.normal(size=(3, d)) * 20, k // 3, axis=0) + rng.normal(size=(k, d)) * 3
    X = np.concatenate([c + spread * rng.normal(size=(n_per, d)) for c in centres]).astype(np.float32)
    y = np.repeat(np.arange(k), n_per)
    return X, y, centres


@pytest.mark.parametrize("method", ["minibatch", "hierarchical", "kmeans"])
def test_separated_blobs_get_one_word_each(rng, method):
    X, y, _ = blobs(rng)
    voc = Vocabulary(n_words=12, method=method, branching=3, random_state=0).fit(X)
    w = voc.transform(X)
    # every blob maps to a single word and different blobs to different words
    for k in range(12):
        assert len(set(w[y == k])) == 1
    assert len({w[y == k][0] for k in range(12)}) == 12


def test_tree_assignment_matches_exact_on_separated_data(rng):
    X, _, _ = blobs(rng, k=12)
    voc = Vocabulary(n_words=12, method="hierarchical", branching=3, random_state=0).fit(X)
    exact = nearest_centre(X, voc.cluster_centers_)
    assert np.array_equal(voc.transform(X), exact)


@pytest.mark.parametrize("n_words,branching", [(37, 4), (10, 10), (100, 10), (15, 2)])
def test_tree_has_exactly_n_words_leaves(rng, n_words, branching):
    X = rng.normal(size=(2000, 8)).astype(np.float32)
    voc = Vocabulary(n_words=n_words, method="hierarchical", branching=branching, random_state=0).fit(X)
    assert voc.n_words_ == n_words
    assert sorted(voc.tree_["word"][voc.tree_["word"] >= 0].tolist()) == list(range(n_words))
    w = voc.transform(X)
    assert w.min() >= 0 and w.max() < n_words


def test_share_is_proportional_and_complete():
    alloc = _share(100, np.array([500, 300, 200]))
    assert alloc.sum() == 100 and alloc.tolist() == [50, 30, 20]
    alloc = _share(10, np.array([100, 1, 1]))  # a child cannot get more leaves than descriptors
    assert alloc.sum() == 10 and alloc[1] == 1 and alloc[2] == 1


def test_nearest_centre_brute_force(rng):
    X = rng.normal(size=(300, 5))
    C = rng.normal(size=(17, 5))
    d = ((X[:, None, :] - C[None]) ** 2).sum(-1)
    assert np.array_equal(nearest_centre(X, C, chunk=64), d.argmin(1))


@pytest.mark.parametrize("method", ["minibatch", "hierarchical"])
def test_save_load_roundtrip_and_determinism(rng, tmp_path, method):
    X = rng.normal(size=(1500, 8)).astype(np.float32)
    a = Vocabulary(n_words=30, method=method, branching=5, random_state=3).fit(X)
    b = Vocabulary(n_words=30, method=method, branching=5, random_state=3).fit(X)
    assert np.array_equal(a.cluster_centers_, b.cluster_centers_)
    a.save(tmp_path / "v.npz", training_files=["x.npz"])
    c = Vocabulary.load(tmp_path / "v.npz")
    assert c.training_files_ == ["x.npz"]
    assert np.array_equal(a.transform(X), c.transform(X))
    assert c.get_params() == a.get_params()


def test_bad_inputs(rng, tmp_path):
    X = rng.normal(size=(100, 8)).astype(np.float32)
    voc = Vocabulary(n_words=5, random_state=0).fit(X)
    with pytest.raises(InputError, match="dimension 9"):
        voc.transform(rng.normal(size=(4, 9)))
    with pytest.raises(InputError, match="cannot make"):
        Vocabulary(n_words=500).fit(X)
    with pytest.raises(InputError, match="method"):
        Vocabulary(n_words=5, method="nope").fit(X)
    with pytest.raises(InputError, match="not found"):
        Vocabulary.load(tmp_path / "missing.npz")
    (tmp_path / "junk.npz").write_bytes(b"junk")
    with pytest.raises(InputError, match="junk.npz"):
        Vocabulary.load(tmp_path / "junk.npz")
    assert voc.transform(np.zeros((0, 8))).shape == (0,)
