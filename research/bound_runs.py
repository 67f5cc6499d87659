"""Runs of :func:`mpcshare.evaluation.compare_strategies` too costly for every comparison, asked for by name.

``oracle_line`` replays the effort-aware hand-over oracle's schedules (``line_oracle_schedules`` of
:mod:`mpcshare.evaluation.handover`), six replays a trial (``benchmarks/bench_family.py --oracle-line``).
"""

from __future__ import annotations

from mpcshare.run_table import StrategyRun

__all__ = ["BOUND_RUNS"]

BOUND_RUNS: tuple[StrategyRun, ...] = (StrategyRun("oracle_line", "schedule", schedule="oracle_line"),)
