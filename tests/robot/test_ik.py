"""Numerical inverse kinematics (robot.ik) on the SuperLimb: reachable tips reached within the limits,
an unreachable one answered with an in-limit configuration nearer to it than the start."""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from robot.ik import inverse_tip_position
from robot.superlimb import superlimb_description


def _tip(model, frame_id: int, q: np.ndarray) -> np.ndarray:
    data = model.createData()
    pin.framesForwardKinematics(model, data, q)
    return data.oMf[frame_id].translation.copy()


def test_reachable_tips_are_reached_within_the_limits():
    arm = superlimb_description()
    lo, hi = arm.limits.q_min, arm.limits.q_max
    rng = np.random.default_rng(4)
    for _ in range(5):
        target = _tip(arm.model, arm.tip_frame_id, rng.uniform(lo, hi))
        q = inverse_tip_position(arm.model, arm.tip_frame_id, target, lo, hi, q_prefer=arm.q_home)
        assert np.all(q >= lo) and np.all(q <= hi)
        assert np.linalg.norm(_tip(arm.model, arm.tip_frame_id, q) - target) < 1e-6


def test_an_unreachable_tip_gets_the_nearest_configuration_within_the_limits():
    arm = superlimb_description()
    lo, hi = arm.limits.q_min, arm.limits.q_max
    home = _tip(arm.model, arm.tip_frame_id, arm.q_home)
    far = home + np.array([0.0, 0.0, 2.0])  # 2 m above the home tip: beyond the arm's reach
    q = inverse_tip_position(arm.model, arm.tip_frame_id, far, lo, hi, q_prefer=arm.q_home)
    assert np.all(q >= lo) and np.all(q <= hi)
    reached = np.linalg.norm(_tip(arm.model, arm.tip_frame_id, q) - far)
    assert 1.0 < reached < np.linalg.norm(home - far)  # stretched toward it, still out of reach
