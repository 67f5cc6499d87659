"""The arm and the shared controller of ``mpcshare run`` from its configuration, checked before anything is sent.

The ``[robot]`` mount is given in the plate frame with the controller's default base pose
(``mpcshare.control.workspace.DEFAULT_BASE_POSE``, the pose used without a torso input) and turned into
the torso frame of the description: ``p_torso = Rᵀ·(p_plate − t)``. A file ``example-robot-data:PATH`` is
``PATH`` in the ``example-robot-data`` package's models (e.g. ``panda_description/urdf/panda.urdf``).
Every failure is a :class:`~mpcshare.runtime.config.RunConfigError` naming the file, table and key.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from mpcshare.control.controller import SharedController
from mpcshare.control.workspace import DEFAULT_BASE_POSE
from mpcshare.errors import ControllerSetupError
from mpcshare.runtime.config import RunConfig, RunConfigError, check_against_model
from robot.default_arm import as_description
from robot.description import RobotDescription, braking_torque_ratio
from robot.errors import ControllerConfigError

__all__ = ["make_controller", "robot_description"]

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


def robot_description(config: RunConfig) -> RobotDescription:
    """The arm of ``config.robot`` (module docstring); the SuperLimb when no file is given."""
    spec = config.robot
    if spec.file is None:
        return as_description(None)
    assert spec.mount is not None  # parse_run_config requires it with a file
    R, t = DEFAULT_BASE_POSE[:3, :3], DEFAULT_BASE_POSE[:3, 3]
    mount = tuple(float(x) for x in R.T @ (np.asarray(spec.mount) - t))
    try:
        robot = RobotDescription.from_file(_robot_file(config), spec.tip_frame, locked_joints=spec.locked_joints,
                                           mount_xyz=mount, mount_rpy=spec.mount_rpy,
                                           velocity_limit=spec.velocity_limit,
                                           acceleration_limit=spec.acceleration_limit)
    except (ControllerConfigError, ValueError, RuntimeError) as exc:
        raise RunConfigError(f"{config.source}, [robot]: {exc}") from None
    ratio = braking_torque_ratio(robot)
    if ratio > 1.0:
        raise RunConfigError(f"{config.source}, [robot] acceleration_limit: braking at "
                             f"{spec.acceleration_limit / 2:g} rad/s² needs {ratio:.2f}× the torque limit at some "
                             "states; lower acceleration_limit or velocity_limit")
    return robot


def make_controller(config: RunConfig, bundle: Any) -> SharedController:
    """The shared controller of ``bundle`` on the configured arm, after :func:`check_against_model`."""
    robot = robot_description(config)
    check_against_model(config, obs_names=list(bundle.obs_names), vol_names=list(bundle.vol_names),
                        rate_hz=float(bundle.rate_hz), joint_names=robot.joint_names)
    c = config.controller
    try:
        return SharedController.from_bundle(bundle, robot=robot, strategy=c.strategy, beta=c.beta, use_mpc=c.mpc)
    except ControllerSetupError as exc:
        raise RunConfigError(f"{config.source}, [controller]: {exc}") from None
