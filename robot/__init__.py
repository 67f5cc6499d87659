"""Robot side of mpcshare: the SuperLimb description, the QP controller and reference smoothing.

- :mod:`robot.superlimb` — one parametric source → URDF, MJCF, Pinocchio model.
- :mod:`robot.qp` — joint-acceleration QP with position (viable), velocity and torque limits.
- :mod:`robot.constraints`, :mod:`robot.tasks` — the QP's constraint and task objects.
- :mod:`robot.smoothing` — ruckig jerk-limited smoothing of the reference stream.
"""

from .errors import ControllerConfigError, FrameNotFoundError, UnsupportedModelError
from .limits import JointLimits
from .qp import QPConfig, QPController, QPResult, QPStatus
from .smoothing import ReferenceSmoother, SmoothedReference, SmoothingStatus
from .superlimb import (SuperLimbParams, TOOL_FRAME, build_pinocchio_model, mjcf_arm_body, to_mjcf, to_urdf,
                        write_assets)

__all__ = [
    "ControllerConfigError", "FrameNotFoundError", "UnsupportedModelError", "JointLimits",
    "QPConfig", "QPController", "QPResult", "QPStatus",
    "ReferenceSmoother", "SmoothedReference", "SmoothingStatus",
    "SuperLimbParams", "TOOL_FRAME", "build_pinocchio_model", "mjcf_arm_body", "to_mjcf", "to_urdf", "write_assets",
]
