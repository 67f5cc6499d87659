"""Braking caps: the torque-feasibility measure and the search for the largest feasible caps."""

from __future__ import annotations

import itertools

import numpy as np
import pinocchio as pin
import pytest

from robot.braking import braking_caps, braking_torque_ratio, tip_box_states
from robot.description import RobotDescription
from robot.errors import ControllerConfigError
from robot.superlimb import superlimb_description

erd = pytest.importorskip("example_robot_data")
PANDA = "panda_description/urdf/panda.urdf"
FINGERS = ("panda_finger_joint1", "panda_finger_joint2")


@pytest.fixture(scope="module")
def panda() -> RobotDescription:
    path = f"{erd.getModelPath(PANDA)}/{PANDA}"
    return RobotDescription.from_file(path, "panda_hand_tcp", locked_joints=FINGERS, acceleration_limit=10.0)


def test_the_ratio_is_the_worst_acceleration_corner_and_the_superlimb_is_unchanged(panda) -> None:
    """At (almost) no speed the ratio is the worst of all 2⁷ corners of |a| ≤ a_brake, by brute force."""
    slow = RobotDescription.from_model(panda.model, panda.tip_frame, velocity_limit=1e-9, acceleration_limit=10.0)
    lim, data = slow.limits, slow.model.createData()
    states = np.random.default_rng(0).uniform(lim.q_min, lim.q_max, (4, 7))
    corners = np.array(list(itertools.product((-1.0, 1.0), repeat=7))) * lim.a_brake
    brute = max(float(np.max(np.abs(pin.rnea(slow.model, data, q, np.zeros(7), a)) / lim.tau_max))
                for q in states for a in corners)
    assert braking_torque_ratio(slow, states=states) == pytest.approx(brute, rel=1e-9)
    assert braking_torque_ratio(panda, states=states) > brute  # speed adds Coriolis and centrifugal torques
    assert braking_torque_ratio(superlimb_description()) <= 1.0  # the SuperLimb's own limits stay feasible


def test_tip_box_states_put_the_tip_in_the_box_or_say_out_of_reach(panda) -> None:
    lo, hi = np.array([0.3, -0.2, 0.1]), np.array([0.6, 0.2, 0.4])
    states = tip_box_states(panda.model, panda.tip_frame_id, panda.limits.q_min, panda.limits.q_max, lo, hi, n=30)
    assert states.shape == (30, 7)
    data = panda.model.createData()
    for q in states:
        pin.framesForwardKinematics(panda.model, data, q)
        p = data.oMf[panda.tip_frame_id].translation
        assert np.all(p >= lo) and np.all(p <= hi)
        assert np.all(q >= panda.limits.q_min) and np.all(q <= panda.limits.q_max)
    with pytest.raises(ControllerConfigError, match="out of reach"):
        tip_box_states(panda.model, panda.tip_frame_id, panda.limits.q_min, panda.limits.q_max, lo + 5, hi + 5,
                       max_draws=200)


def test_caps_are_the_largest_feasible_and_forced_ones_are_kept(panda) -> None:
    lim = panda.limits
    states = np.random.default_rng(2).uniform(lim.q_min, lim.q_max, (60, panda.n))
    a_ref = np.full(7, 20.0)  # braking at 10 rad/s² from full speed is beyond the Panda's wrist torques
    caps = braking_caps(panda.model, states, lim.v_max, a_ref, lim.tau_max)
    assert 0.0 < caps.scale < 1.0 and caps.ratio <= 0.9
    np.testing.assert_allclose(caps.velocity, caps.scale * lim.v_max)
    np.testing.assert_allclose(caps.acceleration, caps.scale * a_ref)
    capped = RobotDescription.from_model(panda.model, panda.tip_frame, velocity_limit=caps.velocity,
                                         acceleration_limit=caps.acceleration)
    assert braking_torque_ratio(capped, states=states) == pytest.approx(caps.ratio)
    # one grid step faster is infeasible: the caps are the largest on the grid
    fast = RobotDescription.from_model(panda.model, panda.tip_frame, velocity_limit=caps.velocity / 0.98,
                                       acceleration_limit=caps.acceleration / 0.98)
    assert braking_torque_ratio(fast, states=states) > 0.9
    kept = braking_caps(panda.model, states, np.full(7, 1.0), a_ref, lim.tau_max, scale_velocity=False)
    np.testing.assert_allclose(kept.velocity, 1.0)
    assert kept.ratio <= 0.9 and np.all(kept.acceleration < a_ref)
    with pytest.raises(ControllerConfigError, match="torque limit"):
        braking_caps(panda.model, states, lim.v_max, np.full(7, 400.0), lim.tau_max, scale_acceleration=False)
