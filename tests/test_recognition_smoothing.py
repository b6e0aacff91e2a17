"""Smoothing of frame labels over a window (thesis: 6 frames)."""

from __future__ import annotations

import numpy as np

from vidstyle.recognition.smoothing import smooth_labels


def test_isolated_errors_are_removed():
    seq = np.array([0] * 8 + [1] + [0] * 8 + [2, 2] + [0] * 5)
    out, _ = smooth_labels(seq, 3, window=6)
    assert np.array_equal(out, np.zeros_like(seq))


def test_window_one_is_identity():
    seq = np.array([0, 1, 0, 2])
    out, conf = smooth_labels(seq, 3, window=1, confidence=np.array([0.1, 0.2, 0.3, 0.4]))
    assert np.array_equal(out, seq) and np.allclose(conf, [0.1, 0.2, 0.3, 0.4])


def test_window_layout_and_boundaries():
    # window 4 at frame n covers n-2 .. n+1
    seq = np.array([0, 0, 1, 1, 1, 1, 0, 0])
    out, _ = smooth_labels(seq, 2, window=4)
    # frame 1: frames 0..2 -> 0,0,1 -> 0; frame 2: 0..3 -> 0,0,1,1 tie -> class 0 (equal confidence, lower index)
    # frame 3: 1..4 -> 0,1,1,1 -> 1; frame 6: 4..7 -> 1,1,0,0 tie -> 0; frame 7: 5..7 -> 1,0,0 -> 0
    assert out.tolist() == [0, 0, 0, 1, 1, 1, 0, 0]


def test_vote_ties_go_to_higher_summed_confidence():
    seq = np.array([0, 0, 1, 1])
    conf = np.array([0.5, 0.5, 0.9, 0.9])
    out, sconf = smooth_labels(seq, 2, window=4, confidence=conf)
    # frame 2 sees frames 0..3: two votes each, class 1 has the higher confidence sum
    assert out[2] == 1
    assert np.isclose(sconf[2], 0.9)
    conf2 = np.array([0.9, 0.9, 0.5, 0.5])
    out2, _ = smooth_labels(seq, 2, window=4, confidence=conf2)
    assert out2[2] == 0


def test_mean_of_scores():
    scores = np.array([[0.6, 0.4], [0.6, 0.4], [0.1, 0.9], [0.6, 0.4], [0.6, 0.4]])
    labels = scores.argmax(1)
    out, conf = smooth_labels(labels, 2, window=3, scores=scores, method="mean")
    # windows of frames 1, 2, 3 all hold the confident 0.9: class-1 mean (0.4+0.9+0.4)/3 = 0.567 > 0.433;
    # frames 0 and 4 (windows 0..1 and 3..4, clipped) do not
    assert out.tolist() == [0, 1, 1, 1, 0]
    assert np.isclose(conf[2], (0.4 + 0.9 + 0.4) / 3)
