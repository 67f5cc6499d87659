"""QP tasks on the joint acceleration a [rad/s²], each returning its cost terms.

A task with weight w and residual r(a) = A·a − b contributes
w·‖A·a − b‖² = ½·aᵀ(2w·AᵀA)·a − (2w·Aᵀb)ᵀ·a + const, returned by
``compute_qp_objective(state)`` as a named :class:`Objective` ``(H, c)`` with
``H = 2w·AᵀA`` and ``c = −2w·Aᵀb`` (the names of mink and pink).  Arrays a task
caches and returns on every call are read-only.
"""

from __future__ import annotations

import math
from typing import NamedTuple, Protocol, runtime_checkable

import numpy as np

from .errors import ControllerConfigError
from .state import ControlState


class Objective(NamedTuple):
    """Quadratic cost ½·aᵀ·H·a + cᵀ·a of the joint acceleration a; H (n, n) symmetric ⪰ 0, c (n,)."""

    H: np.ndarray
    c: np.ndarray


@runtime_checkable
class Task(Protocol):
    """Anything with ``compute_qp_objective(state) -> Objective(H, c)``."""

    name: str

    def compute_qp_objective(self, state: ControlState) -> Objective: ...


def _readonly(a: np.ndarray) -> np.ndarray:
    a.flags.writeable = False
    return a


def _nonneg(name: str, x: float) -> float:
    x = float(x)
    if not np.isfinite(x) or x < 0:
        raise ControllerConfigError(f"{name} must be finite and ≥ 0, got {x}")
    return x


class TipTrackingTask:
    """Tool-tip acceleration tracking (operational-space PD with feed-forward).

    Desired tip acceleration [m/s²]

        ẍ_des = a_ref + kd·(v_ref − ṗ) + kp·(p_ref − p),

    optionally with the position error clipped to ``max_error`` [m] so that a
    far target does not ask for huge accelerations.  Residual J·a + J̇·v − ẍ_des.
    kp [1/s²], kd [1/s].  Without a reference (``clear_reference``) the task
    contributes nothing.
    """

    name = "tip"

    def __init__(self, weight: float = 1.0, kp: float = 400.0, kd: float = 40.0,
                 max_error: float | None = None) -> None:
        self.weight = _nonneg("weight", weight)
        self.kp = _nonneg("kp", kp)
        self.kd = _nonneg("kd", kd)
        self.max_error = None if max_error is None else _nonneg("max_error", max_error)
        self.p_ref: np.ndarray | None = None
        self.v_ref = np.zeros(3)
        self.a_ref = np.zeros(3)

    def set_reference(self, p_ref: np.ndarray, v_ref: np.ndarray | None = None,
                      a_ref: np.ndarray | None = None) -> None:
        """Tip position [m], velocity [m/s] and acceleration [m/s²] in the world frame."""
        self.p_ref = p_ref
        self.v_ref = np.zeros(3) if v_ref is None else v_ref
        self.a_ref = np.zeros(3) if a_ref is None else a_ref

    def clear_reference(self) -> None:
        self.p_ref = None

    def desired_acceleration(self, state: ControlState) -> np.ndarray:
        """ẍ_des [m/s²] for the current state (requires a reference)."""
        if self.p_ref is None:
            raise ControllerConfigError("desired_acceleration needs a reference: call set_reference first")
        err = self.p_ref - state.p
        if self.max_error is not None:
            norm = math.sqrt(float(err @ err))
            if norm > self.max_error:
                err = err * (self.max_error / norm)
        return self.a_ref + self.kd * (self.v_ref - state.p_dot) + self.kp * err

    def compute_qp_objective(self, state: ControlState) -> Objective:
        n = state.v.size
        if self.p_ref is None or self.weight == 0.0:
            return Objective(np.zeros((n, n)), np.zeros(n))
        b = self.desired_acceleration(state) - state.drift
        Jt = state.J.T * (2.0 * self.weight)
        return Objective(Jt @ state.J, -(Jt @ b))



