"""Mirror-image training: the scovanner2007 descriptor of a left-right mirrored video is (nearly) a
permutation of the original's, and a recognizer trained with the mirror images recognises mirrored
performers (southpaws) that it never saw."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from tests.conftest import SEED
from vidstyle.features import scovanner2007 as S
from vidstyle.recognition import ActionRecognizer, Vocabulary
from vidstyle.recognition.io import VideoFeatures
from vidstyle.recognition.recognizer import mirrored_features


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


def _blob_video(rng, direction, T=16, H=48, W=64):
    """A textured blob crossing the frame rightwards, drifting ``direction`` (-1 up, 0 level, +1 down)."""
    tex = cv2.GaussianBlur(rng.random((H, W)), (0, 0), 1.0)
    r0, c0 = rng.uniform(18, 30), rng.uniform(8, 14)
    speed = rng.uniform(2.0, 3.0)
    t, r, c = np.meshgrid(np.arange(T), np.arange(H), np.arange(W), indexing="ij")
    inside = (r - r0 - direction * 1.5 * t) ** 2 + (c - c0 - speed * t) ** 2 <= rng.uniform(40, 70)
    vol = np.where(inside, 0.5 + 0.4 * np.roll(tex, (0, 0)), 0.15 + 0.05 * tex[None])
    return np.ascontiguousarray(vol, dtype=np.float64)


def _features(vol, name):
    """scovanner2007 descriptors at the salient points of a volume (the features stage's own pieces)."""
    from vidstyle.features.salient import SalientParams, salient_points

    pts = salient_points(vol.astype(np.float32), SalientParams(n_points=10, threshold=0.05, min_distance=3.0))
    pts = pts[(pts[:, 0] >= 4) & (pts[:, 0] < vol.shape[0] - 4)]
    desc = S.quantise(S.histograms(vol, pts))
    return VideoFeatures(desc, pts[:, 0], vol.shape[0], video=name, path=name, variant="scovanner2007")


@pytest.mark.slow
def test_mirror_training_recognises_mirrored_videos():
    """Train on blobs moving right (three drift classes); test on *flipped videos* (moving left), whose
    features are computed from the flipped pixels, not with the mirror permutation under test. Mirror
    training must recognise them; training without it must not."""
    rng = np.random.default_rng(SEED)
    classes = ["Up", "Level", "Down"]
    train, test = [], []
    for k in range(8):
        for ci, d in enumerate((-1, 0, 1)):
            vol = _blob_video(rng, d)
            if k < 5:
                train.append((_features(vol, f"train{k}_{ci}"), ci))
            else:
                test.append((_features(vol[:, :, ::-1].copy(), f"flipped{k}_{ci}"), ci))
    lab = lambda items: [[classes[c]] * f.n_frames for f, c in items]  # noqa: E731
    voc = Vocabulary(n_words=40, random_state=SEED).fit(np.concatenate([f.descriptors for f, _ in train]))
    acc = {}
    for mirror in (False, True):
        rec = ActionRecognizer(vocabulary=voc, n_components=16, context=1, mirror=mirror, grouping=False,
                               random_state=SEED)
        rec.fit([f for f, _ in train], lab(train), classes=classes)
        assert rec.n_mirrored_videos_ == (len(train) if mirror else 0)
        frames = [(f.frame_index.min(), f.frame_index.max()) for f, _ in test]
        hits = total = 0
        for (f, c), (a, b) in zip(test, frames):
            pred = rec.predict(f)[a : b + 1]  # frames with points (the others have empty histograms)
            hits += (pred == classes[c]).sum()
            total += len(pred)
        acc[mirror] = hits / total
    print("mirror accuracy", acc)
    assert acc[True] > 0.8 and acc[True] > acc[False] + 0.2, acc
