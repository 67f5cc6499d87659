"""Data with weakly cued hidden modes (sim.hidden_regime): labels and cue."""

import numpy as np
import pytest

from sim.hidden_regime import HiddenRegimeConfig, generate_hidden_regime


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
