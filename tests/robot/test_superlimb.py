"""The SuperLimb brakes within its torque at every state (the check robot/superlimb/params.py cites)."""

from __future__ import annotations

import itertools

import numpy as np
import pinocchio as pin

from robot.model_files import build_pinocchio_model
from robot.superlimb import SuperLimbParams
from tests.robot.superlimb.models import full_m as _full_m


def test_braking_is_always_torque_feasible() -> None:
    """The viability constraint relies on a_brake being available at every state.

    For q in the limits, |v_i| = v_max,i (the worst velocity products) and every
    sign pattern of ±a_brake, |M(q)·a + h(q, v)| stays below τ_max.
    """
    p = SuperLimbParams()
    model, data, _ = build_pinocchio_model(p)
    signs = np.array(list(itertools.product([-1.0, 1.0], repeat=3)))
    acc = signs * p.braking_acceleration
    rng = np.random.default_rng(7)
    worst = np.zeros(3)
    for q in rng.uniform(p.lower, p.upper, (600, 3)):
        mass = _full_m(model, data, q)
        for s in signs:
            h = pin.nonLinearEffects(model, data, q, s * p.velocity_limit)
            worst = np.maximum(worst, np.abs(acc @ mass.T + h).max(axis=0))
    assert np.all(worst < 0.8 * p.torque_limit), worst / p.torque_limit
