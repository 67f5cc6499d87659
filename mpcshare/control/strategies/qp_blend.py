"""``qp_blend``: authority inside the optimisation, a registered candidate (not the default).

Who leads is the gate's rule (:mod:`.gate`, the same :class:`~.gate.GateSettings`; a bundle's calibrated
``gate`` rule is read), but the parties are not fused before the QP: each keeps its own tip reference chain
(the robot's driven by û_r toward its forecast, the wearer's by û_v) and the QP's tip cost weighs them,
α·‖J·a + J̇·v − ẍ_r‖² + (1 − α)·‖J·a + J̇·v − ẍ_v‖² (:mod:`mpcshare.control.party_fusion`,
:class:`robot.tasks.BlendedTipTrackingTask`). β = 1 − α: a least-squares cost can only weigh two references
convexly, so the wearer's corrections do not add on top of a leading robot as the gate's β does. The gate's
overrides apply.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from mpcshare.control.strategies.base import ArbiterView, Policy, StepInputs, StrategyContext, StrategySpec, Target
from mpcshare.control.strategies.gate import GateSettings
from mpcshare.control.strategies.gate import make as make_gate

__all__ = ["QPBlend", "QPBlendSettings", "SPECS"]


@dataclass(frozen=True)
class QPBlendSettings(GateSettings):
    """The gate's settings (:class:`~.gate.GateSettings`) and ``wearer_offset_m`` [m]: the wearer's reference is
    kept within α·‖p_v − p_r‖ ≤ wearer_offset_m of the robot's (anti-windup: corrections the QP weighs at
    1 − α ≈ 0 do not pile up into a step at the next hand-over). ValueError naming a wrong field."""

    wearer_offset_m: float = 0.002

    def __post_init__(self) -> None:
        super().__post_init__()
        try:
            d = float(self.wearer_offset_m)
        except (TypeError, ValueError):
            raise ValueError(f"wearer_offset_m must be a number, got {self.wearer_offset_m!r}") from None
        if not (math.isfinite(d) and d > 0):
            raise ValueError(f"wearer_offset_m must be finite and > 0 m, got {self.wearer_offset_m!r}")
        object.__setattr__(self, "wearer_offset_m", d)


class QPBlend:
    """The gate's α target with β = 1 − α (module docstring). The policy moves α along the hand-over ramp itself
    (at most dt/``handover_s`` a step from the Arbiter's α, as the Arbiter ramps) so that β is 1 − the α in force."""

    overrides = True

    def __init__(self, rule: Policy, handover_s: float) -> None:
        self.rule, self.handover_s = rule, float(handover_s)
        self.reset()

    def reset(self) -> None:
        """The gate's rule restarted, no step yet."""
        self.rule.reset()
        self._last_t = -math.inf

    def decide(self, t: float, inputs: StepInputs, arbiter: ArbiterView) -> Target:
        d = self.rule.decide(t, inputs, arbiter)
        a = float(d.alpha)
        if d.ramp and self.handover_s > 0:
            step = max(t - self._last_t, 0.0) / self.handover_s if math.isfinite(self._last_t) else 0.0
            a = min(max(a, arbiter.alpha - step), arbiter.alpha + step)
        self._last_t = t
        return Target(a, d.reason, beta=1.0 - a)


def make(ctx: StrategyContext) -> QPBlend:
    """The gate's rule from the context (:func:`.gate.make`), weights α and 1 − α."""
    return QPBlend(make_gate(ctx), ctx.handover_s)


SPECS = (StrategySpec("qp_blend", "A candidate: the gate's authority applied inside the QP, which weighs each "
                      "party's own tip reference by alpha and 1 - alpha.", tunable=False, color="#6b8e23",
                      factory=make, order=7, role="shared", settings=QPBlendSettings, fusion="qp", rule_of="gate",
                      default_run=False),)
