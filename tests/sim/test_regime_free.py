"""Data families of the calibration study: sim.regime_free and sim.hidden_regime."""

import numpy as np
import pytest

from sim.hidden_regime import HiddenRegimeConfig, generate_hidden_regime
from sim.regime_free import RegimeFreeConfig, calibration_family, generate_regime_free


def test_regime_free_is_seeded_and_the_action_is_one_function_of_the_latent():
    cfg = RegimeFreeConfig(latent_dim=2, obs_map="linear", act_map="linear", obs_noise=0.0, act_noise=0.0,
                           n_trials=3, trial_s=30.0)
    a, b = generate_regime_free(cfg, seed=4), generate_regime_free(cfg, seed=4)
    assert all(np.array_equal(x.obs, y.obs) and np.array_equal(x.act, y.act) for x, y in zip(a, b))
    assert len(a) == 3 and a.trials[0].obs.shape == (300, 9) and a.trials[0].mode is None
    # noise-free and linear: the action is a linear function of the observation, one for all trials
    O = np.concatenate([t.obs for t in a.trials])
    U = np.concatenate([t.act for t in a.trials])
    W, *_ = np.linalg.lstsq(O, U, rcond=None)
    assert np.abs(O @ W - U).max() < 1e-9


def test_regime_free_refuses_a_map_that_cannot_be_injective():
    with pytest.raises(ValueError, match="n_obs >= 9"):
        RegimeFreeConfig(latent_dim=5, obs_map="nonlinear", n_obs=8)
    with pytest.raises(ValueError, match="obs_map must be 'linear' or 'nonlinear'"):
        RegimeFreeConfig(obs_map="cubic")


def test_calibration_family_spans_the_kinds():
    fam = calibration_family(20, seed=0)
    kinds = {(c.obs_map, c.act_map) for c, _ in fam}
    assert len(kinds) == 4 and {c.latent_dim for c, _ in fam} == {1, 2, 3, 4, 5}
    assert all(6 <= c.n_trials <= 20 and 60 <= c.trial_s <= 120 for c, _ in fam)


def test_hidden_regime_labels_and_cue():
    d = generate_hidden_regime(HiddenRegimeConfig(cue=1.0, noise=0.0, n_trials=2, trial_s=60.0), seed=1)
    s = np.concatenate([t.mode for t in d.trials])
    o = np.concatenate([t.obs for t in d.trials])
    assert set(np.unique(s)) == {0, 1, 2}
    # without noise the cue channels name the regime exactly; the leader channels do not
    for r in range(3):
        assert np.ptp(o[s == r, 3:5], axis=0).max() < 1e-12
    with pytest.raises(ValueError, match="noise must be >= 0"):
        HiddenRegimeConfig(noise=-1.0)
