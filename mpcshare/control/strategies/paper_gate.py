"""``paper_gate``: the gate of Song & Asada (IEEE T-RO), with what a real loop needs.

α = 1 where the gate of the current (most probable) mode says predictable, else 0; β = the
user's β ∈ [0, 1] while α = 1, else 1. Added: hysteresis (α switches on at gate probability
p ≥ ``on_threshold``, off below ``off_threshold``), a minimum dwell ``min_dwell_s`` between
gate-driven switches, α moving along the hand-over ramp (``handover_s``), and the overrides
(α = 0 at once: no gate decision, π̂ not finite, novelty above the bundle's threshold).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from mpcshare.control.strategies.base import ArbiterView, StepInputs, StrategyContext, StrategySpec, Target

__all__ = ["PaperGate", "PaperGateSettings", "SPECS", "check_thresholds"]


def check_thresholds(on_threshold: float, off_threshold: float) -> None:
    """ValueError unless 0 ≤ off_threshold ≤ on_threshold ≤ 1 (gate probabilities)."""
    if not (0.0 <= off_threshold <= on_threshold <= 1.0) or math.isnan(on_threshold):
        raise ValueError(f"need 0 <= off_threshold <= on_threshold <= 1, got off_threshold {off_threshold!r}, "
                         f"on_threshold {on_threshold!r}")


@dataclass(frozen=True)
class PaperGateSettings:
    """The hysteresis on the gate probability p: the robot takes the lead at p ≥ ``on_threshold`` and gives
    it back below ``off_threshold``. ValueError unless 0 ≤ off_threshold ≤ on_threshold ≤ 1."""

    on_threshold: float = 0.6
    off_threshold: float = 0.5

    def __post_init__(self) -> None:
        object.__setattr__(self, "on_threshold", float(self.on_threshold))
        object.__setattr__(self, "off_threshold", float(self.off_threshold))
        check_thresholds(self.on_threshold, self.off_threshold)


class PaperGate:
    """The paper's gate with hysteresis and dwell (module docstring)."""

    overrides = True

    def __init__(self, on_threshold: float, off_threshold: float, min_dwell_s: float) -> None:
        self.on_threshold, self.off_threshold, self.min_dwell_s = on_threshold, off_threshold, min_dwell_s
        self.reset()

    def reset(self) -> None:
        """The robot does not lead (at the start, and after an override)."""
        self.on = False

    def decide(self, t: float, inputs: StepInputs, arbiter: ArbiterView) -> Target:
        p = float(inputs.gate_proba)  # type: ignore[arg-type]  # finite: the overrides ran first
        dwell_ok = t - arbiter.last_switch_t >= self.min_dwell_s
        if not self.on and p >= self.on_threshold and dwell_ok:
            self.on = True
        elif self.on and p < self.off_threshold and dwell_ok:
            self.on = False
        reason = f"gate probability {p:.2f} " + ("says predictable" if self.on else "says not predictable")
        return Target(1.0 if self.on else 0.0, reason, ramp=True)


def make(ctx: StrategyContext) -> PaperGate:
    """The paper's gate from its settings and the Arbiter's dwell."""
    s: PaperGateSettings = ctx.settings
    return PaperGate(s.on_threshold, s.off_threshold, ctx.min_dwell_s)


SPECS = (StrategySpec("paper_gate", "The paper's gate: the robot leads where the gate of the current mode says "
                      "predictable (with hysteresis, dwell and a ramp).", tunable=True, color="#17becf",
                      factory=make, order=5, role="shared", settings=PaperGateSettings),)
