"""The fusion candidate's α against its equation, by hand."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from research.coming_error.fusion import EPS, TAU_S, FusionPolicy, leaky

PARAMS = {"robot_log_var": [math.log(4e-4), math.log(1e-4)], "correction_gain": 0.5, "log_resid_var": 0.2,
          "wearer_var": [1e-4, 1e-4], "log_correction_prior": [math.log(0.01), math.log(0.01)]}


def test_leaky_mean_by_hand():
    np.testing.assert_allclose(leaky(np.array([0.0, 1.0, 1.0]), 0.1, 0.2), [0.0, 0.5, 0.75])


def test_alpha_is_the_minimum_variance_weight():
    pol = FusionPolicy(PARAMS)
    robot_leads = SimpleNamespace(alpha=1.0)
    step = SimpleNamespace(mode_proba=np.array([0.0, 1.0]), u_v=np.array([0.01, 0.0, 0.0]))
    a = pol.decide(0.0, step, robot_leads)  # first step: c̄ = the mode's prior, 0.01 m/s
    var_r = math.exp(math.log(1e-4) + 0.5 * math.log(0.01 + EPS) + 0.1)
    assert a.alpha == pytest.approx(1e-4 / (var_r + 1e-4)) and a.beta == pytest.approx(1 - a.alpha) and a.ramp
    pushing = SimpleNamespace(mode_proba=np.array([0.0, 1.0]), u_v=np.array([0.1, 0.0, 0.0]))
    b = pol.decide(0.01, pushing, robot_leads)  # the wearer corrects harder: the robot's predicted error grows
    c = 0.01 + 0.01 / TAU_S * (0.1 - 0.01)
    assert b.alpha == pytest.approx(1e-4 / (math.exp(math.log(1e-4) + 0.5 * math.log(c + EPS) + 0.1) + 1e-4))
    assert b.alpha < a.alpha
    wearer_leads = SimpleNamespace(alpha=0.2)
    for k in range(300):  # while the wearer leads, c̄ relaxes to the prior whatever the shoulder does
        d = pol.decide(0.02 + 0.01 * k, pushing, wearer_leads)
    assert d.alpha == pytest.approx(a.alpha, rel=1e-3)


def test_bad_parameters_are_refused():
    with pytest.raises(ValueError, match="one robot log-variance"):
        FusionPolicy({**PARAMS, "wearer_var": [1e-4]})


def test_the_lead_variant_hands_over_whole_with_hysteresis():
    r = math.log(4e-4) - 0.5 * math.log(0.01 + EPS) - 0.1  # σ_r² = 4e-4 at the prior's correction: α* = 0.2
    pol = FusionPolicy({**PARAMS, "robot_log_var": [r, r]}, split=True)
    step = SimpleNamespace(mode_proba=np.array([1.0, 0.0]), u_v=np.zeros(3))
    assert FusionPolicy({**PARAMS, "robot_log_var": [r, r]}).decide(0.0, step, SimpleNamespace(alpha=1.0)).alpha \
        == pytest.approx(0.2)
    assert pol.decide(0.0, step, SimpleNamespace(alpha=1.0)).alpha == 0.0  # the wearer alone
    good = FusionPolicy(PARAMS, split=True)
    easy = SimpleNamespace(mode_proba=np.array([0.0, 1.0]), u_v=np.zeros(3))
    a = good.decide(0.0, easy, SimpleNamespace(alpha=0.0))
    assert a.alpha >= 0.5 and a.beta == pytest.approx(1 - a.alpha)  # α* > 0.55: the robot leads at its share
