"""Sequence models of how a performer chains actions.

All models follow the scikit-learn estimator contract: constructor arguments are stored as given,
``fit(sequences)`` returns ``self``, learned state ends in ``_``. ``sequences`` is a list of 1-D integer
arrays of action indices ``0 .. n_actions-1`` (or :class:`~vidstyle.style.events.EventSequence`).

* :class:`BigramModel` -- closed-form first-order Markov chain over actions, additive smoothing. The
  baseline: with fully observed actions, maximum likelihood for the thesis HMM *is* this count.
* :class:`ActionHMM` -- model (a), the thesis model (Chen 2012 sec. 4.4): hidden states are the true
  actions, transitions learned with EM. Emissions are the *recognised* actions: a confusion-like matrix
  with a strong diagonal Dirichlet prior, which is what lets the HMM tolerate recognition errors
  (sec. 3.1: "certain amounts of detection and segmentation errors are tolerated"). With
  ``learn_emission=False`` the emission is fixed near the identity and EM reduces to counting.
* :class:`ModeHMM` -- model (b): ``K`` hidden behaviour modes that emit actions; ``K`` chosen on
  held-out likelihood (inner cross-validation) or BIC.
* :class:`DurationModel` -- per-action log-normal duration (frames), so generated events carry rhythm.

hmmlearn pitfalls handled here: Dirichlet pseudo-counts on every row so never-visited states get a
smoothed (uniform) row instead of a zero/NaN row, any remaining non-finite row is replaced by uniform;
each fit runs ``n_init`` seeded restarts and keeps the best training log-likelihood; non-convergence
is logged and recorded in ``converged_``.
"""

from __future__ import annotations

import logging
import warnings
from collections.abc import Iterable, Sequence

import numpy as np
from sklearn.base import BaseEstimator

from ..errors import InputError

log = logging.getLogger(__name__)


# ----------------------------------------------------------------------------------------------------
# helpers


def as_int_sequences(sequences: Iterable, n_actions: int | None = None) -> list[np.ndarray]:
    """Validate sequences: each a non-empty 1-D array of action indices in ``[0, n_actions)``."""
    out = []
    for s in sequences:
        a = np.asarray(getattr(s, "actions", s))
        if a.ndim != 1:
            raise ValueError("each sequence must be 1-D")
        if a.size == 0:
            continue
        if not np.issubdtype(a.dtype, np.integer):
            raise ValueError("sequences must hold integer action indices")
        if a.min() < 0 or (n_actions is not None and a.max() >= n_actions):
            raise ValueError(f"action index out of range [0, {n_actions})")
        out.append(a.astype(np.int64))
    return out


def _n_actions_of(seqs: list[np.ndarray], n_actions: int | None) -> int:
    if n_actions is not None:
        return int(n_actions)
    return int(max(int(s.max()) for s in seqs) + 1)


def _rng(random_state) -> np.random.Generator:
    if isinstance(random_state, np.random.Generator):
        return random_state
    if isinstance(random_state, np.random.RandomState):
        return np.random.default_rng(random_state.randint(0, 2**31 - 1))
    return np.random.default_rng(random_state)


def _restart_seeds(random_state, n: int) -> list[int]:
    """``n`` independent integer seeds derived from ``random_state`` (an int seed gives fixed seeds)."""
    if isinstance(random_state, (np.random.Generator, np.random.RandomState)):
        base = int(_rng(random_state).integers(0, 2**31 - 1))
    else:
        base = random_state
    ss = np.random.SeedSequence(base)
    return [int(c.generate_state(1)[0]) for c in ss.spawn(n)]


def bigram_counts(seqs: Sequence[np.ndarray], n: int) -> tuple[np.ndarray, np.ndarray]:
    """(start counts (n,), transition counts (n, n)) of integer sequences."""
    start = np.zeros(n)
    trans = np.zeros((n, n))
    for s in seqs:
        start[s[0]] += 1
        np.add.at(trans, (s[:-1], s[1:]), 1)
    return start, trans


def normalise_rows(m: np.ndarray) -> np.ndarray:
    """Row-normalise; rows that sum to zero or hold non-finite values become uniform."""
    m = np.array(m, dtype=float)
    bad = ~np.all(np.isfinite(m), axis=-1) | (m.sum(axis=-1) <= 0)
    if np.any(bad):
        m[bad] = 1.0
    return m / m.sum(axis=-1, keepdims=True)


