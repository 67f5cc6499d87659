"""Where each preset arm (:mod:`robot.presets`) stands in the eating scene: its base in the plate frame.

Every preset stands on the table to the wearer's right of the plate, its base's z axis up and
its x axis turned toward the plate (yaw π/2 about z), worn on the torso as the SuperLimb is
(:class:`sim.scene.SceneConfig`). Each distance is chosen so that every tip of the controller's
workspace box (``mpcshare.control.workspace``: the plate with a margin, 3 cm below to 25 cm above
it) is reachable (checked on sampled tips by tests/mpcshare/test_arms.py): at 0.45 m for the arms of about
0.85 m reach, 0.60 m for the UR10 (1.3 m).
"""

from __future__ import annotations

import math

__all__ = ["ARM_MOUNTS", "arm_mount"]

Vec3 = tuple[float, float, float]
_FACING_PLATE: Vec3 = (0.0, 0.0, math.pi / 2)

#: preset name → (position [m], roll pitch yaw [rad]) of the arm's base in the plate frame
ARM_MOUNTS: dict[str, tuple[Vec3, Vec3]] = {
    "panda": ((0.0, -0.45, 0.0), _FACING_PLATE),
    "xarm7": ((0.0, -0.45, 0.0), _FACING_PLATE),
    "ur5": ((0.0, -0.45, 0.0), _FACING_PLATE),
    "ur10": ((0.0, -0.60, 0.0), _FACING_PLATE),
    "kinova": ((0.0, -0.45, 0.0), _FACING_PLATE),
}


def arm_mount(name: str) -> tuple[Vec3, Vec3]:
    """(position, rpy) of the preset ``name`` in the plate frame; KeyError naming the ones known."""
    try:
        return ARM_MOUNTS[name]
    except KeyError:
        raise KeyError(f"no mount for the arm {name!r} in the eating scene; known: {', '.join(ARM_MOUNTS)}") from None
