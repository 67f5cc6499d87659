"""The calibrated "modes add information" test (learning.analysis.reference), small calibration study.

The full study (≥ 50 regime-free data sets, power against cue strength) is
benchmarks/bench_calibration.py; here a few regime-free data sets must not claim, a
positive control with a regime the observation does not reveal must claim, and the
statistics are checked against scipy and by hand.
"""

import math

import numpy as np
import pytest
from scipy import signal, stats

from learning.analysis import HELP_EFFECT, MIN_EFFECT, SIGNIFICANCE, AnalysisConfig, analyze
from learning.analysis.reference import (
    REFERENCES,
    min_trials_for,
    mode_evidence,
    reference_segmentation,
    size_matched_kmeans,
    trial_test,
)
from sim.regime_free import calibration_family, generate_regime_free

FAST = {"n_random": 1, "search_windows": (), "search_modes": (), "hmm_restarts": 2}


@pytest.mark.parametrize("k", range(4))
def test_small_regime_free_family_makes_no_claim(k):
    # one data set of each map kind (linear/nonlinear observation and action), 10 trials of 45 s;
    # neither claim ("modes help", "the temporal model adds information") may be made
    cfg, seed = calibration_family(4, seed=7, trial_s=(45.0, 45.0), trials=(10, 10))[k]
    t = analyze(generate_regime_free(cfg, seed), AnalysisConfig(**FAST)).report["segmentation_test"]
    assert t["reachable"] and t["n_trials"] >= 10
    assert not t["significant"], (cfg, t["p_value"], t["effect_size"])
    assert t["p_value"] > SIGNIFICANCE
    claims = t["claims"]
    assert set(claims) == {"modes_help", "temporal_model_adds"}
    assert not claims["temporal_model_adds"]["made"] and claims["temporal_model_adds"]["p_value"] == t["p_value"]
    assert not claims["modes_help"]["made"], (cfg, claims["modes_help"])
    assert claims["modes_help"]["min_effect"] == pytest.approx(HELP_EFFECT)


def _hidden_regime_data(n_trials: int, T: int, seed: int):
    """Windows whose action map switches between 3 regimes every 10 s while the observation
    (a slow 1-D leader signal through 3 channels) carries no trace of the regime."""
    rng = np.random.default_rng(seed)
    b, a = signal.butter(2, 0.05)
    C = np.array([1.0, -1.0, 0.3])
    X, Y, trial, src, regime, feats = [], [], [], [], [], []
    start = 0
    for k in range(n_trials):
        z = signal.lfilter(b, a, rng.standard_normal(T + 200))[200:]
        z /= z.std()
        s = (np.arange(T) // 100 + k) % 3
        o = np.outer(z, [1.0, 0.5, -0.8]) + rng.normal(0, 0.02, (T, 3))
        u = (C[s] * z)[:, None] + rng.normal(0, 0.02, (T, 1))
        lags = 5
        for t in range(lags - 1, T):
            X.append(o[t - lags + 1:t + 1][::-1].ravel() / math.sqrt(lags))
            Y.append(u[t])
            trial.append(k)
            src.append(start + t)
        regime.append(s)
        feats.append(o)
        start += T
    return (np.array(X), np.array(Y), np.array(trial), np.array(src), np.concatenate(feats),
            np.concatenate(regime))


def test_a_regime_the_observation_does_not_reveal_is_claimed():
    X, Y, trial, src, feats, regime = _hidden_regime_data(12, 300, seed=3)
    ev = mode_evidence(X, Y, trial, src, feats, regime, reference="gmm", n_random=1, alpha=SIGNIFICANCE,
                       min_effect=MIN_EFFECT, seed=0)
    t = ev.vs_reference
    assert ev.claimed and t.reachable and t.p_value == pytest.approx(2.0 ** -12)
    assert MIN_EFFECT < t.ci_low <= t.effect <= t.ci_high
    assert ev.vs_random.claimed and ev.p_value == max(t.p_value, ev.vs_random.p_value)
    # The regimes scrambled in time (random labels): on confounded data random thinning beats
    # the spatial reference grouping, but not random groups, so there is no claim.
    rng = np.random.default_rng(0)
    ev0 = mode_evidence(X, Y, trial, src, feats, rng.permutation(regime), n_random=1, min_effect=MIN_EFFECT)
    assert not ev0.vs_random.claimed and not ev0.claimed


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
