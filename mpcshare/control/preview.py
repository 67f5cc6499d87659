"""The MPC's preview of the tip reference over its horizon (the controller's module docstring, item 3):
r_k = p_s + R_bᵀ·(α·(p̂(t + τ + k·dt) − p̂(t + τ)) + β·û_v·k·dt), k = 0 … H, in the arm's model frame
(R_b: the base pose's rotation, plate ← model); else p_s + v_s·k·dt, the smoothed reference extrapolated
at its velocity."""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import numpy as np

from mpcshare.control.fastpath import FastPath
from mpcshare.control.forecast import TipTrajectory

__all__ = ["PreviewPlan", "mpc_preview"]


class PreviewPlan(NamedTuple):
    """The arbitration's output the preview is made from."""

    alpha: float  # the robot's share (0 when the forecast was unusable)
    beta: float  # the wearer's share
    u_v: np.ndarray  # (3,) the wearer's tip velocity [m/s], plate frame
    t_aim: float  # the aimed time t + τ [s] (NaN: no step yet)

    @classmethod
    def empty(cls) -> PreviewPlan:
        """Before the first step: no aimed time (the preview extrapolates the smoothed reference)."""
        return cls(0.0, 0.0, np.zeros(3), math.nan)


def mpc_preview(sm: Any, H: int, dt: float, plan: PreviewPlan, forecast: TipTrajectory, rotation: np.ndarray, *,
                enabled: bool, fast: FastPath | None = None, t_now: float = math.nan,
                mode_proba: np.ndarray | None = None) -> np.ndarray:
    """The MPC's reference (H+1, 3) [m], model frame, from the smoothed state ``sm`` (position, velocity).

    ``rotation``: R_b (3, 3); ``enabled``: the config's ``mpc_preview`` (False: extrapolation only);
    with ``fast`` the forecast is read only up to where it has skill in the current mode (at ``t_now``,
    posterior ``mode_proba``), held beyond.
    """
    k = np.arange(H + 1)[:, None] * dt
    if not (enabled and forecast.ready and math.isfinite(plan.t_aim)):
        return sm.position[None, :] + k * sm.velocity[None, :]
    times = plan.t_aim + k[:, 0]
    if fast is not None:  # the forecast where it has skill, a hold beyond
        times = np.minimum(times, max(fast.preview_until(t_now, mode_proba), plan.t_aim))
    p, _, _ = forecast.sample(times)
    if not math.isfinite(p.sum()):
        return sm.position[None, :] + k * sm.velocity[None, :]
    offset = plan.alpha * (p - p[0]) + plan.beta * k * plan.u_v[None, :]  # plate frame
    return sm.position[None, :] + offset @ rotation
