"""TaskModes(temporal=False): the time-free Gaussian mixture as an HMM whose rows of A are the weights."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats
from sklearn.mixture import GaussianMixture

from learning.modes import TaskModes, mode_agreement
from tests.learning.hmm_samples import sample_hmm


@pytest.fixture(scope="module")
def fitted():
    X, S, L = sample_hmm(K=3, D=4, n_trials=4, T=300, seed=3)
    return X, S, L, TaskModes(3, n_restarts=2, seed=1, temporal=False).fit(X, L)


def test_mixture_modes_are_the_gaussian_mixture(fitted):
    X, S, L, m = fitted
    A = m.transmat_
    np.testing.assert_allclose(A, np.tile(m.startprob_, (3, 1)))  # every row = the weights
    Z = m.transform(X)
    # the causal filter, the smoothed posterior and Viterbi all reduce to the per-sample
    # posterior w_k N(z; μ_k, Σ_k) / Σ_j w_j N(z; μ_j, Σ_j) (scipy as the reference)
    dens = np.column_stack([w * stats.multivariate_normal(mu, cov).pdf(Z) for w, mu, cov in
                            zip(m.startprob_, m.model_.means_, m.model_.covars_)])
    np.testing.assert_allclose(m.filter_proba(X, L), dens / dens.sum(axis=1, keepdims=True), atol=1e-9)
    np.testing.assert_allclose(m.predict_proba(X, L), m.filter_proba(X, L), atol=1e-9)
    np.testing.assert_array_equal(m.predict(X, L), m.filter_proba(X, L).argmax(axis=1))
    assert mode_agreement(m.predict(X, L), S)[0] > 0.9  # well separated states: found without time
    # the fit is scikit-learn's mixture (same seed): same log-likelihood, no transition parameters
    seed = np.random.SeedSequence(m.seed).generate_state(m.n_restarts)[np.argmax(m.restart_logliks_)]
    gm = GaussianMixture(3, reg_covar=m.min_covar, random_state=int(seed), max_iter=m.n_iter, tol=m.tol).fit(Z)
    assert m.score(X, L) == pytest.approx(m.loglik_) == pytest.approx(gm.score(Z) * len(Z))
    assert m.n_parameters_ == TaskModes(3, temporal=True).fit(X, L).n_parameters_ - 3 * 2


def test_the_online_filter_runs_the_mixture(fitted):
    X, _, _, m = fitted
    f = m.make_filter()
    post = np.array([f.step(o) for o in X[:60]])
    np.testing.assert_allclose(post, m.filter_proba(X[:60]), atol=1e-9)


def test_temporal_must_be_a_bool():
    X, _, L = sample_hmm(K=2, D=2, n_trials=2, T=50)
    with pytest.raises(ValueError, match="temporal must be True"):
        TaskModes(2, temporal="mixture").fit(X, L)


def test_a_model_pickled_before_the_option_loads_as_an_hmm(fitted):
    import pickle

    m = fitted[3]
    state = m.__getstate__()
    del state["temporal"]
    old = TaskModes.__new__(TaskModes)
    old.__setstate__(state)
    assert old.temporal is True and "temporal=True" not in repr(old)  # default params are not shown
    assert pickle.loads(pickle.dumps(old)).get_params()["temporal"] is True
