"""The MPC problem as a multiple-shooting NLP for CasADi ``nlpsol`` (IPOPT, fatrop, sqpmethod).

Variables in stage order (x_0, a_0, x_1, a_1, …, x_{H−1}, a_{H−1}, x_H),
x_k = (q_k, v_k); per stage the constraints are the dynamics gap
x_{k+1} − F(x_k, a_k) = 0 first, then the path rows (x_0 = measured state at
stage 0, τ_k, and v, φ⁺, φ⁻ of x_k from stage 1 on), the terminal rows last:
the order fatrop's structure detection reads.  Cost and constraints are those
of :mod:`robot.mpc.problem` (exact Hessian here, solved to convergence), so
these solvers are the reference the real-time iteration is measured against.
Tolerances are absolute on a cost of order 1e4 (w_p = 1e4 /m²): fatrop's
1e-5 is where its dual infeasibility stalls; sqpmethod (exact Hessian,
regularised, DAQP subproblems, no line search) does not reach 1e-5 within
100 iterations here and reports failure (measured in ``benchmarks/bench_mpc.py``).
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from robot.description import RobotDescription
from robot.mpc.problem import Weights, _state_rows, state_row_bounds
from robot.mpc.symbolic import SymbolicArm

_OPTIONS = {
    "ipopt": {"ipopt": {"print_level": 0, "tol": 1e-8, "max_iter": 200, "warm_start_init_point": "yes",
                        "mu_init": 1e-3, "sb": "yes"}, "print_time": False},
    "fatrop": {"structure_detection": "auto", "fatrop": {"print_level": 0, "tol": 1e-5, "max_iter": 200},
               "print_time": False},
    "sqpmethod": {"qpsol": "daqp", "qpsol_options": {"error_on_fail": False},
                  "convexify_strategy": "regularize", "max_iter": 100, "print_header": False,
                  "print_iteration": False, "print_status": False, "print_time": False, "tol_pr": 1e-6,
                  "tol_du": 1e-5},
}


class NlpSolver:
    """``nlpsol(plugin)`` on the multiple-shooting NLP, warm-started (primal and dual)."""

    def __init__(self, plugin: str, robot: RobotDescription, horizon: int, dt: float, weights: Weights) -> None:
        H, n, lim = horizon, robot.n, robot.limits
        arm = SymbolicArm(robot)
        P = ca.SX.sym("P", 2 * n + 3 * (H + 1) + n)
        x0p, p_ref, a_prev = P[:2 * n], ca.reshape(P[2 * n:2 * n + 3 * (H + 1)], 3, H + 1), P[2 * n + 3 * (H + 1):]
        xs = [ca.SX.sym(f"x{k}", 2 * n) for k in range(H + 1)]
        as_ = [ca.SX.sym(f"a{k}", n) for k in range(H)]
        lb_s, ub_s = state_row_bounds(lim)
        tau_max = lim.tau_max
        w, g, lbg, ubg, eq = [], [], [], [], []
        cost = 0
        a_last = a_prev
        for k in range(H):
            x, a = xs[k], as_[k]
            w += [x, a]
            q, v = x[:n], x[n:]
            step = ca.vertcat(q + dt * v + 0.5 * dt * dt * a, v + dt * a)
            rows = [(xs[k + 1] - step, np.zeros(2 * n), np.zeros(2 * n), True)]
            if k == 0:
                rows.append((x - x0p, np.zeros(2 * n), np.zeros(2 * n), True))
            rows.append((arm.inverse_dynamics(q, v, a), -tau_max, tau_max, False))
            if k > 0:
                rows.append((_state_rows(lim, dt, q, v), lb_s, ub_s, False))
                cost += weights.tracking * ca.sumsqr(arm.tip_position(q) - p_ref[:, k])
            for expr, lo, hi, is_eq in rows:
                g.append(expr)
                lbg.append(lo)
                ubg.append(hi)
                eq += [is_eq] * int(expr.numel())
            cost += weights.acceleration * ca.sumsqr(a) + weights.jerk * ca.sumsqr(a - a_last)
            a_last = a
        w.append(xs[H])
        g.append(_state_rows(lim, dt, xs[H][:n], xs[H][n:]))
        lbg.append(lb_s)
        ubg.append(ub_s)
        eq += [False] * (3 * n)
        cost += weights.terminal * ca.sumsqr(arm.tip_position(xs[H][:n]) - p_ref[:, H])
        nlp = {"x": ca.vertcat(*w), "p": P, "f": cost, "g": ca.vertcat(*g)}
        opts = dict(_OPTIONS[plugin])
        if plugin == "fatrop":
            opts["equality"] = eq
        self.solver = ca.nlpsol(f"tip_mpc_{plugin}", plugin, nlp, opts)
        self.horizon, self.plugin = H, plugin
        self.lbg, self.ubg = np.concatenate(lbg), np.concatenate(ubg)
        n_x = 3 * n * H + 2 * n
        self.lbx, self.ubx = np.full(n_x, -np.inf), np.full(n_x, np.inf)
        a_idx = np.concatenate([3 * n * k + 2 * n + np.arange(n) for k in range(H)])
        self.lbx[a_idx] = np.tile(-lim.a_max, H)
        self.ubx[a_idx] = np.tile(lim.a_max, H)
        self.n = n
        self._a_idx = a_idx
        self._lam_x: np.ndarray | None = None
        self._lam_g: np.ndarray | None = None
        self._dt = dt

    def reset(self) -> None:
        self._lam_x = self._lam_g = None

    def solve(self, w0: np.ndarray, q: np.ndarray, v: np.ndarray, p_ref: np.ndarray,
              a_prev: np.ndarray) -> tuple[np.ndarray | None, int, str]:
        """(accelerations (nH,) or None, iterations, status) from the guess w0."""
        H, dt, n = self.horizon, self._dt, self.n
        x_guess = np.zeros(3 * n * H + 2 * n)
        qk, vk = q.copy(), v.copy()
        for k in range(H):
            a = w0[n * k:n * k + n]
            x_guess[3 * n * k:3 * n * (k + 1)] = np.concatenate([qk, vk, a])
            qk, vk = qk + dt * vk + 0.5 * dt * dt * a, vk + dt * a
        x_guess[3 * n * H:] = np.concatenate([qk, vk])
        args = {"x0": x_guess, "p": np.concatenate([q, v, p_ref.reshape(-1), a_prev]),
                "lbx": self.lbx, "ubx": self.ubx, "lbg": self.lbg, "ubg": self.ubg}
        if self._lam_g is not None:
            args["lam_x0"], args["lam_g0"] = self._lam_x, self._lam_g
        sol = self.solver(**args)
        stats = self.solver.stats()
        iterations = int(stats.get("iter_count", 0) or 0)
        if not stats.get("success", False):
            self.reset()
            return None, iterations, str(stats.get("return_status", "failed"))
        self._lam_x, self._lam_g = np.asarray(sol["lam_x"]).ravel(), np.asarray(sol["lam_g"]).ravel()
        return np.asarray(sol["x"]).ravel()[self._a_idx], iterations, "ok"
