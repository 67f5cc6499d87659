"""The robot description: any arm from URDF or MJCF, its MuJoCo bodies, numerical inverse and reach shell;
the SuperLimb as one description (checked against its own closed form and parameters)."""

from __future__ import annotations

import mujoco
import numpy as np
import pinocchio as pin
import pytest

from robot.default_arm import as_description
from robot.description import RobotDescription, braking_torque_ratio
from robot.errors import ControllerConfigError, FrameNotFoundError
from robot.limits import JointLimits
from robot.superlimb import SuperLimbParams, superlimb_description
from robot.superlimb.model_files import build_pinocchio_model, to_mjcf

erd = pytest.importorskip("example_robot_data")
PANDA = "panda_description/urdf/panda.urdf"
FINGERS = ("panda_finger_joint1", "panda_finger_joint2")


@pytest.fixture(scope="module")
def panda_file():
    from pathlib import Path

    return Path(erd.getModelPath(PANDA)) / PANDA


@pytest.fixture(scope="module")
def panda(panda_file) -> RobotDescription:
    return RobotDescription.from_file(panda_file, "panda_hand_tcp", locked_joints=FINGERS, mount_xyz=(0.4, -0.55, 0.2),
                                      mount_rpy=(0.0, 0.1, 1.57), velocity_limit=1.5, acceleration_limit=8.0)


def _tip(robot: RobotDescription, q: np.ndarray) -> np.ndarray:
    data = robot.model.createData()
    pin.framesForwardKinematics(robot.model, data, q)
    return data.oMf[robot.tip_frame_id].translation.copy()


def test_superlimb_is_one_description() -> None:
    p = SuperLimbParams(mount_xyz=(0.1, -0.2, 0.3))
    d = as_description(p)
    assert d.n == 3 and d.tip_frame == "knife_tip" and d.params is p and d.mount_xyz == p.mount_xyz
    np.testing.assert_array_equal(d.limits.tau_max, JointLimits.from_superlimb(p).tau_max)
    np.testing.assert_array_equal(d.q_home, 0.5 * (p.lower + p.upper))
    ref = build_pinocchio_model(p)
    q = np.array([0.3, 0.4, 1.0])
    np.testing.assert_allclose(_tip(d, q), _tip(as_description(d), q))
    pin.framesForwardKinematics(ref.model, ref.data, q)
    np.testing.assert_allclose(_tip(d, q), ref.data.oMf[ref.frame_id].translation, atol=1e-15)
    with pytest.raises(TypeError, match="RobotDescription"):
        as_description("superlimb")


def test_superlimb_from_its_mjcf_file_has_the_same_dynamics(tmp_path) -> None:
    """MJCF input: the SuperLimb's own MJCF (armature, gravity, limits) read by Pinocchio's parser."""
    ref = superlimb_description()
    path = tmp_path / "superlimb.xml"
    path.write_text(to_mjcf())
    with pytest.raises(ControllerConfigError, match="velocity_limit"):  # MJCF has no speed limits
        RobotDescription.from_file(path, "knife_tip")
    # Pinocchio's MJCF reader puts the root body at the origin (its pos is dropped): the mount places it
    d = RobotDescription.from_file(path, "knife_tip", velocity_limit=ref.limits.v_max, mount_xyz=ref.mount_xyz)
    np.testing.assert_allclose(d.limits.tau_max, ref.limits.tau_max)
    rng = np.random.default_rng(0)
    for _ in range(10):
        q, v, a = rng.uniform(ref.limits.q_min, ref.limits.q_max), rng.normal(size=3), rng.normal(size=3)
        np.testing.assert_allclose(pin.rnea(d.model, d.model.createData(), q, v, a),
                                   pin.rnea(ref.model, ref.model.createData(), q, v, a), atol=1e-12)
        np.testing.assert_allclose(_tip(d, q), _tip(ref, q), atol=1e-12)


def test_clear_errors_name_the_valid_choices(panda_file, tmp_path) -> None:
    with pytest.raises(FrameNotFoundError, match="panda_hand_tcp") as exc:
        RobotDescription.from_file(panda_file, "knife", locked_joints=FINGERS)
    assert "'knife'" in str(exc.value)
    with pytest.raises(FrameNotFoundError, match="fixed to the world"):
        RobotDescription.from_file(panda_file, "panda_link0", locked_joints=FINGERS)
    with pytest.raises(ControllerConfigError, match="panda_joint1"):
        RobotDescription.from_file(panda_file, "panda_hand_tcp", locked_joints=("gripper",))
    with pytest.raises(ControllerConfigError, match=".urdf"):
        RobotDescription.from_file(tmp_path / "arm.stl", "tip")
    with pytest.raises(ControllerConfigError, match="does not exist"):
        RobotDescription.from_file(tmp_path / "arm.urdf", "tip")


