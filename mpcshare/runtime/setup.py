"""The arm and the shared controller of ``mpcshare run`` from its configuration, checked before anything is sent.

The ``[robot]`` arm is set up exactly as ``mpcshare sim --robot FILE`` sets it up
(:func:`mpcshare.arms.task_arm`): the mount is in the plate frame with the wearer's torso at rest
(the simulator's convention), and the speed and acceleration caps not given are chosen so that
braking is torque-feasible over the task's workspace (both given: only checked). A file
``example-robot-data:PATH`` is ``PATH`` in the ``example-robot-data`` package's models (e.g.
``panda_description/urdf/panda.urdf``). Every failure is a :class:`~mpcshare.runtime.config.RunConfigError`
naming the file, table and key. :func:`rest_base_pose` is that convention's torso at rest, T_plate_torso,
the base pose ``run`` gives the controller without a torso input.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from mpcshare.arms import TaskArm, task_arm
from mpcshare.arms import rest_base_pose as arm_rest_pose
from mpcshare.control.controller import SharedController
from mpcshare.errors import ControllerSetupError
from mpcshare.runtime.config import RunConfig, RunConfigError, check_against_model
from robot.default_arm import as_description
from robot.description import RobotDescription
from robot.errors import ControllerConfigError

__all__ = ["configured_arm", "make_controller", "rest_base_pose", "robot_description"]

_ERD = "example-robot-data:"


def _robot_file(config: RunConfig) -> Path:
    file = str(config.robot.file)
    if not file.startswith(_ERD):
        return Path(file)
    rel = file[len(_ERD):]
    try:
        import example_robot_data as erd
    except ImportError:
        raise RunConfigError(f"{config.source}, [robot] file: {file!r} needs the example-robot-data package "
                             "(pip install example-robot-data)") from None
    try:
        return Path(erd.getModelPath(rel)) / rel
    except Exception as exc:  # noqa: BLE001 - the package raises plain Exceptions for unknown paths
        raise RunConfigError(f"{config.source}, [robot] file: {rel!r} is not in example-robot-data ({exc})") from None


def rest_base_pose() -> np.ndarray:
    """T_plate_torso (4×4) with the wearer's torso at rest, as the simulator places it
    (:func:`mpcshare.arms.rest_base_pose` of the eating scene)."""
    return arm_rest_pose()


def configured_arm(config: RunConfig) -> TaskArm | None:
    """The arm of ``config.robot`` with its caps (module docstring); None: the SuperLimb (no ``[robot]`` file)."""
    spec = config.robot
    if spec.file is None:
        return None
    try:
        return task_arm(str(_robot_file(config)), tip_frame=spec.tip_frame, mount=spec.mount, mount_rpy=spec.mount_rpy,
                        lock_joints=spec.locked_joints, velocity_limit=spec.velocity_limit,
                        acceleration_limit=spec.acceleration_limit)
    except (ControllerConfigError, ValueError, RuntimeError) as exc:
        raise RunConfigError(f"{config.source}, [robot]: {exc}") from None


def robot_description(config: RunConfig) -> RobotDescription:
    """The arm of ``config.robot`` (:func:`configured_arm`; the SuperLimb when no file is given)."""
    arm = configured_arm(config)
    return as_description(None) if arm is None else arm.scene.robot


def make_controller(config: RunConfig, bundle: Any, arm: TaskArm | None = None) -> SharedController:
    """The shared controller of ``bundle`` on the configured arm (``arm``: :func:`configured_arm`'s, when
    already built), after :func:`check_against_model`."""
    arm = arm or configured_arm(config)
    robot = as_description(None) if arm is None else arm.scene.robot
    check_against_model(config, obs_names=list(bundle.obs_names), vol_names=list(bundle.vol_names),
                        rate_hz=float(bundle.rate_hz), joint_names=robot.joint_names)
    c = config.controller
    try:
        return SharedController.from_bundle(bundle, robot=robot, strategy=c.strategy, beta=c.beta, use_mpc=c.mpc,
                                            base_pose=rest_base_pose())
    except ControllerSetupError as exc:
        raise RunConfigError(f"{config.source}, [controller]: {exc}") from None
