"""Arbitration between the robot's reactive term and the wearer's voluntary term.

Fusion in knife-tip velocity [m/s] (docs/design.md, "Online control"):

    û = α·û_r + β·û_v,    û_r = sat_{v_r}(ṗ̂ + k_r · (p̂ − p_ref)),    û_v = ShoulderMap.tip_velocity(θ)

``p̂``, ``ṗ̂``: the tip position and velocity forecast for the aimed time (``forecast_lead_s`` ahead);
``p_ref``: the tip reference; ``k_r`` [1/s]: a P-gain; ``sat_v(x) = x · min(1, v/‖x‖)``: a speed cap.

α, β per strategy (:mod:`mpcshare.control.strategies`, one module each, in ``REGISTRY``). The
:class:`Arbiter` builds the strategy's per-episode policy and turns its target into α, β:

* the safety overrides (for the shared strategies: no gate decision, π̂ not finite, novelty above the
  bundle's ``novelty_threshold`` for ``novelty_persist_s``, gate probability not finite) set α = 0,
  β = 1 at once and restart the policy;
* a ramped target moves α at most 1/``handover_s`` per second (0: at once);
* β = 1 − α·(1 − β_user) unless the policy names its own β (the paper's β at α ∈ {0, 1}).

Every change of who leads (α crossing 0.5) is logged as a :class:`Handover` with its time and reason.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Callable

import numpy as np

from mpcshare.control.strategies import REGISTRY, StepInputs, StrategyContext, user_strategies
from mpcshare.control.strategies.base import ModeFigures, make_settings, override_reason
from mpcshare.control.strategies.replay import SCHEDULE
from mpcshare.control.types import DEFAULT_BETA, ControllerConfig
from mpcshare.errors import ControllerSetupError, ControllerTypeError

__all__ = ["SCHEDULE", "STRATEGIES", "Arbiter", "Decision", "Handover", "check_strategy", "fuse",
           "reactive_velocity"]

#: The strategies a user may choose, in registry order.
STRATEGIES: tuple[str, ...] = user_strategies()


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
    """Return ``strategy`` or raise ValueError naming the valid choices (from the registry; with
    ``scheduled``: :data:`SCHEDULE` is valid too, and the only valid one)."""
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
    """α, β per step for one strategy of the registry (module docstring), with the hand-over log.

    The defaults of the Arbiter's own settings are :class:`~mpcshare.control.types.ControllerConfig`'s.

    Args:
        strategy: a name of ``mpcshare.control.strategies.REGISTRY`` (:data:`STRATEGIES`, or
            :data:`SCHEDULE` with a ``schedule``).
        beta: the user's β ∈ [0, 1] (weight of the wearer while the robot leads).
        settings: the strategy's settings: an instance of its spec's ``settings`` class, a mapping of its
            fields, or None (its defaults); see :func:`~mpcshare.control.strategies.base.make_settings`.
        novelty_threshold: α = 0 while the novelty score exceeds it (inf: never).
        min_dwell_s: minimum time [s] between two switches of α driven by a policy.
        handover_s: α moves between 0 and 1 over this time [s] instead of at once (0: at once);
            β follows as 1 − α·(1 − β_user). The overrides still act at once.
        novelty_persist_s: the novelty override acts once the novelty has exceeded
            ``novelty_threshold`` without a break for this long [s] (0: at once). A NaN novelty (the
            mode filter failed) acts at once.
        schedule: for strategy ``schedule`` only: t [s] → α target ∈ {0, 1}.
        figures: what the strategies read of the bundle (:class:`~mpcshare.control.strategies.base.ModeFigures`).

    Raises ``ControllerSetupError`` (a ValueError) naming a wrong setting.
    """

    def __init__(self, strategy: str = "gate", beta: float = DEFAULT_BETA, *, settings: Any = None,
                 novelty_threshold: float = math.inf, min_dwell_s: float = ControllerConfig.min_dwell_s,
                 handover_s: float = ControllerConfig.handover_s,
                 novelty_persist_s: float = ControllerConfig.novelty_persist_s,
                 schedule: Callable[[float], float] | None = None, figures: ModeFigures | None = None) -> None:
        if (strategy == SCHEDULE) != (schedule is not None):
            raise ControllerSetupError(f"strategy {SCHEDULE!r} needs a schedule and only it takes one, got strategy "
                                       f"{strategy!r} with schedule={schedule!r}")
        self.strategy = check_strategy(strategy, scheduled=schedule is not None)
        self.beta = check_beta(beta)
        if not (math.isfinite(min_dwell_s) and min_dwell_s >= 0):
            raise ControllerSetupError(f"min_dwell_s must be finite and ≥ 0, got {min_dwell_s!r}")
        if math.isnan(novelty_threshold):
            raise ControllerSetupError("novelty_threshold must not be NaN (use inf to disable)")
        if not (math.isfinite(handover_s) and handover_s >= 0):
            raise ControllerSetupError(f"handover_s must be finite and ≥ 0, got {handover_s!r}")
        if not (math.isfinite(novelty_persist_s) and novelty_persist_s >= 0):
            raise ControllerSetupError(f"novelty_persist_s must be finite and ≥ 0, got {novelty_persist_s!r}")
        self.novelty_persist_s = float(novelty_persist_s)
        self.novelty_threshold = float(novelty_threshold)
        self.handover_s = float(handover_s)
        self.spec = REGISTRY[self.strategy]
        try:
            self.settings = make_settings(self.spec, settings)
            self.context = StrategyContext(beta=self.beta, min_dwell_s=float(min_dwell_s), handover_s=self.handover_s,
                                           settings=self.settings, figures=figures or ModeFigures(),
                                           schedule=schedule)
            self.policy = self.spec.factory(self.context)
        except ControllerSetupError:
            raise
        except TypeError as exc:
            raise ControllerTypeError(f"strategy {self.strategy!r}: {exc}") from None
        except ValueError as exc:
            raise ControllerSetupError(f"strategy {self.strategy!r}: {exc}") from None
        self.reset()

    def reset(self) -> None:
        """Start over: α = the policy's ``initial_alpha`` (0 when it has none: the wearer leads), empty
        hand-over log, the policy restarted."""
        self.handovers: list[Handover] = []
        self.alpha = float(getattr(self.policy, "initial_alpha", 0.0))
        self.last_switch_t = -math.inf
        self._last_t = -math.inf
        self._novel_since = math.inf
        self.policy.reset()

    def decide(self, t: float, gate_proba: float | None, novelty: float = 0.0, prediction_finite: bool = True,
               available: bool = True, *, mode_proba: np.ndarray | None = None, u_r: np.ndarray | None = None,
               u_v: np.ndarray | None = None) -> Decision:
        """α, β at time ``t`` [s] from the step's inputs (``mpcshare.control.strategies.StepInputs``)."""
        inputs = StepInputs(gate_proba, novelty, prediction_finite, available, mode_proba, u_r, u_v)
        if self.policy.overrides:
            why = override_reason(inputs, self._persistent_threshold(t, novelty))
            if why is not None:
                self.policy.reset()
                return self._set(t, 0.0, 1.0, why)
        target = self.policy.decide(t, inputs, self)
        a = float(target.alpha)
        if target.ramp and self.handover_s > 0:  # α moves at most 1/handover_s per second
            step = max(t - self._last_t, 0.0) / self.handover_s if math.isfinite(self._last_t) else 0.0
            a = min(max(a, self.alpha - step), self.alpha + step)
        if target.beta is not None:
            beta = float(target.beta)
        else:
            beta = self.beta if a == 1.0 else (1.0 if a == 0.0 else 1.0 - a * (1.0 - self.beta))
        return self._set(t, a, beta, target.reason)

    def _persistent_threshold(self, t: float, novelty: float) -> float:
        """The novelty threshold in force at ``t``: the bundle's once the novelty has stayed above it for
        ``novelty_persist_s``, else inf (the override waits; a NaN novelty still acts at once)."""
        if novelty <= self.novelty_threshold:
            self._novel_since = math.inf
            return self.novelty_threshold
        self._novel_since = min(self._novel_since, float(t))
        return self.novelty_threshold if t - self._novel_since >= self.novelty_persist_s else math.inf

    def _set(self, t: float, alpha: float, beta: float, reason: str) -> Decision:
        if (alpha >= 0.5) != (self.alpha >= 0.5):
            self.handovers.append(Handover(float(t), self.alpha, alpha, reason))
            self.last_switch_t = float(t)
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
