"""Frame histograms over a context window, normalisation and word grouping."""

from __future__ import annotations

import numpy as np
import pytest

from vidstyle.recognition.histograms import (
    FrameFeaturizer,
    IdentityGrouping,
    WordGrouping,
    context_sum,
    frame_word_counts,
    normalize_rows,
)


def test_counts_and_context_against_brute_force(rng):
    n_frames, V = 30, 7
    fi = np.sort(rng.integers(0, n_frames, 200))
    fi = fi[(fi < 10) | (fi > 14)]  # frames 10..14 have no points
    words = rng.integers(0, V, fi.size)
    C = frame_word_counts(words, fi, n_frames, V).toarray()
    brute = np.zeros((n_frames, V))
    for f, w in zip(fi, words):
        brute[f, w] += 1
    assert np.array_equal(C, brute)
    for c in (0, 1, 2):
        H = context_sum(frame_word_counts(words, fi, n_frames, V), c).toarray()
        expect = np.stack([brute[max(0, n - c) : n + c + 1].sum(0) for n in range(n_frames)])
        assert np.array_equal(H, expect)
    H = FrameFeaturizer(V, 2).transform_video(words, fi, n_frames).toarray()
    assert H[12].sum() == 0  # frames 10..14 empty: frame 12's window 10..14 has nothing
    assert H[11].sum() == brute[9].sum()


def test_normalisations():
    H = np.array([[1.0, 3.0, 0.0], [0.0, 0.0, 0.0]])
    assert np.allclose(normalize_rows(H, "l1"), [[0.25, 0.75, 0], [0, 0, 0]])
    assert np.allclose(normalize_rows(H, "sqrt"), [[0.5, np.sqrt(0.75), 0], [0, 0, 0]])
    assert np.allclose(np.linalg.norm(normalize_rows(H, "l2")[0]), 1)
    assert np.array_equal(normalize_rows(H, "none"), H)


def test_perfectly_correlated_words_are_pooled(rng):
    n = 400
    base = rng.poisson(2.0, size=(n, 6)).astype(float)
    H = base.copy()
    H[:, 4] = base[:, 1] * 2  # word 4 is a scaled copy of word 1 -> correlation 1
    H[:, 5] = 0  # word 5 never occurs: no distribution, never grouped
    g = WordGrouping(threshold=0.9).fit(H)
    assert g.groups_[1] == g.groups_[4]
    assert len(set(g.groups_[[0, 1, 2, 3, 5]])) == 5
    assert g.n_groups_ == 5 and g.n_related_pairs_ == 1
    out = g.transform(H)
    assert out.shape == (n, 5)
    assert np.allclose(out[:, g.groups_[1]], H[:, 1] + H[:, 4])
    assert np.allclose(out.sum(1), H.sum(1))  # pooling keeps every count


def test_components_chain_but_pairs_do_not(rng):
    n = 2000
    z = rng.normal(size=(n, 3))
    # a-b correlated, b-c correlated, a-c less: components merge all three, pairs only neighbours
    a = z[:, 0]
    b = z[:, 0] + z[:, 1]
    c = z[:, 1] * 1.0 + 0.1 * z[:, 2]
    H = np.stack([a, b, c, z[:, 2] * 5], 1)
    corr = np.corrcoef(H.T)
    thr = 0.6
    assert corr[0, 1] > thr and corr[1, 2] > thr and corr[0, 2] < thr
    comp = WordGrouping(threshold=thr).fit(H)
    assert comp.groups_[0] == comp.groups_[1] == comp.groups_[2] != comp.groups_[3]
    pairs = WordGrouping(threshold=thr, pooling="pairs").fit(H)
    out = pairs.transform(H)
    assert np.allclose(out[:, 0], a + b)
    assert np.allclose(out[:, 1], a + b + c)
    assert np.allclose(out[:, 2], b + c)
    assert np.allclose(out[:, 3], H[:, 3])


def test_distribution_over_classes_and_videos(rng):
    H = rng.poisson(1.0, size=(60, 4)).astype(float)
    y = np.repeat([0, 1, 2], 20)
    H[y == 0, 0] += 5
    H[y == 0, 2] += 5  # words 0 and 2 both mark class 0
    g = WordGrouping(threshold=0.95, distribution="classes").fit(H, y=y)
    assert g.groups_[0] == g.groups_[2]
    with pytest.raises(Exception, match="per-row keys"):
        WordGrouping(distribution="videos").fit(H)


def test_identity_grouping(rng):
    H = rng.poisson(1.0, size=(10, 5)).astype(float)
    g = IdentityGrouping().fit(H)
    assert np.array_equal(g.transform(H), H)
