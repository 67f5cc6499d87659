"""The regularised HMM of learning.modes: its EM step equals hmmlearn's."""

from __future__ import annotations

import pickle

import numpy as np
import pytest
from hmmlearn.hmm import GaussianHMM

from learning.modes import RegularizedGaussianHMM

# hmmlearn's reference computations here use tiny threaded BLAS calls (fixture: conftest.py)
pytestmark = pytest.mark.usefixtures("_one_blas_thread")


def test_regularised_hmm_matches_hmmlearn_em_step(data):
    """The fast scatter statistics and the emission override reproduce hmmlearn's EM."""
    X, _, L = data
    rng = np.random.default_rng(0)
    K, D = 3, X.shape[1]
    init = {"startprob_": np.full(K, 1 / K), "transmat_": np.full((K, K), 1 / K),
            "means_": X[rng.choice(len(X), K)], "covars_": np.array([np.cov(X.T)] * K)}
    kw = {"n_components": K, "covariance_type": "full", "n_iter": 2, "tol": -np.inf,
          "init_params": "", "covars_prior": 0.0, "covars_weight": 1.0, "means_weight": 0.0}
    ours, ref = RegularizedGaussianHMM(**kw), GaussianHMM(**kw)
    ours.reg_covar = 0.0
    for h in (ours, ref):
        h.n_features = D
        for k, v in init.items():
            setattr(h, k, v.copy())
    np.testing.assert_allclose(ours._compute_log_likelihood(X), ref._compute_log_likelihood(X),
                               rtol=1e-10)
    ours.fit(X, L)
    ref.fit(X, L)
    np.testing.assert_allclose(ours.means_, ref.means_, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(ours.covars_, ref.covars_, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(ours.transmat_, ref.transmat_, rtol=1e-9)
    # the per-parameter-set factor cache follows every change of the parameters
    for means in (ours.means_ + 0.5, X[rng.choice(len(X), K)]):
        ours.means_, ref.means_ = means.copy(), means.copy()
        np.testing.assert_allclose(ours._compute_log_likelihood(X), ref._compute_log_likelihood(X),
                                   rtol=1e-10)
    assert "_whitener_cache" not in pickle.loads(pickle.dumps(ours)).__dict__
