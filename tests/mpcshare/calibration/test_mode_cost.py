"""Per-mode costs of the two parties from closed-loop episodes, their prices and the cutting modes."""

from __future__ import annotations

import numpy as np
import pytest

from mpcshare.calibration.mode_cost import cutting_effort, cutting_modes, mode_costs, price_order


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
