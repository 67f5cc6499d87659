"""The SuperLimb: one arm's own knowledge, beside the general stack of :mod:`robot`.

- :mod:`robot.superlimb.params` — every number in one parametric source (``SuperLimbParams``);
- :mod:`robot.superlimb.model_files` — URDF, MJCF and the Pinocchio model from it (cannot drift);
- :mod:`robot.superlimb.kinematics` — the closed-form inverse of the knife tip (the fast path);
- :mod:`robot.superlimb.description` — the SuperLimb as a :class:`robot.description.RobotDescription`.
"""

from .description import SuperLimbDescription, superlimb_description
from .params import (
    ASSETS_DIR,
    GRAVITY,
    TOOL_FRAME,
    Actuator,
    Inertia6,
    Inertial,
    JointParams,
    LinkParams,
    SuperLimbParams,
    Vec3,
    rod_inertial,
    rpy_to_matrix,
    rpy_to_quat,
)

__all__ = ["ASSETS_DIR", "GRAVITY", "TOOL_FRAME", "Actuator", "Inertia6", "Inertial", "JointParams", "LinkParams",
           "SuperLimbDescription", "SuperLimbParams", "Vec3", "rod_inertial", "rpy_to_matrix", "rpy_to_quat",
           "superlimb_description"]