def test_mount_places_the_arm(panda_file) -> None:
    a = RobotDescription.from_file(panda_file, "panda_hand_tcp", locked_joints=FINGERS)
    b = RobotDescription.from_file(panda_file, "panda_hand_tcp", locked_joints=FINGERS, mount_xyz=(0.1, 0.2, 0.3),
                                   mount_rpy=(0.0, 0.0, np.pi / 2))
    q = a.q_home
    R = pin.rpy.rpyToMatrix(0.0, 0.0, np.pi / 2)
    np.testing.assert_allclose(_tip(b, q), R @ _tip(a, q) + [0.1, 0.2, 0.3], atol=1e-12)


def test_mjcf_bodies_have_pinocchios_dynamics(panda) -> None:
    """The generated MuJoCo arm: inverse dynamics and tip equal Pinocchio's (7 joints, tilted mount)."""
    xml = (f'<mujoco><compiler angle="radian" inertiafromgeom="false" autolimits="true"/>'
           f'<option gravity="0 0 {-panda.gravity}"/><worldbody>{panda.mjcf_body()}</worldbody>'
           f'<actuator>{panda.mjcf_actuators()}</actuator></mujoco>')
    m = mujoco.MjModel.from_xml_string(xml)
    d = mujoco.MjData(m)
    assert m.nv == 7 and m.nu == 7
    np.testing.assert_allclose(m.actuator_ctrlrange[:, 1], panda.limits.tau_max)
    site = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_SITE, panda.tip_frame)
    rng = np.random.default_rng(1)
    data = panda.model.createData()
    for _ in range(10):
        q, v, a = rng.uniform(panda.limits.q_min, panda.limits.q_max), rng.normal(size=7), rng.normal(size=7)
        d.qpos[:], d.qvel[:], d.qacc[:] = q, v, a
        mujoco.mj_inverse(m, d)
        np.testing.assert_allclose(d.qfrc_inverse, pin.rnea(panda.model, data, q, v, a), atol=1e-9)
        np.testing.assert_allclose(d.site_xpos[site], _tip(panda, q), atol=1e-12)


def test_numerical_inverse_reaches_reachable_tips_and_is_best_effort_otherwise(panda) -> None:
    rng = np.random.default_rng(2)
    for _ in range(5):
        target = _tip(panda, rng.uniform(panda.limits.q_min, panda.limits.q_max))
        q = panda.inverse_kinematics(target)
        assert np.all(q >= panda.limits.q_min) and np.all(q <= panda.limits.q_max)
        assert np.linalg.norm(_tip(panda, q) - target) < 1e-6
    far = _tip(panda, panda.q_home) + np.array([3.0, 0.0, 0.0])
    q = panda.inverse_kinematics(far)
    assert np.all(q >= panda.limits.q_min) and np.all(q <= panda.limits.q_max)
    assert 2.0 < np.linalg.norm(_tip(panda, q) - far) < 3.0  # stretched toward it


def test_superlimb_closed_form_and_numerical_inverse_agree() -> None:
    sl = superlimb_description()
    generic = RobotDescription.from_model(sl.model, sl.tip_frame, acceleration_limit=sl.limits.a_max)
    for q_true in (np.array([0.2, 0.5, 1.2]), np.array([-0.8, 0.1, 0.4])):
        tip = _tip(sl, q_true)
        assert np.linalg.norm(_tip(sl, sl.inverse_kinematics(tip)) - tip) < 1e-10
        assert np.linalg.norm(_tip(generic, generic.inverse_kinematics(tip)) - tip) < 1e-6


def test_sampled_reach_shell_holds_every_tip_and_matches_the_superlimbs_exact_one(panda) -> None:
    shell = panda.reach_shell(margin=0.0)
    rng = np.random.default_rng(3)
    r = np.array([np.linalg.norm(_tip(panda, q) - shell.pivot)
                  for q in rng.uniform(panda.limits.q_min, panda.limits.q_max, (300, 7))])
    assert r.max() <= shell.r_max + 1e-9 and r.min() >= shell.r_min - 1e-9
    sl = superlimb_description()
    exact = sl.reach_shell(margin=0.0)
    generic = RobotDescription.from_model(sl.model, sl.tip_frame).reach_shell(margin=0.0)
    np.testing.assert_allclose(generic.pivot, exact.pivot - [0.0, 0.0, sl.params.joints[1].origin_xyz[2]], atol=1e-12)
    assert generic.r_max > 0.9 * exact.r_max


def test_braking_feasibility_is_measured(panda_file) -> None:
    sl = superlimb_description()
    assert braking_torque_ratio(sl) <= 1.0  # the SuperLimb's braking accelerations are chosen so
    fast = RobotDescription.from_file(panda_file, "panda_hand_tcp", locked_joints=FINGERS, acceleration_limit=60.0)
    assert braking_torque_ratio(fast, 200) > 1.0
