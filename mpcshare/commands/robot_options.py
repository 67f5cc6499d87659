"""``--robot PRESET|FILE``: simulate another arm than the SuperLimb.

A preset (:mod:`robot.presets`: ``panda``, ``xarm7``, ``ur5``, ``ur10``, ``kinova``, from the
example-robot-data package) brings its file, tip frame, locked fingers and its place beside the
plate (:mod:`sim.arm_mounts`); ``--tip-frame``, ``--mount``, ``--mount-rpy`` and
``--lock-joints`` override them. A URDF or MJCF file needs ``--tip-frame`` and ``--mount``: the
position [m] of the file's root in the plate frame (origin at the plate's centre on its top
surface, x away from the wearer, z up) with the wearer at rest, ``--mount-rpy`` its orientation
[rad]. The arm is worn on the torso as the SuperLimb is (it sways with it). The speed and
acceleration caps are chosen so that braking is torque-feasible over the task's workspace
(:func:`mpcshare.arms.task_arm`) and printed in one line; ``--velocity-limit`` and
``--acceleration-limit`` force them.

Nothing here imports MuJoCo when the command line loads: the arm is built when the command runs.
"""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING

from mpcshare.commands.base import CommandError, positive_float

if TYPE_CHECKING:
    from sim.scene import SceneConfig

__all__ = ["add_robot_arguments", "scene_from_args"]


def add_robot_arguments(p: argparse.ArgumentParser) -> None:
    """The arm's options (module docstring)."""
    from robot.presets import ARM_PRESETS

    g = p.add_argument_group("arm (default: the SuperLimb)")
    g.add_argument("--robot", default=None, metavar="PRESET|FILE",
                   help=f"an arm preset ({', '.join(ARM_PRESETS)}) or the arm's URDF (.urdf) or MJCF (.xml, .mjcf) "
                        "file")
    g.add_argument("--tip-frame", default=None, metavar="NAME",
                   help="the frame of the arm that holds the knife tip (required with a file)")
    g.add_argument("--mount", nargs=3, type=float, default=None, metavar=("X", "Y", "Z"),
                   help="position of the arm's base in the plate frame [m] (required with a file)")
    g.add_argument("--mount-rpy", nargs=3, type=float, default=None, metavar=("R", "P", "Y"),
                   help="orientation of the arm's base, roll pitch yaw [rad] (default: the preset's, or 0 0 0)")
    g.add_argument("--lock-joints", nargs="+", default=None, metavar="JOINT",
                   help="joints held fixed (e.g. a gripper's fingers; default: the preset's)")
    g.add_argument("--velocity-limit", type=positive_float, default=None,
                   help="cap on every joint speed [rad/s] (default: chosen, see above)")
    g.add_argument("--acceleration-limit", type=positive_float, default=None,
                   help="joint acceleration limit [rad/s²], braking at half of it (default: chosen)")


def scene_from_args(args: argparse.Namespace) -> SceneConfig | None:
    """The scene with the arm of ``--robot`` (None without it: the default scene and the SuperLimb);
    prints the caps in one line."""
    robot = getattr(args, "robot", None)
    if robot is None:
        given = [f"--{n.replace('_', '-')}" for n in ("tip_frame", "mount", "mount_rpy", "lock_joints",
                                                      "velocity_limit", "acceleration_limit")
                 if getattr(args, n, None) is not None]
        if given:
            raise CommandError(f"{', '.join(given)} need --robot PRESET|FILE (the SuperLimb has its own)")
        return None
    from mpcshare.arms import task_arm
    from robot.errors import ControllerConfigError

    try:
        arm = task_arm(robot, tip_frame=args.tip_frame, mount=args.mount, mount_rpy=args.mount_rpy,
                       lock_joints=args.lock_joints, velocity_limit=args.velocity_limit,
                       acceleration_limit=args.acceleration_limit)
    except (ControllerConfigError, ValueError, RuntimeError) as exc:
        raise CommandError(f"--robot {robot}: {exc}") from None
    print(f"arm caps: {arm.summary}")
    return arm.scene
