"""The runs asked for by name: not among the default runs, each a schedule that the comparison knows."""

from __future__ import annotations

from mpcshare.evaluation.handover import SCHEDULE_SOURCES
from mpcshare.run_table import DEFAULT_RUNS
from research.bound_runs import BOUND_RUNS


def test_the_bound_runs_are_known_schedules_outside_the_default_runs() -> None:
    assert {r.name for r in BOUND_RUNS} == {"oracle_line"}
    assert not {r.name for r in BOUND_RUNS} & {r.name for r in DEFAULT_RUNS}
    assert all(r.schedule in SCHEDULE_SOURCES for r in BOUND_RUNS)
