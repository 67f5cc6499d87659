"""``--robot FILE --tip-frame NAME --mount X Y Z``: simulate another arm than the SuperLimb.

The arm is a URDF or MJCF file (:meth:`robot.description.RobotDescription.from_file`); its
tip frame holds the knife; the mount is the position [m] of the file's root in the plate
frame (origin at the plate's centre on its top surface, x away from the wearer, z up) with
the wearer at rest, and ``--mount-rpy`` its orientation [rad]. The arm is worn on the
torso as the SuperLimb is (it sways with it). Files give position, velocity and torque
limits; acceleration limits are given here (``--acceleration-limit``, braking at half of
it); braking must be torque-feasible everywhere, which is checked on sampled states.
"""

from __future__ import annotations

import argparse

from mpcshare.commands.base import CommandError, positive_float
from robot.description import RobotDescription, braking_torque_ratio
from robot.errors import ControllerConfigError
from sim.scene import SceneConfig

__all__ = ["add_robot_arguments", "scene_from_args"]


def add_robot_arguments(p: argparse.ArgumentParser) -> None:
    """The arm's options (module docstring)."""
    g = p.add_argument_group("arm (default: the SuperLimb)")
    g.add_argument("--robot", default=None, metavar="FILE", help="the arm's URDF (.urdf) or MJCF (.xml, .mjcf) file")
    g.add_argument("--tip-frame", default=None, metavar="NAME", help="the frame of the arm that holds the knife tip")
    g.add_argument("--mount", nargs=3, type=float, default=None, metavar=("X", "Y", "Z"),
                   help="position of the arm's base in the plate frame [m] (required with --robot)")
    g.add_argument("--mount-rpy", nargs=3, type=float, default=(0.0, 0.0, 0.0), metavar=("R", "P", "Y"),
                   help="orientation of the arm's base, roll pitch yaw [rad] (default 0 0 0)")
    g.add_argument("--lock-joints", nargs="+", default=(), metavar="JOINT",
                   help="joints held fixed (e.g. a gripper's fingers)")
    g.add_argument("--velocity-limit", type=positive_float, default=None,
                   help="cap on every joint speed [rad/s] (default: the file's limits)")
    g.add_argument("--acceleration-limit", type=positive_float, default=10.0,
                   help="joint acceleration limit [rad/s²], braking at half of it (default 10)")


def scene_from_args(args: argparse.Namespace) -> SceneConfig | None:
    """The scene with the arm of ``--robot`` (None without it: the default scene and the SuperLimb)."""
    path = getattr(args, "robot", None)
    if path is None:
        given = [f"--{n.replace('_', '-')}" for n in ("tip_frame", "mount") if getattr(args, n, None) is not None]
        if given:
            raise CommandError(f"{', '.join(given)} need --robot FILE (the SuperLimb has its own)")
        return None
    if args.mount is None:
        raise CommandError("--robot needs --mount X Y Z: the arm's base in the plate frame [m]")
    scene = SceneConfig()
    try:
        robot = RobotDescription.from_file(path, args.tip_frame or "", locked_joints=tuple(args.lock_joints),
                                           mount_xyz=scene.mount_in_torso(tuple(args.mount)),
                                           mount_rpy=tuple(args.mount_rpy), velocity_limit=args.velocity_limit,
                                           acceleration_limit=args.acceleration_limit)
    except (ControllerConfigError, ValueError, RuntimeError) as exc:
        raise CommandError(f"--robot {path}: {exc}") from None
    ratio = braking_torque_ratio(robot)
    if ratio > 1.0:
        raise CommandError(f"--robot {path}: braking at {args.acceleration_limit / 2:g} rad/s² from full speed needs "
                           f"{ratio:.2f}× the torque limit at some states; lower --acceleration-limit or "
                           "--velocity-limit")
    return SceneConfig(robot=robot)
