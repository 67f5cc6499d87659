"""learning.modes.TaskModes: fitting, determinism, degenerate data, errors, parallel restarts."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from sklearn.exceptions import NotFittedError

from learning.modes import TaskModes, check_sequences, mode_agreement, mode_ari
from tests.learning.hmm_samples import sample_hmm, vanilla_hmm

# hmmlearn's reference computations here use tiny threaded BLAS calls (fixture: conftest.py)
pytestmark = pytest.mark.usefixtures("_one_blas_thread")


def test_recovers_known_modes(data, fitted):
    X, S, L = data
    acc, mapping = mode_agreement(fitted.predict(X, L), S)
    assert acc >= 0.95
    assert sorted(mapping.values()) == [0, 1, 2, 3]
    assert mode_ari(fitted.predict(X, L), S) > 0.9
    assert fitted.converged_
    assert fitted.empty_modes_.size == 0
    assert 1 < fitted.n_iter_ < fitted.n_iter
    # the causal filter is nearly as good on clear data
    assert mode_agreement(fitted.filter_proba(X, L).argmax(1), S)[0] >= 0.9


def test_fitted_attributes_and_parameter_count(data, fitted):
    X, _, L = data
    K, D = 4, 9
    assert fitted.n_features_in_ == D and fitted.n_components_ == D
    assert fitted.n_parameters_ == (K - 1) + K * (K - 1) + K * D + K * D * (D + 1) // 2
    assert fitted.n_parameters_ == sum(fitted.model_._get_n_fit_scalars_per_param().values())
    assert len(fitted.restart_logliks_) == 3
    assert fitted.loglik_ == pytest.approx(max(fitted.restart_logliks_))
    np.testing.assert_allclose(fitted.transmat_.sum(1), 1.0)
    assert (fitted.transmat_ > 0).all()  # one pseudo-transition everywhere
    assert (fitted.expected_durations_ > 10).all()  # true: 1 / 0.03 ≈ 33 samples
    score = fitted.score(X, L)
    assert score == pytest.approx(fitted.loglik_, rel=1e-9)
    assert fitted.bic(X, L) == pytest.approx(-2 * score + fitted.n_parameters_ * np.log(len(X)))
    assert fitted.bic(X, L) == pytest.approx(vanilla_hmm(fitted).bic(fitted.transform(X), L))
    P = fitted.predict_proba(X, L)
    assert P.shape == (len(X), 4)
    np.testing.assert_allclose(P.sum(1), 1.0)


def test_deterministic_for_a_seed(data):
    X, _, L = data
    a = TaskModes(3, n_restarts=2, seed=7, n_pca=5).fit(X, L)
    b = TaskModes(3, n_restarts=2, seed=7, n_pca=5).fit(X, L)
    np.testing.assert_array_equal(a.model_.means_, b.model_.means_)
    np.testing.assert_array_equal(a.model_.transmat_, b.model_.transmat_)
    np.testing.assert_array_equal(a.predict(X, L), b.predict(X, L))
    assert a.restart_logliks_ == b.restart_logliks_


@pytest.mark.parametrize("cov", ["diag", "spherical", "tied"])
def test_other_covariance_types(data, cov):
    X, S, L = data
    m = TaskModes(4, covariance_type=cov, n_restarts=2).fit(X, L)
    # the true covariances are anisotropic: spherical states are a poor (but valid) model
    assert mode_agreement(m.predict(X, L), S)[0] > (0.6 if cov == "spherical" else 0.8)
    f = m.make_filter()
    post = np.array([f.step(o) for o in X[:50]])
    np.testing.assert_allclose(post, m.filter_proba(X[:50]), atol=1e-9)


def test_pca_is_fitted_on_training_data_only(data):
    X, _, L = data
    m = TaskModes(2, n_pca=3, n_restarts=1).fit(X[:800], [400, 400])
    assert m.n_components_ == 3
    np.testing.assert_allclose(m.scaler_.mean_, X[:800].mean(0))
    assert m.transform(X[800:]).shape == (len(X) - 800, 3)
    m2 = TaskModes(2, n_pca=0.9, n_restarts=1).fit(X, L)
    assert 1 <= m2.n_components_ <= 9


def test_degenerate_data_does_not_crash():
    rng = np.random.default_rng(0)
    # two distinct points, duplicated, and six states
    X = np.repeat(np.array([[0.0, 1.0, 2.0], [5.0, -1.0, 0.5]]), 100, axis=0)
    X = X[rng.permutation(len(X))]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        m = TaskModes(6, n_restarts=2).fit(X, [120, 80])
    for cov in m.model_.covars_:
        assert np.linalg.eigvalsh(cov).min() > 0
    assert np.isfinite(m.model_.means_).all()
    pred = m.predict(X, [120, 80])
    assert set(np.unique(pred)) <= set(range(6))
    assert np.isfinite(m.score(X, [120, 80]))
    assert np.isfinite(m.predict_proba(X)).all()
    f = m.make_filter(fixed_lag=2)
    for o in X[:10]:
        assert np.isfinite(f.step(o)).all()
    # constant data, and a constant column
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        c = TaskModes(3, n_restarts=1).fit(np.ones((50, 2)))
    assert np.isfinite(c.predict_proba(np.ones((5, 2)))).all()
    Xc = rng.standard_normal((300, 3))
    Xc[:, 1] = 4.0
    assert TaskModes(2, n_restarts=1).fit(Xc).predict(Xc).shape == (300,)


def test_more_states_than_clusters_reports_empty_states():
    X, _, L = sample_hmm(K=2, D=3, n_trials=2, T=300, sep=6.0, seed=3)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        m = TaskModes(5, n_restarts=2).fit(X, L)
    assert m.predict(X, L).shape == (len(X),)
    assert m.empty_modes_.ndim == 1  # reported (possibly none: extra states may split clusters)


def test_clear_errors_on_bad_input(data, fitted):
    X, _, L = data
    with pytest.raises(NotFittedError):
        TaskModes().predict(X)
    with pytest.raises(NotFittedError):
        TaskModes().make_filter()
    Xn = X.copy()
    Xn[5, 2] = np.nan
    with pytest.raises(ValueError, match="NaN or inf.*row 5, column 2"):
        TaskModes(2).fit(Xn, L)
    with pytest.raises(ValueError, match="NaN"):
        fitted.predict(Xn, L)
    with pytest.raises(ValueError, match="8 features.*fitted with 9"):
        fitted.predict(X[:, :8], L)
    with pytest.raises(ValueError, match="lengths sum to"):
        fitted.score(X, [10, 20])
    with pytest.raises(ValueError, match="lengths sum to"):
        TaskModes(2).fit(X, [len(X) - 1])
    with pytest.raises(ValueError, match="positive"):
        check_sequences(X, [0, len(X)])
    with pytest.raises(ValueError, match="2-D"):
        fitted.predict(X[:, 0])
    with pytest.raises(ValueError, match="cannot be split"):
        TaskModes(4).fit(X[:3])
    with pytest.raises(ValueError, match="covariance_type"):
        TaskModes(2, covariance_type="banana").fit(X)
    with pytest.raises(ValueError, match="n_pca"):
        TaskModes(2, n_pca=1.5).fit(X)
    f = fitted.make_filter()
    with pytest.raises(ValueError, match="shape"):
        f.step(X[0, :8])
    with pytest.raises(ValueError, match="non-finite"):
        f.step(np.full(9, np.nan))
    assert f.n_steps == 0  # a rejected observation does not change the state
    with pytest.raises(ValueError, match="fixed_lag"):
        fitted.make_filter(fixed_lag=-1)


def _two_regimes(seed: int = 0, outlier: bool = False) -> tuple[np.ndarray, list[int]]:
    rng = np.random.default_rng(seed)
    Z = rng.normal(size=(1800, 3))
    Z[(np.arange(1800) // 150) % 2 == 1] += 3.0
    if outlier:
        Z[100] = 1e4  # no state explains it: the scaling forward pass underflows
    return Z, [600, 600, 600]


def test_parallel_restarts_give_the_same_model():
    Z, lengths = _two_regimes()
    a = TaskModes(n_modes=2, n_restarts=3, seed=1).fit(Z, lengths)
    b = TaskModes(n_modes=2, n_restarts=3, seed=1, n_jobs=2).fit(Z, lengths)
    assert a.restart_logliks_ == b.restart_logliks_
    assert np.array_equal(a.predict(Z, lengths), b.predict(Z, lengths))


@pytest.mark.parametrize("outlier", [False, True])
def test_scaling_fit_equals_log_fit_and_falls_back(outlier, monkeypatch):
    """The fit runs hmmlearn's "scaling" forward–backward (log space where it underflows):
    the same model as a fit in log space throughout."""
    Z, lengths = _two_regimes(outlier=outlier)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        fast = TaskModes(n_modes=2, n_restarts=2, seed=3).fit(Z, lengths)
        orig = TaskModes._fit_restart_with
        monkeypatch.setattr(TaskModes, "_fit_restart_with",
                            lambda self, Z, lengths, seed, impl: orig(self, Z, lengths, seed, "log"))
        slow = TaskModes(n_modes=2, n_restarts=2, seed=3).fit(Z, lengths)
    assert fast.model_.implementation == "log"
    np.testing.assert_allclose(fast.restart_logliks_, slow.restart_logliks_, rtol=1e-9)
    np.testing.assert_allclose(fast.model_.means_, slow.model_.means_, rtol=1e-7, atol=1e-9)
    assert np.array_equal(fast.predict(Z, lengths), slow.predict(Z, lengths))


def test_restart_ari_compares_every_restart_with_the_kept_partition(data):
    X, S, L = data  # overlapping states (sep 1): restarts end in different optima
    m = TaskModes(4, n_restarts=4, seed=2).fit(X, L)
    kept = int(np.argmax(m.restart_logliks_))
    assert len(m.restart_ari_) == 4 and m.restart_ari_[kept] == 1.0
    assert all(-1.0 <= a <= 1.0 for a in m.restart_ari_)
    # well-separated states: every restart finds the same partition
    X2, _, L2 = sample_hmm(sep=4.0, seed=5)
    assert min(TaskModes(4, n_restarts=3, seed=2).fit(X2, L2).restart_ari_) > 0.99
