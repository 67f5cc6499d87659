"""What a strategy is: its spec in the registry, what it is given, what it decides.

A strategy is a :class:`StrategySpec` (name, one-sentence description, whether ``mpcshare tune``
sweeps it, its plot colour, whether a user may choose it, its role) with a ``factory`` that builds a
per-episode decision object (a :class:`Policy`) from the :class:`StrategyContext` (the user's β,
the arbitration settings, the bundle's per-mode figures). Every control step the
:class:`~mpcshare.control.arbitration.Arbiter` gives the policy the step's
:class:`StepInputs` and turns its :class:`Target` into α, β: a ramped target moves at most
1/``handover_s`` per second; β = 1 − α·(1 − β_user) unless the target names its own β; the
safety overrides (no gate decision, π̂ not finite, novelty above threshold) set α = 0, β = 1 at
once for policies with ``overrides = True``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Callable, Protocol

import numpy as np

__all__ = ["ROLES", "ArbiterView", "Policy", "StepInputs", "StrategyContext", "StrategySpec", "Target",
           "override_reason"]

#: What a strategy is in the comparison: ``shared`` (decides who leads; the reports' *sharing*),
#: ``baseline`` (one party alone), ``mix`` (a constant mixture of the two), ``replay`` (a given schedule).
ROLES = ("shared", "baseline", "mix", "replay")


@dataclass(frozen=True)
class StepInputs:
    """What the controller knows at one step.

    gate_proba: the paper's gate probability of the most probable mode (None: none);
    novelty: −log p(o_t | o_<t); prediction_finite: π̂ has a finite forecast; available: a gate
    decision exists (window full, fork sensor fresh); mode_proba: (K,) filtered mode posterior
    (None: unknown); u_r, u_v: (3,) reactive and voluntary tip velocities [m/s] (None: unknown).
    """

    gate_proba: float | None = None
    novelty: float = 0.0
    prediction_finite: bool = True
    available: bool = True
    mode_proba: np.ndarray | None = None
    u_r: np.ndarray | None = None
    u_v: np.ndarray | None = None


@dataclass(frozen=True)
class Target:
    """A policy's decision: α target ∈ [0, 1], reason, ``ramp`` (move along the hand-over ramp),
    β (None: 1 − α·(1 − β_user), the paper's β at α ∈ {0, 1})."""

    alpha: float
    reason: str
    ramp: bool = False
    beta: float | None = None


@dataclass(frozen=True)
class StrategyContext:
    """What a factory builds a policy from (the Arbiter's settings; see its docstring).

    mode_stats: the bundle's per-mode figures (``mpcshare.control.strategies.gate``), None when
    the bundle has none; transmat: (K, K) the mode model's transition matrix per model tick
    (None: unknown); model_dt: the model period [s]; schedule: t → α target (``schedule`` only).
    """

    beta: float = 0.5
    on_threshold: float = 0.6
    off_threshold: float = 0.5
    min_dwell_s: float = 0.5
    blend_range: tuple[float, float] = (0.5, 0.9)
    handover_s: float = 0.5
    schedule: Callable[[float], float] | None = None
    mode_stats: dict[str, Any] | None = None
    transmat: np.ndarray | None = None
    model_dt: float = 0.1
    options: dict[str, Any] = field(default_factory=dict)


class ArbiterView(Protocol):
    """The arbiter's state a policy may read: the current α, the time of the last hand-over [s]."""

    alpha: float
    last_switch_t: float


class Policy(Protocol):
    """A per-episode decision object. ``overrides``: the safety overrides apply to it (and restart
    it). An optional attribute ``initial_alpha`` sets α at the start (default 0: the wearer leads)."""

    overrides: bool

    def reset(self) -> None: ...

    def decide(self, t: float, inputs: StepInputs, arbiter: ArbiterView) -> Target: ...


@dataclass(frozen=True)
class StrategySpec:
    """One strategy of the registry.

    name; description (one sentence); tunable: swept by ``mpcshare tune``; color: a matplotlib
    colour; factory: StrategyContext → Policy; user: a user may choose it (False: replays or
    tools, e.g. ``schedule``); order: position in the registry (ascending; among the ``shared`` ones,
    the reports name the first present); role: one of :data:`ROLES`. Raises ValueError for another role.
    """

    name: str
    description: str
    tunable: bool
    color: str
    factory: Callable[[StrategyContext], Policy]
    user: bool = True
    order: float = 100.0
    role: str = field(kw_only=True)

    def __post_init__(self) -> None:
        if self.role not in ROLES:
            raise ValueError(f"strategy {self.name!r}: role {self.role!r} is not one of {', '.join(ROLES)}")


def override_reason(inputs: StepInputs, novelty_threshold: float) -> str | None:
    """Why the safety overrides set α = 0 now (None: they do not)."""
    if not inputs.available:
        return "no gate decision available"
    if not inputs.prediction_finite:
        return "reactive prediction not finite"
    if not inputs.novelty <= novelty_threshold:  # NaN counts as unfamiliar
        return f"novelty {inputs.novelty:.3g} above threshold {novelty_threshold:.3g}"
    p = inputs.gate_proba
    if p is None or not math.isfinite(p):
        return "gate probability not finite"
    return None
