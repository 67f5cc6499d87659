"""The causal table rule fitted in hindsight: its score against the switch-priced search and by hand, its
fit against every table."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from research.switch_priced import SwitchPrices, priced_search
from research.table_rule import fit_table, score_schedule, time_in_cell
from tests.research.stroke_worlds import stroke_world


def _parties(e2, effort):
    return ((float(effort[0].mean()), float(np.sqrt(e2[0].mean()))),
            (float(effort[-1].mean()), float(np.sqrt(e2[-1].mean()))))


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_score_of_a_schedule_agrees_with_the_priced_search(seed):
    e2, effort, labels, dot, power, y = stroke_world(seed)
    trial = (labels >= 3).astype(int)
    first = np.array([True, False, False, True, False, False])
    prices = SwitchPrices(np.array([4e-4, 1e-4, 5e-5]), np.array([0.05, 0.0, 0.02]), np.zeros(3, int))
    vol, rea = _parties(e2, effort)
    found = priced_search(e2, effort, labels, first, dot, power, y, 0.3, prices, vol, rea, max_effort=1.0)
    assert found is not None
    s = score_schedule(found.assignment[labels], e2, effort, dot, power, y, trial, prices, vol, rea)
    assert (s.mse, s.effort, s.correlation, s.switches, s.line_ratio) == pytest.approx(
        (found.mse, found.effort, found.correlation, found.switches, found.line_ratio))


def test_the_score_by_hand():
    e2 = np.array([[1.0, 2.0, 3.0, 4.0], [10.0, 20.0, 30.0, 40.0]])
    effort = np.array([[0.5, 0.5, 0.5, 0.5], [0.1, 0.1, 0.1, 0.1]])
    dot, power = np.array([[1.0, 1.0, 0, 0], [0.5, 0.5, 0, 0]]), np.array([[1.0, 1.0, 0, 0], [1.0, 1.0, 0, 0]])
    prices = SwitchPrices(np.array([100.0, 7.0, 0.0]), np.array([1.0, 2.0, 0.0]), np.zeros(3, int))
    s = score_schedule(np.array([1, 0, 0, 1]), e2, effort, dot, power, 2.0, np.array([0, 0, 1, 1]), prices,
                       (0.5, 1.0), (0.1, 5.0))
    # steps: 10 + 2 + 3 + 40, a switch 1→0 (to the wearer, 100) at step 1; 0→1 at step 3 (from the wearer, 7);
    # steps 1 and 2 lie in different trials: no switch there
    assert s.mse == pytest.approx((55.0 + 107.0) / 4) and s.switches == 2
    assert s.effort == pytest.approx((0.1 + 0.5 + 0.5 + 0.1 + 1.0 + 2.0) / 4)
    assert s.correlation == pytest.approx((0.5 + 1.0) / np.sqrt(2.0 * 2.0))
    with pytest.raises(ValueError, match="levels must lie"):
        score_schedule(np.array([2, 0, 0, 1]), e2, effort, dot, power, 2.0, np.zeros(4), prices, (0.5, 1.0),
                       (0.1, 5.0))


def test_time_in_cell_restarts_at_each_change_and_trial():
    cell = np.array([0, 0, 0, 1, 1, 1, 1, 1])
    trial = np.array([0, 0, 0, 0, 0, 1, 1, 1])
    assert time_in_cell(cell, trial, 0.5, (0.0, 1.0)).tolist() == [0, 0, 1, 0, 0, 0, 0, 1]


@pytest.mark.parametrize("seed", [0, 3])
def test_the_fit_is_no_better_than_the_best_table_and_no_worse_than_whole_modes(seed):
    e2, effort, labels, dot, power, y = stroke_world(seed, steps=60, groups=6)
    rng = np.random.default_rng(seed)
    first_feature = rng.integers(0, 2, e2.shape[1])
    second_feature = rng.integers(0, 2, e2.shape[1])
    trial = np.zeros(e2.shape[1], dtype=int)
    prices = SwitchPrices(np.array([2e-5, 1e-5, 0.0]), np.zeros(3), np.zeros(3, int))
    vol, rea = _parties(e2, effort)

    def score(level):
        return score_schedule(level, e2, effort, dot, power, y, trial, prices, vol, rea)

    cap, c = 0.9 * vol[0], 0.3
    fit = fit_table(first_feature, second_feature, score, 3, effort_cap=cap, min_correlation=c)

    def ok(s):
        return s.effort <= cap and s.correlation >= c and s.line_ratio is not None

    every = [score(np.array(t).reshape(2, 2)[first_feature, second_feature])
             for t in itertools.product(range(3), repeat=4)]
    whole = [score(np.repeat(np.array(t)[:, None], 2, axis=1)[first_feature, second_feature])
             for t in itertools.product(range(3), repeat=2)]
    best_every = min(s.line_ratio for s in every if ok(s))
    best_whole = min(s.line_ratio for s in whole if ok(s))
    assert ok(fit.whole_score) and fit.whole_score.line_ratio == pytest.approx(best_whole)
    assert ok(fit.score) and best_every - 1e-12 <= fit.score.line_ratio <= best_whole + 1e-12
    assert score(fit.table[first_feature, second_feature]) == fit.score
