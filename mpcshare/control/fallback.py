"""The last line of defence of :meth:`SharedController.step <mpcshare.control.controller.SharedController.step>`:
what an unexpected exception leaves to work with (``internal_error`` in the controller's status table)."""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from mpcshare.control.types import ControlCommand

__all__ = ["fallback_joint_state", "rest_command"]


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
