"""The arm when none is named: :func:`as_description` turns None or a ``SuperLimbParams`` into the SuperLimb's
description and passes any :class:`~robot.description.RobotDescription` through."""

from __future__ import annotations

from typing import Any

from robot.description import RobotDescription
from robot.superlimb import SuperLimbParams, superlimb_description

__all__ = ["as_description"]


def as_description(robot: Any = None) -> RobotDescription:
    """``robot`` as a description: None → the SuperLimb, a ``SuperLimbParams`` → that SuperLimb,
    a :class:`RobotDescription` → itself; anything else raises a TypeError naming the choices."""
    if isinstance(robot, RobotDescription):
        return robot
    if robot is None or isinstance(robot, SuperLimbParams):
        return superlimb_description(robot)
    raise TypeError(f"robot must be a robot.description.RobotDescription, a robot.superlimb.SuperLimbParams or "
                    f"None (the SuperLimb), got {type(robot).__name__}")
