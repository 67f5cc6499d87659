"""The strategy registry: names, specs, one module each, the Arbiter reads it."""

from __future__ import annotations

import matplotlib.colors
import pytest

from mpcshare.control.arbitration import STRATEGIES, Arbiter, check_strategy
from mpcshare.control.strategies import DEFAULT_STRATEGY, REGISTRY, ROLES, StrategySpec, by_role, user_strategies


def _in_order(names: tuple[str, ...] | list[str], within: tuple[str, ...] | list[str]) -> bool:
    """Whether ``names`` appear in ``within`` in this order (others may come between: a new strategy is one
    module, no test names every strategy)."""
    rest = iter(within)
    return all(n in rest for n in names)


def test_the_registry_holds_the_named_strategies_in_order():
    assert _in_order(["voluntary", "reactive", "mix25", "mix50", "mix75", "gate", "paper_gate", "blend",
                      "qp_blend", "schedule"], list(REGISTRY))
    assert not _in_order(["gate", "voluntary"], list(REGISTRY))
    assert DEFAULT_STRATEGY == "gate" and STRATEGIES == user_strategies() == tuple(list(REGISTRY)[:-1])
    assert {"gate", "paper_gate", "blend"} <= {n for n, s in REGISTRY.items() if s.tunable}
    for name, spec in REGISTRY.items():
        assert isinstance(spec, StrategySpec) and spec.name == name
        assert spec.description.endswith(".") and spec.description.count(". ") == 0, spec.description
        assert matplotlib.colors.is_color_like(spec.color)
    assert len({s.color for s in REGISTRY.values()}) == len(REGISTRY)  # each its own colour in the plots
    with pytest.raises(TypeError):
        REGISTRY["x"] = REGISTRY["gate"]  # read-only


def test_each_strategy_declares_its_role_and_the_shared_ones_come_in_todays_order():
    assert by_role("shared")[0] == "gate"  # the headline names the first present
    assert _in_order(("gate", "paper_gate", "blend", "qp_blend"), by_role("shared"))
    assert _in_order(("voluntary", "reactive"), by_role("baseline"))
    assert _in_order(("mix25", "mix50", "mix75"), by_role("mix")) and "schedule" in by_role("replay")
    assert sorted(n for r in ROLES for n in by_role(r)) == sorted(REGISTRY)
    with pytest.raises(ValueError, match="role 'helper' is not one of shared, baseline, mix, replay"):
        by_role("helper")
    with pytest.raises(ValueError, match="strategy 'x': role 'helper'"):
        StrategySpec("x", "X.", tunable=False, color="k", factory=REGISTRY["gate"].factory, role="helper")
    with pytest.raises(ValueError, match="strategy 'x': fusion 'after' is not one of velocity, qp"):
        StrategySpec("x", "X.", tunable=False, color="k", factory=REGISTRY["gate"].factory, role="shared",
                     fusion="after")


def test_check_strategy_names_the_registry():
    for name in STRATEGIES:
        assert check_strategy(name) == name
    with pytest.raises(ValueError, match="valid choices: " + ", ".join(STRATEGIES)):
        check_strategy("schedule")  # not a user's choice without a schedule


@pytest.mark.parametrize("name,alpha", [("mix25", 0.25), ("mix50", 0.5), ("mix75", 0.75)])
def test_mixtures_are_points_of_the_line(name, alpha):
    """β = 1 − α whatever the user's β, whatever the gate says, no overrides, no hand-overs."""
    arb = Arbiter(name, beta=0.9, novelty_threshold=1.0, handover_s=0.5)
    for k, p in enumerate([0.0, 1.0, float("nan"), None]):
        d = arb.decide(0.1 * k, p, novelty=5.0, prediction_finite=k % 2 == 0, available=k != 3)
        assert (d.alpha, d.beta) == (alpha, pytest.approx(1.0 - alpha))
    assert arb.handovers == []
