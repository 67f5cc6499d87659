"""Arbitration between the robot's reactive term and the wearer's voluntary term.

Fusion in knife-tip velocity [m/s] (docs/design.md, "Online control"):

    û = α·û_r + β·û_v,    û_r = sat_{v_r}(ṗ̂ + k_r · (p̂ − p_ref)),    û_v = ShoulderMap.tip_velocity(θ)

``p̂``, ``ṗ̂`` are the tip position and velocity the reactive predictor π̂ forecasts for the
aimed time (the controller's ``forecast_lead_s`` ahead), ``p_ref`` the current tip
reference, ``k_r`` [1/s] a P-gain and ``sat_v(x) = x · min(1, v/‖x‖)`` a speed cap.

α, β per strategy (:data:`STRATEGIES`):

* ``voluntary``: α = 0, β = 1 (the wearer alone);
* ``reactive``: α = 1, β = 0 (the robot alone; û_r = 0 while π̂ has no finite output);
* ``gate`` (Song & Asada): α = 1 where the gate of the current mode says predictable,
  else 0; β = the user's β ∈ [0, 1] while α = 1, else 1. Added for a real loop:
  hysteresis (α switches on at gate probability ≥ ``on_threshold``, off below
  ``off_threshold``) and a minimum dwell time ``min_dwell_s`` between gate-driven
  switches, so that α does not chatter; and three overrides that set α = 0 at once
  (no dwell): novelty score above the bundle's ``novelty_threshold`` (an unfamiliar
  situation), π̂ not finite, and no gate decision available (window not yet full, the
  fork sensor stale);
* ``blend`` (policy blending, Dragan & Srinivasa 2013): α continuous in the gate's
  calibrated probability p, a linear ramp α = clip((p − p₀)/(p₁ − p₀), 0, 1) with
  (p₀, p₁) = ``blend_range`` (default (0.5, 0.9): no robot share below even odds, the
  whole share from 90 % confidence up); β = 1 − α·(1 − β_user), which is the paper's β at
  α ∈ {0, 1}. The same overrides apply.
* ``schedule`` (:data:`SCHEDULE`, not a controller: the replay of a given hand-over schedule,
  for the placebo ``random_handover`` and the upper bound ``oracle_handover``): α follows
  ``schedule(t)`` ∈ {0, 1} through the same ramp ``handover_s`` and β as the gate; no gate
  overrides (as ``reactive``, û_r = 0 while π̂ has no finite output).

Every change of who leads (α crossing 0.5) is logged as a :class:`Handover` with its
time and reason.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import numpy as np

from mpcshare.control.types import DEFAULT_BETA, ControllerConfig
from mpcshare.errors import ControllerSetupError

__all__ = ["SCHEDULE", "STRATEGIES", "Arbiter", "Decision", "Handover", "fuse", "reactive_velocity"]

STRATEGIES: tuple[str, ...] = ("voluntary", "reactive", "gate", "blend")
#: The strategy that replays a given schedule (Arbiter(..., schedule=f)); not a user choice.
SCHEDULE = "schedule"


@dataclass(frozen=True)
class Handover:
    """A change of who leads: time [s], α before and after, and why."""

    t: float
    alpha_from: float
    alpha_to: float
    reason: str


@dataclass(frozen=True)
class Decision:
    """α, β for one step and the reason for α."""

    alpha: float
    beta: float
    reason: str


def check_strategy(strategy: str, scheduled: bool = False) -> str:
    """Return ``strategy`` or raise ValueError naming the valid choices (with ``scheduled``:
    :data:`SCHEDULE` is valid too, and the only valid one)."""
    if scheduled:
        if strategy != SCHEDULE:
            raise ControllerSetupError(f"a schedule is replayed by strategy {SCHEDULE!r}, got {strategy!r}")
        return strategy
    if strategy not in STRATEGIES:
        raise ControllerSetupError(f"unknown strategy {strategy!r}; valid choices: {', '.join(STRATEGIES)}")
    return strategy


def check_beta(beta: float) -> float:
    """Return β as float or raise ValueError when it is not in [0, 1]."""
    b = float(beta)
    if not (math.isfinite(b) and 0.0 <= b <= 1.0):
        raise ControllerSetupError(f"beta must be in [0, 1], got {beta!r}")
    return b


class Arbiter:
    """α, β per step for one strategy (module docstring), with the hand-over log.

    The defaults of the settings are :class:`~mpcshare.control.types.ControllerConfig`'s.

    Args:
        strategy: one of :data:`STRATEGIES`.
        beta: the user's β ∈ [0, 1] (weight of the wearer while the robot leads).
        novelty_threshold: α = 0 while the novelty score exceeds it (inf: never).
        on_threshold, off_threshold: hysteresis on the gate probability (gate strategy).
        min_dwell_s: minimum time [s] between two gate-driven switches of α.
        blend_range: (p₀, p₁) of the blend ramp.
        schedule: for strategy ``schedule`` only: t [s] → α target ∈ {0, 1}.
        handover_s: the gate's α moves between 0 and 1 over this time [s] instead of at once
            (0: at once); β follows as 1 − α·(1 − β_user). The overrides still act at once.
    """

    def __init__(self, strategy: str = "gate", beta: float = DEFAULT_BETA, *, novelty_threshold: float = math.inf,
                 on_threshold: float = ControllerConfig.on_threshold,
                 off_threshold: float = ControllerConfig.off_threshold,
                 min_dwell_s: float = ControllerConfig.min_dwell_s,
                 blend_range: tuple[float, float] = ControllerConfig.blend_range,
                 handover_s: float = ControllerConfig.handover_s,
                 schedule: Callable[[float], float] | None = None) -> None:
        if (strategy == SCHEDULE) != (schedule is not None):
            raise ControllerSetupError(f"strategy {SCHEDULE!r} needs a schedule and only it takes one, got strategy "
                                       f"{strategy!r} with schedule={schedule!r}")
        self.strategy = check_strategy(strategy, scheduled=schedule is not None)
        self.schedule = schedule
        self.beta = check_beta(beta)
        if not (0.0 <= off_threshold <= on_threshold <= 1.0):
            raise ControllerSetupError(f"need 0 ≤ off_threshold ≤ on_threshold ≤ 1, got {off_threshold!r}, "
                                       f"{on_threshold!r}")
        if not (math.isfinite(min_dwell_s) and min_dwell_s >= 0):
            raise ControllerSetupError(f"min_dwell_s must be finite and ≥ 0, got {min_dwell_s!r}")
        p0, p1 = (float(x) for x in blend_range)
        if not 0.0 <= p0 < p1 <= 1.0:
            raise ControllerSetupError(f"blend_range must satisfy 0 ≤ p0 < p1 ≤ 1, got {blend_range!r}")
        if math.isnan(novelty_threshold):
            raise ControllerSetupError("novelty_threshold must not be NaN (use inf to disable)")
        self.novelty_threshold = float(novelty_threshold)
        self.on_threshold, self.off_threshold = float(on_threshold), float(off_threshold)
        self.min_dwell_s = float(min_dwell_s)
        self.blend_range = (p0, p1)
        if not (math.isfinite(handover_s) and handover_s >= 0):
            raise ControllerSetupError(f"handover_s must be finite and ≥ 0, got {handover_s!r}")
        self.handover_s = float(handover_s)
        self.reset()

    def reset(self) -> None:
        """Start over: α = 0 (or the fixed α of a baseline), empty hand-over log."""
        self.handovers: list[Handover] = []
        self.alpha = 1.0 if self.strategy == "reactive" else 0.0
        self._gate_on = False
        self._last_switch_t = -math.inf
        self._last_t = -math.inf

    def _override(self, gate_proba: float | None, novelty: float, prediction_finite: bool,
                  available: bool) -> str | None:
        if not available:
            return "no gate decision available"
        if not prediction_finite:
            return "reactive prediction not finite"
        if not novelty <= self.novelty_threshold:  # NaN counts as unfamiliar
            return f"novelty {novelty:.3g} above threshold {self.novelty_threshold:.3g}"
        if gate_proba is None or not math.isfinite(gate_proba):
            return "gate probability not finite"
        return None

    def decide(self, t: float, gate_proba: float | None, novelty: float = 0.0,
               prediction_finite: bool = True, available: bool = True) -> Decision:
        """α, β at time ``t`` [s] from the gate probability of the current mode."""
        s = self.strategy
        if s == "voluntary":
            return self._set(t, 0.0, 1.0, "voluntary baseline")
        if s == "reactive":
            return self._set(t, 1.0, 0.0, "reactive baseline")
        if s == SCHEDULE:
            return self._ramped(t, 1.0 if self.schedule(t) >= 0.5 else 0.0, "given schedule")  # type: ignore[misc]
        why = self._override(gate_proba, novelty, prediction_finite, available)
        if why is not None:
            self._gate_on = False
            return self._set(t, 0.0, 1.0, why)
        p = float(gate_proba)  # type: ignore[arg-type]
        if s == "blend":
            p0, p1 = self.blend_range
            a = min(max((p - p0) / (p1 - p0), 0.0), 1.0)
            return self._set(t, a, 1.0 - a * (1.0 - self.beta), f"blend of gate probability {p:.2f}")
        dwell_ok = t - self._last_switch_t >= self.min_dwell_s
        if not self._gate_on and p >= self.on_threshold and dwell_ok:
            self._gate_on = True
        elif self._gate_on and p < self.off_threshold and dwell_ok:
            self._gate_on = False
        reason = f"gate probability {p:.2f} " + ("says predictable" if self._gate_on else "says not predictable")
        return self._ramped(t, 1.0 if self._gate_on else 0.0, reason)

    def _ramped(self, t: float, a: float, reason: str) -> Decision:
        """α toward the target ``a`` ∈ {0, 1} at most 1/handover_s per second; β = 1 − α·(1 − β_user)."""
        if self.handover_s > 0:  # α moves at most 1/handover_s per second (from its reset value at first)
            step = max(t - self._last_t, 0.0) / self.handover_s if math.isfinite(self._last_t) else 0.0
            a = min(max(a, self.alpha - step), self.alpha + step)
        beta = self.beta if a == 1.0 else (1.0 if a == 0.0 else 1.0 - a * (1.0 - self.beta))
        return self._set(t, a, beta, reason)

    def _set(self, t: float, alpha: float, beta: float, reason: str) -> Decision:
        if (alpha >= 0.5) != (self.alpha >= 0.5):
            self.handovers.append(Handover(float(t), self.alpha, alpha, reason))
            self._last_switch_t = float(t)
        self.alpha = alpha
        self._last_t = float(t)
        return Decision(alpha, beta, reason)


def reactive_velocity(p_pred: np.ndarray, p_ref: np.ndarray, gain: float, max_speed: float,
                      feedforward: np.ndarray | None = None) -> np.ndarray:
    """û_r = sat(ṗ̂ + k·(p̂ − p_ref)) [m/s]: the predicted velocity ``feedforward`` ṗ̂ (None: 0)
    plus a P-gain ``gain`` [1/s] toward p̂, norm capped at ``max_speed``."""
    u = gain * (np.asarray(p_pred, dtype=float) - p_ref)
    if feedforward is not None:
        u = u + np.asarray(feedforward, dtype=float)
    n = math.sqrt(float(u @ u))
    return u * (max_speed / n) if n > max_speed else u


def fuse(alpha: float, u_r: np.ndarray, beta: float, u_v: np.ndarray) -> np.ndarray:
    """û = α·û_r + β·û_v [m/s]."""
    return alpha * u_r + beta * u_v
