"""The tip MPC with the wearer's body zones as constraints over its horizon.

:class:`KeepOutTipMPC` is :class:`robot.mpc.tip_mpc.TipMPC` whose Gauss–Newton QP gets,
per node k = 1 … H and zone z, the linearised clearance of the knife tip to the zone
*where the zone will be* (constant-velocity forecast, e.g. the fork's Kalman velocity):

    c_z,k = c_z + v_z·k·dt,   d_k = ‖p(q_k) − c_z,k‖ − r_z − margin ≥ 0
    ⇒  −n_kᵀ·J(q_k)·S_q,k·Δw ≤ d_k                      (n_k = unit(p(q_k) − c_z,k))

with c_z,k the closest point of the zone's (moved) axis, J the tip Jacobian (the node
function's ∂e/∂q divided by the tracking weight's root) and S_q,k the constant
sensitivity of q_k to the accelerations.  The MPC so starts yielding before the hand
arrives, where a one-step filter would have to brake.  The blade behind the tip and
anything the linearisation misses stay with the QP's keep-out rows
(:mod:`robot.keepout`), which filter the MPC's first step as before.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

from robot.keepout import Zone
from robot.mpc.qp import ConicQP, DaqpQP
from robot.mpc.tip_mpc import RTI_SOLVERS, TipMPC

__all__ = ["KeepOutTipMPC"]


class _ZonedProblem:
    """A :class:`~robot.mpc.problem.CondensedProblem` whose ``qp`` also returns the zone rows."""

    def __init__(self, inner, max_zones: int, margin: float, active_distance: float) -> None:
        self.inner, self.max_zones, self.margin, self.active = inner, int(max_zones), float(margin), active_distance
        self.zones: list[Zone] = []

    def __getattr__(self, name: str):
        return getattr(self.inner, name)

    def qp(self, w: np.ndarray, q0: np.ndarray, v0: np.ndarray, p_ref: np.ndarray, a_prev: np.ndarray):
        hess, grad, A, lbA, ubA, lbx, ubx, nd, X = self.inner.qp(w, q0, v0, p_ref, a_prev)
        inner, H = self.inner, self.inner.horizon
        rows = np.zeros((H * self.max_zones, inner.n_w))
        ub = np.full(H * self.max_zones, 1e30)
        tips = nd["tip_next"]
        J = nd["De"] / inner._s[:, None, None]  # ∂p/∂q at q_{k+1}
        JS = np.matmul(J, inner._Sq_next)  # (H, 3, n_w)
        t_k = (np.arange(H) + 1.0) * inner.dt
        for i, z in enumerate(self.zones):
            a = z.a[None, :] + t_k[:, None] * z.velocity[None, :]
            axis = z.b - z.a
            L2 = float(axis @ axis)
            s = np.clip(((tips - a) @ axis) / L2, 0.0, 1.0) if L2 > 1e-18 else np.zeros(H)
            diff = tips - (a + s[:, None] * axis[None, :])
            dist = np.linalg.norm(diff, axis=1)
            n = diff / np.maximum(dist, 1e-9)[:, None]
            d = dist - z.radius - self.margin
            live = d < self.active
            blk = slice(i * H, (i + 1) * H)
            rows[blk] = np.where(live[:, None], -np.einsum("ki,kin->kn", n, JS), 0.0)
            ub[blk] = np.where(live, d, 1e30)
        A = np.vstack([A, rows])
        lbA = np.concatenate([lbA, np.full(ub.size, -1e30)])
        ubA = np.concatenate([ubA, ub])
        return hess, grad, A, lbA, ubA, lbx, ubx, nd, X


class KeepOutTipMPC(TipMPC):
    """:class:`TipMPC` with zone constraints over the horizon (module docstring).

    ``max_zones``: the row budget (H rows per zone); ``margin`` [m] beyond each zone;
    ``active_distance`` [m]: zones farther at every node give no rows. Only the real-time
    iteration solvers (:data:`robot.mpc.tip_mpc.RTI_SOLVERS`) take the rows. Give the zones
    of each solve with :meth:`set_zones` (model world frame, with their velocities).
    """

    def __init__(self, *args, max_zones: int = 4, margin: float = 0.02, active_distance: float = 0.25,
                 **kwargs) -> None:
        super().__init__(*args, **kwargs)
        if self.solver not in RTI_SOLVERS:
            raise ValueError(f"zone constraints need a real-time iteration solver {RTI_SOLVERS}, got {self.solver!r}")
        self.problem = _ZonedProblem(self.problem, max_zones, margin, active_distance)
        n_w, m = self.problem.n_w, self.problem.n_g + self.horizon * int(max_zones)
        if self.solver == "rti-daqp":
            self._qp = DaqpQP(n_w, m)
        else:
            self._qp = ConicQP(self.solver.removeprefix("rti-").removeprefix("casadi-"), n_w, m)

    def set_zones(self, zones: Sequence[Zone]) -> None:
        """The zones of the next solve (model world frame; at most ``max_zones``)."""
        if len(zones) > self.problem.max_zones:
            raise ValueError(f"{len(zones)} zones given, max_zones is {self.problem.max_zones}")
        self.problem.zones = list(zones)
