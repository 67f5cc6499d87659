"""Joint limits (robot.limits): inconsistent limits are refused."""

from __future__ import annotations

import pytest

from robot.limits import JointLimits


def test_limits_validation() -> None:
    from robot.errors import ControllerConfigError

    with pytest.raises(ControllerConfigError):
        JointLimits([0.0], [-1.0], [1.0], [1.0], [1.0], [1.0])
    with pytest.raises(ControllerConfigError):
        JointLimits([0.0], [1.0], [1.0], [1.0], [2.0], [1.0])  # a_brake > a_max
    with pytest.raises(ControllerConfigError):
        JointLimits([0.0, 0.0], [1.0], [1.0], [1.0], [1.0], [1.0])
