"""A second arm for the tests: the Franka Panda of example-robot-data (7 joints, fingers locked), on the table
to the wearer's right of the plate, facing it."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from robot.description import RobotDescription
from sim.scene import SceneConfig

PANDA_FILE = "panda_description/urdf/panda.urdf"
PANDA_TIP = "panda_hand_tcp"
PANDA_FINGERS = ("panda_finger_joint1", "panda_finger_joint2")
MOUNT_PLATE = (0.0, -0.45, 0.0)  # [m] base in the plate frame: beside the plate on the table, to the right
MOUNT_RPY = (0.0, 0.0, math.pi / 2)  # facing the plate (+y)


def panda_path() -> Path:
    erd = pytest.importorskip("example_robot_data")
    return Path(erd.getModelPath(PANDA_FILE)) / PANDA_FILE


def panda(scene: SceneConfig | None = None) -> RobotDescription:
    """The Panda mounted at :data:`MOUNT_PLATE`, speed capped to 1.5 rad/s near the wearer, 8 rad/s² (braking 4)."""
    scene = scene or SceneConfig()
    return RobotDescription.from_file(panda_path(), PANDA_TIP, locked_joints=PANDA_FINGERS,
                                      mount_xyz=scene.mount_in_torso(MOUNT_PLATE), mount_rpy=MOUNT_RPY,
                                      velocity_limit=1.5, acceleration_limit=8.0)
