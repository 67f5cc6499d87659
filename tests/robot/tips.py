"""The world position of an arm's tip frame, for the robot tests."""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from robot.description import RobotDescription


def tip(robot: RobotDescription, q: np.ndarray) -> np.ndarray:
    """The tip frame's position [m] in the world at configuration ``q``."""
    data = robot.model.createData()
    pin.framesForwardKinematics(robot.model, data, q)
    return data.oMf[robot.tip_frame_id].translation.copy()