def forward_log_likelihood(
    start: np.ndarray, trans: np.ndarray, emission: np.ndarray, obs: np.ndarray
) -> float:
    """log P(obs) of a discrete HMM by the scaled forward recursion (Rabiner 1989, eq. 19-21, 91-93).

    ``start`` (K,), ``trans`` (K, K), ``emission`` (K, A), ``obs`` (T,) ints. alpha_t is renormalised
    every step and log P(obs) = sum_t log c_t, the log of the normalisers. -inf if impossible.
    """
    b = emission[:, obs].T  # (T, K)
    alpha = start * b[0]
    total = 0.0
    for t in range(len(obs)):
        if t:
            alpha = (alpha @ trans) * b[t]
        c = alpha.sum()
        if c <= 0:
            return -np.inf
        total += np.log(c)
        alpha = alpha / c
    return float(total)


def stationary_distribution(trans: np.ndarray) -> np.ndarray:
    """Left eigenvector of ``trans`` for eigenvalue 1, normalised (unique for an ergodic chain)."""
    w, v = np.linalg.eig(trans.T)
    pi = np.abs(np.real(v[:, np.argmin(np.abs(w - 1.0))]))
    return pi / pi.sum()


def _converged(m) -> bool:
    """hmmlearn's ``monitor_.converged`` is also true when ``n_iter`` ran out; this is not."""
    h = list(m.monitor_.history)
    return m.monitor_.iter < m.monitor_.n_iter or (len(h) >= 2 and abs(h[-1] - h[-2]) < m.monitor_.tol)


def _sample_categorical(rng: np.random.Generator, p: np.ndarray) -> int:
    return int(np.searchsorted(np.cumsum(p), rng.random() * p.sum(), side="right").clip(0, len(p) - 1))


# ----------------------------------------------------------------------------------------------------
# models


class _SequenceModel(BaseEstimator):
    """Shared scoring API. Subclasses define ``_seq_loglik(seq)`` and ``sample``."""

    def score(self, sequences) -> float:
        """Total log-likelihood (nats) of ``sequences``."""
        seqs = as_int_sequences(sequences, self.n_actions_)
        return float(sum(self._seq_loglik(s) for s in seqs))

    def score_per_event(self, sequences) -> float:
        """Mean log-likelihood per event (nats); comparable across models and data sizes."""
        seqs = as_int_sequences(sequences, self.n_actions_)
        n = sum(len(s) for s in seqs)
        if n == 0:
            raise ValueError("no events to score")
        return self.score(seqs) / n

    def _check_start(self, start: int | None) -> None:
        if start is not None and not 0 <= int(start) < self.n_actions_:
            raise ValueError(f"start action {start} out of range [0, {self.n_actions_})")


class BigramModel(_SequenceModel):
    """First-order Markov chain over actions: P(a_t | a_{t-1}) = (c_ij + alpha) / (c_i + n alpha)."""

    def __init__(self, n_actions: int | None = None, alpha: float = 0.5):
        self.n_actions = n_actions
        self.alpha = alpha

    def fit(self, sequences) -> BigramModel:
        seqs = as_int_sequences(sequences, self.n_actions)
        if not seqs:
            raise ValueError("no events to fit")
        n = _n_actions_of(seqs, self.n_actions)
        self.n_actions_ = n
        sc, tc = bigram_counts(seqs, n)
        self.start_counts_ = sc
        self.transition_counts_ = tc
        self.start_ = normalise_rows(sc + self.alpha)
        self.transition_ = normalise_rows(tc + self.alpha)
        self.n_events_ = int(sum(len(s) for s in seqs))
        self.log_likelihood_ = self.score(seqs)
        return self

    def _seq_loglik(self, s: np.ndarray) -> float:
        return float(np.log(self.start_[s[0]]) + np.log(self.transition_[s[:-1], s[1:]]).sum())

    def action_transition(self) -> np.ndarray:
        return self.transition_

    def sample(self, n: int, start: int | None = None, random_state=None) -> np.ndarray:
        self._check_start(start)
        rng = _rng(random_state)
        out = np.empty(n, dtype=np.int64)
        if n == 0:
            return out
        out[0] = _sample_categorical(rng, self.start_) if start is None else int(start)
        for t in range(1, n):
            out[t] = _sample_categorical(rng, self.transition_[out[t - 1]])
        return out


