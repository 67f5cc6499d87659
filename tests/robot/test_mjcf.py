"""Any description's MuJoCo bodies (robot.mjcf), on the SuperLimb: inverse dynamics, tip and torque
ranges equal Pinocchio's and the limits."""

from __future__ import annotations

import mujoco
import numpy as np
import pinocchio as pin

from robot.superlimb import superlimb_description


def test_the_superlimbs_mjcf_bodies_have_pinocchios_dynamics():
    arm = superlimb_description()
    xml = (f'<mujoco><compiler angle="radian" inertiafromgeom="false" autolimits="true"/>'
           f'<option gravity="0 0 {-arm.gravity}"/><worldbody>{arm.mjcf_body()}</worldbody>'
           f'<actuator>{arm.mjcf_actuators()}</actuator></mujoco>')
    m = mujoco.MjModel.from_xml_string(xml)
    d = mujoco.MjData(m)
    n = arm.model.nv
    assert m.nv == n and m.nu == n
    np.testing.assert_allclose(m.actuator_ctrlrange[:, 1], arm.limits.tau_max)
    np.testing.assert_allclose(m.jnt_range, np.column_stack([arm.limits.q_min, arm.limits.q_max]))
    site = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_SITE, arm.tip_frame)
    data = arm.model.createData()
    rng = np.random.default_rng(5)
    for _ in range(10):
        q, v, a = rng.uniform(arm.limits.q_min, arm.limits.q_max), rng.normal(size=n), rng.normal(size=n)
        d.qpos[:], d.qvel[:], d.qacc[:] = q, v, a
        mujoco.mj_inverse(m, d)
        np.testing.assert_allclose(d.qfrc_inverse, pin.rnea(arm.model, data, q, v, a), atol=1e-9)
        pin.framesForwardKinematics(arm.model, data, q)
        np.testing.assert_allclose(d.site_xpos[site], data.oMf[arm.tip_frame_id].translation, atol=1e-12)