class BlendedTipTrackingTask(TipTrackingTask):
    """Two parties' tip references in one cost (authority inside the optimisation):

        α·w·‖J·a + J̇·v − ẍ_r‖² + (1 − α)·w·‖J·a + J̇·v − ẍ_v‖²,

    ẍ_r, ẍ_v the PD law of :class:`TipTrackingTask` toward each party's reference (each with its own clipped
    error). ``set_reference`` gives the first party's reference (the QP's ``p_ref``), :meth:`set_second` the
    second's and its weight 1 − α ∈ [0, 1]; without a second (:meth:`clear_second`) the task is
    :class:`TipTrackingTask`. Being least squares in the same J·a, the cost equals
    w·‖J·a + J̇·v − (α·ẍ_r + (1 − α)·ẍ_v)‖² plus a constant in a: its minimiser under any constraints is that of
    tracking the blended acceleration, whether a constraint binds or not.
    """

    name = "tip"

    def __init__(self, weight: float = 1.0, kp: float = 400.0, kd: float = 40.0,
                 max_error: float | None = None) -> None:
        super().__init__(weight, kp, kd, max_error)
        self._second = TipTrackingTask(1.0, kp, kd, max_error)
        self.second_weight = 0.0

    def set_second(self, weight: float, p_ref: np.ndarray, v_ref: np.ndarray | None = None,
                   a_ref: np.ndarray | None = None) -> None:
        """The second party's reference [m, m/s, m/s²] and weight 1 − α; ControllerConfigError outside [0, 1]."""
        w = float(weight)
        if not 0.0 <= w <= 1.0:
            raise ControllerConfigError(f"the second party's weight must be in [0, 1], got {weight!r}")
        self._second.set_reference(p_ref, v_ref, a_ref)
        self.second_weight = w

    def clear_second(self) -> None:
        """Back to one reference (weight 1 on ``set_reference``'s)."""
        self._second.clear_reference()
        self.second_weight = 0.0

    def compute_qp_objective(self, state: ControlState) -> Objective:
        w2 = self.second_weight
        if self._second.p_ref is None or w2 == 0.0:
            return super().compute_qp_objective(state)
        n = state.v.size
        Jt = state.J.T * (2.0 * self.weight)
        H = np.zeros((n, n))
        c = np.zeros(n)
        for share, task in ((1.0 - w2, self), (w2, self._second)):
            if share > 0.0 and task.p_ref is not None:
                b = TipTrackingTask.desired_acceleration(task, state) - state.drift
                H = H + share * (Jt @ state.J)
                c = c - share * (Jt @ b)
        return Objective(H, c)


class PostureTask:
    """Joint-space PD toward a posture: residual a − (kp·(q_ref − q) − kd·v).

    q_ref [rad], kp [1/s²], kd [1/s].  Keeps the redundant / singular
    directions defined and the Hessian positive definite.
    """

    name = "posture"

    def __init__(self, q_ref: np.ndarray, weight: float = 1e-3, kp: float = 25.0, kd: float = 10.0) -> None:
        self.q_ref = np.asarray(q_ref, dtype=float).copy()
        self.weight = _nonneg("weight", weight)
        self.kp = _nonneg("kp", kp)
        self.kd = _nonneg("kd", kd)
        self._H = _readonly(2.0 * self.weight * np.eye(self.q_ref.size))

    def compute_qp_objective(self, state: ControlState) -> Objective:
        if self.q_ref.shape != state.q.shape:
            raise ControllerConfigError(f"posture q_ref must have shape {state.q.shape}, got {self.q_ref.shape}")
        target = self.kp * (self.q_ref - state.q) - self.kd * state.v
        return Objective(self._H, (-2.0 * self.weight) * target)


class DampingTask:
    """Joint damping: residual a + kd·v (a decays the velocity at rate kd [1/s])."""

    name = "damping"

    def __init__(self, weight: float = 1e-3, kd: float = 10.0) -> None:
        self.weight = _nonneg("weight", weight)
        self.kd = _nonneg("kd", kd)

    def compute_qp_objective(self, state: ControlState) -> Objective:
        n = state.v.size
        w2 = 2.0 * self.weight
        return Objective(w2 * np.eye(n), w2 * self.kd * state.v)


class AccelerationRegularization:
    """w·‖a‖²: the minimum-effort tie-breaker, keeps H ≻ 0 at singular poses."""

    name = "regularization"

    def __init__(self, weight: float = 1e-6) -> None:
        self.weight = _nonneg("weight", weight)
        if self.weight == 0:
            raise ControllerConfigError("regularization weight must be > 0")
        self._H: np.ndarray | None = None
        self._c: np.ndarray | None = None

    def compute_qp_objective(self, state: ControlState) -> Objective:
        n = state.v.size
        if self._H is None or self._c is None or self._H.shape[0] != n:
            self._H, self._c = _readonly(2.0 * self.weight * np.eye(n)), _readonly(np.zeros(n))
        return Objective(self._H, self._c)
