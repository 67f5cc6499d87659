"""The wearer presets (sim.wearer_presets): ordered by impairment, mild hemiparesis by default, unknown ones refused."""

import numpy as np
import pytest

from sim.wearer import WearerConfig
from sim.wearer_presets import DEFAULT_WEARER_PRESET, wearer_preset, wearer_preset_name


def test_presets_are_ordered_by_impairment_and_the_default_is_mild_hemiparesis():
    assert DEFAULT_WEARER_PRESET == "hemiparetic_mild"
    assert WearerConfig().to_dict() == wearer_preset(DEFAULT_WEARER_PRESET).to_dict()
    assert wearer_preset_name(WearerConfig()) == "hemiparetic_mild"
    assert wearer_preset_name(WearerConfig(reaction_delay_s=0.123)) is None
    u, m, s = (wearer_preset(n) for n in ("unimpaired", "hemiparetic_mild", "hemiparetic_severe"))
    assert u.reaction_delay_s < m.reaction_delay_s < s.reaction_delay_s  # slower
    assert u.rhythmic_bandwidth_hz > m.rhythmic_bandwidth_hz > s.rhythmic_bandwidth_hz
    assert u.bandwidth_hz > m.bandwidth_hz > s.bandwidth_hz
    assert u.max_speed_mps > m.max_speed_mps > s.max_speed_mps  # weaker
    assert u.noise_signal_dependent < m.noise_signal_dependent < s.noise_signal_dependent  # noisier
    for c in (u, m, s):
        assert c.feedback_gain_per_s * c.reaction_delay_s < np.pi / 2  # the delayed loop is stable


def test_an_unknown_preset_names_the_choices():
    with pytest.raises(ValueError, match=r'wearer preset "stroke" not in \[.*unimpaired.*hemiparetic_severe'):
        wearer_preset("stroke")
