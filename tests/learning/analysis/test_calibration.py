"""The calibrated "modes add information" test (learning.analysis.reference), small calibration study.

The full study (≥ 50 regime-free data sets, power against cue strength) is
benchmarks/bench_calibration.py; here a few regime-free data sets must not claim and a
positive control with a regime the observation does not reveal must claim (the statistics
themselves: test_reference.py).
"""

import numpy as np
import pytest

from learning.analysis import HELP_EFFECT, MIN_EFFECT, SIGNIFICANCE, AnalysisConfig, analyze
from learning.analysis.reference import mode_evidence
from sim.regime_free import calibration_family, generate_regime_free
from tests.learning.analysis.regime_windows import hidden_regime_data as _hidden_regime_data

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
