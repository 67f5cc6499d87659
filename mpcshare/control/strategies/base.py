"""What a strategy is: its spec in the registry, what it is given, what it decides.

A strategy is a :class:`StrategySpec` (name, one-sentence description, whether ``mpcshare tune``
sweeps it, its plot colour, whether a user may choose it, its role, the frozen dataclass of its
settings) with a ``factory`` that builds a per-episode decision object (a :class:`Policy`) from the
:class:`StrategyContext` (the user's β, the Arbiter's dwell and ramp, the strategy's settings, the
bundle's per-mode figures). Every control step the
:class:`~mpcshare.control.arbitration.Arbiter` gives the policy the step's
:class:`StepInputs` and turns its :class:`Target` into α, β: a ramped target moves at most
1/``handover_s`` per second; β = 1 − α·(1 − β_user) unless the target names its own β; the
safety overrides (no gate decision, π̂ not finite, novelty above threshold) set α = 0, β = 1 at
once for policies with ``overrides = True``.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import Any, Callable, Mapping, Protocol

import numpy as np

__all__ = ["FUSIONS", "ROLES", "ArbiterView", "ModeFigures", "Policy", "StepInputs", "StrategyContext", "StrategySpec",
           "Target", "make_settings", "override_reason"]

#: What a strategy is in the comparison: ``shared`` (decides who leads; the reports' *sharing*),
#: ``baseline`` (one party alone), ``mix`` (a constant mixture of the two), ``replay`` (a given schedule).
ROLES = ("shared", "baseline", "mix", "replay")

#: Where the two parties meet: ``velocity``, û = α·û_r + β·û_v before the QP, one tip reference (the
#: controller's module docstring); ``qp``, each party's own reference chain, weighted α and 1 − α in the QP's
#: tip cost (:mod:`mpcshare.control.party_fusion`).
FUSIONS = ("velocity", "qp")


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
class ModeFigures:
    """What the strategies read of a bundle: voluntary_share (K,) v_j ∈ [0, 1], each mode's held-out
    unpredictable share (None: the bundle has none); transmat (K, K): the mode model's transition matrix
    per model tick (None: unknown); model_dt: the model period [s]."""

    voluntary_share: np.ndarray | None = None
    transmat: np.ndarray | None = None
    model_dt: float = 0.1

    @property
    def n_modes(self) -> int | None:
        """K from the transition matrix (None without one)."""
        return None if self.transmat is None else int(np.shape(self.transmat)[0])


@dataclass(frozen=True)
class StrategyContext:
    """What a factory builds a policy from.

    beta: the user's β; min_dwell_s [s]: the least time between two hand-overs; handover_s [s]: the α
    ramp; settings: the strategy's own settings (an instance of its spec's ``settings`` class, None for a
    strategy without settings); figures: the bundle's :class:`ModeFigures`; schedule: t → α target
    (``schedule`` only).
    """

    beta: float = 0.5
    min_dwell_s: float = 0.5
    handover_s: float = 0.5
    settings: Any = None
    figures: ModeFigures = field(default_factory=ModeFigures)
    schedule: Callable[[float], float] | None = None


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
    the reports name the first present); role: one of :data:`ROLES`; settings: the frozen dataclass of the
    strategy's settings (None: it has none), every field with a default, validated in its
    ``__post_init__`` (ValueError naming the field); fusion: one of :data:`FUSIONS`; rule_of: the strategy whose
    calibrated rule in a bundle this one reads (None: its own); default_run: among the runs ``sim`` and ``demo`` make
    by default (False: a registered candidate, run when named, e.g. ``--runs``). Raises ValueError for another role
    or fusion.
    """

    name: str
    description: str
    tunable: bool
    color: str
    factory: Callable[[StrategyContext], Policy]
    user: bool = True
    order: float = 100.0
    role: str = field(kw_only=True)
    settings: type | None = field(default=None, kw_only=True)
    fusion: str = field(default="velocity", kw_only=True)
    rule_of: str | None = field(default=None, kw_only=True)
    default_run: bool = field(default=True, kw_only=True)

    def __post_init__(self) -> None:
        if self.role not in ROLES:
            raise ValueError(f"strategy {self.name!r}: role {self.role!r} is not one of {', '.join(ROLES)}")
        if self.fusion not in FUSIONS:
            raise ValueError(f"strategy {self.name!r}: fusion {self.fusion!r} is not one of {', '.join(FUSIONS)}")
        if self.settings is not None and not dataclasses.is_dataclass(self.settings):
            raise TypeError(f"strategy {self.name!r}: settings must be a dataclass, got {self.settings!r}")


def make_settings(spec: StrategySpec, given: Any = None) -> Any:
    """The settings of ``spec``'s strategy: ``given`` as it is when it is an instance of ``spec.settings``, the
    class built from a mapping of field → value (the rest default; a list becomes a tuple), or the defaults for
    None; None for a strategy without settings. Raises ValueError naming the strategy and an unknown or
    invalid field, TypeError for anything else."""
    cls = spec.settings
    if cls is None:
        if given:
            raise ValueError(f"strategy {spec.name!r} has no settings, got {given!r}")
        return None
    if isinstance(given, cls):
        return given
    if given is None:
        return cls()
    if not isinstance(given, Mapping):
        raise TypeError(f"strategy {spec.name!r}: settings must be a {cls.__name__} or a mapping of its fields, "
                        f"got {type(given).__name__}")
    names = [f.name for f in dataclasses.fields(cls)]
    unknown = sorted(set(given) - set(names))
    if unknown:
        raise ValueError(f"unknown {spec.name} setting(s) {unknown}; valid: {', '.join(names)}")
    values = {k: tuple(v) if isinstance(v, list) else v for k, v in given.items()}
    try:
        return cls(**values)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{spec.name} settings: {exc}") from None


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
