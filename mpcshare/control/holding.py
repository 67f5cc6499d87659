"""Holding: what :meth:`SharedController.step <mpcshare.control.controller.SharedController.step>` does when it
cannot run a whole step (the status table of :mod:`mpcshare.control.types`): brake toward the smoothed reference
within the limits (:func:`brake`), and, as the last line of defence after an unexpected exception, the joint state
to brake from (:func:`fallback_joint_state`) and the command at rest when even the QP failed (:func:`rest_command`)."""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np

from mpcshare.control.keepout import KeepOut
from mpcshare.control.types import ControlCommand
from robot.kinematics import TipKinematics
from robot.qp import QPController, QPResult, QPStatus
from robot.smoothing import ReferenceSmoother

__all__ = ["brake", "fallback_joint_state", "rest_command"]


def brake(qp: QPController, keepout: KeepOut | None, smoother: ReferenceSmoother, tip: TipKinematics,
          q: np.ndarray, v: np.ndarray, faults: list[tuple[str, str]]) -> QPResult:
    """The QP braking (zero reference velocity and acceleration) toward the smoothed reference, or the measured tip
    before any reference (no target for a non-finite q); the keep-out's check after it; ``qp_failed`` appended
    when the solver failed."""
    q_ok = math.isfinite(q.sum())
    p_hold = smoother.state()[0] if smoother.initialized else tip.position(q) if q_ok else None
    res = qp.step(q, v, p_hold, np.zeros(3), np.zeros(3))
    if keepout is not None and q_ok and math.isfinite(v.sum()):
        res = keepout.check(qp, q, v, res, faults)
    if res.status is QPStatus.SOLVER_FAILED:
        faults.append(("qp_failed", res.reason))
    return res


def fallback_joint_state(q: Any, v: Any, n: int) -> tuple[np.ndarray, np.ndarray]:
    """(q, v) as (n,) float arrays to brake from; both NaN (the QP holds) when either is unusable."""
    try:
        qa, va = (np.asarray(x, dtype=float).reshape(n) for x in (q, v))
    except Exception:  # noqa: BLE001 — q, v unusable: hold
        qa = va = np.full(n, np.nan)
    return qa, va


def rest_command(n: int, last: ControlCommand | None, mode_proba: np.ndarray, novelty: float, reason: str,
                 t0: float) -> ControlCommand:
    """When even the QP failed: zero torque, velocity and acceleration at the last commanded position
    (zeros before any command), α = 0, β = 1, status ``internal_error``; ``t0``: the step's start
    (``time.perf_counter``) for the ``total`` timing [s]."""
    z = np.zeros(n)
    return ControlCommand(z, last.q_cmd if last else z, z, z, 0.0, 1.0, mode_proba.copy(), novelty,
                          np.full(3, np.nan), "internal_error", (reason,), {"total": time.perf_counter() - t0})
