"""The arm when none is named: None and SuperLimb parameters give the SuperLimb, a description passes through."""

from __future__ import annotations

import pytest

from robot.default_arm import as_description
from robot.superlimb import SuperLimbParams


def test_none_and_parameters_give_the_superlimb_and_a_description_passes_through() -> None:
    default = as_description()
    assert default.tip_frame == "knife_tip" and default.n == 3
    p = SuperLimbParams(mount_xyz=(0.1, -0.2, 0.3))
    mounted = as_description(p)
    assert mounted.params is p and mounted.mount_xyz == p.mount_xyz
    assert as_description(mounted) is mounted


@pytest.mark.parametrize("bad", ["superlimb", 3, object()])
def test_anything_else_is_a_type_error_naming_the_choices(bad) -> None:
    with pytest.raises(TypeError, match="RobotDescription, a robot.superlimb.SuperLimbParams or None"):
        as_description(bad)
