"""The presets' numbers: each builds the preset of the same name, and the default preset is ``WearerConfig()``."""

from __future__ import annotations

import pytest

from sim.wearer import WearerConfig, wearer_preset_name
from sim.wearer_preset_values import DEFAULT_WEARER_PRESET, PRESET_VALUES
from sim.wearer_presets import WEARER_PRESETS


def test_each_preset_is_built_from_its_numbers_and_named_by_them() -> None:
    assert set(PRESET_VALUES) == set(WEARER_PRESETS) and DEFAULT_WEARER_PRESET in PRESET_VALUES
    for name, values in PRESET_VALUES.items():
        assert WEARER_PRESETS[name].to_dict() == WearerConfig(**values).to_dict()
        assert wearer_preset_name(WearerConfig(**values)) == name
    assert WearerConfig().to_dict() == WEARER_PRESETS[DEFAULT_WEARER_PRESET].to_dict()


def test_the_numbers_are_read_only() -> None:
    with pytest.raises(TypeError):
        PRESET_VALUES["unimpaired"]["reaction_delay_s"] = 0.0  # type: ignore[index]
    with pytest.raises(TypeError):
        PRESET_VALUES["new"] = {}  # type: ignore[index]
