"""SuperLimb description: assets, derived limits, Pinocchio ↔ MuJoCo parity."""

from __future__ import annotations

import itertools
import math
from dataclasses import replace

import mujoco
import numpy as np
import pinocchio as pin
import pytest

from robot import model_files as mf
from robot import superlimb as sl
from robot.model_files import build_pinocchio_model, to_mjcf, to_urdf
from robot.superlimb import SuperLimbParams


def _mj(params: SuperLimbParams, extra: str = "") -> tuple[mujoco.MjModel, mujoco.MjData]:
    m = mujoco.MjModel.from_xml_string(to_mjcf(params, extra_worldbody_xml=extra))
    return m, mujoco.MjData(m)


def _full_m(model, data, q) -> np.ndarray:
    m = pin.crba(model, data, q)
    return np.triu(m) + np.triu(m, 1).T


def test_assets_are_up_to_date() -> None:
    assert (sl.ASSETS_DIR / "superlimb.urdf").read_text() == to_urdf(), "run python -m robot"
    assert (sl.ASSETS_DIR / "superlimb.xml").read_text() == to_mjcf(), "run python -m robot"


def test_asset_files_load() -> None:
    model = pin.buildModelFromUrdf(str(sl.ASSETS_DIR / "superlimb.urdf"))
    assert model.nq == 3 and model.existFrame("knife_tip")
    m = mujoco.MjModel.from_xml_path(str(sl.ASSETS_DIR / "superlimb.xml"))
    assert m.nq == 3 and m.nu == 3


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


PARAM_VARIANTS = {
    "default": SuperLimbParams(),
    # a tilted mount and an off-axis inertia exercise the frame conventions
    "tilted": replace(
        SuperLimbParams(mount_xyz=(0.05, -0.3, 0.5), mount_rpy=(0.3, -0.2, 0.8), knife_pitch=1.0),
        links=tuple(replace(link, inertial=replace(
                        link.inertial, inertia=link.inertial.inertia[:3]
                        + tuple(f * min(link.inertial.inertia[:3]) for f in (0.2, -0.3, 0.1))))
                    for link in SuperLimbParams().links),
    ).with_joint("elbow", origin_rpy=(0.1, 0.0, -0.2)),
}


@pytest.mark.parametrize("name", list(PARAM_VARIANTS))
def test_pinocchio_mujoco_parity(name: str) -> None:
    p = PARAM_VARIANTS[name]
    model, data, fid = build_pinocchio_model(p)
    m, d = _mj(p)
    sid = m.site(sl.TOOL_FRAME).id
    mj_mass = np.zeros((m.nv, m.nv))
    rng = np.random.default_rng(42)
    np.testing.assert_allclose(m.dof_armature, model.armature, atol=1e-15)
    assert np.all(m.dof_damping == 0) and np.all(m.dof_frictionloss == 0)
    for _ in range(25):
        q = rng.uniform(p.lower, p.upper)
        v = rng.uniform(-p.velocity_limit, p.velocity_limit)
        d.qpos[:], d.qvel[:] = q, 0.0
        mujoco.mj_forward(m, d)
        pin.framesForwardKinematics(model, data, q)
        np.testing.assert_allclose(d.site_xpos[sid], data.oMf[fid].translation, atol=1e-6)
        np.testing.assert_allclose(d.site_xmat[sid].reshape(3, 3), data.oMf[fid].rotation, atol=1e-6)
        mujoco.mj_fullM(m, d, mj_mass)
        np.testing.assert_allclose(mj_mass, _full_m(model, data, q), atol=1e-6)
        np.testing.assert_allclose(d.qfrc_bias, pin.computeGeneralizedGravity(model, data, q), atol=1e-6)
        d.qvel[:] = v
        mujoco.mj_forward(m, d)
        np.testing.assert_allclose(d.qfrc_bias, pin.nonLinearEffects(model, data, q, v), atol=1e-6)


def test_mass_matrix_contains_armature() -> None:
    """Removing the armature changes M by exactly diag(armature) in both engines."""
    p = SuperLimbParams()
    model, data, _ = build_pinocchio_model(p)
    q = np.array([0.3, 0.4, 0.9])
    with_arm = _full_m(model, data, q)
    model.armature = np.zeros(3)
    np.testing.assert_allclose(with_arm - _full_m(model, data, q), np.diag(p.armature), atol=1e-12)


def test_extra_worldbody_hook() -> None:
    plate = '    <body name="plate" pos="0.4 0 0.3"><geom type="cylinder" size="0.1 0.01"/></body>\n'
    m, _ = _mj(SuperLimbParams(), extra=plate)
    assert m.body("plate").id > 0 and m.nq == 3
    assert "<body" in mf.mjcf_arm_body() and "knife_tip" in mf.mjcf_arm_body()


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
