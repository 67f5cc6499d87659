"""The SuperLimb as one robot description (robot.superlimb.description): parameters, MJCF file, closed form."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from robot.default_arm import as_description
from robot.description import RobotDescription
from robot.errors import ControllerConfigError
from robot.limits import JointLimits
from robot.superlimb import SuperLimbParams, superlimb_description
from robot.superlimb.model_files import build_pinocchio_model, to_mjcf
from tests.robot.tips import tip as _tip


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


def test_superlimb_closed_form_and_numerical_inverse_agree() -> None:
    sl = superlimb_description()
    generic = RobotDescription.from_model(sl.model, sl.tip_frame, acceleration_limit=sl.limits.a_max)
    for q_true in (np.array([0.2, 0.5, 1.2]), np.array([-0.8, 0.1, 0.4])):
        tip = _tip(sl, q_true)
        assert np.linalg.norm(_tip(sl, sl.inverse_kinematics(tip)) - tip) < 1e-10
        assert np.linalg.norm(_tip(generic, generic.inverse_kinematics(tip)) - tip) < 1e-6
