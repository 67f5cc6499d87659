"""The robot description: any arm from URDF or MJCF, its mount, its MuJoCo bodies, numerical inverse,
reach shell and braking (the SuperLimb itself: tests/robot/superlimb/test_description.py)."""

from __future__ import annotations

import mujoco
import numpy as np
import pinocchio as pin
import pytest

from robot.description import RobotDescription, braking_torque_ratio
from robot.errors import ControllerConfigError, FrameNotFoundError
from robot.superlimb import superlimb_description
from tests.robot.tips import tip as _tip

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
