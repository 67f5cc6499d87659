"""`mpcshare tune`'s default trials and seeds: at least ten pairs."""

from __future__ import annotations


def test_default_sweep_has_at_least_ten_pairs():
    from mpcshare.commands.tune import default_trials_and_seeds

    for n_heldout in (1, 2, 3, 4, 5, 8):
        t, s = default_trials_and_seeds(n_heldout, None, None)
        assert t == min(5, n_heldout) and t * s >= 10 and 0.5 ** (t * s) * 6 < 0.01  # Holm over 6 settings
    assert default_trials_and_seeds(4, None, None) == (4, 3)  # the default data: 4 held-out trials
    assert default_trials_and_seeds(4, 2, None) == (2, 5) and default_trials_and_seeds(4, 2, 1) == (2, 1)
