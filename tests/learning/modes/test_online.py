"""Tests of learning.modes.ModeFilter: the online filter equals offline filtering, fixed-lag smoothing and hmmlearn."""

from __future__ import annotations

import numpy as np
import pytest

from learning.modes import HMMFilterParams, ModeFilter, TaskModes
from tests.learning.hmm_samples import sample_hmm, vanilla_hmm

# hmmlearn's reference computations here use tiny threaded BLAS calls (fixture: conftest.py)
pytestmark = pytest.mark.usefixtures("_one_blas_thread")


# ------------------------------------------------------------------ online filter

def test_mode_filter_equals_offline_filter_and_hmmlearn(data, fitted):
    X, _, _ = data
    T = 150
    seq = X[400:400 + T]  # a prefix of the second trial
    f = fitted.make_filter()
    post = np.empty((T, 4))
    logp = np.empty(T)
    for t, o in enumerate(seq):
        post[t] = f.step(o)
        logp[t] = f.log_predictive
        assert f.posterior_time == t
        np.testing.assert_array_equal(post[t], f.filtered)
    np.testing.assert_allclose(post, fitted.filter_proba(seq), rtol=0, atol=1e-9)
    np.testing.assert_allclose(logp, fitted.log_predictive(seq), rtol=0, atol=1e-9)
    ref = vanilla_hmm(fitted)
    Z = fitted.transform(seq)
    for t in (0, 1, 2, 10, 57, T - 1):
        # the smoothed posterior at the last time of a prefix is the filtered one
        np.testing.assert_allclose(post[t], ref.predict_proba(Z[:t + 1])[-1], rtol=0, atol=1e-9)
        assert logp[:t + 1].sum() == pytest.approx(ref.score(Z[:t + 1]), rel=0, abs=1e-9)
    # offline filter restarts at each trial boundary
    both = fitted.filter_proba(X[:800], [400, 400])
    np.testing.assert_allclose(both[400:400 + T], post, atol=1e-9)
    # reset starts a new trial
    f.reset()
    np.testing.assert_allclose(f.step(seq[0]), post[0], atol=1e-12)


def test_mode_filter_with_pca_on_windowed_like_input():
    X, _, L = sample_hmm(D=20, n_trials=3, T=200, seed=5, sep=1.0)
    m = TaskModes(3, n_pca=6, n_restarts=1).fit(X, L)
    f = m.make_filter()
    post = np.array([f.step(o) for o in X[:100]])
    np.testing.assert_allclose(post, m.filter_proba(X[:100]), atol=1e-9)
    ref = vanilla_hmm(m)
    assert m.log_predictive(X[:100]).sum() == pytest.approx(ref.score(m.transform(X[:100])),
                                                            abs=1e-9)


@pytest.mark.parametrize("lag", [1, 3, 8])
def test_fixed_lag_equals_offline_smoothing_on_the_window(data, fitted, lag):
    X, _, _ = data
    seq = X[:60]
    ref = vanilla_hmm(fitted)
    Z = fitted.transform(seq)
    f = fitted.make_filter(fixed_lag=lag)
    for t, o in enumerate(seq):
        p = f.step(o)
        tau = max(t - lag, 0)
        assert f.posterior_time == tau
        np.testing.assert_allclose(p, ref.predict_proba(Z[:t + 1])[tau], rtol=0, atol=1e-9)
        np.testing.assert_allclose(p, f.posterior)
        np.testing.assert_allclose(f.filtered, ref.predict_proba(Z[:t + 1])[-1], atol=1e-9)


def test_novelty_score_flags_outliers(fitted, data):
    X, _, _ = data
    f = fitted.make_filter()
    for o in X[:20]:
        f.step(o)
    usual = f.log_predictive
    f.step(X[20] + 50.0)
    assert f.log_predictive < usual - 100


@pytest.mark.parametrize("n_pca", [None, 4])
def test_mode_filter_from_exported_params(data, n_pca):
    """A filter built from the frozen parameter object alone (no estimator) equals
    ``filter_proba`` on every prefix, with and without PCA; the parameters are read-only
    and survive a round trip through plain arrays (what a model bundle stores)."""
    X, _, L = data
    m = TaskModes(3, n_pca=n_pca, n_restarts=1, covariance_type="diag").fit(X, L)
    params = m.filter_params()
    assert isinstance(params, HMMFilterParams)
    assert params.covars.shape == (3, m.n_components_, m.n_components_)  # full, for any type
    np.testing.assert_allclose(params.covars, m.model_.covars_)
    with pytest.raises(ValueError, match="read-only"):
        params.means[0, 0] = 1.0
    again = HMMFilterParams.from_dict({k: np.array(v) for k, v in params.to_dict().items()})
    seq = X[400:480]
    ref = m.filter_proba(seq)
    for built in (ModeFilter(params), ModeFilter(again), m.make_filter(), ModeFilter(m)):
        post = np.array([built.step(o) for o in seq])
        np.testing.assert_allclose(post, ref, rtol=0, atol=1e-9)
    lag = ModeFilter(params, fixed_lag=2)
    for o in seq[:10]:
        lag.step(o)
    assert lag.posterior_time == 7
    with pytest.raises(TypeError, match="TaskModes or an HMMFilterParams"):
        ModeFilter(np.zeros(3))
    with pytest.raises(ValueError, match="transmat must have shape"):
        HMMFilterParams(**{**params.to_dict(), "transmat": np.eye(2)})
    half = params.to_dict()
    if n_pca:
        half.pop("pca_mean")
    else:
        half["pca_mean"] = np.zeros(9)
    with pytest.raises(ValueError, match="pca_mean and pca_components go together"):
        HMMFilterParams(**half)