class _HMMBase(_SequenceModel):
    """An HMM with ``start_`` (K,), ``transition_`` (K, K), ``emission_`` (K, A) fitted with hmmlearn."""

    def _seq_loglik(self, s: np.ndarray) -> float:
        return forward_log_likelihood(self.start_, self.transition_, self.emission_, s)

    def _fit_hmmlearn(self, seqs, n_states, n_actions, inits, priors, params, seed):
        """Fit one hmmlearn CategoricalHMM from explicit initial values; returns (model, train loglik)."""
        from hmmlearn.hmm import CategoricalHMM

        start0, trans0, emis0 = inits
        sp, tp, ep = priors
        m = CategoricalHMM(
            n_components=n_states,
            n_features=n_actions,
            startprob_prior=sp,
            transmat_prior=tp,
            emissionprob_prior=ep,
            params=params,
            init_params="",
            n_iter=self.n_iter,
            tol=self.tol,
            random_state=np.random.RandomState(seed),
            implementation="scaling",
        )
        m.startprob_ = normalise_rows(start0)
        m.transmat_ = normalise_rows(trans0)
        m.emissionprob_ = normalise_rows(emis0)
        X = np.concatenate(seqs)[:, None]
        lengths = [len(s) for s in seqs]
        # hmmlearn's monitor warns when a MAP step lowers the plain likelihood; convergence is
        # recorded in ``converged_`` instead
        hl_log = logging.getLogger("hmmlearn")
        level = hl_log.level
        hl_log.setLevel(logging.ERROR)
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", RuntimeWarning)
                m.fit(X, lengths)
        finally:
            hl_log.setLevel(level)
        # a never-visited state whose row had no pseudo-counts would be zero/NaN: make it uniform
        m.startprob_ = normalise_rows(m.startprob_)
        m.transmat_ = normalise_rows(m.transmat_)
        m.emissionprob_ = normalise_rows(m.emissionprob_)
        ll = float(m.score(X, lengths))
        if not np.isfinite(ll):
            ll = -np.inf
        return m, ll

    def _keep(self, m, ll, lls, converged) -> None:
        self.start_ = m.startprob_.copy()
        self.transition_ = m.transmat_.copy()
        self.emission_ = m.emissionprob_.copy()
        self.log_likelihood_ = ll
        self.restart_log_likelihoods_ = lls
        self.converged_ = bool(converged)
        self.n_iter_ = int(m.monitor_.iter)
        if not self.converged_:
            (log.debug if getattr(self, "_quiet", False) else log.warning)(
                "%s: EM did not converge in %d iterations (tol %g); keeping the best of %d restarts",
                type(self).__name__, self.n_iter, self.tol, len(lls),
            )

    def _run_restarts(self, seqs, n_states, n_actions, init_fn, priors, params):
        best = None
        lls = []
        for r, seed in enumerate(_restart_seeds(self.random_state, self.n_init)):
            inits = init_fn(r, np.random.default_rng(seed))
            m, ll = self._fit_hmmlearn(seqs, n_states, n_actions, inits, priors, params, seed)
            lls.append(ll)
            log.debug("%s K=%d restart %d: loglik %.3f (converged %s)",
                      type(self).__name__, n_states, r, ll, _converged(m))
            if best is None or ll > best[1] + 1e-9:
                best = (m, ll)
        return best[0], best[1], lls


