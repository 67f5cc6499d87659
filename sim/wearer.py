"""The simulated wearer: drives their own plan or corrects the robot, through the shoulder channel.

Intent p*(t) [m, plate frame]: a held-out demonstration's knife tip, zero-phase low-passed at ``intent_cutoff_hz``.
Feed-forward beside delayed feedback (McRuer & Jex 1967, IEEE Trans. HFE 8:231; IEEE Trans. HMS 50:68, 2020):

- **own plan**, no reaction delay: p*, zero-phase low-passed once at f_r (``rhythmic_bandwidth_hz``),
  |G(f)| = 1 / (1 + (√2 − 1)·(f/f_r)⁴) (Butterworth 2nd order, forward and backward) → p_r, ṗ_r;
- **corrections**, per control step k: e = p*(t_k − d) − p(t_k − d) (reaction delay d),
  w = clip((‖e‖ − δ)/δ, 0, 1) (dead band δ), u_c = w·K·e;
- **who leads**: ``step(k, tip, alpha_cue)`` gets the previous step's α, perceived d later; α ≥ 0.5: the robot
  leads (λ = 0), else the wearer (λ = 1 with ``feedforward``); a missing cue (None, NaN) keeps the last
  perceived leader, the wearer before any. u = λ·ṗ_r(t_k) + u_c, scaled to ‖u‖ ≤ ``max_speed_mps``;
- **shoulder** (robot.shoulder.ShoulderMap, n angles, P⁺ for fewer than three): z = P⁻¹u/g, corrective part
  through a critically damped low-pass at f_c (``bandwidth_hz``): z = LP_fc(z_c) + z_r; past the map's dead
  zone δ_θ: θ₀ = z + δ_θ·clip(z/ε, −1, 1), ε = 0.1·δ_θ; motor noise θ = θ₀ + σ₀·n₁ + c·|θ₀|⊙n₂,
  n ~ N(0, I) (Harris & Wolpert 1998, Nature 394:780). θ [rad].

``desired_velocity`` is the last u [m/s], ``engagement`` the last w, ``wearer_leads`` the leader perceived.
Settings: :class:`WearerConfig` (default ``hemiparetic_mild``), sources in :mod:`sim.wearer_presets`;
bad settings raise :class:`sim.errors.WearerConfigError`.
"""

from __future__ import annotations

import json
import math
from collections import deque
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np
from scipy import signal

from robot.shoulder import ShoulderMap
from sim.errors import WearerConfigError
from sim.task import EATING
from sim.wearer_preset_values import PRESET_VALUES

__all__ = ["SimulatedWearer", "WearerConfig", "rhythmic_plan", "smooth_intent", "wearer_preset_name"]

_DEADZONE_RAMP = 0.1  # ε / δ_θ: below ε the wearer relaxes toward rest instead of holding δ_θ


@dataclass(frozen=True)
class WearerConfig:
    """Settings of :class:`SimulatedWearer`; the defaults are the ``hemiparetic_mild`` preset.

    Attributes (sources in :mod:`sim.wearer_presets`):
        reaction_delay_s: d [s], of the corrections and of perceiving the α cue.
        bandwidth_hz: f_c [Hz], the corrective path's critically damped low-pass.
        rhythmic_bandwidth_hz: f_r [Hz], −3 dB point of the zero-phase filter of the plan.
        deadband_m: δ [m], tip errors tolerated before a correction starts.
        feedback_gain_per_s: K [1/s], corrective velocity per metre of error.
        feedforward: drive the plan when leading (False: a purely corrective wearer).
        max_speed_mps: cap on ‖u‖ [m/s] (weakness: how fast the shoulder can command).
        noise_rad: σ₀ [rad], tremor and postural sway of the shoulder.
        noise_signal_dependent: c [-], standard deviation per unit of |θ|.
        intent_cutoff_hz: [Hz] zero-phase low-pass of the recorded intent (sensor noise).
        shoulder: the shoulder map the controller uses (gain, dead zone, its n channels).
    """

    reaction_delay_s: float = 0.3
    bandwidth_hz: float = 1.5
    rhythmic_bandwidth_hz: float = 2.5
    deadband_m: float = 0.01
    feedback_gain_per_s: float = 1.5
    feedforward: bool = True
    max_speed_mps: float = 0.3
    noise_rad: float = 0.003
    noise_signal_dependent: float = 0.15
    intent_cutoff_hz: float = 5.0
    shoulder: ShoulderMap = field(default_factory=EATING.shoulder_map)

    def __post_init__(self) -> None:
        for name in ("reaction_delay_s", "deadband_m", "feedback_gain_per_s", "noise_rad",
                     "noise_signal_dependent"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v >= 0):
                raise WearerConfigError(f"WearerConfig.{name} must be finite and >= 0, got {v!r}")
        for name in ("bandwidth_hz", "rhythmic_bandwidth_hz", "max_speed_mps", "intent_cutoff_hz"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0):
                raise WearerConfigError(f"WearerConfig.{name} must be finite and > 0, got {v!r}")

    def to_dict(self) -> dict[str, Any]:
        """JSON-able settings (the shoulder map as its gain and dead zone); compare configs with this."""
        d = asdict(self)
        d["shoulder"] = {"gain": float(self.shoulder.gain), "deadband_rad": float(self.shoulder.deadband_rad)}
        return d

    def __call__(self, intent: np.ndarray, rate_hz: float, *, seed: int = 0) -> SimulatedWearer:
        """The wearer with these settings (a :class:`sim.wearer_protocol.WearerFactory`)."""
        return SimulatedWearer(intent, rate_hz, self, seed=seed)


