"""Every arm preset in the eating task: caps chosen feasible, the workspace reached, a short closed loop
without a limit violation; forced caps kept or refused; a bad name or a file without a mount refused."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from mpcshare.arms import task_arm
from mpcshare.control.controller import SharedController
from mpcshare.control.workspace import DEFAULT_WORKSPACE
from robot.braking import HEADROOM, braking_torque_ratio, tip_box_states
from robot.errors import ControllerConfigError
from robot.presets import ARM_PRESETS
from sim.closed_loop import run_episode
from sim.metrics import episode_metrics
from tests.mpcshare.control.controller_doubles import demos_and_bundle

pytest.importorskip("example_robot_data")
TARGETS = np.array([[0.0, 0.0, 0.02], [0.1, 0.0, 0.0], [-0.08, 0.08, 0.05], [0.05, -0.1, 0.15]])  # plate frame [m]


@pytest.fixture(scope="module")
def demos_bundle():
    return demos_and_bundle(0)


@pytest.mark.parametrize("name", sorted(ARM_PRESETS))
def test_each_preset_runs_the_task_with_feasible_caps_and_no_violation(name: str, demos_bundle) -> None:
    arm = task_arm(name)
    robot, scene = arm.scene.robot, arm.scene
    plate = np.asarray(scene.plate_position)
    # the caps: braking feasible on the workspace's states (fresh ones, another seed) with the margin kept
    states = tip_box_states(robot.model, robot.tip_frame_id, robot.limits.q_min, robot.limits.q_max,
                            plate + DEFAULT_WORKSPACE.lower, plate + DEFAULT_WORKSPACE.upper, n=100, seed=7)
    assert arm.chosen and arm.ratio <= HEADROOM and braking_torque_ratio(robot, states=states) <= 1.0
    assert name in robot.name and "rad/s" in arm.summary
    data = robot.model.createData()
    for target in TARGETS + plate:  # on and above the plate: reached
        q = robot.inverse_kinematics(target)
        pin.framesForwardKinematics(robot.model, data, q)
        assert np.linalg.norm(data.oMf[robot.tip_frame_id].translation - target) < 2e-3, (name, target)
    demos, bundle = demos_bundle
    controller = SharedController(bundle, robot=robot, strategy="reactive")
    episode = run_episode(controller, demos.trials[-1], scene=scene, duration_s=1.0, seed=1, record=True)
    assert episode.info["limit_violations"] == 0 and episode.info["brake_infeasible_steps"] == 0
    assert episode.q.shape[1] == robot.n and np.isfinite(episode_metrics(episode)["tracking_rmse_m"])


def test_forced_caps_are_kept_or_refused() -> None:
    slow = task_arm("panda", velocity_limit=1.0)
    assert np.all(slow.scene.robot.limits.v_max <= 1.0 + 1e-12) and "acceleration chosen" in slow.summary
    both = task_arm("panda", velocity_limit=1.0, acceleration_limit=4.0)
    assert not both.chosen and "as given" in both.summary
    np.testing.assert_allclose(both.scene.robot.limits.a_max, 4.0)
    with pytest.raises(ControllerConfigError, match="braking at 40 rad/s²"):
        task_arm("panda", velocity_limit=2.0, acceleration_limit=80.0)


def test_a_bad_name_or_a_file_without_mount_is_refused() -> None:
    with pytest.raises(ControllerConfigError, match="presets: panda"):
        task_arm("iiwa")
    path = str(ARM_PRESETS["panda"].path())
    with pytest.raises(ControllerConfigError, match="--mount"):
        task_arm(path, tip_frame="panda_hand_tcp")