class ActionHMM(_HMMBase):
    """Model (a): hidden states = true actions; emissions = recognised actions.

    Parameters
    ----------
    alpha : Dirichlet pseudo-count added to every start/transition cell (smoothing; unvisited rows
        become uniform).
    learn_emission : learn the confusion-like emission matrix (else fixed at ``1 - 1e-6`` diagonal).
    emission_prior : pseudo-events per row of the emission prior, spread ``1 - emission_eps`` on the
        diagonal and ``emission_eps`` over the other actions: the strong diagonal keeps state ``i``
        meaning action ``i`` (no label switching) while letting EM learn systematic confusions.
    """

    def __init__(
        self,
        n_actions: int | None = None,
        alpha: float = 0.5,
        learn_emission: bool = True,
        emission_prior: float = 10.0,
        emission_eps: float = 0.05,
        n_init: int = 4,
        n_iter: int = 200,
        tol: float = 1e-3,
        random_state=None,
    ):
        self.n_actions = n_actions
        self.alpha = alpha
        self.learn_emission = learn_emission
        self.emission_prior = emission_prior
        self.emission_eps = emission_eps
        self.n_init = n_init
        self.n_iter = n_iter
        self.tol = tol
        self.random_state = random_state

    def fit(self, sequences) -> ActionHMM:
        seqs = as_int_sequences(sequences, self.n_actions)
        if not seqs:
            raise ValueError("no events to fit")
        A = _n_actions_of(seqs, self.n_actions)
        self.n_actions_ = A
        sc, tc = bigram_counts(seqs, A)
        eye = np.eye(A)
        if self.learn_emission:
            eps = self.emission_eps
            e_mean = (1 - eps) * eye + eps / max(A - 1, 1) * (1 - eye)
            e_prior = 1.0 + self.emission_prior * e_mean
            params = "ste"
        else:
            e_mean = (1 - 1e-6) * eye + 1e-6 / max(A - 1, 1) * (1 - eye)
            e_prior = 1.0
            params = "st"

        def init(r: int, rng: np.random.Generator):
            if r == 0:  # the closed-form count solution: EM's fixed point when emissions are exact
                return sc + self.alpha, tc + self.alpha, e_mean
            trans = np.stack([rng.dirichlet(row + self.alpha + 1.0) for row in tc])
            start = rng.dirichlet(sc + self.alpha + 1.0)
            emis = e_mean
            if self.learn_emission:
                emis = np.stack([rng.dirichlet(50.0 * row) for row in e_mean]) + 1e-6
            return start, trans, emis

        priors = (1.0 + self.alpha, 1.0 + self.alpha, e_prior)
        m, ll, lls = self._run_restarts(seqs, A, A, init, priors, params)
        self._keep(m, ll, lls, _converged(m))
        self.n_events_ = int(sum(len(s) for s in seqs))
        return self

    def action_transition(self) -> np.ndarray:
        return self.transition_

    def sample(self, n: int, start: int | None = None, random_state=None) -> np.ndarray:
        """Hidden (true-action) chain: the performer's style, free of recognition noise."""
        self._check_start(start)
        rng = _rng(random_state)
        out = np.empty(n, dtype=np.int64)
        if n == 0:
            return out
        out[0] = _sample_categorical(rng, self.start_) if start is None else int(start)
        for t in range(1, n):
            out[t] = _sample_categorical(rng, self.transition_[out[t - 1]])
        return out


