"""One robot description for any arm: Pinocchio model, tip frame, joint limits, mount.

:class:`RobotDescription` is what the QP, the MPC, the controller, the MuJoCo scene and
the servo take. Build one from a file (URDF or MJCF, :meth:`RobotDescription.from_file`)
or from a Pinocchio model (:meth:`RobotDescription.from_model`); the SuperLimb is one
description among others (:func:`robot.superlimb.superlimb_description`), which adds its
own knowledge (its hand-written MJCF, the closed-form inverse, the exact reach shell).

Frames: the model's world frame is the frame the arm is worn in (the wearer's torso,
x forward, y left, z up); the **mount** (``mount_xyz`` [m], ``mount_rpy`` [rad], URDF
roll-pitch-yaw) places the file's root in it and is applied to the model (the joints
and frames attached to the root; Pinocchio's MJCF reader drops the root body's own pose, so
an MJCF arm is placed by the mount alone). Limits: position [rad], velocity [rad/s] and torque
[N·m] from the file, acceleration [rad/s²] and the braking deceleration the viable
position limit relies on [rad/s²] given here (files have none).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Sequence

import numpy as np
import pinocchio as pin

from robot.braking import braking_torque_ratio
from robot.errors import ControllerConfigError, FrameNotFoundError, UnsupportedModelError
from robot.limits import JointLimits

__all__ = ["RobotDescription", "braking_torque_ratio", "mount_model"]

Vec3 = tuple[float, float, float]
FILE_KINDS = {".urdf": "URDF", ".xml": "MJCF", ".mjcf": "MJCF"}


def _rpy_matrix(rpy: Sequence[float]) -> np.ndarray:
    return pin.rpy.rpyToMatrix(*(float(a) for a in rpy))


def mount_model(model, xyz: Sequence[float], rpy: Sequence[float] = (0.0, 0.0, 0.0)) -> None:
    """Place the model's root at ``xyz`` [m], ``rpy`` [rad] in its world frame (in place)."""
    M = pin.SE3(_rpy_matrix(rpy), np.asarray(xyz, dtype=float))
    for j in range(1, model.njoints):
        if model.parents[j] == 0:
            model.jointPlacements[j] = M * model.jointPlacements[j]
    for k in range(1, model.nframes):
        frame = model.frames[k]
        if frame.parentJoint == 0:
            frame.placement = M * frame.placement
            model.frames[k] = frame


def _bounded_continuous(urdf: str) -> str:
    """The URDF text with every continuous joint made revolute within its limits (±2π where none)."""
    import xml.etree.ElementTree as ET

    root = ET.fromstring(urdf)
    for joint in root.iter("joint"):
        if joint.get("type") != "continuous":
            continue
        joint.set("type", "revolute")
        limit = joint.find("limit")
        if limit is None:
            limit = ET.SubElement(joint, "limit")
        for key, value in (("lower", -2 * np.pi), ("upper", 2 * np.pi)):
            limit.set(key, limit.get(key) or repr(value))
    return ET.tostring(root, encoding="unicode")


def _per_joint(name: str, value: Any, n: int) -> np.ndarray | None:
    if value is None:
        return None
    arr = np.broadcast_to(np.asarray(value, dtype=float), (n,)).copy()
    if not (np.all(np.isfinite(arr)) and np.all(arr > 0)):
        raise ControllerConfigError(f"{name} must be finite and > 0 for every joint, got {value!r}")
    return arr


