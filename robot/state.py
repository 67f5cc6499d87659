"""Per-step robot quantities shared by all constraints and tasks (one Pinocchio pass)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

_LWA = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED


@dataclass
class ControlState:
    """State of the robot at one control step.

    q [rad], v [rad/s], dt [s]; M (n, n) joint-space inertia incl. armature
    [kg·m²]; h (n,) = C(q, v)·v + g(q) [N·m]; tip position p [m], velocity
    p_dot = J·v [m/s]; J (3, n) translational Jacobian of the tool frame in the
    world-aligned frame; drift (3,) = J̇·v [m/s²], the tool's classical
    acceleration at zero joint acceleration.
    """

    q: np.ndarray
    v: np.ndarray
    dt: float
    M: np.ndarray
    h: np.ndarray
    p: np.ndarray
    p_dot: np.ndarray
    J: np.ndarray
    drift: np.ndarray


class StateEvaluator:
    """Fills a :class:`ControlState` from (q, v) with Pinocchio, reusing one ``data``."""

    def __init__(self, model, frame_id: int) -> None:
        self.model = model
        self.data = model.createData()
        self.frame_id = int(frame_id)
        self._zero = np.zeros(model.nv)
        self._upper = np.triu_indices(model.nv, 1)

    def __call__(self, q: np.ndarray, v: np.ndarray, dt: float) -> ControlState:
        """Kinematics (FK with a = 0 gives the drift J̇·v), CRBA and RNEA for (q, v)."""
        model, data, fid = self.model, self.data, self.frame_id
        pin.forwardKinematics(model, data, q, v, self._zero)
        placement = pin.updateFramePlacement(model, data, fid)
        p_dot = pin.getFrameVelocity(model, data, fid, _LWA).linear
        drift = pin.getFrameClassicalAcceleration(model, data, fid, _LWA).linear
        pin.computeJointJacobians(model, data)  # uses the placements of forwardKinematics above
        J = pin.getFrameJacobian(model, data, fid, _LWA)[:3]
        M = pin.crba(model, data, q).copy()
        M[self._upper[1], self._upper[0]] = M[self._upper]  # crba fills the upper triangle
        h = pin.rnea(model, data, q, v, self._zero).copy()
        return ControlState(q, v, dt, M, h, placement.translation.copy(), p_dot, J, drift)
