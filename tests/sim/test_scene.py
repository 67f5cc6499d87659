"""The MuJoCo scene: frames, base pose against MuJoCo's body poses, fork placement, sway."""

import mujoco
import numpy as np
import pytest

from robot.kinematics import ArmGeometry, forward_tip
from robot.superlimb import rpy_to_matrix
from sim.scene import EatingScene, SceneConfig, pose_matrix


def test_physics_rate_integrator_and_dofs():
    s = EatingScene()
    assert s.model.opt.timestep == 0.001
    assert s.model.opt.integrator == mujoco.mjtIntegrator.mjINT_EULER
    assert s.model.nv == 3 and s.model.nu == 3
    np.testing.assert_allclose(s.model.actuator_ctrlrange[:, 1], s.config.params.torque_limit)


@pytest.mark.parametrize("t", [0.0, 1.7, 13.3])
def test_base_pose_matches_mujoco_bodies_and_tip(t):
    s = EatingScene(seed=4)
    q = np.array([0.4, 0.3, 1.1])
    s.set_state(q, np.zeros(3), t)
    d = s.data
    T_world_torso = pose_matrix(d.xmat[s.torso_body].reshape(3, 3), d.xpos[s.torso_body])
    T_world_plate = pose_matrix(d.xmat[s.plate_body].reshape(3, 3), d.xpos[s.plate_body])
    expected = np.linalg.inv(T_world_plate) @ T_world_torso
    np.testing.assert_allclose(s.base_pose(t), expected, atol=1e-12)
    # the knife tip: MuJoCo's site in the plate frame = base_pose applied to the model's forward kinematics
    tip_model = forward_tip(ArmGeometry.from_params(s.config.params), q)
    np.testing.assert_allclose(s.tip_in_plate(), s.torso_to_plate(s.base_pose(t), tip_model[None])[0], atol=1e-12)
    np.testing.assert_allclose(s.plate_to_torso(s.base_pose(t), s.tip_in_plate()[None])[0], tip_model, atol=1e-12)


def test_torso_sways_by_millimetres_to_centimetres():
    c = SceneConfig()
    ts = np.arange(0.0, 40.0, 0.05)
    poses = np.array([c.torso_pose(t, np.zeros(2))[0] for t in ts])
    span = poses.max(axis=0) - poses.min(axis=0)
    assert 0.005 < span.max() < 0.05
    s = EatingScene(seed=1)
    b = np.array([s.base_pose(t)[:3, 3] for t in ts])
    assert np.ptp(b, axis=0).max() > 0.005  # the controller sees the motion


def test_fork_follows_pose_in_plate_frame_and_ignores_missing_values():
    s = EatingScene()
    pose = np.array([0.03, -0.02, 0.05, 0.1, -0.5, 0.2])
    s.set_fork(pose)
    mujoco.mj_forward(s.model, s.data)
    site = mujoco.mj_name2id(s.model, mujoco.mjtObj.mjOBJ_SITE, "fork_tip")
    np.testing.assert_allclose(s.data.site_xpos[site] - s.plate_p, pose[:3], atol=1e-12)
    np.testing.assert_allclose(s.data.xmat[s.fork_body].reshape(3, 3), rpy_to_matrix(pose[3:]), atol=1e-9)
    s.set_fork(np.array([np.nan, 0, 0, 0, 0, 0]))
    mujoco.mj_forward(s.model, s.data)
    np.testing.assert_allclose(s.data.site_xpos[site] - s.plate_p, pose[:3], atol=1e-12)


def test_bad_config_is_refused():
    with pytest.raises(ValueError, match="multiple"):
        SceneConfig(timestep=0.003, control_period=0.01)
