"""QP constraints on the joint acceleration a [rad/s²], each a small object.

Every limit returns its rows as a named :class:`Constraint` ``(G, h)`` meaning
``G·a ≤ h`` for the current :class:`~robot.state.ControlState`, from
``compute_qp_inequalities(state)`` (the names of mink and pink).  The kinematic
ones are per-joint intervals and also expose ``bounds(state) -> Bounds(lo, hi)``;
the controller intersects those in priority order (see
:func:`intersect_by_priority`) so that a state outside the limits still gives a
well-defined, non-empty box.  Returned arrays are read-only.

One control period dt [s] with constant acceleration a is integrated exactly:

    v⁺ = v + a·dt,      q⁺ = q + v·dt + ½·a·dt² = q + dt·(v + v⁺)/2
"""

from __future__ import annotations

import math
from typing import NamedTuple, Protocol, Sequence, runtime_checkable

import numpy as np

from .limits import JointLimits
from .state import ControlState


def _readonly(*arrays: np.ndarray) -> None:
    for a in arrays:
        a.flags.writeable = False


class Constraint(NamedTuple):
    """Linear inequality rows on the joint acceleration: ``G·a ≤ h``; G (m, n), h (m,)."""

    G: np.ndarray
    h: np.ndarray


class Bounds(NamedTuple):
    """A per-joint interval ``lo ≤ a ≤ hi`` [rad/s²], each (n,)."""

    lo: np.ndarray
    hi: np.ndarray


class PriorityBox(NamedTuple):
    """Result of :func:`intersect_by_priority`: the box ``lo ≤ a ≤ hi`` and, per joint,
    ``conflict`` = how many lower-priority intervals had to be collapsed (0: none)."""

    lo: np.ndarray
    hi: np.ndarray
    conflict: np.ndarray


@runtime_checkable
class Limit(Protocol):
    """Anything that gives a fixed number of rows ``G·a ≤ h`` for the current state."""

    name: str

    def num_rows(self, n: int) -> int: ...

    def compute_qp_inequalities(self, state: ControlState) -> Constraint: ...


class BoxConstraint:
    """A per-joint interval lo ≤ a ≤ hi; rows are ``[I; −I]·a ≤ [hi; −lo]``.

    Subclasses implement :meth:`bounds`.
    """

    name = "box"

    def bounds(self, state: ControlState) -> Bounds:
        raise NotImplementedError(f"{type(self).__name__} must implement bounds(state)")

    def num_rows(self, n: int) -> int:
        return 2 * n

    def compute_qp_inequalities(self, state: ControlState) -> Constraint:
        lo, hi = self.bounds(state)
        eye = np.eye(lo.size)
        G, h = np.vstack([eye, -eye]), np.concatenate([hi, -lo])
        _readonly(G, h)
        return Constraint(G, h)


class AccelerationLimit(BoxConstraint):
    """|a_i| ≤ a_max,i [rad/s²]."""

    name = "acceleration"

    def __init__(self, limits: JointLimits) -> None:
        self.a_max = limits.a_max
        self._neg = -self.a_max
        _readonly(self._neg)

    def bounds(self, state: ControlState) -> Bounds:
        return Bounds(self._neg, self.a_max)


class VelocityLimit(BoxConstraint):
    """|v⁺_i| ≤ v_max,i [rad/s]  ⇔  (−v_max − v)/dt ≤ a ≤ (v_max − v)/dt."""

    name = "velocity"

    def __init__(self, limits: JointLimits) -> None:
        self.v_max = limits.v_max

    def bounds(self, state: ControlState) -> Bounds:
        inv_dt = 1.0 / state.dt
        return Bounds((-self.v_max - state.v) * inv_dt, (self.v_max - state.v) * inv_dt)


def viable_velocity_bound(gap: np.ndarray, v: np.ndarray, dt: float, a_brake: np.ndarray) -> np.ndarray:
    """Largest next velocity v⁺ [rad/s] toward a limit at distance ``gap`` = q_lim − q [rad].

    After the step the arm must still be able to stop before the limit by
    decelerating at a_brake (A).  With exact integration, braking at A from
    v⁺ > 0 covers at most v⁺²/(2A) + A·dt²/8 (the last partial step adds at
    most A·dt²/8), so we require (q⁺ the position after this step)

        v⁺ ≤ 0   or   q⁺ + v⁺²/(2A) + A·dt²/8 ≤ q_lim,

    and always q⁺ ≤ q_lim.  Substituting q⁺ = q + dt(v + v⁺)/2 the second
    condition is a quadratic in v⁺ whose discriminant simplifies, so the union
    is exactly (no linearisation needed, per joint)

        v⁺ ≤ max(0, (−A·dt + sqrt(8A·(gap − v·dt/2)))/2)     and
        v⁺ ≤ 2·gap/dt − v                                       (q⁺ ≤ q_lim).

    The set {v ≤ 0 or q + v²/(2A) + A·dt²/8 ≤ q_lim} is invariant under
    braking a = max(−A, −v/dt), so the constraint stays feasible forever when
    A is available (torque-feasible).
    """
    d = np.maximum(gap - 0.5 * dt * v, 0.0)
    u_viable = np.maximum(0.0, 0.5 * (np.sqrt(8.0 * a_brake * d) - a_brake * dt))
    return np.minimum(u_viable, 2.0 * gap / dt - v)


