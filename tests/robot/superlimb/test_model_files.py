"""The SuperLimb's files (robot.superlimb.model_files): assets up to date, Pinocchio ↔ MuJoCo parity, hooks."""

from __future__ import annotations

from dataclasses import replace

import mujoco
import numpy as np
import pinocchio as pin
import pytest

from robot import model_files as mf
from robot import superlimb as sl
from robot.model_files import build_pinocchio_model, to_mjcf, to_urdf
from robot.superlimb import SuperLimbParams
from tests.robot.superlimb.models import full_m as _full_m
from tests.robot.superlimb.models import mj as _mj


def test_assets_are_up_to_date() -> None:
    assert (sl.ASSETS_DIR / "superlimb.urdf").read_text() == to_urdf(), "run python -m robot"
    assert (sl.ASSETS_DIR / "superlimb.xml").read_text() == to_mjcf(), "run python -m robot"


def test_asset_files_load() -> None:
    model = pin.buildModelFromUrdf(str(sl.ASSETS_DIR / "superlimb.urdf"))
    assert model.nq == 3 and model.existFrame("knife_tip")
    m = mujoco.MjModel.from_xml_path(str(sl.ASSETS_DIR / "superlimb.xml"))
    assert m.nq == 3 and m.nu == 3


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
