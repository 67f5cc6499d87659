"""Wearer presets from the literature: an unimpaired shoulder, mild and severe hemiparesis.

Published figures, or estimates from the nearest ones; none tuned to a simulation result (each derivation:
docs/design.md, "The wearer presets' sources"). ``DEFAULT_WEARER_PRESET`` = ``hemiparetic_mild`` = ``WearerConfig()``.

| setting | unimpaired | hemiparetic_mild | hemiparetic_severe |
|---|---|---|---|
| reaction_delay_s d [s] | 0.20 | 0.30 | 0.45 |
| rhythmic_bandwidth_hz f_r [Hz] | 4.0 | 2.5 | 1.5 |
| bandwidth_hz f_c (corrective) [Hz] | 2.0 | 1.5 | 1.0 |
| feedback_gain_per_s K [1/s] | 2.0 | 1.5 | 1.0 |
| max_speed_mps [m/s] | 0.5 | 0.3 | 0.15 |
| noise_signal_dependent c [-] | 0.10 | 0.15 | 0.25 |
| noise_rad σ₀ [rad] | 0.002 | 0.003 | 0.004 |
| deadband_m δ [m] | 0.01 | 0.01 | 0.01 |

Sources. d: Luce 1986; McRuer & Jex 1967; Dickstein et al. 1993, 1996; Pauley, Phadke et al. 2015; Miall 1996.
f_r: Zawadzki & Siemieński 2010; Shimoyama et al. 1990; Ao, Song & Tong 2015. f_c: Neilson et al. 1988; Ao 2015.
K: not a figure, K·d ≤ 0.45 < π/2 for all. Speed: Atkeson & Hollerbach 1985; DeJong et al. 2012; McCrea & Eng 2005.
Noise: Harris & Wolpert 1998; Jones et al. 2002; Kang & Cauraugh 2014; Elble & Koller 1990. δ: Loram et al. 2011.
"""

from __future__ import annotations

from types import MappingProxyType
from typing import Mapping

from sim.errors import WearerConfigError
from sim.wearer import WearerConfig, wearer_preset_name
from sim.wearer_preset_values import DEFAULT_WEARER_PRESET, PRESET_VALUES

__all__ = ["DEFAULT_WEARER", "DEFAULT_WEARER_PRESET", "WEARER_PRESETS", "wearer_preset", "wearer_preset_name"]

#: name → settings (module docstring for the sources; the numbers in :mod:`sim.wearer_preset_values`); read-only.
WEARER_PRESETS: Mapping[str, WearerConfig] = MappingProxyType({name: WearerConfig(**values)
                                                               for name, values in PRESET_VALUES.items()})

#: the default wearer of a closed-loop episode (``sim.closed_loop.run_episode``): a wearer factory
DEFAULT_WEARER: WearerConfig = WEARER_PRESETS[DEFAULT_WEARER_PRESET]


def wearer_preset(name: str) -> WearerConfig:
    """The settings of preset ``name`` (a key of :data:`WEARER_PRESETS`), or a
    :class:`sim.errors.WearerConfigError` (a ValueError) naming the choices."""
    try:
        return WEARER_PRESETS[name]
    except (KeyError, TypeError):
        raise WearerConfigError(f'wearer preset "{name}" not in {list(WEARER_PRESETS)}') from None
