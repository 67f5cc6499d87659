"""Named arms of the ``example-robot-data`` package: the file, the tool frame, the joints to lock.

A preset is what a user would otherwise type for a common arm (``--robot FILE --tip-frame NAME
--lock-joints ...``): the URDF inside the installed package, the frame at the tool's end that
holds a tool, the gripper joints held fixed, and whether continuous joints are bounded to
revolute ones (:meth:`robot.description.RobotDescription.from_file`). Where an arm stands is
the task's choice, not the arm's (the eating scene's mounts: :mod:`sim.arm_mounts`).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

from robot.errors import ControllerConfigError

__all__ = ["ARM_PRESETS", "ArmPreset", "arm_preset", "is_preset_name"]


@dataclass(frozen=True)
class ArmPreset:
    """One arm: ``file`` relative to example-robot-data's robots folder, ``tip_frame``,
    ``locked_joints`` (held at 0, or their lower limit), ``continuous_as_revolute``, ``about``."""

    name: str
    file: str
    tip_frame: str
    locked_joints: tuple[str, ...] = ()
    continuous_as_revolute: bool = False
    about: str = ""

    def path(self) -> Path:
        """The URDF in the installed example-robot-data; ControllerConfigError when it is missing."""
        try:
            import example_robot_data
        except ImportError:
            raise ControllerConfigError(f"arm preset {self.name!r} needs the package example-robot-data "
                                        "(pip install example-robot-data)") from None
        path = Path(example_robot_data.getModelPath(self.file)) / self.file
        if not path.is_file():
            raise ControllerConfigError(f"arm preset {self.name!r}: {self.file} is not in the installed "
                                        f"example-robot-data ({path})")
        return path

    def description(self, *, tip_frame: str | None = None, **options: Any):
        """The arm as a :class:`robot.description.RobotDescription` (``options`` as ``from_file``)."""
        from robot.description import RobotDescription

        options.setdefault("name", self.name)
        return RobotDescription.from_file(self.path(), tip_frame or self.tip_frame, locked_joints=self.locked_joints,
                                          continuous_as_revolute=self.continuous_as_revolute, **options)


ARM_PRESETS: dict[str, ArmPreset] = {p.name: p for p in (
    ArmPreset("panda", "panda_description/urdf/panda.urdf", "panda_hand_tcp",
              ("panda_finger_joint1", "panda_finger_joint2"), about="Franka Emika Panda, 7 joints"),
    ArmPreset("xarm7", "xarm_description/urdf/xarm7.urdf", "link_eef", about="UFactory xArm 7, 7 joints"),
    ArmPreset("ur5", "ur_description/urdf/ur5_robot.urdf", "tool0", about="Universal Robots UR5, 6 joints"),
    ArmPreset("ur10", "ur_description/urdf/ur10_robot.urdf", "tool0", about="Universal Robots UR10, 6 joints"),
    ArmPreset("kinova", "kinova_description/robots/kinova.urdf", "j2s6s200_end_effector",
              continuous_as_revolute=True, about="Kinova Jaco 2 (j2s6s200), 6 joints"),

)}


def is_preset_name(robot: str) -> bool:
    """Whether ``robot`` names a preset (a path with a folder or a file suffix never does)."""
    return robot in ARM_PRESETS


def arm_preset(name: str) -> ArmPreset:
    """The preset ``name``; ControllerConfigError listing the presets when there is none."""
    try:
        return ARM_PRESETS[name]
    except KeyError:
        raise ControllerConfigError(f"no arm preset {name!r}; presets: {', '.join(ARM_PRESETS)} "
                                    "(or a URDF/MJCF file)") from None