class ModeHMM(_HMMBase):
    """Model (b): ``K`` hidden behaviour modes emitting actions; ``K`` chosen from ``k_range``.

    ``criterion="heldout"`` picks the ``K`` with the best mean held-out log-likelihood per event over
    ``n_folds`` folds of the training sequences (sequences alternate between folds; a single sequence
    is cut into contiguous parts); ``"bic"`` minimises -2 logL + p ln N on all training events.
    ``n_modes`` fixes ``K`` and skips the selection. ``alpha`` / ``emission_alpha``: Dirichlet
    pseudo-counts per start/transition cell and per emission cell (a small emission prior keeps a
    mode's action distribution sharp; 0.5 leaks ~5 % of every mode's mass to all actions).
    """

    def __init__(
        self,
        n_modes: int | None = None,
        k_range: Sequence[int] = (1, 2, 3, 4, 5, 6),
        criterion: str = "heldout",
        n_folds: int = 2,
        n_actions: int | None = None,
        alpha: float = 0.5,
        emission_alpha: float = 0.05,
        n_init: int = 4,
        n_iter: int = 200,
        tol: float = 1e-3,
        random_state=None,
    ):
        self.n_modes = n_modes
        self.k_range = k_range
        self.criterion = criterion
        self.n_folds = n_folds
        self.n_actions = n_actions
        self.alpha = alpha
        self.emission_alpha = emission_alpha
        self.n_init = n_init
        self.n_iter = n_iter
        self.tol = tol
        self.random_state = random_state

    @staticmethod
    def n_free_parameters(K: int, A: int) -> int:
        return (K - 1) + K * (K - 1) + K * (A - 1)

    def _fit_k(self, seqs: list[np.ndarray], K: int, A: int) -> tuple:
        sc, tc = bigram_counts(seqs, A)

        def init(r: int, rng: np.random.Generator):
            if r == 0 and K >= A:
                # states 0..A-1 start as the count chain (identity emission); extra modes are noisy
                # copies, so EM starts where the bigram model is and can only improve the likelihood
                start = np.full(K, 1e-3)
                start[:A] += sc + self.alpha
                trans = np.full((K, K), 1e-3)
                trans[:A, :A] += tc + self.alpha
                emis = np.full((K, A), 1e-2)
                emis[np.arange(A), np.arange(A)] = 1.0
                for k in range(A, K):
                    j = int(rng.integers(A))
                    trans[k, :A] += tc[j] + self.alpha
                    trans[:A, k] += 0.5 * trans[:A, j]
                    emis[k] = emis[j] + rng.dirichlet(np.ones(A)) * 0.2
                return start, trans, emis
            start = rng.dirichlet(np.ones(K)) + 1e-3
            trans = rng.dirichlet(np.ones(K), size=K) + np.eye(K) * rng.random() + 1e-3
            emis = rng.dirichlet(np.ones(A), size=K) + 1e-3
            return start, trans, emis

        priors = (1.0 + self.alpha, 1.0 + self.alpha, 1.0 + self.emission_alpha)
        return self._run_restarts(seqs, K, A, init, priors, "ste")

    def _folds(self, seqs: list[np.ndarray]) -> list[tuple[list[np.ndarray], list[np.ndarray]]]:
        nf = max(2, int(self.n_folds))
        if len(seqs) >= nf:
            parts = [seqs[i::nf] for i in range(nf)]
        else:  # cut every sequence into nf contiguous parts; part i of every sequence forms fold i
            parts = [[] for _ in range(nf)]
            for s in seqs:
                for i, piece in enumerate(np.array_split(s, nf)):
                    if len(piece):
                        parts[i].append(piece)
        return [
            ([s for j, p in enumerate(parts) if j != i for s in p], parts[i])
            for i in range(nf)
            if parts[i] and any(parts[j] for j in range(nf) if j != i)
        ]

    def fit(self, sequences) -> ModeHMM:
        seqs = as_int_sequences(sequences, self.n_actions)
        if not seqs:
            raise ValueError("no events to fit")
        A = _n_actions_of(seqs, self.n_actions)
        self.n_actions_ = A
        n_events = int(sum(len(s) for s in seqs))
        self.selection_scores_: dict[int, float] = {}
        if self.n_modes is not None:
            K = int(self.n_modes)
        else:
            ks = sorted({int(k) for k in self.k_range})
            if not ks or ks[0] < 1:
                raise ValueError(f"k_range must hold positive integers, got {self.k_range}")
            if self.criterion == "bic":
                for k in ks:
                    m, ll, _ = self._fit_k(seqs, k, A)
                    self.selection_scores_[k] = -2 * ll + self.n_free_parameters(k, A) * np.log(n_events)
                K = min(ks, key=lambda k: (self.selection_scores_[k], k))
            elif self.criterion == "heldout":
                folds = self._folds(seqs)
                if not folds:
                    raise ValueError("too few events for held-out model selection")
                for k in ks:
                    per_event = []
                    for train, test in folds:
                        sub = ModeHMM(
                            n_modes=k, n_actions=A, alpha=self.alpha, emission_alpha=self.emission_alpha,
                            n_init=self.n_init,
                            n_iter=self.n_iter, tol=self.tol, random_state=self.random_state,
                        )
                        sub._quiet = True  # selection fits: non-convergence is only a debug message
                        sub.fit(train)
                        per_event.append(sub.score_per_event(test))
                    self.selection_scores_[k] = float(np.mean(per_event))
                best = max(self.selection_scores_.values())
                # the smallest K within 0.002 nats/event of the best: no modes the data cannot support
                K = min(k for k in ks if self.selection_scores_[k] >= best - 2e-3)
            else:
                raise ValueError(f"criterion must be 'heldout' or 'bic', got {self.criterion!r}")
        if K < 1:
            raise ValueError(f"n_modes must be >= 1, got {K}")
        self.n_modes_ = K
        m, ll, lls = self._fit_k(seqs, K, A)
        self._keep(m, ll, lls, _converged(m))
        self.n_events_ = n_events
        self.bic_ = float(-2 * ll + self.n_free_parameters(K, A) * np.log(n_events))
        return self

    def action_transition(self) -> np.ndarray:
        """Implied P(a_{t+1} | a_t) at stationarity: sum_{m,m'} P(m | a_t) T[m, m'] E[m', a_{t+1}]."""
        pi = stationary_distribution(self.transition_)
        joint = pi[:, None] * self.emission_  # P(m, a) at stationarity, (K, A)
        post = normalise_rows(joint.T)  # P(m | a), (A, K)
        return normalise_rows(post @ self.transition_ @ self.emission_)

    def sample(self, n: int, start: int | None = None, random_state=None) -> np.ndarray:
        """Actions emitted by a sampled mode chain; with ``start`` the first mode is drawn from
        P(mode | first action = start) and the first action is ``start``."""
        self._check_start(start)
        rng = _rng(random_state)
        out = np.empty(n, dtype=np.int64)
        if n == 0:
            return out
        if start is None:
            mode = _sample_categorical(rng, self.start_)
            out[0] = _sample_categorical(rng, self.emission_[mode])
        else:
            mode = _sample_categorical(rng, normalise_rows(self.start_ * self.emission_[:, int(start)]))
            out[0] = int(start)
        for t in range(1, n):
            mode = _sample_categorical(rng, self.transition_[mode])
            out[t] = _sample_categorical(rng, self.emission_[mode])
        return out


