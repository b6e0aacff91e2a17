"""Sequence models of the behaviour style: likelihoods against brute force, recovery of known chains."""

from __future__ import annotations

import itertools
import os

import numpy as np
import pytest
from sklearn.base import clone

from vidstyle.style.models import (
    ActionHMM,
    BigramModel,
    DurationModel,
    ModeHMM,
    forward_log_likelihood,
    stationary_distribution,
)
from vidstyle.style.ngram import jensen_shannon, ngram_counts, ngram_jsd
from vidstyle.style.synthetic import random_chain, sample_chain

SEED = int(os.environ.get("VIDSTYLE_TEST_SEED", "0"))


@pytest.fixture
def rng():
    print(f"VIDSTYLE_TEST_SEED={SEED}")
    return np.random.default_rng(SEED)


def _chain(rng, A=6):
    c = random_chain(rng, A)
    return c["start"], c["transition"]


def _seqs(rng, start, trans, n_seq, length):
    return [sample_chain(start, trans, length, rng) for _ in range(n_seq)]


def test_forward_matches_brute_force_enumeration(rng):
    K, A, T = 3, 4, 5
    start = rng.dirichlet(np.ones(K))
    trans = rng.dirichlet(np.ones(K), size=K)
    emis = rng.dirichlet(np.ones(A), size=K)
    obs = rng.integers(A, size=T)
    total = 0.0
    for path in itertools.product(range(K), repeat=T):
        p = start[path[0]] * emis[path[0], obs[0]]
        for t in range(1, T):
            p *= trans[path[t - 1], path[t]] * emis[path[t], obs[t]]
        total += p
    assert forward_log_likelihood(start, trans, emis, obs) == pytest.approx(np.log(total), rel=1e-10)


def test_forward_matches_hmmlearn(rng):
    from hmmlearn.hmm import CategoricalHMM

    K, A = 3, 5
    m = CategoricalHMM(n_components=K, n_features=A)
    m.startprob_ = rng.dirichlet(np.ones(K))
    m.transmat_ = rng.dirichlet(np.ones(K), size=K)
    m.emissionprob_ = rng.dirichlet(np.ones(A), size=K)
    obs = rng.integers(A, size=50)
    ours = forward_log_likelihood(m.startprob_, m.transmat_, m.emissionprob_, obs)
    assert ours == pytest.approx(m.score(obs[:, None]), rel=1e-9)


def test_bigram_error_shrinks_with_data(rng):
    start, trans = _chain(rng)
    maes = [np.abs(BigramModel(6).fit(_seqs(rng, start, trans, 4, n)).transition_ - trans).mean()
            for n in (50, 500, 5000)]
    assert maes[0] > maes[1] > maes[2]
    assert maes[2] < 0.02


def test_bigram_likelihood_is_closed_form():
    g = BigramModel(n_actions=3, alpha=1.0).fit([np.array([0, 1, 1, 2])])
    # start counts [1,0,0] +1 -> [2,1,1]/4; row 0: [0,1,0]+1 -> [1,2,1]/4; row 1: [0,1,1]+1 -> [1,2,2]/5
    expected = np.log(2 / 4) + np.log(2 / 4) + np.log(2 / 5) + np.log(2 / 5)
    assert g.score([np.array([0, 1, 1, 2])]) == pytest.approx(expected)
    assert g.log_likelihood_ == pytest.approx(expected)


def test_action_hmm_fixed_emission_reduces_to_counting(rng):
    start, trans = _chain(rng)
    seqs = _seqs(rng, start, trans, 3, 200)
    a = ActionHMM(6, learn_emission=False, random_state=0).fit(seqs)
    g = BigramModel(6).fit(seqs)
    np.testing.assert_allclose(a.transition_, g.transition_, atol=1e-4)
    assert a.score(seqs) == pytest.approx(g.score(seqs), rel=1e-4)


