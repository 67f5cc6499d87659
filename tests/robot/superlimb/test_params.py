"""The SuperLimb's parameters (robot.superlimb.params): derived limits, overrides, invalid values, rotations."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pinocchio as pin
import pytest

from robot import superlimb as sl
from robot.model_files import build_pinocchio_model
from robot.superlimb import SuperLimbParams
from tests.robot.superlimb.models import mj as _mj


def test_derived_limits_follow_actuator_and_reduction() -> None:
    p = SuperLimbParams()
    by = {j.name: j for j in p.joints}
    act = by["shoulder"].actuator
    # shoulder: belt 1:3, elbow 1:2, base 1:1 right-angle drive
    assert by["shoulder"].transmission_ratio == 3.0 and by["elbow"].transmission_ratio == 2.0
    assert by["base_yaw"].axis == (0.0, 0.0, 1.0)
    np.testing.assert_allclose(by["shoulder"].torque_limit, 0.95 * 3.0 * act.peak_torque)
    np.testing.assert_allclose(by["elbow"].torque_limit, 0.95 * 2.0 * act.peak_torque)
    np.testing.assert_allclose(by["elbow"].armature, act.rotor_inertia * (act.gear_ratio * 2.0) ** 2)
    np.testing.assert_allclose(by["shoulder"].armature, act.rotor_inertia * (act.gear_ratio * 3.0) ** 2)
    for j in p.joints:
        assert j.velocity_limit <= act.max_output_speed / j.transmission_ratio + 1e-12
        assert j.velocity_limit <= j.speed_cap
    # gravity holding torque at the worst pose stays within the continuous rating
    model, data, _ = build_pinocchio_model(p)
    g_max = max(np.abs(pin.computeGeneralizedGravity(model, data, q)).max()
                for q in np.random.default_rng(0).uniform(p.lower, p.upper, (500, 3)))
    assert g_max < min(j.rated_joint_torque for j in p.joints[1:])


def test_overrides_reach_every_description() -> None:
    p = SuperLimbParams().with_joint("elbow", torque_limit_override=1.5, velocity_limit_override=0.7,
                                      armature_override=0.01, upper=2.0)
    model, _, _ = build_pinocchio_model(p)
    i = model.getJointId("elbow") - 1
    assert model.effortLimit[i] == 1.5 and model.velocityLimit[i] == 0.7
    assert model.upperPositionLimit[i] == 2.0 and model.armature[i] == 0.01
    m, _ = _mj(p)
    assert m.jnt_range[m.joint("elbow").id][1] == 2.0
    assert m.dof_armature[m.joint("elbow").dofadr[0]] == 0.01
    np.testing.assert_array_equal(m.actuator("elbow_motor").ctrlrange, [-1.5, 1.5])


@pytest.mark.parametrize("bad", [
    dict(lower=1.0, upper=0.5),
    dict(torque_limit_override=0.0),
    dict(braking_acceleration=500.0),
])
def test_invalid_parameters_raise(bad: dict) -> None:
    with pytest.raises(ValueError):
        SuperLimbParams().with_joint("shoulder", **bad)
    with pytest.raises(KeyError):
        SuperLimbParams().with_joint("wrist")


def test_rpy_quat_matrix_agree() -> None:
    rng = np.random.default_rng(3)
    for rpy in rng.uniform(-math.pi, math.pi, (20, 3)):
        mat = np.zeros(9)
        mujoco.mju_quat2Mat(mat, sl.rpy_to_quat(rpy))
        np.testing.assert_allclose(mat.reshape(3, 3), sl.rpy_to_matrix(rpy), atol=1e-12)
        np.testing.assert_allclose(sl.rpy_to_matrix(rpy), pin.rpy.rpyToMatrix(rpy), atol=1e-12)
