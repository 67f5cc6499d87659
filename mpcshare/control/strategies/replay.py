"""``schedule``: the replay of a given hand-over schedule (not a controller, not a user's choice):
α follows ``schedule(t)`` along the hand-over ramp: 0 below 0.5 (the wearer leads), else the schedule's
value (the robot leads at that share; below 1 the convex mixture, β = 1 − α, as the gate's ``robot_alphas``),
with the gate's β at 1; no overrides
(as ``reactive``, û_r = 0 while π̂ has no finite output). It replays the placebo
``random_handover`` and the upper bound ``oracle_handover``."""

from __future__ import annotations

from typing import Callable

from mpcshare.control.strategies.base import ArbiterView, StepInputs, StrategyContext, StrategySpec, Target

__all__ = ["SCHEDULE", "Replay", "SPECS"]

SCHEDULE = "schedule"


class Replay:
    """α target = ``schedule(t)`` where it is ≥ 0.5 (capped at 1), else 0."""

    overrides = False

    def __init__(self, schedule: Callable[[float], float]) -> None:
        self.schedule = schedule

    def reset(self) -> None:
        """No state."""

    def decide(self, t: float, inputs: StepInputs, arbiter: ArbiterView) -> Target:
        a = self.schedule(t)
        a = min(float(a), 1.0) if a >= 0.5 else 0.0
        return Target(a, "given schedule", ramp=True, beta=1.0 - a if 0.5 <= a < 1.0 else None)


def make(ctx: StrategyContext) -> Replay:
    """The replay of ``ctx.schedule`` (which must be given)."""
    if ctx.schedule is None:
        raise ValueError(f"strategy {SCHEDULE!r} needs a schedule (t -> alpha target)")
    return Replay(ctx.schedule)


SPECS = (StrategySpec(SCHEDULE, "The replay of a given hand-over schedule (placebo and oracle runs).",
                      tunable=False, color="#7f7f7f", factory=make, user=False, order=99, role="replay"),)