def test_action_hmm_tolerates_recognition_errors(rng):
    """States are true actions, emissions recognised ones: a learned confusion beats plain counting."""
    start, trans = _chain(rng)
    A = 6
    confusion = 0.8 * np.eye(A) + 0.2 * np.roll(np.eye(A), 1, axis=1)  # action i read as i+1, 20 %
    seqs = []
    for s in _seqs(rng, start, trans, 20, 300):
        seqs.append(np.array([rng.choice(A, p=confusion[x]) for x in s]))
    a = ActionHMM(A, n_init=2, n_iter=500, random_state=0).fit(seqs)
    g = BigramModel(A).fit(seqs)
    mae_a = np.abs(a.transition_ - trans).mean()
    mae_g = np.abs(g.transition_ - trans).mean()
    assert mae_a < 0.7 * mae_g
    assert np.abs(a.emission_ - confusion).mean() < 0.05
    assert np.all(np.diag(a.emission_) > 0.6)  # no label switching


def test_never_visited_state_gets_a_uniform_row():
    seqs = [np.array([0, 1, 2, 0, 1, 2, 1])]
    for model in (ActionHMM(n_actions=4, random_state=0), ModeHMM(n_modes=5, n_actions=4, random_state=0),
                  BigramModel(n_actions=4)):
        model.fit(seqs)
        for name in ("start_", "transition_", "emission_"):
            m = getattr(model, name, None)
            if m is not None:
                assert np.all(np.isfinite(m)), (type(model).__name__, name)
                np.testing.assert_allclose(m.sum(axis=-1), 1.0)
        t = model.action_transition()
        assert np.all(np.isfinite(t)) and np.allclose(t.sum(axis=1), 1.0)
        if not isinstance(model, ModeHMM):  # states are actions: the unseen action's row is uniform
            np.testing.assert_allclose(t[3], np.full(4, 0.25), atol=0.01)


def test_fits_are_deterministic_and_keep_the_best_restart(rng):
    start, trans = _chain(rng)
    seqs = _seqs(rng, start, trans, 3, 120)
    m1 = ModeHMM(n_modes=3, n_actions=6, n_init=3, random_state=7).fit(seqs)
    m2 = ModeHMM(n_modes=3, n_actions=6, n_init=3, random_state=7).fit(seqs)
    np.testing.assert_array_equal(m1.transition_, m2.transition_)
    np.testing.assert_array_equal(m1.emission_, m2.emission_)
    assert len(m1.restart_log_likelihoods_) == 3
    assert m1.log_likelihood_ == pytest.approx(max(m1.restart_log_likelihoods_))
    assert m1.score(seqs) == pytest.approx(m1.log_likelihood_, rel=1e-9)


def test_estimator_conventions():
    m = ModeHMM(k_range=(1, 2), n_init=2, random_state=3)
    assert m.get_params()["k_range"] == (1, 2)
    c = clone(m)
    assert c.get_params() == m.get_params() and not hasattr(c, "n_modes_")
    assert m.fit([np.array([0, 1, 0, 1, 1, 0, 2, 0])]) is m
    assert m.n_modes_ in (1, 2)


def _mode_data(rng, n_seq, length):
    """Two persistent modes whose action sets overlap: a first-order chain over actions cannot tell
    which mode emitted a shared action, a 2-mode HMM can."""
    emis = np.array([[0.25, 0.25, 0.25, 0.25, 0, 0], [0, 0, 0.25, 0.25, 0.25, 0.25]])
    trans = np.array([[0.95, 0.05], [0.05, 0.95]])
    out = []
    for _ in range(n_seq):
        z = rng.integers(2)
        s = []
        for _ in range(length):
            s.append(rng.choice(6, p=emis[z]))
            z = rng.choice(2, p=trans[z])
        out.append(np.array(s))
    return out


def test_mode_hmm_finds_hidden_modes_and_beats_bigram(rng):
    train, test = _mode_data(rng, 4, 150), _mode_data(rng, 4, 150)
    m = ModeHMM(k_range=(1, 2, 3, 4), n_actions=6, n_init=3, random_state=0).fit(train)
    assert m.n_modes_ >= 2
    g = BigramModel(6).fit(train)
    assert m.score_per_event(test) > g.score_per_event(test) + 0.05


