"""Wearer presets from the literature: an unimpaired shoulder, mild and severe hemiparesis.

The numbers are chosen from published figures (or, where none was found, estimated
from the nearest ones, and marked as estimates); none is tuned to a simulation
result.  ``DEFAULT_WEARER_PRESET`` is ``hemiparetic_mild``, the paper's users (Song &
Asada: a person with hemiplegia commanding the SuperLimb through the affected-side
shoulder), and ``WearerConfig()`` equals it.

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

Sources:

* **Reaction delay d.**  Unimpaired: simple visual reaction times of about 190–220 ms
  (Luce 1986, *Response Times*; Kosinski's review of the reaction-time literature),
  the human operator's effective delay in tracking 0.1–0.2 s plus neuromuscular lag
  (McRuer & Jex 1967, IEEE Trans. HFE 8:231) → 0.2 s.  After stroke, reaction times
  of the paretic arm are longer than of the non-paretic arm and of age-matched
  controls (elbow flexion: Dickstein et al. 1993, Phys Ther 73:374; Dickstein,
  Abulaffio & Pillar 1996, Neurorehabil Neural Repair 10:107; wrist: Bi & Wan, 98
  stroke survivors against 20 controls); choice reaction times of 474 ± 144 ms (right
  hemiplegia) and 402 ± 127 ms (left) against 332 ± 73 ms in controls (Pauley,
  Phadke et al. 2015, non-paretic leg), a ratio of 1.2–1.45 → mild 0.2 × 1.45 ≈ 0.3 s.
  Severe: an estimate, the stroke group's mean plus one SD (≈ 620 ms, ratio ≈ 1.9)
  with the slower proximal joints of Dickstein 1996 → 0.45 s.  Visuomotor
  feedback-loop delays in manual tracking of 264–341 ms (Miall 1996, J Mot Behav
  28:125) bracket these values.
* **Rhythmic bandwidth f_r** (self-paced, zero phase).  Unimpaired: the rate limit of
  voluntary rhythmic movement is taken as 5–7 Hz for wrist and finger tapping (as
  cited in the study of the world's fastest drummer, who reached 10 Hz); cyclic elbow
  movements reach 8.4 Hz at 0.1 rad and slow down as the amplitude grows (Zawadzki &
  Siemieński 2010, Acta Bioeng Biomech 12(2)); clapping tops out at 7–8 Hz (PubMed
  19429090, 2009).  A proximal shoulder moving the arm by centimetres is slower → 4 Hz
  (an estimate, within the 3–5 Hz of arm oscillation).  After stroke the affected
  side taps more slowly and less regularly (Shimoyama, Ninchoji & Uemura 1990, Arch
  Neurol 47:681; cued tapping at 1.25 Hz less regular on the affected side: Brain Res
  Bull 2006, 20 chronic patients) and tracks sinusoids with intermittent
  sub-movements in the 0.8–1.8 Hz band (Ao, Song & Tong 2015, PLoS One 10:e0128328)
  → mild 2.5 Hz, severe 1.5 Hz (estimates from these).
* **Corrective bandwidth f_c.**  Unimpaired: voluntary tracking bandwidth ≈ 1–2 Hz,
  intermittent corrections at ≈ 2 Hz (Neilson, Neilson & O'Dwyer 1988, Biol Cybern
  58:63; crossover at a few rad/s in McRuer & Jex 1967) → 2 Hz.  After stroke the
  corrections are slower and more intermittent (Ao et al. 2015; paretic tracking of
  0.2–0.4 Hz sinusoids impaired: J Phys Ther Sci 2011, 23:141) → mild 1.5 Hz, severe
  1.0 Hz (estimates).
* **Feedback gain K.**  Not a literature figure: chosen so the delayed loop stays as
  well damped for every preset, K·d ≤ 0.45 < π/2 (2 × 0.2, 1.5 × 0.3, 1.0 × 0.45).
* **Max speed** (weakness).  Unimpaired self-paced reaching peaks at about 0.5–1 m/s
  (an estimate from the reaching literature, e.g. Atkeson & Hollerbach 1985, J
  Neurosci 5:2318) → 0.5 m/s of commanded tip speed.  People with hemiparesis reach
  slowly: as fast as they can, only as quick as controls at their preferred speed
  (DeJong, Schaefer & Lang 2012, Neurorehabil Neural Repair 26:362); slow, segmented
  reaches with the more affected arm (McCrea & Eng 2005, Exp Brain Res 162:70) →
  mild 0.3 m/s, severe 0.15 m/s (estimates).
* **Noise.**  Signal-dependent motor noise with a coefficient of variation of 5–15 %
  (Harris & Wolpert 1998, Nature 394:780; Jones, Hamilton & Wolpert 2002, J
  Neurophysiol 88:1533) → 0.10 unimpaired.  Greater neuromotor noise in the more
  affected arm (McCrea & Eng 2005: Fitts' slope and intercept increased) and larger
  force variability of the paretic hand (Kang & Cauraugh 2014, PLoS One 9:e101817) →
  0.15 and 0.25 (estimates, 1.5× and 2.5×).  σ₀: physiological tremor and postural
  sway of a few mrad (Elble & Koller 1990, *Tremor*), more after stroke (estimate);
  all below the shoulder map's 0.01 rad dead zone.
* **Dead band δ** = 1 cm for all: errors of about a centimetre tolerated before a
  correction starts (intermittent control with an error threshold: Loram, Gollee,
  Lakie & Gawthrop 2011, J Physiol 589:307); no stroke-specific figure found.
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
