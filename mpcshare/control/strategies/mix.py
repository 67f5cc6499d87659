"""Constant mixtures of the two parties, the points of the voluntary–reactive line:
``mix25``, ``mix50``, ``mix75`` with α = 0.25, 0.5, 0.75 and β = 1 − α, a convex combination
û = α·û_r + (1 − α)·û_v of the ``reactive`` (α = 1, β = 0) and ``voluntary`` (α = 0, β = 1)
commands, independent of the user's β. No overrides (as the line's ends)."""

from __future__ import annotations

from mpcshare.control.strategies.base import StrategySpec
from mpcshare.control.strategies.fixed import Fixed

__all__ = ["SPECS", "mixture"]


def mixture(alpha: float, order: float, color: str) -> StrategySpec:
    """The spec of the constant mixture α, β = 1 − α."""
    name = f"mix{round(alpha * 100):d}"
    return StrategySpec(name, f"A constant mixture of the two parties: alpha = {alpha:g}, beta = 1 - alpha.",
                        tunable=False, color=color,
                        factory=lambda ctx: Fixed(alpha, 1.0 - alpha, f"constant mixture alpha {alpha:g}"),
                        order=order, role="mix")


SPECS = (mixture(0.25, 2.25, "#f7a6c9"), mixture(0.5, 2.5, "#bcbd22"), mixture(0.75, 2.75, "#8c564b"))
