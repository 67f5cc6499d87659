"""Joint limits of a controlled robot: position, velocity, acceleration, braking, torque."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .errors import ControllerConfigError


def _vec(name: str, value: object, n: int) -> np.ndarray:
    arr = np.asarray(value, dtype=float)
    if arr.ndim == 0:
        arr = np.full(n, float(arr))
    if arr.shape != (n,):
        raise ControllerConfigError(f"{name}: expected shape ({n},), got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ControllerConfigError(f"{name}: must be finite")
    return arr.copy()


@dataclass(frozen=True)
class JointLimits:
    """Per-joint limits, all arrays of shape (n,).

    q_min, q_max [rad]; v_max [rad/s]; a_max [rad/s²] (box on the commanded
    acceleration); a_brake [rad/s²] (deceleration the position limit relies on
    to stop, must be torque-feasible everywhere, ≤ a_max); tau_max [N·m]
    (symmetric, |τ| ≤ tau_max).  The arrays are read-only copies.
    """

    q_min: np.ndarray
    q_max: np.ndarray
    v_max: np.ndarray
    a_max: np.ndarray
    a_brake: np.ndarray
    tau_max: np.ndarray

    def __post_init__(self) -> None:
        n = np.asarray(self.q_min).size
        for name in ("q_min", "q_max", "v_max", "a_max", "a_brake", "tau_max"):
            arr = _vec(name, getattr(self, name), n)
            arr.flags.writeable = False
            object.__setattr__(self, name, arr)
        if np.any(self.q_min >= self.q_max):
            raise ControllerConfigError("q_min must be < q_max for every joint")
        for name in ("v_max", "a_max", "a_brake", "tau_max"):
            if np.any(getattr(self, name) <= 0):
                raise ControllerConfigError(f"{name} must be > 0")
        if np.any(self.a_brake > self.a_max):
            raise ControllerConfigError("a_brake must be ≤ a_max")

    @property
    def n(self) -> int:
        return int(self.q_min.size)

    @classmethod
    def from_model(cls, model, a_max: object, a_brake: object | None = None) -> "JointLimits":
        """Position, velocity and effort limits from a Pinocchio ``model``.

        URDF has no acceleration limits: ``a_max`` [rad/s²] (scalar or (nv,))
        must be given; ``a_brake`` defaults to ``a_max / 2``.
        """
        n = model.nv
        a_max_v = _vec("a_max", a_max, n)
        a_brake_v = a_max_v / 2.0 if a_brake is None else _vec("a_brake", a_brake, n)
        return cls(model.lowerPositionLimit.copy(), model.upperPositionLimit.copy(),
                   model.velocityLimit.copy(), a_max_v, a_brake_v, model.effortLimit.copy())

    @classmethod
    def from_superlimb(cls, params) -> "JointLimits":
        """Limits of a :class:`robot.superlimb.SuperLimbParams` (joint order of the model)."""
        return cls(params.lower, params.upper, params.velocity_limit, params.acceleration_limit,
                   params.braking_acceleration, params.torque_limit)
