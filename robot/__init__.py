"""Robot side of mpcshare: any arm's description, the QP controller, the MPC and reference smoothing.

- :mod:`robot.description` — ``RobotDescription``: one arm (URDF or MJCF → Pinocchio model, tip
  frame, limits, mount) for the QP, the MPC, the controller, the scene and the servo;
  :mod:`robot.mjcf` writes any description's MuJoCo bodies; :mod:`robot.ik` its numerical
  inverse kinematics; :mod:`robot.braking` the speed and acceleration caps whose braking is
  torque-feasible; :mod:`robot.presets` the common arms of example-robot-data; :mod:`robot.default_arm`
  the arm when none is named (the SuperLimb).
- :mod:`robot.superlimb` — the SuperLimb, one description among others, with its own knowledge:
  one parametric source (``SuperLimbParams``) for its URDF, MJCF and Pinocchio model, the
  closed-form inverse kinematics (``superlimb_description()``).
- :mod:`robot.qp` — joint-acceleration QP with position (viable), velocity and torque limits;
  its settings and results in :mod:`robot.qp_types`.
- :mod:`robot.constraints`, :mod:`robot.tasks` — the QP's limits (``Constraint(G, h)`` rows)
  and tasks (``Objective(H, c)`` costs); :mod:`robot.solvers` — the QP back-ends.
- :mod:`robot.smoothing` — ruckig jerk-limited smoothing of the reference stream.
- :mod:`robot.shoulder` — shoulder angles → knife-tip velocity (the voluntary channel).
- :mod:`robot.kinematics` — the tip's position (a cheap Pinocchio FK for the controller) and
  the reach shell of any arm.
- :mod:`robot.mpc` — the knife-tip MPC (CasADi), imported on demand.
"""

from .constraints import Bounds, Constraint, Limit
from .default_arm import as_description
from .description import RobotDescription
from .errors import ControllerConfigError, FrameNotFoundError, UnsupportedModelError
from .limits import JointLimits
from .qp import QPConfig, QPController, QPResult, QPStatus
from .smoothing import ReferenceSmoother, SmoothedReference, SmoothingStatus
from .state import ControlState
from .superlimb import TOOL_FRAME, SuperLimbParams, superlimb_description
from .superlimb.model_files import PinocchioModel, build_pinocchio_model, mjcf_arm_body, to_mjcf, to_urdf, write_assets
from .tasks import Objective, Task

__all__ = [
    "ControllerConfigError", "FrameNotFoundError", "UnsupportedModelError", "JointLimits",
    "QPConfig", "QPController", "QPResult", "QPStatus", "ControlState",
    "Bounds", "Constraint", "Limit", "Objective", "Task",
    "ReferenceSmoother", "SmoothedReference", "SmoothingStatus",
    "RobotDescription", "as_description", "superlimb_description", "SuperLimbParams", "TOOL_FRAME",
    "PinocchioModel", "build_pinocchio_model", "mjcf_arm_body", "to_mjcf",
    "to_urdf", "write_assets",
]
