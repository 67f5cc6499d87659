"""A strategy's typed settings: built from a mapping, checked field by field, one class per strategy."""

from __future__ import annotations

import dataclasses

import pytest

from mpcshare.control.strategies import REGISTRY
from mpcshare.control.strategies.base import make_settings
from mpcshare.control.strategies.blend import BlendSettings
from mpcshare.control.strategies.gate import GateSettings


def test_settings_come_from_an_instance_a_mapping_or_the_defaults():
    gate = REGISTRY["gate"]
    given = GateSettings(lead_s=1.0)
    assert make_settings(gate, given) is given and make_settings(gate, None) == GateSettings()
    built = make_settings(gate, {"wearer_modes": [0, 2], "robot_alphas": [0.5, 1, 1], "share_on": 1})
    assert built == GateSettings(wearer_modes=(0, 2), robot_alphas=(0.5, 1.0, 1.0), share_on=1.0)
    assert isinstance(built.share_on, float) and built.wearer_modes == (0, 2)
    assert make_settings(REGISTRY["blend"], {"blend_range": [0.4, 0.8]}) == BlendSettings((0.4, 0.8))
    assert make_settings(REGISTRY["reactive"], None) is None


def test_a_wrong_setting_is_named():
    with pytest.raises(ValueError, match=r"unknown blend setting\(s\) \['p0'\]; valid: blend_range"):
        make_settings(REGISTRY["blend"], {"p0": 0.4})
    with pytest.raises(ValueError, match="gate settings: gate setting lead_s must be a number"):
        make_settings(REGISTRY["gate"], {"lead_s": "soon"})
    with pytest.raises(ValueError, match="paper_gate settings: need 0 <= off_threshold <= on_threshold"):
        make_settings(REGISTRY["paper_gate"], {"on_threshold": 0.3, "off_threshold": 0.6})
    with pytest.raises(ValueError, match="strategy 'voluntary' has no settings"):
        make_settings(REGISTRY["voluntary"], {"lead_s": 1.0})
    with pytest.raises(TypeError, match="a GateSettings or a mapping of its fields, got BlendSettings"):
        make_settings(REGISTRY["gate"], BlendSettings())


def test_every_strategys_settings_are_frozen_with_defaults():
    for name, spec in REGISTRY.items():
        if spec.settings is None:
            continue
        s = spec.settings()
        with pytest.raises(dataclasses.FrozenInstanceError):
            setattr(s, dataclasses.fields(s)[0].name, 0.0)
        assert make_settings(spec, dataclasses.asdict(s)) == s, name
