"""The analysis settings (learning.analysis.config): each invalid one refused by name."""

import pytest

from learning.analysis import AnalysisConfig


@pytest.mark.parametrize("kwargs, match", [
    ({"scope": "global"}, "scope"), ({"n_modes": 0}, "n_modes"), ({"K": ()}, "K"),
    ({"K": (0.0,)}, "K"), ({"n_random": 0}, "n_random"), ({"target_hz": 0}, "target_hz"),
])
def test_bad_settings(kwargs, match):
    with pytest.raises(ValueError, match=match):
        AnalysisConfig(**kwargs)