class PositionLimit(BoxConstraint):
    """q_min ≤ q⁺ ≤ q_max, jointly viable with braking at a_brake [rad/s²].

    See :func:`viable_velocity_bound` for the upper side; the lower side is its
    mirror image (q → −q).  Returns a ≤ (u_up − v)/dt and a ≥ (−u_low − v)/dt.
    """

    name = "position"

    def __init__(self, limits: JointLimits) -> None:
        self.q_min, self.q_max, self.a_brake = limits.q_min, limits.q_max, limits.a_brake
        self._q_min, self._q_max, self._a = self.q_min.tolist(), self.q_max.tolist(), self.a_brake.tolist()

    def bounds(self, state: ControlState) -> Bounds:
        # Scalar loop: for a handful of joints plain floats are ~10× faster than numpy calls.
        dt = state.dt
        inv_dt = 1.0 / dt
        lo, hi = [], []
        for q, v, q_lo, q_hi, a in zip(state.q.tolist(), state.v.tolist(), self._q_min, self._q_max, self._a):
            u_up = _viable_bound_scalar(q_hi - q, v, dt, a)
            u_low = _viable_bound_scalar(q - q_lo, -v, dt, a)
            lo.append((-u_low - v) * inv_dt)
            hi.append((u_up - v) * inv_dt)
        return Bounds(np.array(lo), np.array(hi))


def _viable_bound_scalar(gap: float, v: float, dt: float, a_brake: float) -> float:
    """Scalar twin of :func:`viable_velocity_bound` (same formula, tested to agree)."""
    d = gap - 0.5 * dt * v
    u_viable = max(0.0, 0.5 * (math.sqrt(8.0 * a_brake * d) - a_brake * dt)) if d > 0.0 else 0.0
    return min(u_viable, 2.0 * gap / dt - v)


class TorqueLimit:
    """|τ_i| ≤ τ_max,i [N·m] with τ = M(q)·a + h(q, v):  [M; −M]·a ≤ [τ_max − h; τ_max + h]."""

    name = "torque"

    def __init__(self, limits: JointLimits) -> None:
        self.tau_max = limits.tau_max

    def num_rows(self, n: int) -> int:
        return 2 * n

    def compute_qp_inequalities(self, state: ControlState) -> Constraint:
        M, h = state.M, state.h
        G, ub = np.concatenate([M, -M]), np.concatenate([self.tau_max - h, self.tau_max + h])
        _readonly(G, ub)
        return Constraint(G, ub)


def intersect_by_priority(boxes: Sequence[tuple[np.ndarray, np.ndarray]]) -> PriorityBox:
    """Intersect intervals in priority order, first = most important.

    Where a lower-priority interval does not meet the running intersection
    (the state is outside that limit, e.g. a start beyond a position limit),
    the running interval collapses to its end point nearest to it: maximum
    effort toward satisfying the violated limit without breaking the more
    important ones.  An interval that is itself empty (lo > hi) is replaced by
    its midpoint.  Returns ``PriorityBox(lo, hi, conflict)`` with ``conflict[i]``
    the number of intervals that had to be collapsed for joint i.
    """
    lo, hi = boxes[0]
    for c_lo, c_hi in boxes[1:]:  # fast path: the plain intersection is what the priority gives when non-empty
        lo, hi = np.maximum(lo, c_lo), np.minimum(hi, c_hi)
    if bool((lo <= hi).all()):
        return PriorityBox(lo, hi, np.zeros(lo.size, dtype=int))
    lo, hi = boxes[0]
    conflict = np.zeros(lo.size, dtype=int)
    for c_lo, c_hi in boxes[1:]:
        bad = c_lo > c_hi
        if bad.any():
            mid = 0.5 * (c_lo + c_hi)
            c_lo, c_hi = np.where(bad, mid, c_lo), np.where(bad, mid, c_hi)
        below = c_hi < lo  # wants less than we may give: pin at lo
        above = c_lo > hi  # wants more: pin at hi
        new_lo = np.where(below, lo, np.where(above, hi, np.maximum(lo, c_lo)))
        new_hi = np.where(below, lo, np.where(above, hi, np.minimum(hi, c_hi)))
        conflict += below | above | bad
        lo, hi = new_lo, new_hi
    return PriorityBox(lo, hi, conflict)


class DefaultConstraints(NamedTuple):
    """The controller's default limits: ``boxes`` in priority order, ``rows`` the general ones."""

    boxes: list[BoxConstraint]
    rows: list[Limit]


def default_constraints(limits: JointLimits) -> DefaultConstraints:
    """Box constraints in priority order (acceleration, velocity, position) and the torque limit."""
    return DefaultConstraints([AccelerationLimit(limits), VelocityLimit(limits), PositionLimit(limits)],
                              [TorqueLimit(limits)])