@dataclass(frozen=True, eq=False)
class RobotDescription:
    """An arm as the whole stack sees it (module docstring).

    ``model``: Pinocchio model, mount applied, revolute/prismatic joints only (nq = nv);
    ``tip_frame``: the tool frame tracked; ``limits``: :class:`~robot.limits.JointLimits`;
    ``q_home`` (nv,) [rad]: the posture the QP's posture task and the inverse kinematics
    prefer (default: the middle of the position limits); ``source``: where it came from.
    """

    name: str
    model: Any
    tip_frame: str
    limits: JointLimits
    mount_xyz: Vec3 = (0.0, 0.0, 0.0)
    mount_rpy: Vec3 = (0.0, 0.0, 0.0)
    q_home: np.ndarray | None = None
    source: str = ""
    tip_frame_id: int = field(init=False)

    def __post_init__(self) -> None:
        m = self.model
        if m.nq != m.nv:
            raise UnsupportedModelError(f"{self.name}: nq={m.nq} ≠ nv={m.nv} (free-flyer, spherical or continuous "
                                        "joints); lock them or describe them as revolute joints with limits")
        if not m.existFrame(self.tip_frame):
            raise FrameNotFoundError(f"{self.name}: no frame {self.tip_frame!r}; valid frames: "
                                     f"{[f.name for f in m.frames][1:]}")
        fid = int(m.getFrameId(self.tip_frame))
        if m.frames[fid].parentJoint == 0:
            raise FrameNotFoundError(f"{self.name}: frame {self.tip_frame!r} is fixed to the world; choose a frame "
                                     f"on the arm: {[f.name for f in m.frames if f.parentJoint > 0]}")
        if self.limits.n != m.nv:
            raise ControllerConfigError(f"{self.name}: limits are for {self.limits.n} joints, the model has {m.nv}")
        home = 0.5 * (self.limits.q_min + self.limits.q_max) if self.q_home is None else \
            np.asarray(self.q_home, dtype=float)
        if home.shape != (m.nv,) or np.any(home < self.limits.q_min) or np.any(home > self.limits.q_max):
            raise ControllerConfigError(f"{self.name}: q_home must be ({m.nv},) within the position limits")
        object.__setattr__(self, "q_home", home)
        object.__setattr__(self, "tip_frame_id", fid)

    # ------------------------------------------------------------------ figures
    @property
    def n(self) -> int:
        """Number of joints (= nq = nv)."""
        return int(self.model.nv)

    @property
    def joint_names(self) -> list[str]:
        return [str(self.model.names[j]) for j in range(1, self.model.njoints)]

    @property
    def gravity(self) -> float:
        """|g| [m/s²] of the model (gravity along −z of the world frame)."""
        return float(-self.model.gravity.linear[2])

    # ------------------------------------------------------------------ what each part asks of the arm
    def mjcf_body(self, indent: int = 4) -> str:
        """The arm as an MJCF body subtree (:func:`robot.mjcf.mjcf_arm_body`), mounted in its parent body."""
        from robot.mjcf import mjcf_arm_body

        lim = self.limits
        return mjcf_arm_body(self.model, self.tip_frame, lim.q_min, lim.q_max, lim.tau_max, indent)

    def mjcf_actuators(self, indent: int = 4) -> str:
        """One torque motor per joint within ±τ_max (:func:`robot.mjcf.mjcf_actuators`)."""
        from robot.mjcf import mjcf_actuators

        return mjcf_actuators(self.model, self.limits.tau_max, indent)

    def inverse_kinematics(self, tip: np.ndarray, q_prefer: np.ndarray | None = None) -> np.ndarray:
        """A configuration (n,) within the limits whose tip is nearest ``tip`` (3,) [m] (:mod:`robot.ik`)."""
        from robot.ik import inverse_tip_position

        pref = self.q_home if q_prefer is None else q_prefer
        return inverse_tip_position(self.model, self.tip_frame_id, tip, self.limits.q_min, self.limits.q_max, pref)

    def reach_shell(self, margin: float = 0.01):
        """The tip's reach shell (:meth:`robot.kinematics.ReachShell.sampled`), ``margin`` [m] inside."""
        from robot.kinematics import ReachShell

        return ReachShell.sampled(self.model, self.tip_frame_id, self.limits.q_min, self.limits.q_max, margin)

    # ------------------------------------------------------------------ construction
    @classmethod
    def from_model(cls, model, tip_frame: str, *, name: str | None = None, mount_xyz: Sequence[float] = (0, 0, 0),
                   mount_rpy: Sequence[float] = (0, 0, 0), acceleration_limit: Any = 10.0,
                   braking_acceleration: Any = None, velocity_limit: Any = None, torque_limit: Any = None,
                   q_home: np.ndarray | None = None, source: str = "") -> RobotDescription:
        """Description of a Pinocchio ``model`` (copied, then mounted).

        ``acceleration_limit`` [rad/s²] (scalar or per joint), ``braking_acceleration``
        [rad/s²] (default half of it; must be torque-feasible everywhere, which
        :func:`robot.description.braking_torque_ratio` checks), ``velocity_limit`` [rad/s] and
        ``torque_limit`` [N·m]: caps below the file's (also what a file without them needs).
        """
        if model.nq != model.nv:
            raise UnsupportedModelError(f"{name or model.name}: nq={model.nq} ≠ nv={model.nv} (free-flyer, spherical "
                                        "or continuous joints); lock them or make them revolute with limits "
                                        "(from_file: continuous_as_revolute=True)")
        model = model.copy()
        mount_model(model, mount_xyz, mount_rpy)
        n = model.nv
        a_max = _per_joint("acceleration_limit", acceleration_limit, n)
        a_brake = _per_joint("braking_acceleration", braking_acceleration, n)
        v_max = np.asarray(model.velocityLimit, dtype=float).copy()
        tau_max = np.asarray(model.effortLimit, dtype=float).copy()
        for arr, cap in ((v_max, _per_joint("velocity_limit", velocity_limit, n)),
                         (tau_max, _per_joint("torque_limit", torque_limit, n))):
            if cap is not None:
                np.copyto(arr, np.minimum(np.where(np.isfinite(arr) & (arr > 0), arr, np.inf), cap))
        names = [str(model.names[j]) for j in range(1, model.njoints)]
        for what, arr, option in (("velocity", v_max, "velocity_limit"), ("torque", tau_max, "torque_limit")):
            bad = [names[i] for i in range(n) if not (np.isfinite(arr[i]) and arr[i] > 0)]
            if bad:
                raise ControllerConfigError(f"joints {bad} have no {what} limit in the file: give {option}=")
        lo, hi = model.lowerPositionLimit, model.upperPositionLimit
        bad = [names[i] for i in range(n) if not (np.isfinite(lo[i]) and np.isfinite(hi[i]) and lo[i] < hi[i])]
        if bad:
            raise ControllerConfigError(f"joints {bad} have no finite position limits in the file")
        limits = JointLimits(lo.copy(), hi.copy(), v_max, a_max, a_max / 2.0 if a_brake is None else a_brake, tau_max)
        return cls(name or str(model.name), model, tip_frame, limits, tuple(float(x) for x in mount_xyz),
                   tuple(float(x) for x in mount_rpy), q_home, source)

    @classmethod
    def from_file(cls, path: str | Path, tip_frame: str, *, locked_joints: Sequence[str] = (),
                  continuous_as_revolute: bool = False, **options: Any) -> RobotDescription:
        """Description of a URDF (``.urdf``) or MJCF (``.xml``, ``.mjcf``) file; ``options`` as
        :meth:`from_model`. ``locked_joints``: joints held at 0 (or their lower limit if 0 is
        outside), e.g. a gripper's fingers. ``continuous_as_revolute`` (URDF): a continuous joint
        becomes a revolute one within its ``<limit lower upper>``, ±2π [rad] where the file has none."""
        path = Path(path)
        kind = FILE_KINDS.get(path.suffix.lower())
        if kind is None:
            raise ControllerConfigError(f"{path}: unknown robot file type {path.suffix!r}; "
                                        f"valid: {', '.join(FILE_KINDS)}")
        if not path.is_file():
            raise ControllerConfigError(f"robot file {path} does not exist")
        if kind == "URDF":
            text = path.read_text()
            model = pin.buildModelFromXML(_bounded_continuous(text) if continuous_as_revolute else text)
        else:
            model = pin.buildModelFromMJCF(str(path))
        if locked_joints:
            missing = [j for j in locked_joints if not model.existJointName(j)]
            if missing:
                raise ControllerConfigError(f"no joint(s) {missing} to lock; joints: {list(model.names)[1:]}")
            q = np.clip(np.zeros(model.nq), model.lowerPositionLimit, model.upperPositionLimit)
            model = pin.buildReducedModel(model, [model.getJointId(j) for j in locked_joints], q)
        options.setdefault("source", str(path))
        return cls.from_model(model, tip_frame, **options)
