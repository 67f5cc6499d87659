"""The one table of runs (mpcshare.run_table): every user strategy of the registry in its order, then the
runs that are not strategies, each with its own colour; the tuned and realisable subsets; stable codes."""

from __future__ import annotations

import zlib

from mpcshare.control.strategies import DEFAULT_STRATEGY, REGISTRY, user_strategies
from mpcshare.run_table import (
    ALL_RUNS,
    DEFAULT_RUNS,
    EXTRA_RUNS,
    RANDOM_DRAWS,
    REALISABLE,
    RUN_COLORS,
    RUN_NAMES,
    TUNABLE,
    strategy_code,
)


def test_the_runs_are_the_user_strategies_in_registry_order_then_the_extra_runs():
    users = user_strategies()
    assert users == tuple(n for n, s in REGISTRY.items() if s.user)
    assert [(r.name, r.strategy, r.use_mpc, r.oracle) for r in ALL_RUNS[:len(users)]] == \
        [(n, n, False, False) for n in users]
    assert ALL_RUNS[len(users):] == EXTRA_RUNS
    assert RUN_NAMES == tuple(r.name for r in ALL_RUNS) and len(set(RUN_NAMES)) == len(RUN_NAMES)
    # the default runs: all but the registered candidates whose spec keeps them out (they run when named)
    left_out = {n for n, s in REGISTRY.items() if s.user and not s.default_run}
    assert "qp_blend" in left_out and DEFAULT_RUNS == tuple(r for r in ALL_RUNS if r.name not in left_out)
    assert f"{DEFAULT_STRATEGY}_mpc" in RUN_NAMES and DEFAULT_STRATEGY in users


def test_the_placebo_and_the_oracle_replay_schedules():
    by_name = {r.name: r for r in EXTRA_RUNS}
    assert by_name["random_handover"].schedule == "random" and by_name["random_handover"].draws == RANDOM_DRAWS
    assert by_name["oracle_handover"].schedule == "oracle" and by_name["oracle_handover"].draws == 1
    assert by_name["oracle_preview"].oracle and not by_name["oracle_preview"].use_mpc


def test_every_run_has_a_colour_and_the_subsets_are_the_users_choices():
    assert set(RUN_NAMES) <= set(RUN_COLORS)
    assert all(RUN_COLORS[n] == REGISTRY[n].color for n in REGISTRY)
    assert REALISABLE == user_strategies() and set(TUNABLE) <= set(REALISABLE)
    assert TUNABLE == tuple(n for n in REALISABLE if REGISTRY[n].tunable)


def test_strategy_codes_are_the_crc32_of_the_name():
    assert strategy_code("gate") == zlib.crc32(b"gate") == 0xB82B9894  # the same in every process and version
    assert len({strategy_code(n) for n in RUN_NAMES}) == len(RUN_NAMES)
