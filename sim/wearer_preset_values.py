"""The wearer presets' numbers: name → keyword arguments of :class:`sim.wearer.WearerConfig` (their sources,
and the presets as settings, in :mod:`sim.wearer_presets`)."""

from __future__ import annotations

from types import MappingProxyType
from typing import Mapping

__all__ = ["DEFAULT_WEARER_PRESET", "PRESET_VALUES"]

DEFAULT_WEARER_PRESET = "hemiparetic_mild"

#: name → settings [units of :class:`sim.wearer.WearerConfig`]; read-only.
PRESET_VALUES: Mapping[str, Mapping[str, float]] = MappingProxyType({
    "unimpaired": MappingProxyType(dict(reaction_delay_s=0.2, bandwidth_hz=2.0, rhythmic_bandwidth_hz=4.0,
                                        feedback_gain_per_s=2.0, max_speed_mps=0.5, noise_rad=0.002,
                                        noise_signal_dependent=0.10)),
    "hemiparetic_mild": MappingProxyType(dict(reaction_delay_s=0.3, bandwidth_hz=1.5, rhythmic_bandwidth_hz=2.5,
                                              feedback_gain_per_s=1.5, max_speed_mps=0.3, noise_rad=0.003,
                                              noise_signal_dependent=0.15)),
    "hemiparetic_severe": MappingProxyType(dict(reaction_delay_s=0.45, bandwidth_hz=1.0, rhythmic_bandwidth_hz=1.5,
                                                feedback_gain_per_s=1.0, max_speed_mps=0.15, noise_rad=0.004,
                                                noise_signal_dependent=0.25)),
})
