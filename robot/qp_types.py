"""Settings and results of :class:`robot.qp.QPController` (named, so that nothing is a bare tuple)."""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum
from typing import NamedTuple

import numpy as np

__all__ = ["QPConfig", "QPResult", "QPStatus", "Actuation", "VerifiedActuation", "RelaxedSolution"]


class Actuation(NamedTuple):
    """Joint acceleration a [rad/s²] and the torque τ = M(q)·a + h(q, v) [N·m] that produces it."""

    a: np.ndarray
    tau: np.ndarray


class VerifiedActuation(NamedTuple):
    """An :class:`Actuation` after clip-and-verify; ``ok`` False when the limits could not be met."""

    a: np.ndarray
    tau: np.ndarray
    ok: bool


class RelaxedSolution(NamedTuple):
    """Answer of the slack QP: a [rad/s²] and slack s ≥ 0 [rad/s²] (both None on failure),
    the solver's iterations and status text."""

    a: np.ndarray | None
    slack: np.ndarray | None
    iterations: int
    status: str


class QPStatus(str, Enum):
    """Outcome of one controller step (see the module docstring)."""

    OK = "ok"
    RECOVERING = "recovering"
    RELAXED = "relaxed"
    INVALID_REFERENCE = "invalid_reference"
    INVALID_STATE = "invalid_state"
    SOLVER_FAILED = "solver_failed"


@dataclass
class QPResult:
    """One control period's command.

    a [rad/s²], tau [N·m], v_next [rad/s], q_next [rad]; ``tip_error`` [m]
    ‖p_ref − p‖ at the current state (nan without reference); ``slack``
    [rad/s²] largest box relaxation; ``manipulability`` √det(J·Jᵀ) [m³];
    ``iterations`` of the solver; ``solve_time`` [s] of the whole step.
    """

    a: np.ndarray
    tau: np.ndarray
    v_next: np.ndarray
    q_next: np.ndarray
    status: QPStatus
    reason: str = ""
    tip_error: float = float("nan")
    slack: float = 0.0
    manipulability: float = float("nan")
    iterations: int = 0
    solve_time: float = 0.0

    @property
    def ok(self) -> bool:
        return self.status is QPStatus.OK


@dataclass
class QPConfig:
    """Controller settings.

    dt [s] control period; tip_kp [1/s²], tip_kd [1/s], tip_max_error [m]
    (None: no clipping); posture gains [1/s²], [1/s]; ``q_posture`` [rad]
    (None: middle of the joint range); slack weights ρ₁ (linear), ρ₂
    (quadratic); ``solver``: ``"auto"`` (default: DAQP if installed, else OSQP),
    ``"daqp"`` (dense active set, fastest), ``"osqp"`` (persistent workspace,
    warm-started) or ``"qpsolvers:<name>"``;
    ``eps`` OSQP tolerance.
    """

    dt: float = 0.01
    tip_weight: float = 1.0
    tip_kp: float = 400.0
    tip_kd: float = 40.0
    tip_max_error: float | None = 0.1
    posture_weight: float = 1e-4
    posture_kp: float = 25.0
    posture_kd: float = 10.0
    q_posture: np.ndarray | None = None
    damping_weight: float = 0.0
    damping_kd: float = 10.0
    regularization: float = 1e-6
    slack_linear: float = 1e4
    slack_quadratic: float = 1e2
    solver: str = "auto"
    eps: float = 1e-9
    singular_threshold: float = 1e-4
