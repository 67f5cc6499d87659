"""The effort-aware hand-over oracle ``oracle_line``: its schedules minimise the priced cost (checked
against brute force) and the run keeps the lowest line ratio within the effort cap."""

from __future__ import annotations

import itertools
from types import SimpleNamespace

import numpy as np
import pytest

from mpcshare.control.types import ControllerConfig
from mpcshare.evaluation.handover import line_oracle_schedules
from mpcshare.evaluation.runs import best_on_line

DT = 0.01


def _episode(err_mm: np.ndarray, effort_rad: np.ndarray) -> SimpleNamespace:
    """An episode whose tip misses its intent by ``err_mm`` along x and whose shoulder is at ``effort_rad``."""
    n = err_mm.size
    tip = np.zeros((n, 3))
    tip[:, 0] = 1e-3 * err_mm
    shoulder = np.zeros((n, 3))
    shoulder[:, 1] = effort_rad
    return SimpleNamespace(t=DT * np.arange(n), tip=tip, tip_intent=np.zeros((n, 3)), voluntary=shoulder)


def _priced_cost(on: np.ndarray, vol, rea, c: float) -> float:
    """Σ_k (e_k² + μ·ε_k) of the party ``on`` picks (1: the robot), μ = c·(m_r − m_v)/(E_v − E_r)."""
    e0, e1 = vol.tip[:, 0], rea.tip[:, 0]
    f0, f1 = vol.voluntary[:, 1], rea.voluntary[:, 1]
    mu = c * (np.mean(e1 ** 2) - np.mean(e0 ** 2)) / (np.mean(f0) - np.mean(f1))
    return float(np.sum(np.where(on, e1 ** 2 + mu * f1, e0 ** 2 + mu * f0)))


def test_the_schedule_hands_the_robot_what_it_tracks_and_the_wearer_what_it_does_not():
    n = 200
    vol = _episode(np.full(n, 1.0), np.full(n, 0.1))
    rea = _episode(np.r_[np.full(n // 2, 1.0), np.full(n // 2, 10.0)], np.zeros(n))
    (sched,) = line_oracle_schedules(vol, rea, ControllerConfig(min_dwell_s=0.5), weights=(1.0,),
                                     switch_costs_s=(0.5,))
    np.testing.assert_array_equal(sched.on, np.r_[np.ones(n // 2, bool), np.zeros(n // 2, bool)])


@pytest.mark.parametrize("c", [0.3, 1.0, 3.0])
def test_the_schedule_minimises_the_priced_cost_against_brute_force(c):
    rng = np.random.default_rng(7)
    n = 10
    vol = _episode(rng.uniform(0.5, 3.0, n), rng.uniform(0.05, 0.2, n))
    rea = _episode(rng.uniform(0.5, 8.0, n), rng.uniform(0.0, 0.05, n))
    (sched,) = line_oracle_schedules(vol, rea, ControllerConfig(min_dwell_s=0.0), weights=(c,),
                                     switch_costs_s=(0.0,))
    best = min(_priced_cost(np.array(on, bool), vol, rea, c) for on in itertools.product((0, 1), repeat=n))
    assert _priced_cost(sched.on, vol, rea, c) == pytest.approx(best, rel=1e-12)


def test_distinct_schedules_only_and_a_clear_error_for_a_negative_price():
    n = 100
    vol = _episode(np.full(n, 1.0), np.full(n, 0.1))
    rea = _episode(np.full(n, 1.0), np.zeros(n))  # the robot tracks as well everywhere: one schedule
    assert len(line_oracle_schedules(vol, rea)) == 1
    with pytest.raises(ValueError, match="weights must be finite and >= 0"):
        line_oracle_schedules(vol, rea, weights=(-1.0,))


def _m(rms_mm: float, effort: float) -> dict[str, float]:
    return {"tracking_rmse_m": 1e-3 * rms_mm, "voluntary_effort": effort}


def test_the_run_keeps_the_lowest_line_ratio_within_the_effort_cap():
    vol, rea = _m(1.0, 1.0), _m(3.0, 0.1)
    # at effort 0.5 the line is at 3 − 2·(0.4/0.9) = 2.11 mm; at 0.9 (over the cap) at 1.22 mm
    within, over = ("A", _m(1.9, 0.5)), ("B", _m(1.0, 0.9))
    done = [over, within, ("vol", vol), ("rea", rea)]
    assert best_on_line(done, vol, rea)[0] == "A"
    assert best_on_line([over, ("vol", vol), ("rea", rea)], vol, rea)[0] == "rea"  # line ratio 1
    assert best_on_line([over, ("vol", vol)], vol, rea)[0] == "B"  # none within the cap: the lowest of all


def test_compare_strategies_runs_the_line_oracle_by_name():
    """``oracle_line`` (asked for by name: it is not a default run) replays its schedules beside the pure runs
    and keeps one episode a trial, never above the line (the pure runs are among its candidates)."""
    from mpcshare.evaluation import StrategyRun, compare_strategies
    from mpcshare.run_table import DEFAULT_RUNS
    from sim.demonstrator import generate_demonstrations
    from tests.sim.controllers import IdleController

    assert "oracle_line" not in {r.name for r in DEFAULT_RUNS}
    demos = generate_demonstrations(n_subjects=1, minutes=0.1, seed=5)
    runs = [StrategyRun("voluntary", "voluntary"), StrategyRun("reactive", "reactive"),
            StrategyRun("oracle_line", "schedule", schedule="oracle_line")]
    comp = compare_strategies(None, demos, [0], runs=runs, duration_s=1.0,
                              make_controller=lambda bundle, **options: IdleController(), log=None)
    m = comp.strategies["oracle_line"]
    assert m["tracking_rmse_m"] > 0 and m["line_ratio"] <= 1.0 + 1e-9


def test_the_placebo_replays_the_gates_share_while_the_robot_leads():
    """A gate whose robot leads at α = 0.5 (``robot_alphas``): the placebo counts those steps as the robot's
    (α ≥ 0.5, not > 0.5) and replays them at 0.5, the convex mixture, not at 1 and not as the wearer's."""
    from mpcshare.control.arbitration import Arbiter
    from mpcshare.evaluation.handover import random_schedules_from, schedule_record

    alpha = np.r_[np.zeros(50), np.full(150, 0.5)]
    rec = schedule_record(SimpleNamespace(t=DT * np.arange(200), alpha=alpha))
    assert rec["on_alpha"] == 0.5 and rec["on_steps"] == 150
    (sched,) = random_schedules_from(rec, 1, [0, 1])
    values = {sched(t) for t in DT * np.arange(200)}
    assert values == {0.0, 0.5} and np.mean(sched.on) == pytest.approx(0.75)
    arb = Arbiter("schedule", beta=0.5, handover_s=0.0, schedule=lambda t: 0.5)
    d = arb.decide(0.0, None)
    assert (d.alpha, d.beta) == (0.5, 0.5)
    assert Arbiter("schedule", beta=0.5, handover_s=0.0, schedule=lambda t: 1.0).decide(0.0, None).beta == 0.5
