"""What ``mpcshare run`` sends on an effort interface (a ``Float64MultiArray`` of joint torques [N·m]).

Efforts are total joint torques, gravity included (the controller's τ = M(q)·a + h(q, v)). With the command's
``driver_compensates_gravity`` (drivers that add g(q) themselves, e.g. Franka's effort interface) g(q) of the
arm's model is subtracted from every effort sent, the stop's included. The protective stop's efforts brake the
arm to rest at q_stop and hold it there (:class:`robot.holding_torque.HoldingTorque`): the brake from the
measured (q, v); g(q) alone while the joint state is stale; zeros without an arm model (``source`` says which,
:data:`robot.holding_torque.SOURCES`). Never raises in the loop: a g(q) that cannot be computed is NaN, which
the loop turns into a stop.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from robot.holding_torque import HoldingTorque

__all__ = ["EffortCommand"]

_NOTES = {"brake": "", "gravity": "; stop torque: gravity alone (no fresh joint velocities)",
          "zero": "; stop torque: zeros (no arm model or joint state)"}


class EffortCommand:
    """The efforts of the module docstring for ``robot`` (a :class:`robot.description.RobotDescription`; None:
    no model, a stop of zeros) at the period ``period_s`` [s]; ``compensated``: ``driver_compensates_gravity``
    (ValueError naming ``where`` without a model)."""

    def __init__(self, robot: Any, period_s: float, n: int, *, compensated: bool = False, where: str = "") -> None:
        if compensated and robot is None:
            raise ValueError(f"{where} driver_compensates_gravity: needs the arm's model (the controller's robot), "
                             "and this controller has none")
        self.holding = HoldingTorque(robot, period_s) if robot is not None else None
        self.compensated, self.n = compensated, n
        self.source: str | None = None  # the last stop's

    def command(self, tau: np.ndarray, q: np.ndarray, q_last: np.ndarray | None) -> np.ndarray:
        """The controller's ``tau`` as sent: less g(q) when compensated (at ``q_last`` when ``q`` is not finite);
        NaN when g cannot be computed."""
        if not self.compensated:
            return tau
        if not np.isfinite(q).all() and q_last is not None:
            q = q_last
        try:
            return tau - self.holding.gravity(q)
        except Exception:  # noqa: BLE001 - the caller stops on a non-finite command
            return np.full_like(tau, np.nan)

    def stop(self, q: np.ndarray | None, v: np.ndarray | None, q_stop: np.ndarray | None) -> np.ndarray:
        """The stop's efforts from the last measured ``q``, ``v`` (None: unknown or stale) to rest at ``q_stop``;
        its source in ``source``; never raises."""
        n = self.n
        if self.holding is None:
            self.source = "zero"
            return np.zeros(n)
        q = q if q is not None else np.full(n, np.nan)
        v = v if v is not None else np.full(n, np.nan)
        tau, self.source = self.holding(q, v, q_stop if q_stop is not None else q)
        if self.compensated:  # g(q) alone, or zeros, is then zeros: the driver's own holding torque
            tau = self.command(tau, q, None) if self.source == "brake" else np.zeros(n)
            if not np.isfinite(tau).all():
                tau, self.source = np.zeros(n), "zero"
        return tau

    def note(self, values: dict[str, object]) -> str:
        """The last stop's source into ``values`` (``stop_torque``); the status message's note for a fallback."""
        if self.source is None:
            return ""
        values["stop_torque"] = self.source
        return _NOTES[self.source]
