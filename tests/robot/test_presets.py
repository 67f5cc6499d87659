"""Arm presets of example-robot-data: each builds a description; an unknown name lists them."""

from __future__ import annotations

import numpy as np
import pytest

from robot.errors import ControllerConfigError
from robot.presets import ARM_PRESETS, arm_preset, is_preset_name

pytest.importorskip("example_robot_data")

JOINTS = {"panda": 7, "xarm7": 7, "ur5": 6, "ur10": 6, "kinova": 6}


def test_the_presets_are_the_common_arms() -> None:
    assert set(ARM_PRESETS) == set(JOINTS)
    assert is_preset_name("panda") and not is_preset_name("panda.urdf") and not is_preset_name("robots/panda")


@pytest.mark.parametrize("name", sorted(JOINTS))
def test_each_preset_builds_its_arm(name: str) -> None:
    robot = arm_preset(name).description()
    assert robot.name == name and robot.n == JOINTS[name] and robot.model.nq == robot.model.nv
    assert robot.source.endswith(".urdf") and robot.tip_frame == ARM_PRESETS[name].tip_frame
    lim = robot.limits
    assert np.all(lim.q_min < lim.q_max) and np.all(lim.v_max > 0) and np.all(lim.tau_max > 0)


def test_continuous_joints_become_bounded_revolute_ones() -> None:
    kinova = arm_preset("kinova")
    robot = kinova.description()
    np.testing.assert_allclose(robot.limits.q_max[[0, 3, 5]], 2 * np.pi, rtol=1e-9)  # the file's ±2π
    from robot.description import RobotDescription
    from robot.errors import UnsupportedModelError

    with pytest.raises(UnsupportedModelError, match="continuous"):
        RobotDescription.from_file(kinova.path(), kinova.tip_frame)


def test_an_unknown_preset_lists_the_presets() -> None:
    with pytest.raises(ControllerConfigError) as err:
        arm_preset("iiwa")
    assert "'iiwa'" in str(err.value) and all(name in str(err.value) for name in ARM_PRESETS)
