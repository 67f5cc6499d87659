"""Position kinematics of any arm's tip (Pinocchio) and its reach shell.

* :class:`TipKinematics` — the tool frame's position p(q) [m] by Pinocchio's frame forward
  kinematics only (no Jacobian, no dynamics): the cheap tip position the controller uses.
* :class:`ReachShell` (model frame) — bounds ``[r_min + margin, r_max − margin]`` on the tip's
  distance from a pivot; a reference outside cannot be reached by any posture and is
  projected radially onto the shell (the other joint limits are the QP's). Two ways to
  find the bounds: the SuperLimb's exact one (the distance from the shoulder pivot on the
  base-yaw axis is a function of the elbow angle only: sweep the elbow) and, for any arm,
  :meth:`ReachShell.sampled` (pivot: the first joint's origin, fixed in the world; bounds
  from sampled configurations refined by local optimisation).

The SuperLimb's closed-form inverse lives in :mod:`robot.superlimb.kinematics` (re-exported
here for old imports); any arm's numerical inverse in :mod:`robot.ik`.
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin

from robot.errors import FrameNotFoundError
from robot.superlimb.kinematics import ArmGeometry, forward_tip, inverse_tip, nearest_reachable_q, reachable
from robot.superlimb.params import TOOL_FRAME

__all__ = ["ArmGeometry", "ReachShell", "TipKinematics", "forward_tip", "inverse_tip", "nearest_reachable_q",
           "reachable"]


class TipKinematics:
    """p(q) [m]: the tool frame's position in the model's world frame (Pinocchio frame FK).

    Args: model (Pinocchio), frame name (default the SuperLimb's tool frame). Raises
    :class:`~robot.errors.FrameNotFoundError` naming the valid frames for an unknown one.
    """

    def __init__(self, model, frame: str = TOOL_FRAME) -> None:
        if not model.existFrame(frame):
            names = [f.name for f in model.frames]
            raise FrameNotFoundError(f'Frame "{frame}" not in {names}')
        self.model = model
        self.frame_id = model.getFrameId(frame)
        self._data = model.createData()

    def position(self, q: np.ndarray) -> np.ndarray:
        """Tool-frame position [m] at joint angles ``q`` [rad] (a new array)."""
        pin.framesForwardKinematics(self.model, self._data, np.asarray(q, dtype=float))
        return self._data.oMf[self.frame_id].translation.copy()


class ReachShell:
    """Distance bounds of the tip from the shoulder pivot, from a Pinocchio model (module docstring).

    Args: model (Pinocchio), tool frame id, names of the shoulder and elbow joints,
    ``margin`` [m] kept inside the shell.
    """

    def __init__(self, model, frame_id: int, shoulder_joint: str = "shoulder", elbow_joint: str = "elbow",
                 margin: float = 0.01, n_samples: int = 721) -> None:
        data = model.createData()
        q = pin.neutral(model)
        pin.forwardKinematics(model, data, q)
        self.pivot = data.oMi[model.getJointId(shoulder_joint)].translation.copy()
        j = model.joints[model.getJointId(elbow_joint)].idx_q
        lo, hi = model.lowerPositionLimit[j], model.upperPositionLimit[j]
        r = []
        for e in np.linspace(lo, hi, n_samples):
            q[j] = e
            pin.framesForwardKinematics(model, data, q)
            r.append(float(np.linalg.norm(data.oMf[frame_id].translation - self.pivot)))
        self.r_min, self.r_max = min(r) + margin, max(r) - margin
        if not self.r_min < self.r_max:
            raise ValueError(f"reach shell is empty with margin {margin} m")

    @classmethod
    def sampled(cls, model, frame_id: int, lower: np.ndarray, upper: np.ndarray, margin: float = 0.01,
                n_samples: int = 2000, seed: int = 0) -> ReachShell:
        """Any arm's shell (module docstring): pivot o = the origin of the first joint of the tool's chain
        (its parent is the world: fixed); r(q) = ‖p(q) − o‖ over ``n_samples`` uniform configurations
        within [lower, upper] [rad], the extremes refined by bounded local search (scipy L-BFGS-B).

        Sampling can only under-estimate r_max and over-estimate r_min: the shell is conservative.
        """
        from scipy.optimize import minimize

        data = model.createData()
        first = model.frames[frame_id].parentJoint
        while first and model.parents[first] != 0:
            first = model.parents[first]
        if first == 0:
            raise ValueError(f"frame {model.frames[frame_id].name!r} is not moved by any joint")
        pin.forwardKinematics(model, data, pin.neutral(model))
        pivot = data.oMi[first].translation.copy()

        def radius(q: np.ndarray) -> float:
            pin.framesForwardKinematics(model, data, q)
            return float(np.linalg.norm(data.oMf[frame_id].translation - pivot))

        lower, upper = np.asarray(lower, dtype=float), np.asarray(upper, dtype=float)
        Q = np.random.default_rng(seed).uniform(lower, upper, (n_samples, model.nq))
        r = np.array([radius(q) for q in Q])
        bounds = list(zip(lower, upper))
        r_min = min(float(r.min()), float(minimize(radius, Q[r.argmin()], bounds=bounds, method="L-BFGS-B").fun))
        r_max = max(float(r.max()), -float(minimize(lambda q: -radius(q), Q[r.argmax()], bounds=bounds,
                                                    method="L-BFGS-B").fun))
        shell = cls.__new__(cls)
        shell.pivot, shell.r_min, shell.r_max = pivot, r_min + margin, r_max - margin
        if not shell.r_min < shell.r_max:
            raise ValueError(f"reach shell is empty with margin {margin} m")
        return shell

    def clamp(self, p: np.ndarray) -> tuple[np.ndarray, bool]:
        """Project ``p`` (model frame) radially into the shell; return (point, was clamped)."""
        d = p - self.pivot
        r = math.sqrt(float(d @ d))
        if self.r_min <= r <= self.r_max:
            return p, False
        if r < 1e-9:
            d, r = np.array([1.0, 0.0, 0.0]), 1.0
        return self.pivot + d * (min(max(r, self.r_min), self.r_max) / r), True
