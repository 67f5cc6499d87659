"""Given hand-over schedules: the matched-random placebo, the oracle, and their replay by the arbiter."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from mpcshare.control.arbitration import Arbiter
from mpcshare.evaluation.schedule import LevelSchedule, StepSchedule, oracle_schedule, random_schedule, schedule_stats


def _gate_like() -> np.ndarray:
    """300 steps: off 40, on 80, off 60, on 70, off 50."""
    return np.repeat([False, True, False, True, False], [40, 80, 60, 70, 50])


def test_random_schedule_matches_share_count_and_dwell_exactly():
    gate = _gate_like()
    stats = schedule_stats(gate)
    assert (stats.on_steps, stats.handovers, stats.min_interior, stats.first_on) == (150, 4, 60, False)
    for seed in range(20):
        s = random_schedule(stats, 50, seed)
        got = schedule_stats(s)
        assert s.size == gate.size
        assert got.on_steps == stats.on_steps and got.handovers == stats.handovers
        assert got.first_on == stats.first_on and got.min_interior >= 50


def test_random_schedules_differ_by_seed_and_repeat_with_it():
    stats = schedule_stats(_gate_like())
    draws = [random_schedule(stats, 50, [7, 0, j]) for j in range(4)]
    for a, b in itertools.combinations(draws, 2):
        assert not np.array_equal(a, b)
    assert np.array_equal(random_schedule(stats, 50, [7, 0, 1]), draws[1])


def test_random_schedule_refuses_what_cannot_fit():
    stats = schedule_stats(_gate_like())
    with pytest.raises(ValueError, match="cannot fit"):
        random_schedule(stats, 200, 0)
    with pytest.raises(ValueError, match="dwell"):
        random_schedule(stats, 0, 0)


def test_oracle_schedule_beats_both_pure_runs_with_the_dwell():
    """Robot better in the middle third, wearer better elsewhere, with noise that tempts chattering."""
    rng = np.random.default_rng(3)
    n = 300
    e_wearer = np.full(n, 0.010) + rng.uniform(0, 0.004, n)
    e_robot = np.full(n, 0.020) + rng.uniform(0, 0.004, n)
    e_robot[100:200] = 0.004
    e_robot[150] = 0.05  # one bad robot step: the dwell forbids handing back for it alone
    dwell = 30
    on = oracle_schedule(e_wearer, e_robot, dwell)

    def cost(x: np.ndarray) -> float:
        return float(np.sum(np.where(x, e_robot, e_wearer) ** 2))

    assert cost(on) <= cost(np.zeros(n, bool)) and cost(on) <= cost(np.ones(n, bool))
    assert cost(on) < 0.8 * min(cost(np.zeros(n, bool)), cost(np.ones(n, bool)))
    stats = schedule_stats(on)
    assert stats.min_interior is None or stats.min_interior >= dwell
    assert on[100:200].all() and not on[:95].any() and not on[205:].any()


def test_oracle_schedule_is_the_optimum_on_a_small_case():
    """Brute force over all 2^10 schedules with interior segments ≥ 3."""
    rng = np.random.default_rng(0)
    e0, e1 = rng.uniform(0, 1, 10), rng.uniform(0, 1, 10)
    best = min((np.array(bits, bool) for bits in itertools.product([0, 1], repeat=10)
                if (schedule_stats(np.array(bits, bool)).min_interior or 99) >= 3),
               key=lambda x: float(np.sum(np.where(x, e1, e0) ** 2)))
    on = oracle_schedule(e0, e1, 3)
    assert np.sum(np.where(on, e1, e0) ** 2) == pytest.approx(np.sum(np.where(best, e1, e0) ** 2))


@pytest.mark.parametrize("dwell", [1, 3])
@pytest.mark.parametrize("switch_cost", [0.0, 0.3, 2.0])
def test_oracle_schedule_with_a_switch_cost_is_the_optimum(dwell, switch_cost):
    """Brute force over all 2^10 schedules: Σ e² + switch_cost · hand-overs, interior segments ≥ dwell."""
    rng = np.random.default_rng(1)
    e0, e1 = rng.uniform(0, 1, 10), rng.uniform(0, 1, 10)

    def cost(x):
        return float(np.sum(np.where(x, e1, e0) ** 2)) + switch_cost * schedule_stats(x).handovers

    best = min(cost(np.array(bits, bool)) for bits in itertools.product([0, 1], repeat=10)
               if (schedule_stats(np.array(bits, bool)).min_interior or 99) >= dwell)
    assert cost(oracle_schedule(e0, e1, dwell, switch_cost)) == pytest.approx(best)
    with pytest.raises(ValueError, match="switch_cost"):
        oracle_schedule(e0, e1, dwell, -1.0)


def test_arbiter_replays_a_schedule_through_the_ramp():
    times = np.arange(200) * 0.01
    on = np.repeat([False, True, False], [50, 100, 50])
    arb = Arbiter("schedule", 0.3, handover_s=0.5, schedule=StepSchedule(times, on, lead_s=0.25))
    alpha = np.array([arb.decide(t, None, available=False).alpha for t in times])
    assert ((alpha > 0.5) == on).mean() > 0.98  # the ramp crosses 0.5 on the scheduled steps
    assert len(arb.handovers) == 2 and np.all(np.abs(np.diff(alpha)) <= 0.01 / 0.5 + 1e-12)
    with pytest.raises(ValueError, match="schedule"):
        Arbiter("gate", schedule=StepSchedule(times, on))
    with pytest.raises(ValueError, match="schedule"):
        Arbiter("schedule")


def test_a_level_schedule_is_replayed_at_its_shares():
    """A robot share of 0.5 replays as the mixture (β = 1 − α), 0 as the wearer, 1 as the robot alone."""
    times = np.arange(300) * 0.01
    levels = np.repeat([1.0, 0.5, 0.0], 100)
    sched = LevelSchedule(times, levels)
    assert [sched(t) for t in (0.0, 0.995, 1.0, 2.5, 9.0)] == [1.0, 1.0, 0.5, 0.0, 0.0]
    assert LevelSchedule(times, levels, lead_s=0.2)(0.85) == 0.5  # read ahead
    arb = Arbiter("schedule", 0.3, handover_s=0.0, schedule=sched)
    d = arb.decide(1.5, None, available=False)
    assert d.alpha == 0.5 and d.beta == pytest.approx(0.5)
    with pytest.raises(ValueError, match="at step 3"):
        LevelSchedule(times[:4], np.array([0.0, 0.5, 1.0, 0.25]))
    with pytest.raises(ValueError, match="equal-length"):
        LevelSchedule(times, levels[:-1])
