"""Explicit-duration smoother (smoothing "duration"): Viterbi over the state-expanded HMM against a
brute-force search over every label sequence of a tiny problem, scored directly from the run-length
distributions (not from the expanded chain's hazards)."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from vidstyle.recognition.smoothing import (DurationModel, duration_model, duration_viterbi, label_runs,
                                            smooth_labels)


def _model(rng, K=3, D=(2, 3, 4)):
    pmf = np.zeros((K, max(D)))
    for k, d in enumerate(D):
        p = rng.random(d) + 0.05
        pmf[k, :d] = p / p.sum()
    change = rng.random((K, K)) + 0.05
    np.fill_diagonal(change, 0.0)
    change /= change.sum(axis=1, keepdims=True)
    return DurationModel(pmf, np.array(D), rng.uniform(0.2, 0.8, K), change, np.ones(K, np.int64))


def _score(labels, E, m: DurationModel, start: str) -> float:
    """log P(labels, emissions) with the first run starting at its best sub-state (``any``) or at its onset."""
    runs = label_runs(labels)
    K = m.n_classes
    total = float(E[np.arange(len(labels)), labels].sum())
    for (a, _, _), (b, _, _) in zip(runs[:-1], runs[1:]):
        total += np.log(m.change[a, b])
    for r, (k, d, _) in enumerate(runs[1:], start=1):
        total += np.log(m.length_pmf(k, d) if r < len(runs) - 1 else m.survival(k, d))
    k, d, _ = runs[0]
    one = len(runs) == 1
    if start == "onset":
        return total - np.log(K) + np.log(m.survival(k, d) if one else m.length_pmf(k, d))
    Dk = int(m.n_substates[k])
    mean = sum(m.survival(k, i + 1) for i in range(Dk - 1)) + m.survival(k, Dk) / (1 - m.tail[k])
    best = -np.inf
    for s in range(Dk):  # start sub-state s: frames s + 1 .. of the run already (s = Dk - 1: the tail)
        w = m.survival(k, s + 1) if s < Dk - 1 else m.survival(k, Dk) / (1 - m.tail[k])
        cont = (m.survival(k, s + d) if one else m.length_pmf(k, s + d)) / m.survival(k, s + 1)
        if cont > 0:
            best = max(best, np.log(w / mean) - np.log(K) + np.log(cont))
    return total + best


@pytest.mark.parametrize("start", ["any", "onset"])
@pytest.mark.parametrize("n", [1, 2, 5, 7])
def test_viterbi_matches_brute_force(rng, start, n):
    for _ in range(4):
        m = _model(rng)
        E = np.log(rng.dirichlet(np.ones(3), size=n))
        seqs = [np.array(s) for s in itertools.product(range(3), repeat=n)]
        scores = np.array([_score(s, E, m, start) for s in seqs])
        got = duration_viterbi(E, m, start=start)
        assert np.isclose(_score(got, E, m, start), scores.max(), rtol=0, atol=1e-9)


def test_short_runs_are_priced_by_their_duration():
    """A 2-frame flicker inside a long run goes when the class never lasts 2 frames, a real 8-frame run stays."""
    K = 2
    seqs = [np.array([0] * 30 + [1] * 8 + [0] * 30 + [1] * 8 + [0] * 30)]
    m = duration_model(seqs, K)
    s = np.full((90, K), 0.3)
    s[:, 0] = 0.7
    s[10:12] = [0.3, 0.7]   # flicker of 2 frames
    s[50:58] = [0.2, 0.8]   # a real run of 8
    out, _ = smooth_labels(s.argmax(1), K, 6, None, s, "duration", durations=m)
    want = np.zeros(90, int)
    want[50:58] = 1
    np.testing.assert_array_equal(out, want)
    assert m.n_runs.tolist() == [1, 2]  # complete runs only: the first and last 0-runs touch the ends


def test_duration_model_learns_the_lengths(rng):
    seqs = [np.concatenate([np.full(rng.integers(9, 12), 0), np.full(rng.integers(19, 22), 1)] * 6) for _ in range(5)]
    m = duration_model(seqs, 2, floor=0.0)
    mean0 = sum(d * m.length_pmf(0, d) for d in range(1, 200))
    mean1 = sum(d * m.length_pmf(1, d) for d in range(1, 300))
    assert 9 < mean0 < 12 and 18 < mean1 < 23
    assert np.isclose(sum(m.length_pmf(1, d) for d in range(1, 2000)), 1.0, atol=1e-6)
    np.testing.assert_allclose(m.change, [[0, 1], [1, 0]])


def test_label_runs():
    assert label_runs([0, 0, 1, 1, 1, 0]) == [(0, 2, False), (1, 3, True), (0, 1, False)]
    assert label_runs([]) == []
