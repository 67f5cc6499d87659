"""Per-mode costs of the two parties from closed-loop episodes, their prices and the cutting modes."""

from __future__ import annotations

import numpy as np
import pytest

from mpcshare.calibration.mode_cost import (
    beyond_the_wearer_alone,
    cutting_effort,
    cutting_modes,
    mode_costs,
    predicted_point,
    price_order,
    prune_sets,
)


class _Episode:
    def __init__(self, mode, err_m, effort_rad):
        n = len(mode)
        self.mode = np.asarray(mode)
        self.tip_intent = np.ones((n, 3))
        self.tip = self.tip_intent.copy()
        self.tip[:, 2] += err_m
        self.voluntary = np.zeros((n, 3))
        self.voluntary[:, 0] = effort_rad


def test_costs_and_prices_against_hand_computed_figures():
    rng = np.random.default_rng(0)
    mode = rng.integers(-1, 3, 400)  # -1: no estimate yet, dropped
    err_w = rng.uniform(0, 0.01, 400)
    err_r = rng.uniform(0, 0.03, 400) * (mode != 2)  # the robot is perfect in mode 2
    eff_w, eff_r = rng.uniform(0.05, 0.1, 400), rng.uniform(0.0, 0.02, 400)
    c = mode_costs([_Episode(mode, err_w, eff_w)], [_Episode(mode, err_r, eff_r)], 4)
    for j in range(3):
        s = mode == j
        mw, mr = np.mean(err_w[s] ** 2), np.mean(err_r[s] ** 2)
        assert c["rms_wearer_mm"][j] == pytest.approx(1e3 * np.sqrt(mw))
        assert c["effort_robot_rad"][j] == pytest.approx(np.mean(eff_r[s]))
        price = max(mr - mw, 0.0) / (np.mean(eff_w[s]) - np.mean(eff_r[s]))
        assert c["price_mm2_per_rad"][j] == pytest.approx(1e6 * price)
    assert c["share"][:3] == pytest.approx([np.mean(mode[mode >= 0] == j) for j in range(3)])
    assert c["share"][3] == 0 and c["rms_wearer_mm"][3] is None  # a mode never seen: JSON-able
    assert price_order(c) == sorted([0, 1], key=lambda j: -c["price_mm2_per_rad"][j])  # mode 2: nothing to save


def test_a_mode_that_costs_no_effort_has_a_finite_price_and_comes_first():
    mode = np.repeat([0, 1], 50)
    wearer = _Episode(mode, np.full(100, 0.001), np.repeat([0.1, 0.0], 50))
    robot = _Episode(mode, np.full(100, 0.01), np.repeat([0.0, 0.0], 50))
    c = mode_costs([wearer], [robot], 2)
    assert np.isfinite(c["price_mm2_per_rad"]).all()
    assert price_order(c) == [1, 0]


def test_cutting_modes_by_majority_of_labels():
    mode = np.repeat([0, 1, 2], 10)
    labels = np.concatenate([np.zeros(10), np.r_[np.zeros(4), np.ones(6)], np.ones(10)]).astype(int)
    ep = _Episode(mode, np.zeros(30), np.zeros(30))
    assert cutting_modes([ep], [labels], cutting_label=1, n_modes=3) == [1, 2]
    assert cutting_modes([ep], [labels[:15]], cutting_label=1, n_modes=3) == []  # labels shorter: 1 has 4 of 5 at 0


def test_refuses_missing_episodes():
    with pytest.raises(ValueError, match="both parties"):
        mode_costs([], [], 3)


