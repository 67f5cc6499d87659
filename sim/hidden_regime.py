"""Data with hidden regimes whose observation cue is weak: the power side of the calibration study.

A slow leader signal z(t) (unit RMS, critically damped low-pass of white noise) and a
hidden regime s(t) ∈ {0, 1, 2} (semi-Markov, gamma(4) dwell times of mean ``dwell_s``,
each switch to another regime) produce

    o_t = [0.3 z, 0.2 z, −0.25 z, cue·c_{s,1}, cue·c_{s,2}, 0] + ε_o
    u_t = C_s z_t + b_s + ε_u                                           (C_s, b_s ~ N(0, 1))

with c_s three unit vectors 120° apart; ε_o has std ``z_noise`` on the three leader
channels and ``noise`` on the three cue channels (both 0.3 by default). With precise
leader channels (``z_noise`` 0.02) the HMM models the leader's range instead and never
finds the regimes (agreement at chance for cue/noise 0.25–2, measured): what the
HMM discovers, not the test, limits the power there. The regime changes the action map;
the observation carries it only through the cue, a distance √3·cue between regimes
against the noise: at cue/noise ≲ 0.5 one observation barely tells the regimes apart,
time does. Channels are on different scales: analyse with ``scope="channel"``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from learning.data import Demonstrations, Trial
from sim.regime_free import _drift

__all__ = ["HiddenRegimeConfig", "generate_hidden_regime"]

_CUES = np.array([[1.0, 0.0], [-0.5, np.sqrt(0.75)], [-0.5, -np.sqrt(0.75)]])
_LOADINGS = np.array([0.3, 0.2, -0.25])


@dataclass(frozen=True)
class HiddenRegimeConfig:
    """Parameters (see module doc); ``cue`` and ``noise`` in units of the observation."""

    cue: float = 0.15
    noise: float = 0.3
    z_noise: float = 0.3
    act_noise: float = 0.02
    drift_s: float = 2.0
    dwell_s: float = 8.0
    n_trials: int = 12
    trial_s: float = 60.0
    rate_hz: float = 10.0

    def __post_init__(self) -> None:
        if int(self.n_trials) != self.n_trials or self.n_trials < 1:
            raise ValueError(f"n_trials must be a positive integer, got {self.n_trials!r}")
        for name in ("cue", "noise", "z_noise", "act_noise"):
            if not getattr(self, name) >= 0:
                raise ValueError(f"{name} must be >= 0, got {getattr(self, name)!r}")
        for name in ("drift_s", "dwell_s", "trial_s", "rate_hz"):
            if not getattr(self, name) > 0:
                raise ValueError(f"{name} must be > 0, got {getattr(self, name)!r}")


def _regimes(rng: np.random.Generator, n: int, dwell: float) -> np.ndarray:
    out = np.empty(n, dtype=np.int64)
    t, s = 0, int(rng.integers(3))
    while t < n:
        d = max(int(rng.gamma(4.0, dwell / 4.0)), 1)
        out[t:t + d] = s
        t += d
        s = int((s + rng.integers(1, 3)) % 3)
    return out


def generate_hidden_regime(config: HiddenRegimeConfig | None = None, seed: int = 0) -> Demonstrations:
    """A data set with three hidden regimes (see module doc); ``Trial.mode`` is the true regime."""
    c = config or HiddenRegimeConfig()
    rng = np.random.default_rng(seed)
    C, b = rng.normal(0, 1, (3, 3)), rng.normal(0, 1, (3, 3))
    n = int(round(c.trial_s * c.rate_hz))
    trials = []
    for k in range(int(c.n_trials)):
        z = _drift(rng, n, 1, c.drift_s, c.rate_hz)[:, 0]
        s = _regimes(rng, n, c.dwell_s * c.rate_hz)
        obs = np.column_stack([np.outer(z, _LOADINGS), c.cue * _CUES[s], np.zeros(n)])
        obs += rng.normal(0, 1, obs.shape) * np.repeat([c.z_noise, c.noise], 3)
        act = C[s] * z[:, None] + b[s] + rng.normal(0, c.act_noise, (n, 3))
        t = k * (c.trial_s + 10.0) + np.arange(n) / c.rate_hz
        trials.append(Trial(obs=obs, act=act, t=t, trial_id=k, subject=0, mode=s))
    return Demonstrations(trials, c.rate_hz, [f"o{j}" for j in range(6)], [f"u{j}" for j in range(3)])
