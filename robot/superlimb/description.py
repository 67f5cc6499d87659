"""The SuperLimb as a :class:`robot.description.RobotDescription`, with its own knowledge.

Over the general description it keeps: the MJCF written from the same parameters as its
URDF (knife geom, colours; :mod:`robot.superlimb.model_files`), the closed-form inverse
kinematics (:mod:`robot.superlimb.kinematics`, exact and ≈ 100× faster than the numerical
one; the numerical one is used if the layout leaves the closed form's assumptions) and the
exact reach shell (the elbow sweep about the shoulder pivot).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from robot.description import RobotDescription
from robot.limits import JointLimits

from .kinematics import ArmGeometry, nearest_reachable_q
from .model_files import build_pinocchio_model, mjcf_actuators, mjcf_arm_body
from .params import TOOL_FRAME, SuperLimbParams

__all__ = ["SuperLimbDescription", "superlimb_description"]


@dataclass(frozen=True, eq=False)
class SuperLimbDescription(RobotDescription):
    """The SuperLimb of ``params`` (module docstring); build with :func:`superlimb_description`."""

    params: SuperLimbParams = field(default_factory=SuperLimbParams)

    def mjcf_body(self, indent: int = 4) -> str:
        return mjcf_arm_body(self.params, indent=indent)

    def mjcf_actuators(self, indent: int = 4) -> str:
        return mjcf_actuators(self.params, indent=indent)

    def inverse_kinematics(self, tip: np.ndarray, q_prefer: np.ndarray | None = None) -> np.ndarray:
        try:
            geom = ArmGeometry.from_params(self.params)
        except ValueError:  # a layout outside the closed form: the general numerical inverse
            return super().inverse_kinematics(tip, q_prefer)
        return nearest_reachable_q(geom, np.asarray(tip, dtype=float), q_prefer)

    def reach_shell(self, margin: float = 0.01):
        from robot.kinematics import ReachShell

        return ReachShell(self.model, self.tip_frame_id, margin=margin)


def superlimb_description(params: SuperLimbParams | None = None) -> SuperLimbDescription:
    """The SuperLimb's description: Pinocchio model from its URDF, ``knife_tip``, its derived limits."""
    p = params or SuperLimbParams()
    return SuperLimbDescription(name=p.name, model=build_pinocchio_model(p).model, tip_frame=TOOL_FRAME,
                                limits=JointLimits.from_superlimb(p), mount_xyz=p.mount_xyz,
                                mount_rpy=p.mount_rpy, source="robot.superlimb", params=p)
