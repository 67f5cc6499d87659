"""The CasADi arm model (generated from the Pinocchio model) against Pinocchio's own algorithms to 1e-9:
the SuperLimb's variants and a second arm (Franka Panda, 7 joints, from example-robot-data)."""

from __future__ import annotations

from dataclasses import replace

import casadi as ca
import numpy as np
import pinocchio as pin
import pytest

from robot.description import RobotDescription
from robot.mpc.symbolic import SymbolicArm
from robot.superlimb import Actuator, SuperLimbParams, rod_inertial
from robot.superlimb.model_files import build_pinocchio_model

TOL = 1e-9


def _off_axis(params: SuperLimbParams) -> SuperLimbParams:
    """Products of inertia and a lateral centre of mass on every link."""
    links = []
    for link in params.links:
        i = link.inertial
        base = min(i.inertia[:3])
        links.append(replace(link, inertial=replace(
            i, com=(i.com[0], i.com[1] + 0.01, i.com[2] - 0.005),
            inertia=i.inertia[:3] + (0.2 * base, -0.3 * base, 0.1 * base))))
    return replace(params, links=tuple(links))


def _longer_links() -> SuperLimbParams:
    p = SuperLimbParams(forearm_length=0.30, knife_length=0.10, knife_pitch=0.3)
    links = list(p.links)
    links[2] = replace(links[2], inertial=rod_inertial(0.3, 0.35, 0.02, point_mass=0.5, point_x=0.08))
    return replace(p, links=tuple(links)).with_joint("elbow", origin_xyz=(0.35, 0.0, 0.0))


VARIANTS = {
    "default": SuperLimbParams(),
    "tilted_mount_off_axis": _off_axis(
        SuperLimbParams(mount_xyz=(0.05, -0.3, 0.5), mount_rpy=(0.3, -0.2, 0.8), knife_pitch=1.0)
    ).with_joint("elbow", origin_rpy=(0.1, 0.0, -0.2)).with_joint("shoulder", origin_xyz=(0.01, 0.02, 0.07)),
    "longer_links": _longer_links(),
    "skew_axis_heavy_rotor": SuperLimbParams(gravity=3.7)
    .with_joint("base_yaw", axis=(0.0, 0.6, 0.8), actuator=Actuator(rotor_inertia=9e-6))
    .with_joint("elbow", armature_override=0.2),
}


def _pin_reference(model, data, fid: int, q: np.ndarray, v: np.ndarray):
    pin.computeJointJacobians(model, data, q)
    pin.framesForwardKinematics(model, data, q)
    J = pin.getFrameJacobian(model, data, fid, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)[:3]
    M = pin.crba(model, data, q)
    M = np.triu(M) + np.triu(M, 1).T
    return data.oMf[fid].translation.copy(), J, M, pin.nonLinearEffects(model, data, q, v).copy()


@pytest.mark.parametrize("name", list(VARIANTS))
def test_matches_pinocchio_at_random_states(name: str) -> None:
    params = VARIANTS[name]
    arm = SymbolicArm(params)
    model, data, fid = build_pinocchio_model(params)
    rng = np.random.default_rng(sum(map(ord, name)))
    for _ in range(30):
        # beyond the joint limits and speed caps too: the model is exact everywhere
        q = rng.uniform(params.lower - 0.5, params.upper + 0.5)
        v = rng.uniform(-2.0, 2.0, 3) * params.velocity_limit
        a = rng.uniform(-1.0, 1.0, 3) * params.acceleration_limit
        p_ref, J_ref, M_ref, h_ref = _pin_reference(model, data, fid, q, v)
        np.testing.assert_allclose(np.asarray(arm.tip_position(q)).ravel(), p_ref, rtol=0, atol=TOL)
        np.testing.assert_allclose(np.asarray(arm.tip_jacobian(q)), J_ref, rtol=0, atol=TOL)
        np.testing.assert_allclose(np.asarray(arm.mass_matrix(q)), M_ref, rtol=0, atol=TOL)
        np.testing.assert_allclose(np.asarray(arm.nonlinear_effects(q, v)).ravel(), h_ref, rtol=0, atol=TOL)
        tau = pin.rnea(model, data, q, v, a)  # Pinocchio 3 adds armature·a itself
        np.testing.assert_allclose(np.asarray(arm.inverse_dynamics(q, v, a)).ravel(), tau, rtol=0, atol=TOL)


