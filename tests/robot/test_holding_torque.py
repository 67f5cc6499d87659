"""The brake that holds an arm at rest at a posture (robot/holding_torque.py), on the SuperLimb's model."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from robot.default_arm import as_description
from robot.holding_torque import HoldingTorque


@pytest.fixture(scope="module")
def robot():
    return as_description(None)


def test_at_rest_at_the_posture_it_is_the_gravity_torque(robot):
    hold = HoldingTorque(robot, 0.01)
    q = np.array([0.1, 0.4, -0.3])
    tau, source = hold(q, np.zeros(3), q)
    g = pin.computeGeneralizedGravity(robot.model, robot.model.createData(), q)
    assert source == "brake" and np.allclose(tau, g, atol=1e-12) and np.abs(g).max() > 0.1


def test_it_brakes_a_moving_arm_within_the_limits(robot):
    hold = HoldingTorque(robot, 0.01)
    q, v = np.array([0.1, 0.4, -0.3]), np.array([0.5, -0.4, 0.3])
    tau, source = hold(q, v, q)
    data = robot.model.createData()
    a = pin.aba(robot.model, data, q, v, tau)
    assert source == "brake" and np.all(a * v < 0)  # every joint decelerates
    assert np.all(np.abs(tau) <= robot.limits.tau_max + 1e-12)
    # simulated with the torque held over each period, the arm comes to rest near the posture
    for _ in range(200):
        tau, _ = hold(q, v, np.array([0.1, 0.4, -0.3]))
        a = pin.aba(robot.model, data, q, v, tau)
        q, v = q + (v + 0.5 * 0.01 * a) * 0.01, v + a * 0.01
    assert np.abs(v).max() < 1e-3 and np.abs(q - [0.1, 0.4, -0.3]).max() < 0.05


def test_without_velocities_gravity_alone_and_without_anything_zeros(robot):
    hold = HoldingTorque(robot, 0.01)
    q = np.array([0.1, 0.4, -0.3])
    tau, source = hold(q, np.full(3, np.nan), q)
    assert source == "gravity" and np.allclose(tau, hold.gravity(q))
    tau, source = hold(np.full(3, np.nan), np.zeros(3), np.full(3, np.nan))
    assert source == "zero" and np.array_equal(tau, np.zeros(3))
    tau, source = hold([1.0], None, "x")  # unusable arguments: still an answer
    assert source == "zero"
    with pytest.raises(ValueError, match="period_s"):
        HoldingTorque(robot, 0.0)
