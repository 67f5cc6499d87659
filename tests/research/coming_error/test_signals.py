"""The signal functions of research/coming_error against hand-computed values and well-kept libraries."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats
from sklearn.metrics import roc_auc_score

from research.coming_error.signals import (
    AdaptiveConformal,
    GammaDwell,
    auc,
    dwell_runs,
    entropy,
    future_mean,
    past_mean,
    time_in_state,
)


def test_windows_by_hand():
    x = np.array([1.0, 2.0, 3.0, 4.0, 5.0])
    np.testing.assert_allclose(past_mean(x, 2), [1.0, 1.5, 2.5, 3.5, 4.5])
    np.testing.assert_allclose(future_mean(x, 2), [2.5, 3.5, 4.5, np.nan, np.nan])
    np.testing.assert_allclose(past_mean(np.column_stack([x, -x]), 3)[-1], [4.0, -4.0])
    with pytest.raises(ValueError, match="at least 1"):
        past_mean(x, 0)


def test_time_in_state_and_dwell_runs():
    lab = np.array([0, 0, 1, 1, 1, 0, 2, 2])
    np.testing.assert_allclose(time_in_state(lab, 0.1), [0.1, 0.2, 0.1, 0.2, 0.3, 0.1, 0.1, 0.2])
    states, durs = dwell_runs(lab, np.zeros(8, dtype=int), 0.1)
    np.testing.assert_array_equal(states, [1, 0])  # the first and last runs are censored
    np.testing.assert_allclose(durs, [0.3, 0.1])


def test_gamma_hazard_matches_scipy():
    rng = np.random.default_rng(0)
    d0, d1 = rng.gamma(3.0, 0.5, 400), rng.gamma(0.8, 2.0, 400)
    law = GammaDwell.fit(np.r_[np.zeros(400), np.ones(400)], np.r_[d0, d1])
    assert law.shape[0] == pytest.approx(3.0, rel=0.2) and law.scale[1] == pytest.approx(2.0, rel=0.25)
    d = np.array([0.2, 1.0, 3.0])
    k, th = law.shape[0], law.scale[0]
    want = stats.gamma.pdf(d, k, scale=th) / stats.gamma.sf(d, k, scale=th)
    np.testing.assert_allclose(law.hazard(d, np.zeros(3)), want, rtol=1e-9)
    np.testing.assert_allclose(law.change_within(d, 0.5, np.zeros(3)),
                               1 - stats.gamma.sf(d + 0.5, k, scale=th) / stats.gamma.sf(d, k, scale=th), rtol=1e-9)
    assert np.all(np.diff(law.hazard(d, np.zeros(3))) > 0)  # shape > 1: the hazard grows with time in the mode
    assert np.all(np.diff(law.hazard(d, np.ones(3))) < 0)  # shape < 1: it falls
    kp, _, thp = stats.gamma.fit(np.r_[d0, d1], floc=0)  # a state never seen takes the pooled law
    np.testing.assert_allclose(law.hazard(d, np.full(3, 7)),
                               stats.gamma.pdf(d, kp, scale=thp) / stats.gamma.sf(d, kp, scale=thp), rtol=1e-6)
    with pytest.raises(ValueError, match="at least 5"):
        GammaDwell.fit(np.zeros(2), np.ones(2))


def test_auc_matches_sklearn_with_ties():
    rng = np.random.default_rng(1)
    y = rng.integers(0, 2, 500)
    s = np.round(y + rng.normal(0, 1.5, 500), 1)  # ties
    assert auc(y, s) == pytest.approx(roc_auc_score(y, s), abs=1e-12)
    assert auc([0, 0, 1], [0.1, 0.4, 0.3]) == pytest.approx(0.5)
    assert auc(np.ones(4), np.arange(4.0)) is None


def test_adaptive_conformal_covers_iid_and_shifting_scores():
    rng = np.random.default_rng(2)
    s = np.abs(rng.normal(0, 1, 4000))
    q, err = AdaptiveConformal(0.1, 0.01, window=500).radii(s)
    assert np.isnan(q[0]) and np.nanmean(err[100:]) == pytest.approx(0.1, abs=0.02)
    s2 = np.r_[s[:2000], 5 * s[2000:]]  # the scale jumps: the radius follows, coverage recovers
    q2, err2 = AdaptiveConformal(0.1, 0.01, window=500).radii(s2)
    assert np.nanmean(err2[2000:]) == pytest.approx(0.1, abs=0.03)
    assert np.median(q2[3000:]) > 3 * np.median(q2[1000:2000])
    _, err3 = AdaptiveConformal(0.1, 0.01, window=500, delay=50).radii(s)
    assert np.nanmean(err3[200:]) == pytest.approx(0.1, abs=0.02)


def test_entropy_by_hand():
    np.testing.assert_allclose(entropy(np.array([[1.0, 0.0], [0.5, 0.5]])), [0.0, np.log(2)])


def test_conformal_radius_is_numpys_quantile_of_the_window():
    s = np.random.default_rng(3).exponential(1.0, 300)
    q, _ = AdaptiveConformal(0.2, 1e-9, window=50).radii(s)  # γ → 0: a fixed level
    assert q[120] == pytest.approx(np.quantile(s[70:120], 0.8), rel=1e-6)
