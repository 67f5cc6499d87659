"""The simulated wearer: corrects the knife toward their intent through the shoulder channel.

The intent is the knife-tip motion of a held-out demonstration, p*(t) [m] in the
plate frame (zero-phase low-passed at ``intent_cutoff_hz``: the plan, without
the recording's sensor noise).  Every control step k (period Δ) the wearer

1. perceives the tip error with a reaction delay d:  e = p*(t_k − d) − p(t_k − d);
2. engages in proportion to how far it exceeds a tolerated band (deadband δ):
   w = clip((‖e‖ − δ)/δ, 0, 1)  — small errors are tolerated, and where the
   robot serves the intent the wearer stays still;
3. wants the tip velocity  u = w·(ṗ*(t_k) + K·e), capped at ``max_speed_mps``
   (feed-forward of their own plan plus delayed error feedback);
4. turns it into shoulder angles θ_des = ShoulderMap.angles_for(u) (the
   controller maps them back);
5. moves the shoulder through a critically damped second-order low-pass at
   ``bandwidth_hz`` (limited bandwidth) and adds noise, constant plus
   signal-dependent:  θ = θ_f + σ₀·n₁ + c·|θ_f|⊙n₂,  n ~ N(0, I).

Default values and their sources:

* ``reaction_delay_s`` = 0.2 s: visual reaction and visuomotor feedback delays of
  150–250 ms (Luce 1986, *Response Times*; McRuer & Jex 1967, IEEE Trans. HFE 8:231,
  effective delay of the human operator in tracking ≈ 0.1–0.2 s plus neuromuscular lag).
* ``bandwidth_hz`` = 2 Hz: voluntary tracking bandwidth ≈ 1–2 Hz, intermittent
  corrections at ≈ 2 Hz (Neilson, Neilson & O'Dwyer 1988, Biol Cybern 58:63;
  crossover at a few rad/s in McRuer & Jex 1967).
* ``deadband_m`` = 0.01 m: errors of about a centimetre tolerated before a correction
  starts (intermittent control with an error threshold: Loram, Gollee, Lakie &
  Gawthrop 2011, J Physiol 589:307).
* ``feedback_gain_per_s`` = 2 /s: error time constant 0.5 s, stable with the delay
  (K·d = 0.4 < π/2).
* ``noise_signal_dependent`` = 0.1: motor noise with a standard deviation
  proportional to the command, coefficient of variation ≈ 5–15 % (Harris &
  Wolpert 1998, Nature 394:780; Jones, Hamilton & Wolpert 2002, J Neurophysiol 88:1533).
* ``noise_rad`` = 0.002 rad: physiological tremor and postural sway of the shoulder,
  a few mrad (Elble & Koller 1990, *Tremor*), below ShoulderMap's 0.01 rad dead zone.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass, field

import numpy as np
from scipy import signal

from robot.shoulder import ShoulderMap

__all__ = ["SimulatedWearer", "WearerConfig", "smooth_intent"]


@dataclass(frozen=True)
class WearerConfig:
    """Settings of :class:`SimulatedWearer` (module docstring for meanings and sources)."""

    reaction_delay_s: float = 0.2
    bandwidth_hz: float = 2.0
    deadband_m: float = 0.01
    feedback_gain_per_s: float = 2.0
    feedforward: bool = True
    max_speed_mps: float = 0.3
    noise_rad: float = 0.002
    noise_signal_dependent: float = 0.1
    intent_cutoff_hz: float = 5.0
    shoulder: ShoulderMap = field(default_factory=ShoulderMap)

    def __post_init__(self) -> None:
        for name in ("reaction_delay_s", "deadband_m", "feedback_gain_per_s", "noise_rad",
                     "noise_signal_dependent"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v >= 0):
                raise ValueError(f"WearerConfig.{name} must be finite and >= 0, got {v!r}")
        for name in ("bandwidth_hz", "max_speed_mps", "intent_cutoff_hz"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0):
                raise ValueError(f"WearerConfig.{name} must be finite and > 0, got {v!r}")


def smooth_intent(positions: np.ndarray, rate_hz: float, cutoff_hz: float) -> tuple[np.ndarray, np.ndarray]:
    """Zero-phase Butterworth low-pass (order 2, forward-backward) of (T, 3) positions [m].

    Returns (positions, velocities [m/s]); the wearer knows their own plan, so
    looking ahead here is no cheat.  Short trials (too short for the filter's
    padding) are returned unfiltered.
    """
    p = np.asarray(positions, dtype=float)
    if cutoff_hz < 0.5 * rate_hz and p.shape[0] > 15:
        b, a = signal.butter(2, cutoff_hz / (0.5 * rate_hz))
        p = signal.filtfilt(b, a, p, axis=0)
    vel = np.gradient(p, 1.0 / rate_hz, axis=0) if p.shape[0] > 1 else np.zeros_like(p)
    return p, vel


class SimulatedWearer:
    """One wearer following one intent trajectory (T, 3) [m] sampled at ``rate_hz`` (the control rate).

    :meth:`step` is called once per control step with the perceived knife tip and
    returns the shoulder angles (3,) [rad].  ``desired_velocity`` holds the last
    wanted tip velocity u [m/s] (for the conflict metric and tests).
    """

    def __init__(self, intent: np.ndarray, rate_hz: float, config: WearerConfig | None = None,
                 seed: int = 0) -> None:
        self.config = c = config or WearerConfig()
        intent = np.asarray(intent, dtype=float)
        if intent.ndim != 2 or intent.shape[1] != 3 or intent.shape[0] < 1:
            raise ValueError(f"intent must be (T, 3) knife-tip positions, got shape {intent.shape}")
        if not np.isfinite(intent).all():
            raise ValueError("intent has non-finite knife-tip positions; fill or drop them first")
        if not rate_hz > 0:
            raise ValueError(f"rate_hz must be > 0, got {rate_hz}")
        self.rate_hz = float(rate_hz)
        self.intent, self.intent_velocity = smooth_intent(intent, rate_hz, c.intent_cutoff_hz)
        self.delay_steps = round(c.reaction_delay_s * rate_hz)
        # critically damped 2nd-order low-pass, discretised per step: x'' = ω²(u − x) − 2ω x'
        self._a = math.exp(-2.0 * math.pi * c.bandwidth_hz / rate_hz)
        self._seed = seed
        self.reset()

    def reset(self) -> None:
        """Forget the perceived history and the shoulder state; restart the noise stream."""
        self._errors: deque[np.ndarray] = deque(maxlen=self.delay_steps + 1)
        self._s1 = np.zeros(3)
        self._s2 = np.zeros(3)
        self._rng = np.random.default_rng(self._seed)
        self.desired_velocity = np.zeros(3)
        self.engagement = 0.0

    def step(self, k: int, tip: np.ndarray) -> np.ndarray:
        """Shoulder angles (3,) [rad] at control step k for the perceived tip (3,) [m] (module steps 1–5)."""
        c = self.config
        k = min(max(int(k), 0), self.intent.shape[0] - 1)
        tip = np.asarray(tip, dtype=float)
        err_now = self.intent[k] - tip if np.isfinite(tip).all() else np.zeros(3)
        self._errors.append(err_now)
        if len(self._errors) > self.delay_steps:
            e = self._errors[0]  # perceived d = delay_steps steps ago
        else:
            e = np.zeros(3)  # nothing perceived yet
        norm = float(np.sqrt(e @ e))
        w = min(max((norm - c.deadband_m) / c.deadband_m, 0.0), 1.0) if c.deadband_m > 0 else float(norm > 0)
        u = c.feedback_gain_per_s * e
        if c.feedforward:
            u = u + self.intent_velocity[k]
        u = w * u
        speed = float(np.sqrt(u @ u))
        if speed > c.max_speed_mps:
            u = u * (c.max_speed_mps / speed)
        self.desired_velocity, self.engagement = u, w
        theta_des = c.shoulder.angles_for(u) if w > 0 else np.zeros(3)
        # two cascaded first-order stages with the same pole = critically damped second order
        a = self._a
        self._s1 = a * self._s1 + (1.0 - a) * theta_des
        self._s2 = a * self._s2 + (1.0 - a) * self._s1
        theta = self._s2.copy()
        if c.noise_rad > 0 or c.noise_signal_dependent > 0:
            n = self._rng.standard_normal(6)
            theta = theta + c.noise_rad * n[:3] + c.noise_signal_dependent * np.abs(theta) * n[3:]
        return theta