def wearer_preset_name(config: WearerConfig) -> str | None:
    """The name of the preset (:mod:`sim.wearer_presets`) whose settings equal ``config`` (compared by
    ``to_dict``), or None."""
    d = config.to_dict()
    return next((name for name, values in PRESET_VALUES.items() if WearerConfig(**values).to_dict() == d), None)


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


def rhythmic_plan(positions: np.ndarray, rate_hz: float, bandwidth_hz: float) -> tuple[np.ndarray, np.ndarray]:
    """The self-generated motion: (positions [m], velocities [m/s]) of the plan at the rhythmic bandwidth.

    Zero-phase filter with |G(f)| = 1/(1 + (√2 − 1)(f/f_r)⁴): a 2nd-order Butterworth at
    f_r/(√2 − 1)^¼ ≈ 1.25·f_r run forward and backward, so the gain is 1/√2 at f_r and
    the phase 0 everywhere.  Unfiltered where that cutoff reaches Nyquist or the plan is
    too short for the filter's padding.
    """
    per_pass_hz = bandwidth_hz / (math.sqrt(2.0) - 1.0) ** 0.25
    return smooth_intent(positions, rate_hz, per_pass_hz)


class SimulatedWearer:
    """One wearer following one intent trajectory (T, 3) [m] sampled at ``rate_hz`` (the control rate).

    Follows :class:`sim.wearer_protocol.Wearer`; the class and its config are wearer factories.

    :meth:`step` is called once per control step with the perceived knife tip (and the
    controller's α of the previous step as the cue) and returns the shoulder angles (n,)
    [rad] (module docstring).
    """

    def __init__(self, intent: np.ndarray, rate_hz: float, config: WearerConfig | None = None,
                 seed: int = 0) -> None:
        self.config = c = config or WearerConfig()
        intent = np.asarray(intent, dtype=float)
        if intent.ndim != 2 or intent.shape[1] != 3 or intent.shape[0] < 1:
            raise WearerConfigError(f"intent must be (T, 3) knife-tip positions, got shape {intent.shape}")
        if not np.isfinite(intent).all():
            raise WearerConfigError("intent has non-finite knife-tip positions; fill or drop them first")
        if not rate_hz > 0:
            raise WearerConfigError(f"rate_hz must be > 0, got {rate_hz}")
        self.rate_hz = float(rate_hz)
        self.intent, self.intent_velocity = smooth_intent(intent, rate_hz, c.intent_cutoff_hz)
        self.plan, self.plan_velocity = rhythmic_plan(self.intent, rate_hz, c.rhythmic_bandwidth_hz)
        self.delay_steps = round(c.reaction_delay_s * rate_hz)
        # critically damped 2nd-order low-pass, discretised per step: x'' = ω²(u − x) − 2ω x'
        self._a = math.exp(-2.0 * math.pi * c.bandwidth_hz / rate_hz)
        self._to_z = c.shoulder.inverse() / c.shoulder.gain  # u [m/s] → z [rad], (n, 3)
        self._seed = seed
        self.reset()

    def reset(self) -> None:
        """Forget the perceived history, the leader and the shoulder state; restart the noise stream."""
        self._errors: deque[np.ndarray] = deque(maxlen=self.delay_steps + 1)
        self._cues: deque[float] = deque(maxlen=self.delay_steps + 1)
        n = self.config.shoulder.n_channels
        self._s1 = np.zeros(n)
        self._s2 = np.zeros(n)
        self._rng = np.random.default_rng(self._seed)
        self.desired_velocity = np.zeros(3)
        self.engagement = 0.0
        self.wearer_leads = True
        self.perceived_alpha = float("nan")

    def info(self) -> dict[str, Any]:
        """The episode's record of this wearer: the shoulder map, the dead band and the preset's name (or None)."""
        c = self.config
        out = {"shoulder_gain": c.shoulder.gain, "shoulder_deadband_rad": c.shoulder.deadband_rad,
               "wearer_deadband_m": c.deadband_m, "wearer_preset": wearer_preset_name(c)}
        if not np.array_equal(c.shoulder.matrix, EATING.shoulder_to_plate):
            out["shoulder_matrix"] = json.dumps(c.shoulder.matrix.tolist())
        return out

    def _perceive_cue(self, alpha_cue: float | None) -> None:
        """Push the cue into the delay line; the one given d steps ago decides who leads (if finite)."""
        try:
            cue = float("nan") if alpha_cue is None else float(alpha_cue)
        except (TypeError, ValueError):
            cue = float("nan")
        self._cues.append(cue)
        if len(self._cues) > self.delay_steps:
            seen = self._cues[0]
            if math.isfinite(seen):
                self.perceived_alpha = seen
                self.wearer_leads = seen < 0.5

    def step(self, k: int, tip: np.ndarray, alpha_cue: float | None = None) -> np.ndarray:
        """Shoulder angles (n,) [rad] (the shoulder map's channels) at control step k for the perceived
        tip (3,) [m].

        ``alpha_cue``: the controller's α of the previous step (None or NaN: no cue now).
        """
        c = self.config
        k = min(max(int(k), 0), self.intent.shape[0] - 1)
        self._perceive_cue(alpha_cue)
        tip = np.asarray(tip, dtype=float)
        err_now = self.intent[k] - tip if tip.shape == (3,) and all(map(math.isfinite, tip.tolist())) \
            else np.zeros(3)
        self._errors.append(err_now)
        e = self._errors[0] if len(self._errors) > self.delay_steps else np.zeros(3)  # perceived d ago
        norm = math.sqrt(float(e @ e))
        w = min(max((norm - c.deadband_m) / c.deadband_m, 0.0), 1.0) if c.deadband_m > 0 else float(norm > 0)
        u_c = w * c.feedback_gain_per_s * e
        u_r = self.plan_velocity[k] if (c.feedforward and self.wearer_leads) else np.zeros(3)
        u = u_r + u_c
        speed = math.sqrt(float(u @ u))
        if speed > c.max_speed_mps:
            scale = c.max_speed_mps / speed
            u, u_r, u_c = u * scale, u_r * scale, u_c * scale
        self.desired_velocity, self.engagement = u, w
        # the corrective part through the corrective bandwidth (two equal first-order stages)
        a = self._a
        self._s1 = a * self._s1 + (1.0 - a) * (self._to_z @ u_c)
        self._s2 = a * self._s2 + (1.0 - a) * self._s1
        z = self._s2 + self._to_z @ u_r
        eps = _DEADZONE_RAMP * c.shoulder.deadband_rad
        # np.clip(z / ε, −1, 1) as its two ufuncs (the same values, without np.clip's dispatch)
        theta = z + (c.shoulder.deadband_rad * np.minimum(np.maximum(z / eps, -1.0), 1.0) if eps > 0 else 0.0)
        if c.noise_rad > 0 or c.noise_signal_dependent > 0:
            d = theta.size
            n = self._rng.standard_normal(2 * d)
            theta = theta + c.noise_rad * n[:d] + c.noise_signal_dependent * np.abs(theta) * n[d:]
        return theta
