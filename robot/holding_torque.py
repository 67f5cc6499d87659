"""The joint torque that brakes an arm to rest at a posture and holds it there, gravity included.

For an effort interface's protective stop: a critically damped joint-space brake, inverse dynamics of the
arm's rigid-body model (pinocchio's RNEA),

    a = clip(−ω²·(q − q_hold) − 2ω·v, ±a_brake),   τ = clip(M(q)·a + h(q, v), ±tau_max)

with ω = min(:data:`HOLD_OMEGA`, 0.3 / T) [rad/s] (T the command period: ω·T ≤ 0.3 keeps the brake stable under
a torque held over the period). At rest at q_hold, τ = g(q), the holding torque. Never raises: where the brake
cannot be computed (non-finite q, v or q_hold; a failing model) it falls back to g(q) alone, then to zeros, and
says which (:data:`SOURCES`).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

__all__ = ["HOLD_OMEGA", "SOURCES", "HoldingTorque"]

#: The brake's natural frequency ω [rad/s] (critically damped) at command periods of 15 ms and shorter.
HOLD_OMEGA = 20.0

#: Where a holding torque came from: the brake, gravity alone g(q), or zeros.
SOURCES = ("brake", "gravity", "zero")


class HoldingTorque:
    """The brake of the module docstring for ``robot`` (a :class:`robot.description.RobotDescription`) at the
    command period ``period_s`` [s] (> 0, else ValueError)."""

    def __init__(self, robot: Any, period_s: float) -> None:
        if not period_s > 0:
            raise ValueError(f"HoldingTorque: period_s must be > 0, got {period_s!r}")
        self.robot = robot
        self.omega = min(HOLD_OMEGA, 0.3 / period_s)
        self._data = robot.model.createData()
        self._n = int(robot.model.nv)

    def gravity(self, q: np.ndarray) -> np.ndarray:
        """g(q) (n,) [N·m], the torque that holds the arm still at q; ValueError for a non-finite q."""
        import pinocchio as pin

        q = np.asarray(q, dtype=float)
        if q.shape != (self._n,) or not math.isfinite(q.sum()):
            raise ValueError(f"gravity: q must be ({self._n},) and finite")
        return np.array(pin.computeGeneralizedGravity(self.robot.model, self._data, q), dtype=float)

    def __call__(self, q: np.ndarray, v: np.ndarray, q_hold: np.ndarray) -> tuple[np.ndarray, str]:
        """(τ (n,) [N·m], its source in :data:`SOURCES`) braking from the measured (q [rad], v [rad/s]) to rest
        at ``q_hold`` [rad]; never raises."""
        import pinocchio as pin

        lim = self.robot.limits
        try:
            q, v, q_hold = (np.asarray(x, dtype=float).reshape(self._n) for x in (q, v, q_hold))
            if math.isfinite(q.sum() + v.sum() + q_hold.sum()):
                w = self.omega
                a = np.clip(-w * w * (q - q_hold) - 2.0 * w * v, -lim.a_brake, lim.a_brake)
                tau = np.array(pin.rnea(self.robot.model, self._data, q, v, a), dtype=float)
                if math.isfinite(tau.sum()):
                    return np.clip(tau, -lim.tau_max, lim.tau_max), "brake"
        except Exception:  # noqa: BLE001 - the stop must go out: fall back to gravity alone
            pass
        try:
            q_g = q if isinstance(q, np.ndarray) and q.shape == (self._n,) and math.isfinite(q.sum()) else q_hold
            tau = self.gravity(q_g)
            if math.isfinite(tau.sum()):
                return np.clip(tau, -lim.tau_max, lim.tau_max), "gravity"
        except Exception:  # noqa: BLE001 - then zeros, said by the source
            pass
        return np.zeros(self._n), "zero"
