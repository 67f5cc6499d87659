"""The switch-priced splice search, against brute force over every assignment."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from mpcshare.line_ratio import line_ratio
from research.splice_bound import group_sums
from research.switch_priced import (
    SwitchPrices,
    chain_knapsack,
    estimate_prices,
    priced_search,
    switch_class,
)
from tests.research.stroke_worlds import stroke_world as _world


def _brute_chain(cost, shift, price, price_shift, first):
    """Per (end level, bin) the lowest chain cost over every assignment."""
    best: dict[tuple[int, int], float] = {}
    levels, groups = cost.shape
    for a in itertools.product(range(levels), repeat=groups):
        c = sum(cost[lv, g] for g, lv in enumerate(a))
        b = sum(shift[lv, g] for g, lv in enumerate(a))
        for g in range(1, groups):
            if a[g] != a[g - 1] and not first[g]:
                c += price[a[g - 1], a[g]]
                b += price_shift[a[g - 1], a[g]]
        key = (a[-1], b)
        best[key] = min(best.get(key, np.inf), c)
    return best


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_chain_knapsack_is_exact(seed):
    rng = np.random.default_rng(seed)
    levels, groups = 3, 6
    cost = rng.normal(0, 1, (levels, groups))
    shift = rng.integers(0, 4, (levels, groups))
    price = rng.uniform(0, 2, (levels, levels))
    price_shift = rng.integers(0, 3, (levels, levels))
    first = np.array([True, False, False, True, False, False])
    size = int(shift.max(axis=0).sum() + price_shift.max() * groups) + 1
    dp, _ = chain_knapsack(cost, shift, np.ones_like(cost, dtype=bool), price, price_shift, first, size)
    want = _brute_chain(cost, shift, price, price_shift, first)
    for lv in range(levels):
        for b in range(size):
            assert dp[lv, b] == pytest.approx(want.get((lv, b), np.inf), abs=1e-12)


def _score(a, e2, effort, labels, dot, power, y, prices, first):
    """(MSE, mean effort, ρ, switches) of assignment ``a`` with the switch prices, from its definition."""
    sums = [group_sums(v, labels)[1] for v in (e2, effort, dot, power)]
    cols = np.arange(len(a))
    m, e, x, s = (v[np.array(a), cols].sum() for v in sums)
    p_e, p_t = prices.matrices(e2.shape[0])
    n_sw = 0
    for g in range(1, len(a)):
        if a[g] != a[g - 1] and not first[g]:
            m, e, n_sw = m + p_e[a[g - 1], a[g]], e + p_t[a[g - 1], a[g]], n_sw + 1
    return m / labels.size, e / labels.size, x / np.sqrt(y * s), n_sw


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
@pytest.mark.parametrize("price", [0.0, 3e-4])
def test_the_schedule_found_saws_pays_its_switches_and_no_assignment_beats_it_by_much(seed, price):
    e2, effort, labels, dot, power, y = _world(seed)
    first = np.array([True, False, False, True, False, False])
    prices = SwitchPrices(np.array([price, price / 2, price / 4]), np.array([0.02, 0.0, 0.01]), np.zeros(3, int))
    vol = (float(effort[0].mean()), float(np.sqrt(e2[0].mean())))
    rea = (float(effort[-1].mean()), float(np.sqrt(e2[-1].mean())))
    c, cap = 0.5, 0.75 * vol[0]
    found = priced_search(e2, effort, labels, first, dot, power, y, c, prices, vol, rea, bins=4000, grid_ratio=1.1,
                          lambdas=43)
    ratios = []
    for a in itertools.product(range(3), repeat=6):
        m, e, rho, _ = _score(a, e2, effort, labels, dot, power, y, prices, first)
        if rho >= c and e <= cap and (r := line_ratio(float(np.sqrt(m)), e, vol, rea)) is not None:
            ratios.append(r)
    want = min(ratios, default=None)
    if want is None:
        assert found is None
        return
    assert found is not None
    m, e, rho, n_sw = _score(tuple(found.assignment), e2, effort, labels, dot, power, y, prices, first)
    assert (found.mse, found.effort, found.correlation, found.switches) == pytest.approx((m, e, rho, n_sw))
    assert rho >= c and e <= cap
    assert want * (1 - 1e-9) <= found.line_ratio <= want * 1.1  # a search: feasible, near the exact best


def test_a_high_price_leaves_no_switch():
    e2, effort, labels, dot, power, y = _world(5)
    first = np.array([True, False, False, False, False, False])
    vol = (float(effort[0].mean()), float(np.sqrt(e2[0].mean())))
    rea = (float(effort[-1].mean()), float(np.sqrt(e2[-1].mean())))
    free = priced_search(e2, effort, labels, first, dot, power, y, 0.2, SwitchPrices.zero(), vol, rea,
                         max_effort=1.0)
    dear = priced_search(e2, effort, labels, first, dot, power, y, 0.2,
                         SwitchPrices(np.full(3, 1.0), np.zeros(3), np.zeros(3, int)), vol, rea, max_effort=1.0)
    assert free is not None and dear is not None
    assert free.switches > 0 and dear.switches == 0


def test_prices_are_estimated_from_the_excess_around_each_switch():
    level = np.array([1, 1, 0, 0, 0, 2, 2, 1, 0, 0])
    first = np.zeros(10, dtype=bool)
    first[[0, 8]] = True  # the switch at group 8 begins a new trial: not a switch
    truth = {0: 5.0, 1: 3.0, 2: 1.0}  # per class, split over the switch's group and the next
    x_e2, x_ef = np.zeros(10), np.zeros(10)
    for g in range(1, 10):
        if level[g] != level[g - 1] and not first[g]:
            c = switch_class(level[g - 1], level[g])
            x_e2[g] += 0.6 * truth[c]
            x_e2[g + 1] += 0.4 * truth[c]
            x_ef[g] += 0.1 * (c + 1)
    p = estimate_prices([(level, first, x_e2, x_ef)])
    assert list(p.counts) == [1, 1, 1]  # 1→0 at 2; 0→2 at 5; 2→1 at 7 (robot levels); 1→0 at 8 begins a trial
    # each takes its own group and the next, except 2→1 at 7: group 8 begins a trial, so 7 alone
    assert p.error == pytest.approx([5.0, 3.0, 0.6 * 1.0])
    assert p.effort == pytest.approx([0.1, 0.2, 0.3])
    none = estimate_prices([(np.zeros(4, int), np.array([True, False, False, False]), np.ones(4), np.ones(4))])
    assert list(none.error) == [0.0, 0.0, 0.0]
    with pytest.raises(ValueError, match="equal-length"):
        estimate_prices([(level, first[:3], x_e2, x_ef)])


def test_bad_input_is_named():
    e2, effort, labels, dot, power, y = _world(0)
    vol, rea = (0.1, 0.01), (0.01, 0.02)
    with pytest.raises(ValueError, match="first must be"):
        priced_search(e2, effort, labels, np.zeros(6, bool), dot, power, y, 0.5, SwitchPrices.zero(), vol, rea)
    with pytest.raises(ValueError, match="min_correlation"):
        priced_search(e2, effort, labels, np.ones(6, bool), dot, power, y, 1.5, SwitchPrices.zero(), vol, rea)
    with pytest.raises(ValueError, match="levels, steps"):
        priced_search(e2[:, :10], effort, labels, np.ones(6, bool), dot, power, y, 0.5, SwitchPrices.zero(), vol, rea)


def test_next_targets_raise_the_target_by_the_shortfall_and_lower_the_cap_by_the_excess():
    from research.switch_priced import next_targets

    assert next_targets(0.6, 0.75, 0.5, 0.80) == pytest.approx((0.72, 0.69))
    assert next_targets(0.6, 0.75, None, 0.70) == (0.6, 0.75)  # no cutting, within the cap: unchanged
    assert next_targets(0.99, 0.06, 0.0, 2.0) == (1.0, 0.05)  # bounded
