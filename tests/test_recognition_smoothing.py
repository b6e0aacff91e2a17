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


def test_viterbi_removes_short_runs_and_keeps_boundaries():
    from vidstyle.recognition.smoothing import transition_matrix, viterbi

    # training chain: long runs of 0 then 1 -> sticky transitions
    T = transition_matrix([np.array([0] * 50 + [1] * 50)], 2)
    assert T[0, 0] > 0.9 and np.allclose(T.sum(1), 1)
    # scores favour 0 for 20 frames, then 1 for 20, with a 2-frame blip of 1 inside the 0 run
    s = np.full((40, 2), 0.3)
    s[:20, 0] = 0.7
    s[20:, 1] = 0.7
    s[5:7] = [0.4, 0.6]
    raw = np.argmax(s, axis=1)
    out, conf = smooth_labels(raw, 2, window=6, scores=s, method="viterbi", transitions=T)
    assert (out[:20] == 0).all() and (out[20:] == 1).all()
    assert conf.shape == (40,)
    # brute force over every path of a tiny problem agrees with the dynamic programme
    import itertools

    rng = np.random.default_rng(0)
    le, lt = np.log(rng.random((6, 3))), np.log(rng.random((3, 3)))
    best = max(itertools.product(range(3), repeat=6),
               key=lambda p: sum(le[t, p[t]] for t in range(6)) + sum(lt[p[t], p[t + 1]] for t in range(5)))
    assert tuple(viterbi(le, lt)) == best
    # window <= 1 is "no smoothing" for every method
    same, _ = smooth_labels(raw, 2, window=1, scores=s, method="viterbi", transitions=T)
    assert (same == raw).all()
