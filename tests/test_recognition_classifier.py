"""One-vs-all + one-vs-one SVMs: claim resolution, packed decision values, a separable problem."""

from __future__ import annotations

from itertools import combinations

import numpy as np
import pytest
from sklearn.svm import SVC

from vidstyle.errors import InputError
from vidstyle.recognition.classifier import OvaOvoSVC, OvrSVC, combine_ova_ovo, rbf_kernel

PAIRS3 = list(combinations(range(3), 2))  # (0,1), (0,2), (1,2)


def test_single_claim_wins_regardless_of_ovo():
    ova = np.array([[-1.0, 0.5, -0.2]])
    ovo = np.array([[5.0, 5.0, -5.0]])  # the duels would all say class 0, but only class 1 claimed
    pred, stats = combine_ova_ovo(ova, ovo, PAIRS3)
    assert pred.tolist() == [1] and stats["single_claim"] == 1


def test_two_claims_settled_by_their_duel():
    ova = np.array([[0.9, 0.2, -1.0], [0.9, 0.2, -1.0]])
    # pair (0,1): > 0 means class 0; the duel overrides the larger one-vs-all value in row 1
    ovo = np.array([[1.0, 0.0, 0.0], [-1.0, 0.0, 0.0]])
    pred, stats = combine_ova_ovo(ova, ovo, PAIRS3)
    assert pred.tolist() == [0, 1] and stats["multi_claim"] == 2


def test_no_claim_top_two_duel():
    ova = np.array([[-0.1, -0.5, -0.2]])  # nobody claims: top two are classes 0 and 2
    ovo = np.array([[9.0, -1.0, 9.0]])  # (0,2) < 0 -> class 2; (0,1) and (1,2) must be ignored
    pred, stats = combine_ova_ovo(ova, ovo, PAIRS3)
    assert pred.tolist() == [2] and stats["no_claim"] == 1


def test_three_way_cycle_goes_to_higher_ova():
    ova = np.array([[0.3, 0.8, 0.5]])
    ovo = np.array([[1.0, -1.0, 1.0]])  # 0 beats 1, 2 beats 0, 1 beats 2: one win each
    pred, _ = combine_ova_ovo(ova, ovo, PAIRS3)
    assert pred.tolist() == [1]
    ovo = np.array([[1.0, 1.0, 1.0]])  # 0 beats both
    assert combine_ova_ovo(ova, ovo, PAIRS3)[0].tolist() == [0]


def test_packed_decisions_equal_sklearn(rng):
    X = rng.normal(size=(240, 5))
    y = rng.integers(0, 3, 240)
    X[np.arange(240), y] += 2.0
    clf = OvaOvoSVC(C=3.0).fit(X, y)
    Xt = rng.normal(size=(50, 5))
    ova, ovo = clf.decision_values(Xt)
    for k, svc in enumerate(clf.ova_):
        assert np.allclose(ova[:, k], svc.decision_function(Xt), atol=1e-9)
    for p, svc in enumerate(clf.ovo_):
        assert np.allclose(ovo[:, p], svc.decision_function(Xt), atol=1e-9)
    # an independent check of the pair convention: retrain pair (0, 2) in sklearn, class 0 positive
    i, j = clf.pairs_[1]
    m = (y == i) | (y == j)
    ref = SVC(C=3.0, gamma=clf.gamma_).fit(X[m], y[m] == i)
    assert np.allclose(ovo[:, 1], ref.decision_function(Xt), atol=1e-9)
    assert np.allclose(rbf_kernel(Xt[:3], X[:4], 0.5), np.exp(-0.5 * ((Xt[:3, None] - X[None, :4]) ** 2).sum(-1)))


@pytest.mark.parametrize("cls", [OvaOvoSVC, OvrSVC])
def test_separable_problem(rng, cls):
    K, d = 5, 8
    centres = rng.normal(size=(K, d)) * 4
    y = np.repeat(np.arange(K), 60)
    X = centres[y] + rng.normal(size=(len(y), d))
    yt = np.repeat(np.arange(K), 40)
    Xt = centres[yt] + rng.normal(size=(len(yt), d))
    clf = cls().fit(X, y)
    assert (clf.predict(Xt) == yt).mean() >= 0.98
    pred, scores, conf = clf.predict_with_scores(Xt)
    assert np.allclose(scores.sum(1), 1) and np.allclose(conf, scores[np.arange(len(pred)), pred])


def test_needs_two_classes(rng):
    with pytest.raises(InputError, match="at least 2"):
        OvaOvoSVC().fit(rng.normal(size=(10, 2)), np.zeros(10))


def test_kernel_cache_changes_speed_not_the_machines(rng, monkeypatch):
    # 1500 frames: the whole kernel (~9 MB as libsvm's float rows) overflows a 0.5 MB cache many times over
    X = rng.normal(size=(1500, 6))
    y = rng.integers(0, 3, 1500)
    X[np.arange(1500), y] += 1.0
    small = OvaOvoSVC(C=10.0, cache_size=0.5).fit(X, y)
    large = OvaOvoSVC(C=10.0, cache_size=200.0).fit(X, y)
    assert np.array_equal(small.support_vectors_, large.support_vectors_)
    assert np.allclose(small.dual_coef_, large.dual_coef_, atol=1e-9)
    assert np.allclose(small.intercept_, large.intercept_, atol=1e-9)
    # the default divides the budget among the machines trained at once
    import vidstyle.recognition.classifier as classifier
    from vidstyle.recognition.defaults import SVM_CACHE_MB

    seen = []
    real = classifier._fit_binary
    monkeypatch.setattr(classifier, "_fit_binary", lambda *a: seen.append(a[-1]) or real(*a))
    OvaOvoSVC(n_jobs=2).fit(X[:90], y[:90])
    assert seen and set(seen) == {SVM_CACHE_MB / 2}
    with pytest.raises(InputError, match="cache_size"):
        OvaOvoSVC(cache_size=0).fit(X[:90], y[:90])
