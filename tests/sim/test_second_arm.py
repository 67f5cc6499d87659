"""The eating closed loop end to end on a second arm: the Franka Panda of example-robot-data (7 joints),
placed by the scene beside the plate, driven by the full SharedController."""

from __future__ import annotations

import numpy as np
import pytest

from mpcshare.control.controller import SharedController
from sim.closed_loop import run_episode
from sim.metrics import episode_metrics
from sim.scene import EatingScene, SceneConfig
from tests.mpcshare.control.controller_doubles import demos_and_bundle
from tests.sim.second_arm import MOUNT_PLATE, panda


@pytest.fixture(scope="module")
def scene() -> SceneConfig:
    return SceneConfig(robot=panda())


def test_scene_places_the_second_arm(scene) -> None:
    world = EatingScene(scene)
    assert world.model.nv == 7 and world.model.nu == 7
    np.testing.assert_allclose(world.model.actuator_ctrlrange[:, 1], scene.robot.limits.tau_max)
    world.set_state(scene.robot.q_home, np.zeros(7))
    base = world.model.body(f"{scene.robot.joint_names[0]}_body")
    # the first joint's body sits at the mount (plate frame + plate position), its axis vertical
    np.testing.assert_allclose(world.data.xpos[base.id] - world.plate_p - [0, 0, 0.333], MOUNT_PLATE, atol=0.02)


def test_eating_closed_loop_on_the_second_arm(scene) -> None:
    demos, bundle = demos_and_bundle(0)
    trial = demos.trials[-1]
    controller = SharedController(bundle, robot=scene.robot, strategy="reactive")
    assert controller.qp.n == 7
    episode = run_episode(controller, trial, scene=scene, duration_s=4.0, seed=3)
    m = episode_metrics(episode)
    print(f"second arm (Panda), reactive, 4 s: tracking RMS {m['tracking_rmse_m'] * 1e3:.1f} mm")
    assert episode.q.shape[1] == 7 and episode.info["limit_violations"] == 0
    assert episode.info["servo_fallback_steps"] == 0 and episode.info["brake_infeasible_steps"] == 0
    assert set(episode.status) <= {"ok", "reference_unreachable", "missing_observation"}
    assert m["tracking_rmse_m"] < 0.03
