"""Regime-free demonstrations: data with *no* hidden mode, for calibrating the analysis.

A slowly drifting latent leader signal z(t) ∈ ℝᵐ (m = 1…5) is seen through
``n_obs`` channels with small noise, and the action is *one* function of it:

    z   = critically damped low-pass of white noise (time constant ``drift_s``), unit RMS
    o_t = h(z_t) + ε_o,   h(z) = A z           ("linear")
                          h_j(z) = tanh(a_j·z) (even j), 0.5 sin(b_j·z) (odd j)   ("nonlinear")
    u_t = g(z_t) + ε_u,   g(z) = C z           ("linear")
                          g(z) = tanh(C z) + 0.5 cos(D z)     ("nonlinear")

A, C have i.i.d. N(0, 1/m) entries, B, D N(0, 4/m) (one draw per data set, shared by
all trials). The observation map is injective (the linear map, or the tanh channels,
need n_obs ≥ m, resp. ⌈n_obs/2⌉ ≥ m): the observation determines the latent and hence
the action, so there is no hidden state. (A folding map, where distant latents look
alike, would be hidden state that time can recover: a real finding, not a false one.)
ε_o, ε_u are i.i.d. Gaussian with std ``obs_noise``, ``act_noise`` (units of the
unit-RMS latent). Any structure a segmentation finds here is observation-space
structure, not a regime: the analysis must not claim that modes add information
(``benchmarks/bench_calibration.py``, ``tests/learning/analysis/test_calibration.py``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np
from scipy import signal

from learning.data import Demonstrations, Trial

__all__ = ["RegimeFreeConfig", "calibration_family", "generate_regime_free"]

MapKind = Literal["linear", "nonlinear"]


@dataclass(frozen=True)
class RegimeFreeConfig:
    """One family of regime-free data sets.

    Attributes:
        latent_dim: dimension m of the leader signal (1…5 in the calibration study).
        obs_map, act_map: "linear" or "nonlinear" (see module doc).
        n_obs: observation channels; n_act: action channels (multiples of 3 suit
            the analysis's per-sensor scaling).
        obs_noise, act_noise: noise std relative to the unit-RMS latent [-].
        drift_s: time constant of the latent's drift [s].
        n_trials: trials; trial_s: length of each [s]; rate_hz: sample rate [Hz].
    """

    latent_dim: int = 2
    obs_map: MapKind = "linear"
    act_map: MapKind = "linear"
    n_obs: int = 9
    n_act: int = 3
    obs_noise: float = 0.02
    act_noise: float = 0.02
    drift_s: float = 2.0
    n_trials: int = 12
    trial_s: float = 90.0
    rate_hz: float = 10.0

    def __post_init__(self) -> None:
        for name in ("latent_dim", "n_obs", "n_act", "n_trials"):
            if int(getattr(self, name)) != getattr(self, name) or getattr(self, name) < 1:
                raise ValueError(f"{name} must be a positive integer, got {getattr(self, name)!r}")
        for name in ("obs_map", "act_map"):
            if getattr(self, name) not in ("linear", "nonlinear"):
                raise ValueError(f"{name} must be 'linear' or 'nonlinear', got {getattr(self, name)!r}")
        for name in ("obs_noise", "act_noise"):
            if not getattr(self, name) >= 0:
                raise ValueError(f"{name} must be >= 0, got {getattr(self, name)!r}")
        for name in ("drift_s", "trial_s", "rate_hz"):
            if not getattr(self, name) > 0:
                raise ValueError(f"{name} must be > 0, got {getattr(self, name)!r}")
        need = self.latent_dim if self.obs_map == "linear" else 2 * self.latent_dim - 1
        if self.n_obs < need:
            raise ValueError(f"n_obs = {self.n_obs} cannot observe a {self.latent_dim}-D latent through a "
                             f"{self.obs_map} map injectively; it needs n_obs >= {need}")
        if int(round(self.trial_s * self.rate_hz)) < 2:
            raise ValueError(f"a trial of {self.trial_s} s at {self.rate_hz} Hz has fewer than 2 samples")


def _drift(rng: np.random.Generator, n: int, m: int, tau_s: float, rate_hz: float) -> np.ndarray:
    """(n, m) critically damped low-pass of white noise, scaled to unit RMS per channel."""
    a = np.exp(-1.0 / (tau_s * rate_hz))
    burn = int(5 * tau_s * rate_hz)  # start in the stationary regime
    w = rng.standard_normal((n + burn, m))
    z = signal.lfilter([(1 - a) ** 2], [1.0, -2 * a, a * a], w, axis=0)[burn:]
    return z / np.sqrt(np.mean(z**2, axis=0, keepdims=True))


def _obs_map(kind: MapKind, z: np.ndarray, A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """h(z): linear, or even channels tanh(A z) (injective) and odd channels 0.5 sin(B z)."""
    if kind == "linear":
        return z @ A.T
    out = np.tanh(z @ A.T)
    out[:, 1::2] = 0.5 * np.sin(z @ B[1::2].T)
    return out


def _act_map(kind: MapKind, z: np.ndarray, C: np.ndarray, D: np.ndarray) -> np.ndarray:
    """g(z): linear, or tanh(C z) + 0.5 cos(D z)."""
    if kind == "linear":
        return z @ C.T
    return np.tanh(z @ C.T) + 0.5 * np.cos(z @ D.T)


def generate_regime_free(config: RegimeFreeConfig | None = None, seed: int = 0) -> Demonstrations:
    """A regime-free data set (see module doc); the same seed gives the same data.

    Trials are independent stretches of the latent drift; there are no mode labels
    (``Trial.mode`` is None).
    """
    c = config or RegimeFreeConfig()
    rng = np.random.default_rng(seed)
    m = int(c.latent_dim)
    s = 1.0 / np.sqrt(m)
    A, B = rng.normal(0, s, (c.n_obs, m)), rng.normal(0, 2 * s, (c.n_obs, m))
    C, D = rng.normal(0, s, (c.n_act, m)), rng.normal(0, 2 * s, (c.n_act, m))
    n = int(round(c.trial_s * c.rate_hz))
    trials = []
    for k in range(int(c.n_trials)):
        z = _drift(rng, n, m, c.drift_s, c.rate_hz)
        obs = _obs_map(c.obs_map, z, A, B) + rng.normal(0, c.obs_noise, (n, c.n_obs))
        act = _act_map(c.act_map, z, C, D) + rng.normal(0, c.act_noise, (n, c.n_act))
        t = k * (c.trial_s + 10.0) + np.arange(n) / c.rate_hz
        trials.append(Trial(obs=obs, act=act, t=t, trial_id=k, subject=0))
    return Demonstrations(trials, c.rate_hz, [f"o{j}" for j in range(c.n_obs)],
                          [f"u{j}" for j in range(c.n_act)])


def calibration_family(n_sets: int, seed: int = 0, trial_s: tuple[float, float] = (60.0, 120.0),
                       trials: tuple[int, int] = (6, 20)) -> list[tuple[RegimeFreeConfig, int]]:
    """``n_sets`` (config, data seed) pairs spanning the regime-free family: linear and
    nonlinear observation and action maps (cycled), latent dimension 1–5 (cycled), obs noise
    0.01–0.1 and action noise 0.01–0.05 (log-uniform), drift 1.5–4 s, ``trials`` trials of
    ``trial_s`` seconds at 10 Hz (uniform, integer trials)."""
    rng = np.random.default_rng(seed)
    maps = [("linear", "linear"), ("linear", "nonlinear"), ("nonlinear", "linear"), ("nonlinear", "nonlinear")]
    out = []
    for k in range(n_sets):
        om, am = maps[k % 4]
        m = 1 + (k // 4) % 5  # 9 channels observe up to 5 latents through either map
        out.append((RegimeFreeConfig(
            latent_dim=m, obs_map=om, act_map=am,
            obs_noise=float(np.exp(rng.uniform(np.log(0.01), np.log(0.1)))),
            act_noise=float(np.exp(rng.uniform(np.log(0.01), np.log(0.05)))),
            drift_s=float(rng.uniform(1.5, 4.0)), n_trials=int(rng.integers(trials[0], trials[1] + 1)),
            trial_s=float(rng.uniform(*trial_s))), int(rng.integers(2**31))))
    return out
