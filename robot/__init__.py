"""Robot side of mpcshare: the SuperLimb description, the QP controller and reference smoothing.

- :mod:`robot.superlimb` — one parametric source (``SuperLimbParams``); :mod:`robot.model_files`
  turns it into URDF, MJCF and a Pinocchio model.
- :mod:`robot.qp` — joint-acceleration QP with position (viable), velocity and torque limits;
  its settings and results in :mod:`robot.qp_types`.
- :mod:`robot.constraints`, :mod:`robot.tasks` — the QP's limits (``Constraint(G, h)`` rows)
  and tasks (``Objective(H, c)`` costs); :mod:`robot.solvers` — the QP back-ends.
- :mod:`robot.smoothing` — ruckig jerk-limited smoothing of the reference stream.
- :mod:`robot.shoulder` — shoulder angles → knife-tip velocity (the voluntary channel).
- :mod:`robot.kinematics` — the tip's position: closed form (reach, start pose), a cheap
  Pinocchio FK for the controller, the reach shell.
- :mod:`robot.mpc` — the knife-tip MPC (CasADi), imported on demand.
"""

from .constraints import Bounds, Constraint, Limit
from .errors import ControllerConfigError, FrameNotFoundError, UnsupportedModelError
from .limits import JointLimits
from .model_files import PinocchioModel, build_pinocchio_model, mjcf_arm_body, to_mjcf, to_urdf, write_assets
from .qp import QPConfig, QPController, QPResult, QPStatus
from .smoothing import ReferenceSmoother, SmoothedReference, SmoothingStatus
from .state import ControlState
from .superlimb import TOOL_FRAME, SuperLimbParams
from .tasks import Objective, Task

__all__ = [
    "ControllerConfigError", "FrameNotFoundError", "UnsupportedModelError", "JointLimits",
    "QPConfig", "QPController", "QPResult", "QPStatus", "ControlState",
    "Bounds", "Constraint", "Limit", "Objective", "Task",
    "ReferenceSmoother", "SmoothedReference", "SmoothingStatus",
    "SuperLimbParams", "TOOL_FRAME", "PinocchioModel", "build_pinocchio_model", "mjcf_arm_body", "to_mjcf",
    "to_urdf", "write_assets",
]
