"""Tests of mpcshare.training.config: a bad setting is refused with its name."""

import pytest

from mpcshare.training.config import TrainConfig


@pytest.mark.parametrize("kw, match", [
    ({"percentile": 120}, "percentile"), ({"heldout_fraction": 1.0}, "heldout_fraction"),
    ({"gate_kernel": "poly"}, "gate_kernel"), ({"gate_max_samples": 10}, "gate_max_samples"),
    ({"device": "tpu"}, "device"), ({"n_modes": 0}, "n_modes"), ({"burn_in": -1}, "burn_in"),
])
def test_config_names_the_bad_setting(kw, match):
    with pytest.raises(ValueError, match=match):
        TrainConfig(**kw)