class DurationModel(BaseEstimator):
    """Per-action log-normal event duration (frames): log d ~ N(mu_a, sigma_a^2).

    Actions with fewer than ``min_count`` events borrow the pooled fit of all events; ``sigma`` is
    floored at ``min_sigma`` so a constant-duration action still samples valid (rounded) frames.
    """

    def __init__(self, n_actions: int | None = None, min_count: int = 2, min_sigma: float = 0.02):
        self.n_actions = n_actions
        self.min_count = min_count
        self.min_sigma = min_sigma

    def fit(self, actions: Sequence[np.ndarray], durations: Sequence[np.ndarray]) -> DurationModel:
        a = np.concatenate([np.asarray(x, dtype=np.int64) for x in actions]) if len(actions) else np.zeros(0, int)
        d = np.concatenate([np.asarray(x, dtype=float) for x in durations]) if len(durations) else np.zeros(0)
        if a.shape != d.shape:
            raise ValueError("actions and durations differ in length")
        if a.size == 0:
            raise ValueError("no events to fit")
        if np.any(d <= 0):
            raise ValueError("durations must be positive")
        A = int(self.n_actions if self.n_actions is not None else a.max() + 1)
        self.n_actions_ = A
        logd = np.log(d)
        pooled = (float(logd.mean()), max(float(logd.std()), self.min_sigma))
        self.mu_ = np.full(A, pooled[0])
        self.sigma_ = np.full(A, pooled[1])
        self.count_ = np.zeros(A, dtype=np.int64)
        self.mean_frames_ = np.full(A, np.nan)
        self.sd_frames_ = np.full(A, np.nan)
        for k in range(A):
            sel = a == k
            self.count_[k] = int(sel.sum())
            if self.count_[k] == 0:
                continue
            self.mean_frames_[k] = float(d[sel].mean())
            self.sd_frames_[k] = float(d[sel].std())
            if self.count_[k] >= self.min_count:
                self.mu_[k] = float(logd[sel].mean())
                self.sigma_[k] = max(float(logd[sel].std()), self.min_sigma)
        return self

    def sample(self, actions: np.ndarray, random_state=None) -> np.ndarray:
        rng = _rng(random_state)
        actions = np.asarray(actions, dtype=np.int64)
        z = rng.standard_normal(actions.shape)
        return np.maximum(1, np.rint(np.exp(self.mu_[actions] + self.sigma_[actions] * z))).astype(np.int64)


def require_transitions(seqs: Sequence[np.ndarray], what: str) -> None:
    """An :class:`InputError` unless the events can teach transitions (>= 2 events, >= 2 actions)."""
    n = sum(len(s) for s in seqs)
    distinct = set(np.concatenate(seqs).tolist()) if n else set()
    if n < 2 or len(distinct) < 2:
        raise InputError(
            f"{what}: need at least 2 events of at least 2 different actions to learn transitions, "
            f"got {n} event(s) of {len(distinct)} action(s)"
        )