def test_the_effort_of_leaving_the_cutting_to_the_wearer_against_the_splice_of_the_two_runs():
    """cutting_effort is the mean effort of the run spliced from the wearer's steps in the cutting modes and
    the robot's elsewhere, over the wearer's mean effort alone (both runs see the same modes here)."""
    rng = np.random.default_rng(1)
    mode = rng.integers(0, 3, 600)
    eff_w, eff_r = rng.uniform(0.05, 0.2, 600), rng.uniform(0.0, 0.03, 600)
    zero = np.zeros(600)
    c = mode_costs([_Episode(mode, zero, eff_w)], [_Episode(mode, zero, eff_r)], 3)
    spliced = np.where(np.isin(mode, [0, 2]), eff_w, eff_r).mean()
    assert cutting_effort(c, [0, 2]) == pytest.approx(spliced / eff_w.mean())
    assert cutting_effort(c, [0, 1, 2]) == pytest.approx(1.0)
    assert cutting_effort(c, []) is None
    unseen = mode_costs([_Episode(mode, zero, eff_w)], [_Episode(mode, zero, eff_r)], 4)  # mode 3 never seen
    assert cutting_effort(unseen, [0]) is None


#: the per-mode costs of the demo's rule choice (default data, trials 10 and 11, 60 s each)
DEMO_COSTS = {"share": [0.425, 0.27666666666666667, 0.11, 0.18833333333333332],
              "rms_wearer_mm": [7.27134409399527, 9.158421290121057, 8.540558236249888, 26.06010641530786],
              "rms_robot_mm": [23.8187180401594, 23.9165831573501, 24.57892527561725, 23.250436959728304],
              "effort_wearer_rad": [0.05972740712972807, 0.06039666604116731, 0.1898296080887222, 0.12263350933857159],
              "effort_robot_rad": [0.07972483106381997, 0.08097246554771512, 0.07300009240770138, 0.07347640735994043]}


def test_the_predicted_point_of_a_rule_mixes_the_parties_figures_by_mode():
    effort, rms = predicted_point(DEMO_COSTS, [0, 1, 2, 3])  # the wearer alone: the voluntary run's own figures
    assert effort == pytest.approx(0.0860711267833812) and rms == pytest.approx(0.013476010220342954)
    effort, rms = predicted_point(DEMO_COSTS, [2])
    p = DEMO_COSTS["share"]
    assert effort == pytest.approx(p[0] * 0.07972483106381997 + p[1] * 0.08097246554771512
                                   + p[2] * 0.1898296080887222 + p[3] * 0.07347640735994043)
    assert rms == pytest.approx(np.sqrt(p[0] * 23.8187180401594 ** 2 + p[1] * 23.9165831573501 ** 2
                                        + p[2] * 8.540558236249888 ** 2 + p[3] * 23.250436959728304 ** 2) * 1e-3)
    assert predicted_point({**DEMO_COSTS, "rms_robot_mm": [None, 1.0, 1.0, 1.0]}, [2]) is None


def test_only_the_sets_beyond_the_wearer_alone_on_both_counts_are_pruned():
    """On the demo's costs, leading the cutting mode 2 alone costs 1.06x the wearer's effort at 22.6 mm (the
    wearer alone: 13.5 mm): left out; every other set saves effort; the empty set is never left out."""
    sets = [[0], [0, 2], [0, 1], [0, 1, 2], [2], []]
    kept, pruned = prune_sets(DEMO_COSTS, sets, 0.0860711267833812)
    assert kept == [[0], [0, 2], [0, 1], [0, 1, 2], []] and [r["wearer_modes"] for r in pruned] == [[2]]
    assert pruned[0]["predicted_effort_vs_voluntary"] == pytest.approx(1.0573, abs=1e-4)
    assert pruned[0]["predicted_rmse_m"] == pytest.approx(0.02257, abs=1e-5) and "1.06x" in pruned[0]["why"]
    assert prune_sets(DEMO_COSTS, sets, 0.086, prune=False) == (sets, [])
    assert not beyond_the_wearer_alone(DEMO_COSTS, [])
    cheap = {**DEMO_COSTS, "effort_wearer_rad": [0.10, 0.10, 0.19, 0.12]}  # leading mode 2 alone now saves effort
    assert not beyond_the_wearer_alone(cheap, [2])
