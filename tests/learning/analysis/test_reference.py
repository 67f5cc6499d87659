"""The statistics of learning.analysis.reference against scipy and by hand: the trial test,
size-matched k-means, the reference grouping, one pass shared by many groupings."""

import numpy as np
import pytest
from scipy import stats

from learning.analysis import MIN_EFFECT, SIGNIFICANCE
from learning.analysis.reference import (
    REFERENCES,
    min_trials_for,
    mode_evidence,
    reference_segmentation,
    size_matched_kmeans,
    trial_test,
)
from tests.learning.analysis.regime_windows import hidden_regime_data as _hidden_regime_data


def test_trial_test_is_the_wilcoxon_of_per_trial_log_ratios():
    rng = np.random.default_rng(1)
    trial = np.repeat(np.arange(12), 50)
    q_b = rng.uniform(1, 3, trial.size)
    q_a = q_b * np.repeat(rng.uniform(0.6, 1.05, 12), 50)
    t = trial_test(q_a, q_b, trial, min_effect=0.05, seed=4)
    a = np.array([np.median(q_a[trial == k]) for k in range(12)])
    b = np.array([np.median(q_b[trial == k]) for k in range(12)])
    r = np.log(b / a)
    assert t.p_value == pytest.approx(stats.wilcoxon(r - 0.05, alternative="greater").pvalue)
    assert t.effect == pytest.approx(np.median(r)) and t.ci_low <= t.effect <= t.ci_high
    assert np.array_equal(t.median_a, a) and t.n_trials == 12
    # several reference draws: a trial's reference median is the mean of its per-draw medians
    two = trial_test(q_a, np.stack([q_b, 2 * q_b]), trial)
    assert np.allclose(two.median_b, 1.5 * b)


def test_too_few_trials_cannot_claim_however_clear_the_effect():
    assert min_trials_for(1e-3) == 10 and min_trials_for(0.05) == 5
    trial = np.repeat(np.arange(9), 20)
    q_b = np.ones(trial.size)
    t = trial_test(0.1 * q_b, q_b, trial)
    assert t.p_value == pytest.approx(2.0 ** -9) and not t.reachable and not t.claimed
    t10 = trial_test(0.1 * np.ones(200), np.ones(200), np.repeat(np.arange(10), 20))
    assert t10.reachable and t10.claimed


def test_equal_quotients_give_no_evidence():
    trial = np.repeat(np.arange(12), 10)
    q = np.random.default_rng(2).uniform(1, 2, trial.size)
    t = trial_test(q, q.copy(), trial)
    assert t.p_value == 1.0 and t.effect == 0.0 and not t.claimed


def test_size_matched_kmeans_keeps_the_sizes_and_finds_clusters():
    rng = np.random.default_rng(5)
    centres = np.array([[0, 0], [5, 0], [0, 5]])
    Z = np.concatenate([c + rng.normal(0, 0.5, (n, 2)) for c, n in zip(centres, (300, 200, 100))])
    labels = size_matched_kmeans(Z, [100, 300, 200], seed=0)
    assert np.bincount(labels, minlength=3).tolist() == [100, 300, 200]
    # the biggest group takes the biggest cluster whole
    assert np.all(labels[:300] == 1)
    with pytest.raises(ValueError, match="sum to the 600 rows"):
        size_matched_kmeans(Z, [100, 100], seed=0)


@pytest.mark.parametrize("method", REFERENCES)
def test_reference_uses_as_many_groups_and_no_time(method):
    rng = np.random.default_rng(6)
    Z = rng.normal(size=(400, 3))
    labels = np.repeat([0, 1, 2, 3], 100)
    g = reference_segmentation(Z, labels, method, seed=0)
    assert len(np.unique(g)) == 4
    # time-free: shuffling the rows shuffles the groups with them (the seeded fit sees
    # the same set of points)
    perm = rng.permutation(400)
    g2 = reference_segmentation(Z[perm], labels, method, seed=0)
    assert stats.contingency.crosstab(g[perm], g2).count.max(axis=1).sum() >= 0.97 * 400
    with pytest.raises(ValueError, match="reference must be one of"):
        reference_segmentation(Z, labels, "hmm")


def test_mode_evidence_shared_pass_equals_per_grouping_calls():
    """Random groupings in one pointwise_quotients_multi pass = one call per grouping."""
    from learning.analysis.reference import random_labelings
    from learning.lipschitz import pointwise_quotients

    X, Y, trial, src, feats, regime = _hidden_regime_data(4, 250, seed=5)
    kw = dict(reference="gmm", n_random=3, alpha=SIGNIFICANCE, min_effect=MIN_EFFECT, seed=2)
    shared = mode_evidence(X, Y, trial, src, feats, regime, **kw)
    single = mode_evidence(X, Y, trial, src, feats, regime, quotient=pointwise_quotients, **kw)
    assert np.array_equal(shared.q_random, single.q_random)
    assert np.array_equal(shared.q_modes, single.q_modes)
    assert shared.vs_random.p_value == single.vs_random.p_value
    rand = random_labelings(regime[src], 3, seed=2)
    assert np.array_equal(shared.q_random[1], pointwise_quotients(X, Y, rand[1]))
    with pytest.raises(ValueError, match=r"q_random must be \(n_random, N\) = \(3, "):
        mode_evidence(X, Y, trial, src, feats, regime, q_random=shared.q_random[:2], **kw)
