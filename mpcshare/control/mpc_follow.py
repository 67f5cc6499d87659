"""Following the tip MPC's plan: solve on a preview every n-th step, hand the QP its references.

Every ``every`` steps :meth:`MPCFollower.step` solves ``mpc.solve(q, v, preview, deadline_s)``
on the preview (H+1, 3) [m] (model frame) the controller builds; in between it follows the
last plan shifted by the steps since it was solved. The QP's references at t + dt are the
plan's tip at step j + 1 with central differences (dt the control period):

    p = x_{j+1},   ṗ = (x_{j+2} − x_j)/(2·dt),   p̈ = (x_{j+2} − 2·x_{j+1} + x_j)/dt²

A failed or late solve returns None with a fault (``mpc_failed`` / ``mpc_timeout``): the QP then
tracks the smoothed reference alone. It never raises.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from mpcshare.errors import ControllerSetupError

__all__ = ["MPCFollower"]

Fault = tuple[str, str]


class MPCFollower:
    """The MPC's plan for the QP (module docstring). ``mpc``: an object with ``solve`` and ``horizon``."""

    def __init__(self, mpc: Any, dt: float, deadline_s: float, every: int = 1) -> None:
        if not (hasattr(mpc, "solve") and int(getattr(mpc, "horizon", 0)) >= 2):
            raise ControllerSetupError("mpc must have solve(q, v, p_ref, deadline_s) and a horizon of at least 2 steps")
        self.mpc, self.dt, self.deadline_s, self.every = mpc, float(dt), float(deadline_s), max(int(every), 1)
        self.reset()

    @property
    def horizon(self) -> int:
        return int(self.mpc.horizon)

    def reset(self) -> None:
        """Forget the plan (and reset the MPC's warm start when it has one)."""
        self._plan: np.ndarray | None = None
        self._age = 0
        if hasattr(self.mpc, "reset"):
            self.mpc.reset()

    def step(self, q: np.ndarray, v: np.ndarray, make_preview: Callable[[int], np.ndarray],
             faults: list[Fault]) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
        """(p, ṗ, p̈) for the QP at t + dt, or None (fault appended) when there is no usable plan."""
        H = self.horizon
        if self._plan is not None and 0 < self._age < self.every and self._age + 2 <= H:
            j = self._age
            self._age += 1
            return self._reference(self._plan, j)
        self._plan, self._age = None, 0
        try:
            r = self.mpc.solve(q, v, make_preview(H), deadline_s=self.deadline_s)
        except Exception as exc:  # noqa: BLE001 — the QP takes over
            faults.append(("mpc_failed", f"MPC raised {type(exc).__name__}: {exc}; QP tracks the smoothed reference"))
            return None
        timed_out = r.solve_time > self.deadline_s or "time" in str(r.status).lower()
        if not r.ok or not np.all(np.isfinite(r.tip_plan)):
            faults.append(("mpc_timeout" if timed_out else "mpc_failed",
                           f"MPC {r.status}; QP tracks the smoothed reference"))
            return None
        if timed_out:
            faults.append(("mpc_timeout", f"MPC took {r.solve_time * 1e3:.2f} ms > deadline; "
                                          "QP tracks the smoothed reference"))
            return None
        self._plan, self._age = np.asarray(r.tip_plan, dtype=float), 1
        return self._reference(self._plan, 0)

    def _reference(self, tp: np.ndarray, j: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        dt = self.dt
        return tp[j + 1], (tp[j + 2] - tp[j]) / (2 * dt), (tp[j + 2] - 2 * tp[j + 1] + tp[j]) / dt ** 2