def test_mode_selection_by_bic_prefers_one_mode_for_iid_data(rng):
    seqs = [rng.choice(4, p=[0.4, 0.3, 0.2, 0.1], size=200) for _ in range(3)]
    m = ModeHMM(k_range=(1, 2, 3), criterion="bic", n_actions=4, n_init=2, random_state=0).fit(seqs)
    assert m.n_modes_ == 1
    np.testing.assert_allclose(m.emission_[0], [0.4, 0.3, 0.2, 0.1], atol=0.05)


def test_mode_hmm_implied_transition_recovers_a_chain(rng):
    start, trans = _chain(rng)
    seqs = _seqs(rng, start, trans, 4, 500)
    m = ModeHMM(n_modes=6, n_actions=6, n_init=2, random_state=0).fit(seqs)
    assert np.abs(m.action_transition() - trans).mean() < 0.05


def test_sampling_is_deterministic_and_starts_where_asked(rng):
    start, trans = _chain(rng)
    seqs = _seqs(rng, start, trans, 2, 200)
    for model in (BigramModel(6).fit(seqs), ActionHMM(6, n_init=1, random_state=0).fit(seqs),
                  ModeHMM(n_modes=4, n_actions=6, n_init=1, random_state=0).fit(seqs)):
        a = model.sample(30, start=2, random_state=5)
        b = model.sample(30, start=2, random_state=5)
        assert a[0] == 2 and len(a) == 30 and np.array_equal(a, b)
        assert not np.array_equal(a, model.sample(30, start=2, random_state=6))
        with pytest.raises(ValueError):
            model.sample(3, start=6)


def test_samples_follow_the_learned_chain(rng):
    start, trans = _chain(rng)
    a = ActionHMM(6, n_init=1, random_state=0).fit(_seqs(rng, start, trans, 4, 1000))
    gen = [a.sample(2000, random_state=1)]
    assert np.abs(BigramModel(6).fit(gen).transition_ - trans).mean() < 0.03


def test_stationary_distribution():
    t = np.array([[0.9, 0.1], [0.5, 0.5]])
    np.testing.assert_allclose(stationary_distribution(t), [5 / 6, 1 / 6])


def test_duration_model_recovers_lognormal(rng):
    acts = rng.integers(3, size=3000)
    mu = np.log(np.array([8.0, 15.0, 30.0]))
    durs = np.exp(mu[acts] + 0.2 * rng.standard_normal(acts.size))
    d = DurationModel(n_actions=4).fit([acts], [durs])
    np.testing.assert_allclose(d.mu_[:3], mu, atol=0.02)
    np.testing.assert_allclose(d.sigma_[:3], 0.2, atol=0.02)
    assert d.count_[3] == 0 and np.isfinite(d.mu_[3])  # unseen action borrows the pooled fit
    s = d.sample(np.array([0, 1, 2, 3]), random_state=0)
    assert s.dtype.kind == "i" and np.all(s >= 1)


def test_jensen_shannon_properties(rng):
    p = {("a",): 3, ("b",): 1}
    q = {("b",): 2, ("c",): 2}
    assert jensen_shannon(p, p) == 0.0
    assert jensen_shannon(p, {k: 2 * v for k, v in p.items()}) == pytest.approx(0.0, abs=1e-12)
    assert jensen_shannon(p, q) == pytest.approx(jensen_shannon(q, p))
    assert jensen_shannon({"x": 1}, {"y": 1}) == pytest.approx(1.0)
    # against scipy (which returns the square root of the divergence)
    from scipy.spatial.distance import jensenshannon

    pv, qv = rng.dirichlet(np.ones(5)), rng.dirichlet(np.ones(5))
    ours = jensen_shannon(dict(enumerate(pv)), dict(enumerate(qv)))
    assert ours == pytest.approx(jensenshannon(pv, qv, base=2) ** 2, rel=1e-9)


def test_ngrams_do_not_span_sequences():
    c = ngram_counts([np.array([0, 1, 2]), np.array([3, 4])], 2)
    assert c == {(0, 1): 1, (1, 2): 1, (3, 4): 1}
    assert ngram_jsd([np.array([0, 1, 0, 1])], [np.array([1, 0, 1, 0])], 1) == 0.0
