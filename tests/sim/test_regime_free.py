"""Data without hidden modes (sim.regime_free), the calibration family of the analysis."""

import numpy as np
import pytest

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
