"""Another arm than the SuperLimb, set up for the eating task: a preset or a file, its mount, its caps.

:func:`task_arm` builds the arm (a preset of :mod:`robot.presets`, placed where
:mod:`sim.arm_mounts` puts it, or a URDF/MJCF file at a given mount in the plate frame) and
chooses its speed and acceleration caps (:func:`robot.braking.braking_caps`): the largest caps,
scaled down together from the file's speed limits and :data:`ACCELERATION_REFERENCE`, whose
braking is torque-feasible at every sampled configuration with the tip in the controller's
workspace box (:data:`mpcshare.control.workspace.DEFAULT_WORKSPACE`, the torso at rest). A
speed or acceleration given by the caller is kept (the other one is chosen); both given are
only checked (braking torque ratio ≤ 1 on the same states).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Sequence

import numpy as np

from mpcshare.control.workspace import DEFAULT_WORKSPACE, WorkspaceBox
from robot.braking import braking_caps, braking_torque_ratio, tip_box_states
from robot.description import RobotDescription
from robot.errors import ControllerConfigError
from robot.presets import arm_preset, is_preset_name
from sim.arm_mounts import arm_mount
from sim.scene import SceneConfig

__all__ = ["ACCELERATION_REFERENCE", "TaskArm", "rest_base_pose", "task_arm"]

ACCELERATION_REFERENCE = 10.0  # [rad/s²] the acceleration cap scaled down with the file's speeds (braking at half)
N_STATES = 500  # sampled configurations with the tip in the workspace box


@dataclass(frozen=True)
class TaskArm:
    """The scene with the arm, the caps' one-line ``summary`` and how they were set (``chosen``); its controller's
    mount is :func:`rest_base_pose` of ``scene``."""

    scene: SceneConfig
    summary: str
    chosen: bool
    ratio: float
    n_states: int


def rest_base_pose(scene: SceneConfig | None = None) -> np.ndarray:
    """T_plate_torso (4×4) with the wearer's torso at rest in ``scene`` (default: the eating scene): the plate
    at ``plate_position`` in the torso frame, axes aligned. Every arm's description has its mount in the
    torso frame, so this is the base pose its controller is given when no torso pose is measured."""
    T = np.eye(4)
    T[:3, 3] = -np.asarray((scene or SceneConfig()).plate_position, dtype=float)
    return T


def _describe(robot: str, tip_frame: str | None, mount: Sequence[float] | None, mount_rpy: Sequence[float] | None,
              lock_joints: Sequence[str] | None, scene: SceneConfig, **limits) -> RobotDescription:
    if is_preset_name(robot):
        preset = arm_preset(robot)
        xyz, rpy = arm_mount(robot)
        xyz, rpy = (xyz if mount is None else mount), (rpy if mount_rpy is None else mount_rpy)
        options = {} if lock_joints is None else {"locked_joints": tuple(lock_joints)}
        desc = preset.description(tip_frame=tip_frame, mount_xyz=scene.mount_in_torso(tuple(xyz)), mount_rpy=rpy,
                                  **options, **limits)
        return desc
    if Path(robot).suffix == "" and "/" not in robot:
        arm_preset(robot)  # raises: no such preset, naming them
    if mount is None:
        raise ControllerConfigError(f"{robot}: a file needs --mount X Y Z, the arm's base in the plate frame [m]")
    return RobotDescription.from_file(robot, tip_frame or "", locked_joints=tuple(lock_joints or ()),
                                      mount_xyz=scene.mount_in_torso(tuple(mount)),
                                      mount_rpy=tuple(mount_rpy or (0.0, 0.0, 0.0)), **limits)


def task_arm(robot: str, *, tip_frame: str | None = None, mount: Sequence[float] | None = None,
             mount_rpy: Sequence[float] | None = None, lock_joints: Sequence[str] | None = None,
             velocity_limit: float | None = None, acceleration_limit: float | None = None,
             workspace: WorkspaceBox = DEFAULT_WORKSPACE, seed: int = 0) -> TaskArm:
    """The arm ``robot`` (a preset name or a URDF/MJCF path) in the eating scene with its caps (module
    docstring). ``tip_frame``, ``mount`` [m], ``mount_rpy`` [rad] and ``lock_joints`` override a
    preset's; a file needs ``mount``. Raises ControllerConfigError (no preset of that name, no
    reach of the workspace box, no feasible caps, forced caps infeasible) naming what is wrong."""
    base = SceneConfig()
    given = {"acceleration_limit": acceleration_limit or ACCELERATION_REFERENCE}
    if velocity_limit is not None:
        given["velocity_limit"] = velocity_limit
    desc = _describe(robot, tip_frame, mount, mount_rpy, lock_joints, base, **given)
    plate = np.asarray(base.plate_position, dtype=float)
    lim = desc.limits
    states = tip_box_states(desc.model, desc.tip_frame_id, lim.q_min, lim.q_max, plate + workspace.lower,
                            plate + workspace.upper, n=N_STATES, seed=seed)
    if velocity_limit is not None and acceleration_limit is not None:
        ratio = braking_torque_ratio(desc, seed=seed, states=states)
        if ratio > 1.0:
            raise ControllerConfigError(f"braking at {acceleration_limit / 2:g} rad/s² from {velocity_limit:g} rad/s "
                                        f"needs {ratio:.2f}× the torque limit at some states; lower "
                                        "--acceleration-limit or --velocity-limit (or give neither: they are chosen)")
        summary = (f"velocity ≤ {velocity_limit:g} rad/s, acceleration ≤ {acceleration_limit:g} rad/s² as given "
                   f"(braking at half: {ratio:.2f}× the torque limit at worst)")
        return TaskArm(SceneConfig(robot=desc), summary, False, ratio, len(states))
    caps = braking_caps(desc.model, states, lim.v_max, lim.a_max, lim.tau_max,
                        scale_velocity=velocity_limit is None, scale_acceleration=acceleration_limit is None,
                        seed=seed)
    chosen = _describe(robot, tip_frame, mount, mount_rpy, lock_joints, base, velocity_limit=caps.velocity,
                       acceleration_limit=caps.acceleration)
    which = "chosen" if velocity_limit is None and acceleration_limit is None else \
        ("acceleration chosen" if velocity_limit is not None else "velocity chosen")
    summary = f"{caps.summary()}, {which} over {len(states)} configurations with the tip in the workspace"
    return TaskArm(SceneConfig(robot=chosen), summary, True, caps.ratio, len(states))
