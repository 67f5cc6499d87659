"""``gate``: the default shared strategy. Until the expected-cost rule of issue 28 lands, the paper's
gate (:mod:`mpcshare.control.strategies.paper_gate`) with the same settings."""

from __future__ import annotations

from mpcshare.control.strategies.base import StrategySpec
from mpcshare.control.strategies.paper_gate import make

__all__ = ["SPECS"]

SPECS = (StrategySpec("gate", "The default shared strategy: who leads is decided per step.", tunable=True,
                      color="C0", factory=make, order=4),)
