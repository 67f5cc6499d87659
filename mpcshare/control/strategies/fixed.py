"""The two parties alone: ``voluntary`` (α = 0, β = 1, the wearer) and ``reactive`` (α = 1, β = 0,
the robot; û_r = 0 while π̂ has no finite output). No overrides: they are the ends of the
voluntary–reactive line."""

from __future__ import annotations

from dataclasses import dataclass

from mpcshare.control.strategies.base import ArbiterView, StepInputs, StrategySpec, Target

__all__ = ["REACTIVE", "VOLUNTARY", "Fixed"]


@dataclass
class Fixed:
    """A constant α, β with a fixed reason."""

    alpha: float
    beta: float
    reason: str
    overrides: bool = False

    @property
    def initial_alpha(self) -> float:
        """α from the start (no hand-over is logged for a constant α)."""
        return self.alpha

    def reset(self) -> None:
        """Nothing to forget."""

    def decide(self, t: float, inputs: StepInputs, arbiter: ArbiterView) -> Target:
        return Target(self.alpha, self.reason, beta=self.beta)


VOLUNTARY = StrategySpec("voluntary", "The wearer alone: alpha = 0, beta = 1.", tunable=False, color="#d62728",
                         factory=lambda ctx: Fixed(0.0, 1.0, "voluntary baseline"), order=0, role="baseline")
REACTIVE = StrategySpec("reactive", "The robot alone: alpha = 1, beta = 0.", tunable=False, color="#2ca02c",
                        factory=lambda ctx: Fixed(1.0, 0.0, "reactive baseline"), order=1, role="baseline")
SPECS = (VOLUNTARY, REACTIVE)
