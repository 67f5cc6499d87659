"""Predictability statistics: thresholds, shares, tests against scipy, order selection."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from learning.analysis.predictability import (
    compare_quotients,
    compare_segmentation,
    compare_voluntary_shares,
    lipschitz_index,
    narx_regressors,
    random_segmentation,
    select_order,
    split_reactive_voluntary,
    threshold_from_percentile,
    voluntary_mask,
    voluntary_share,
)
from learning.lipschitz import pointwise_quotients


def test_threshold_matches_numpy_and_handles_inf():
    rng = np.random.default_rng(0)
    q = rng.exponential(size=101)
    for p in (0, 5, 50, 95, 100):
        assert threshold_from_percentile(q, p) == pytest.approx(np.percentile(q, p), rel=1e-12)
    q2 = np.array([1.0, 2.0, 3.0, np.inf])
    assert threshold_from_percentile(q2, 50) == pytest.approx(2.5)
    assert threshold_from_percentile(q2, 90) == np.inf  # numpy gives nan here
    assert threshold_from_percentile(q2, 100 * 2 / 3) == 3.0
    with pytest.raises(ValueError):
        threshold_from_percentile(q2, 101)


def test_split_and_share_per_trial():
    q = np.array([0.5, 6.0, 11.0, 5.0, np.inf, 1.0, 2.0, 3.0])
    trial = np.array([7, 7, 7, 7, 2, 2, 2, 2])
    r, v = split_reactive_voluntary(q, 5.0)
    assert v.tolist() == [False, True, True, False, True, False, False, False]
    assert np.array_equal(r, ~v) and np.array_equal(voluntary_mask(q, 5.0), v)
    share = voluntary_share(q, trial, 5.0)
    assert list(share) == [2, 7]
    assert share == {2: 0.25, 7: 0.5}
    assert voluntary_share(q, trial, 10.0) == {2: 0.25, 7: 0.25}


def test_random_segmentation_preserves_sizes_and_is_seeded():
    labels = np.repeat([0, 1, 2, 5], [40, 7, 30, 23])
    for method in ("permutation", "contiguous"):
        a = random_segmentation(labels, seed=3, method=method)
        b = random_segmentation(labels, seed=3, method=method)
        c = random_segmentation(labels, seed=4, method=method)
        assert np.array_equal(a, b) and not np.array_equal(a, c)
        assert np.array_equal(np.unique(a, return_counts=True)[1],
                              np.unique(labels, return_counts=True)[1])
    cont = random_segmentation(labels, seed=1, method="contiguous")
    assert (np.diff(cont) != 0).sum() == 3  # four contiguous blocks
    with pytest.raises(ValueError):
        random_segmentation(labels, method="blocks")


def test_compare_quotients_matches_scipy():
    rng = np.random.default_rng(1)
    a = rng.exponential(1.0, 60)
    b = rng.exponential(2.0, 80)
    res = compare_quotients(a, b)
    ref = stats.mannwhitneyu(a, b, alternative="less", method="asymptotic")
    assert res.statistic == pytest.approx(ref.statistic)
    assert res.p_value == pytest.approx(ref.pvalue)
    cliff = np.mean(a[:, None] > b[None]) - np.mean(a[:, None] < b[None])
    assert res.effect_size == pytest.approx(cliff)
    assert res.p_value < 0.05 and res.effect_size < 0
    assert res.median_a == pytest.approx(np.median(a)) and res.n_b == 80


def test_compare_segmentation_true_modes_more_predictable():
    """Two modes with different linear maps: within-mode quotients are smaller."""
    rng = np.random.default_rng(2)
    n = 400
    X = rng.uniform(-1, 1, size=(n, 2))
    mode = np.repeat([0, 1], n // 2)
    Y = np.where(mode[:, None] == 0, X @ [[1.0], [0.5]], X @ [[-3.0], [2.0]] + 1.0)
    res = compare_segmentation(X, Y, mode, n_random=2, seed=5)
    assert res.q_random.shape == (2, n)
    assert np.allclose(res.q_segmentation, pointwise_quotients(X, Y, mode))
    assert res.test.p_value < 1e-6 and res.test.effect_size < -0.3
    again = compare_segmentation(X, Y, mode, n_random=2, seed=5)
    assert np.array_equal(again.q_random, res.q_random)
    ref = stats.mannwhitneyu(res.q_segmentation, res.q_random.ravel(), alternative="less",
                             method="asymptotic")
    assert res.test.p_value == pytest.approx(ref.pvalue)


def test_compare_voluntary_shares_matches_scipy_wilcoxon():
    rng = np.random.default_rng(3)
    trial = np.repeat(np.arange(12), 50)
    q_b = rng.exponential(6.0, trial.size)
    q_a = q_b * rng.uniform(0.3, 1.0, trial.size)  # uniformly smaller quotients
    out = compare_voluntary_shares(q_a, q_b, trial, K=(5.0, 10.0))
    assert [r.K for r in out] == [5.0, 10.0]
    for r in out:
        sa = np.array(list(voluntary_share(q_a, trial, r.K).values()))
        sb = np.array(list(voluntary_share(q_b, trial, r.K).values()))
        ref = stats.wilcoxon(sa, sb, alternative="less")
        assert r.statistic == pytest.approx(ref.statistic)
        assert r.p_value == pytest.approx(ref.pvalue)
        assert np.array_equal(r.shares_a, sa) and r.p_value < 0.01 and r.effect_size < 0
    same = compare_voluntary_shares(q_a, q_a, trial, K=5.0)[0]
    assert same.p_value == 1.0 and same.effect_size == 0.0


def test_lipschitz_index_definition():
    rng = np.random.default_rng(4)
    X = rng.normal(size=(120, 3))
    y = np.sin(X[:, 0]) + X[:, 1] * X[:, 2]
    p = 5
    i, j = np.triu_indices(120, 1)
    r = np.abs(y[i] - y[j]) / np.linalg.norm(X[i] - X[j], axis=1)
    top = np.sort(r)[-p:]
    expected = np.exp(np.mean(np.log(np.sqrt(3) * top)))
    assert lipschitz_index(X, y, p=p) == pytest.approx(expected, rel=1e-12)
    assert lipschitz_index(np.r_[X, X[:1]], np.r_[y, y[:1] + 1.0], p=p) == np.inf


def test_narx_regressors_layout():
    u = np.arange(10.0)
    y = 100 + np.arange(10.0)
    Phi, t = narx_regressors(u, y, 2, 1)
    assert Phi.shape == (8, 3)
    assert Phi[0].tolist() == [101.0, 100.0, 1.0] and t[0] == 102.0


def _narendra(T, seed):
    rng = np.random.default_rng(seed)
    u = rng.uniform(-1, 1, T)
    y = np.zeros(T)
    for k in range(1, T - 1):
        y[k + 1] = y[k] * y[k - 1] * (y[k] + 2.5) / (1 + y[k] ** 2 + y[k - 1] ** 2) + u[k]
    return u, y


@pytest.mark.parametrize("seed", [0, 1])
def test_select_order_recovers_known_system(seed):
    """y(k+1) = y(k)y(k−1)(y(k)+2.5)/(1+y(k)²+y(k−1)²) + u(k): order 2 in y, 1 in u."""
    u, y = _narendra(600, seed)
    res = select_order(u, y, max_lag=3)
    assert (res.n_y, res.n_u) == (2, 1)
    assert res.index[2, 1] < 0.1 * res.index[1, 1]  # the knee is sharp
    assert res.index.shape == (4, 4) and np.isnan(res.index[0, 0])


def test_paired_wilcoxon_matches_scipy_and_handles_ties():
    from scipy import stats as sps

    from learning.analysis.predictability import paired_wilcoxon

    a = np.array([0.1, 0.2, 0.15, 0.05, 0.3, 0.12])
    b = np.array([0.4, 0.5, 0.35, 0.2, 0.45, 0.1])
    stat, p, eff = paired_wilcoxon(a, b, "less")
    ref = sps.wilcoxon(a, b, alternative="less")
    assert stat == pytest.approx(ref.statistic) and p == pytest.approx(ref.pvalue)
    assert -1.0 <= eff < 0.0
    assert paired_wilcoxon(a, a) == (0.0, 1.0, 0.0)
    with pytest.raises(ValueError, match="equal length"):
        paired_wilcoxon(a, b[:-1])