def test_parameters_reach_the_model() -> None:
    """A changed parameter changes the symbolic model (the comparison above is not vacuous)."""
    q, v = np.array([0.2, 0.4, 0.8]), np.array([0.5, -1.0, 1.5])
    base = SymbolicArm()
    for changed in (SuperLimbParams(knife_length=0.2), SuperLimbParams(gravity=1.0),
                    SuperLimbParams().with_joint("shoulder", armature_override=0.5)):
        other = SymbolicArm(changed)
        diff = (np.abs(np.asarray(other.tip_position(q)) - np.asarray(base.tip_position(q))).max()
                + np.abs(np.asarray(other.mass_matrix(q)) - np.asarray(base.mass_matrix(q))).max()
                + np.abs(np.asarray(other.nonlinear_effects(q, v)) - np.asarray(base.nonlinear_effects(q, v))).max())
        assert diff > 1e-3


def test_functions_accept_symbols() -> None:
    """The functions compose into larger CasADi graphs (as the MPC uses them)."""
    arm = SymbolicArm()
    q = ca.MX.sym("q", 3)
    f = ca.Function("f", [q], [ca.sumsqr(arm.tip_position(q))])
    q0 = np.array([0.1, 0.2, 0.3])
    assert float(f(q0)) == pytest.approx(float(np.sum(np.asarray(arm.tip_position(q0)) ** 2)), abs=1e-12)


def test_zero_axis_is_rejected() -> None:
    with pytest.raises(ValueError, match="axis"):
        SymbolicArm(SuperLimbParams().with_joint("elbow", axis=(0.0, 0.0, 0.0)))


def _panda() -> RobotDescription:
    erd = pytest.importorskip("example_robot_data")
    model = erd.load("panda").model
    return RobotDescription.from_model(model, "panda_hand_tcp", mount_xyz=(0.1, -0.3, 0.2), mount_rpy=(0.2, 0.0, 0.5),
                                       velocity_limit=1.5)


def test_second_arm_matches_pinocchio_rnea_crba_and_aba() -> None:
    """Panda with its two prismatic fingers (a branching tree, prismatic joints, a tilted mount)."""
    robot = _panda()
    model, data, fid = robot.model, robot.model.createData(), robot.tip_frame_id
    model.armature = np.linspace(0.01, 0.1, model.nv)  # the armature term is used too
    arm = SymbolicArm(robot)
    assert arm.n == 9
    rng = np.random.default_rng(5)
    for _ in range(20):
        q = rng.uniform(robot.limits.q_min, robot.limits.q_max)
        v, a, tau = rng.normal(size=9), rng.normal(size=9) * 3.0, rng.normal(size=9) * 5.0
        p_ref, J_ref, M_ref, h_ref = _pin_reference(model, data, fid, q, v)
        np.testing.assert_allclose(np.asarray(arm.tip_position(q)).ravel(), p_ref, rtol=0, atol=TOL)
        np.testing.assert_allclose(np.asarray(arm.tip_jacobian(q)), J_ref, rtol=0, atol=TOL)
        np.testing.assert_allclose(np.asarray(arm.mass_matrix(q)), M_ref, rtol=0, atol=TOL)
        np.testing.assert_allclose(np.asarray(arm.nonlinear_effects(q, v)).ravel(), h_ref, rtol=0, atol=TOL)
        np.testing.assert_allclose(np.asarray(arm.inverse_dynamics(q, v, a)).ravel(), pin.rnea(model, data, q, v, a),
                                   rtol=0, atol=TOL)
        np.testing.assert_allclose(np.asarray(arm.forward_dynamics(q, v, tau)).ravel(),
                                   pin.aba(model, data, q, v, tau), rtol=0, atol=1e-7)


def test_superlimb_forward_dynamics_matches_aba() -> None:
    params = VARIANTS["skew_axis_heavy_rotor"]
    arm = SymbolicArm(params)
    model, data, _ = build_pinocchio_model(params)
    rng = np.random.default_rng(1)
    for _ in range(10):
        q, v, tau = rng.uniform(params.lower, params.upper), rng.normal(size=3), rng.normal(size=3)
        np.testing.assert_allclose(np.asarray(arm.forward_dynamics(q, v, tau)).ravel(),
                                   pin.aba(model, data, q, v, tau), rtol=0, atol=1e-9)
