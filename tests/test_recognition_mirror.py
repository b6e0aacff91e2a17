"""Mirror-image training: the scovanner2007 descriptor of a left-right mirrored video is (nearly) a
permutation of the original's, and a recognizer trained with the mirror images recognises mirrored
performers (southpaws) that it never saw."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from tests.conftest import SEED
from vidstyle.features import scovanner2007 as S
from vidstyle.formats.dataset import read_dataset as load_dataset
from vidstyle.formats.labels import read_labels as load_labels
from vidstyle.recognition import ActionRecognizer, Vocabulary, load_features
from vidstyle.recognition.io import VideoFeatures
from vidstyle.recognition.recognizer import mirrored_features
from vidstyle.recognition.splits import make_split
from vidstyle.recognition.synthetic import make_dataset


def test_mirror_permutation_is_an_involution_of_bins_and_subregions():
    perm = S.mirror_permutation()
    assert sorted(perm.tolist()) == list(range(S.DIM))
    np.testing.assert_array_equal(perm[perm], np.arange(S.DIM))  # mirroring twice is the identity
    bins = S.orientation_bins()
    for sub in range(8):
        k = np.arange(80)
        src = perm[sub * 80 + k]
        # column sub-region swapped, row and frame kept; bin direction reflected in g1
        assert np.all(src // 80 == sub ^ 1)
        np.testing.assert_allclose(bins[src % 80], bins[k] * [-1, 1, 1], atol=1e-12)


def test_permuted_descriptor_matches_the_flipped_video():
    rng = np.random.default_rng(SEED)
    vol = rng.random((20, 60, 80))
    vol = np.stack([cv2.GaussianBlur(f, (0, 0), 2) for f in vol])
    pts = np.stack([rng.integers(6, 14, 150), rng.integers(0, 60, 150), rng.integers(0, 80, 150)], 1)
    a = S.histograms(vol, pts)
    flipped = vol[:, :, ::-1].copy()
    pf = pts.copy()
    pf[:, 2] = 79 - pts[:, 2]
    b = S.histograms(flipped, pf)  # computed from the mirrored video itself

    def cos(x, y):
        return (x * y).sum(1) / np.linalg.norm(x, axis=1) / np.linalg.norm(y, axis=1)

    assert np.median(cos(a[:, S.mirror_permutation()], b)) > 0.95
    assert np.median(cos(a, b)) < 0.7  # without the permutation the descriptors disagree
    q = S.mirror_descriptors(S.quantise(a))
    assert q.dtype == np.uint8 and q.shape == (150, 640)
    with pytest.raises(ValueError):
        S.mirror_descriptors(np.zeros((3, 128)))


def test_mirrored_features_only_for_scovanner2007():
    v = VideoFeatures(np.zeros((4, 640), np.uint8), np.arange(4), 4, variant="scovanner2007")
    assert mirrored_features(v).descriptors.shape == (4, 640)
    assert mirrored_features(VideoFeatures(np.zeros((4, 256)), np.arange(4), 4, variant="thesis")) is None
    assert mirrored_features(VideoFeatures(np.zeros((4, 640)), np.arange(4), 4, variant="thesis")) is None


def test_mirror_training_recognises_unseen_mirrored_performers(tmp_path):
    make_dataset(tmp_path, n_performers=5, views=("front",), seed=SEED, dim=640, reps=(2, 3), n_actions=6)
    ds = load_dataset(tmp_path)
    split = make_split(ds, "unseen-performer", seed=SEED)
    feats = lambda ids: [load_features(tmp_path / "features" / f"{i}.npz") for i in ids]  # noqa: E731
    labels = lambda ids: [load_labels(tmp_path / "labels" / f"{i}.json").labels for i in ids]  # noqa: E731
    desc = np.concatenate([f.descriptors for f in feats(split.vocab)])
    voc = Vocabulary(n_words=120, random_state=SEED).fit(np.concatenate([desc, S.mirror_descriptors(desc)]))
    test = [mirrored_features(f) for f in feats(split.test)]  # the test performers, all mirrored
    truth = labels(split.test)
    acc = {}
    for mirror in (False, True):
        rec = ActionRecognizer(vocabulary=voc, n_components=48, mirror=mirror, random_state=SEED)
        rec.fit(feats(split.train), labels(split.train), classes=ds.classes)
        assert rec.n_mirrored_videos_ == (len(split.train) if mirror else 0)
        hits = sum((rec.predict(v) == np.asarray(t)).sum() for v, t in zip(test, truth))
        acc[mirror] = hits / sum(len(t) for t in truth)
    assert acc[True] > 0.8 and acc[True] > acc[False] + 0.2, acc
