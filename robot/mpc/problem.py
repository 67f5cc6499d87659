"""The tip-tracking optimal control problem of :class:`robot.mpc.tip_mpc.TipMPC`, in CasADi.

Decision variables: joint accelerations a_0 … a_{H−1} [rad/s²], constant over dt [s]; from the
measured x_0 = (q_0, v_0):  v_{k+1} = v_k + a_k·dt,  q_{k+1} = q_k + v_k·dt + ½·a_k·dt².  Cost (a sum
of squares, Gauss–Newton ready; p [m] the tip in the model's world frame, a_{−1} = a_prev):

    Σ_{k=1}^{H−1} w_p‖p(q_k) − p_ref,k‖² + w_T‖p(q_H) − p_ref,H‖² + w_a Σ_k ‖a_k‖² + w_j Σ_k ‖a_k − a_{k−1}‖²

Constraints: torque −τ_max ≤ M(q_k)·a_k + h(q_k, v_k) ≤ τ_max (k < H); |a_k| ≤ a_max; for k = 1 … H
|v_k| ≤ v_max and the viable position, per joint with braking deceleration A [rad/s²]:

    q_k + v₊²/(2A) + v₊·dt/2 + A·dt²/8 ≤ q_max,  v₊ = max(v_k, 0)   (mirrored for q_min)

which implies the QP's bound (:func:`robot.constraints.viable_velocity_bound`) and is invariant
under braking, so the problem is recursively feasible (argument: docs/design.md, "The tip MPC").
:class:`CondensedProblem` gives per-node CasADi functions and the constant sensitivities ∂X/∂w for
a Gauss–Newton QP in the nH accelerations assembled with numpy; :class:`robot.mpc.nlp.NlpSolver`
poses the same problem as a multiple-shooting NLP for CasADi's ``nlpsol`` solvers.
Negative weights, or zero acceleration and jerk weights together, raise ``ValueError``.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from robot.description import RobotDescription
from robot.limits import JointLimits
from robot.mpc.codegen import compiled
from robot.mpc.symbolic import SymbolicArm


@dataclass(frozen=True)
class Weights:
    """Cost weights: tracking w_p [1/m²], terminal w_T [1/m²], acceleration w_a [s⁴/rad²], jerk w_j [s⁴/rad²]."""

    tracking: float = 1e4
    terminal: float = 1e5
    acceleration: float = 1e-5
    jerk: float = 1e-4

    def check(self) -> None:
        for name in ("tracking", "terminal", "acceleration", "jerk"):
            value = getattr(self, name)
            if not (np.isfinite(value) and value >= 0):
                raise ValueError(f"weight {name!r} must be finite and ≥ 0, got {value}")
        if self.acceleration <= 0 and self.jerk <= 0:
            raise ValueError("the acceleration or the jerk weight must be > 0 (keeps the Hessian positive definite)")


def _state_rows(limits: JointLimits, dt: float, q: ca.SX, v: ca.SX) -> ca.SX:
    """(v, φ⁺, φ⁻) of one node, 3n rows (module docstring)."""
    A = ca.DM(limits.a_brake)
    margin = A * (dt * dt / 8.0)
    vp, vm = ca.fmax(v, 0.0), ca.fmax(-v, 0.0)
    up = q + vp * vp / (2.0 * A) + 0.5 * dt * vp + margin
    low = q - vm * vm / (2.0 * A) - 0.5 * dt * vm - margin
    return ca.vertcat(v, up, low)


def state_row_bounds(limits: JointLimits) -> tuple[np.ndarray, np.ndarray]:
    """Bounds of :func:`_state_rows`: |v| ≤ v_max, φ⁺ ≤ q_max, φ⁻ ≥ q_min."""
    inf = np.full(limits.n, np.inf)
    v_max = limits.v_max
    return (np.concatenate([-v_max, -inf, limits.q_min]), np.concatenate([v_max, limits.q_max, inf]))


def pack_parameters(q0: np.ndarray, v0: np.ndarray, p_ref: np.ndarray, a_prev: np.ndarray) -> np.ndarray:
    """Parameter vector P = (q_0, v_0, p_ref (H+1, 3) row by row, a_prev) of both forms."""
    return np.concatenate([q0, v0, p_ref.reshape(-1), a_prev])


class CondensedProblem:
    """Gauss–Newton QP of the problem in the accelerations w = (a_0, …, a_{H−1}) (nH,), n joints.

    ``qp(w, q0, v0, p_ref, a_prev)`` returns the QP in the step Δ

        min ½ΔᵀHΔ + cᵀΔ   s.t.   lbA ≤ AΔ ≤ ubA,   lbx ≤ Δ ≤ ubx

    with H = JᵣᵀJᵣ, c = Jᵣᵀr and rows per node k (4n each): τ_k, then v, φ⁺,
    φ⁻ of node k+1, linearised at w.  One CasADi call (a node function mapped
    over the horizon, compiled to C when a compiler is available, see
    :mod:`robot.mpc.codegen`) evaluates every node's values and Jacobians with
    respect to its own (x, a); the chain rule through the constant
    sensitivities X = s₀(x₀) + S·w is numpy (batched blocks).  Arguments go
    through CasADi's zero-copy ``Function.buffer`` (converting numpy arrays to
    ``DM`` costs more than the evaluation).
    """

    def __init__(self, robot: RobotDescription, horizon: int, dt: float, weights: Weights,
                 codegen: bool = True) -> None:
        self.robot, self.horizon, self.dt, self.weights = robot, horizon, dt, weights
        H, n, lim = horizon, robot.n, robot.limits
        self.n = n
        # layout of one node's output column: name → (rows, shape)
        self._LAYOUT = (("g", (4 * n,)), ("Dgx", (n, 2 * n)), ("M", (n, n)), ("Dgs", (3 * n, 2 * n)), ("e", (3,)),
                        ("De", (3, n)), ("tip", (3,)), ("tip_next", (3,)))
        arm = SymbolicArm(robot)
        x, a, xn = ca.SX.sym("x", 2 * n), ca.SX.sym("a", n), ca.SX.sym("xn", 2 * n)
        ref, s = ca.SX.sym("r", 3), ca.SX.sym("s")
        tau = arm.inverse_dynamics(x[:n], x[n:], a)
        tip_next = arm.tip_position(xn[:n])
        e = s * (tip_next - ref)
        gs = _state_rows(lim, dt, xn[:n], xn[n:])
        parts = {"g": ca.vertcat(tau, gs), "Dgx": ca.jacobian(tau, x), "M": ca.jacobian(tau, a),
                 "Dgs": ca.jacobian(gs, xn), "e": e, "De": ca.jacobian(e, xn[:n]),
                 "tip": arm.tip_position(x[:n]), "tip_next": tip_next}
        # matrices are stored transposed (row-major) so that numpy reads them without a swap
        column = ca.cse(ca.densify(ca.vertcat(*[ca.vec(ca.densify(parts[name].T)) for name, _ in self._LAYOUT])))
        node = ca.Function("tip_mpc_node", [x, a, xn, ref, s], [column])
        node, self.evaluation = compiled(node, enable=codegen)
        self.nodes = node.map(H)
        self._slices = {}
        offset = 0
        for name, shape in self._LAYOUT:
            size = int(np.prod(shape))
            self._slices[name] = (slice(offset, offset + size), shape)
            offset += size
        self.node_rows = offset
        # zero-copy buffers: CasADi reads (2n, H) column-major = numpy (H, 2n) row-major
        self._x_now, self._a = np.zeros((H, 2 * n)), np.zeros((H, n))
        self._x_next, self._ref = np.zeros((H, 2 * n)), np.zeros((H, 3))
        self._s = np.full(H, np.sqrt(weights.tracking))
        self._s[-1] = np.sqrt(weights.terminal)
        self._out = np.zeros((H, offset))
        self._buffer, self._eval = self.nodes.buffer()
        for i, arr in enumerate((self._x_now, self._a, self._x_next, self._ref, self._s)):
            self._buffer.set_arg(i, memoryview(arr))
        self._buffer.set_res(0, memoryview(self._out))

        # constant sensitivities of the exact double integrator: x_k = s0_k(x0) + Σ_{j<k} S[k, :, j] a_j
        n_w = n * H
        S = np.zeros((H + 1, 2 * n, n_w))
        eye = np.eye(n)
        for k in range(H + 1):
            for j in range(k):
                S[k, :n, n * j:n * j + n] = (k - j - 0.5) * dt * dt * eye
                S[k, n:, n * j:n * j + n] = dt * eye
        self.S = S
        self._S_now, self._S_next, self._Sq_next = S[:H], S[1:], np.ascontiguousarray(S[1:, :n, :])
        self._S_flat = S.reshape(2 * n * (H + 1), n_w)
        Phi = np.zeros((H + 1, 2 * n, 2 * n))  # x_k = Φ_k·x0 at zero acceleration: q0 + k·dt·v0, v0
        Phi[:, :, :] = np.eye(2 * n)
        Phi[:, :n, n:] = (np.arange(H + 1) * dt)[:, None, None] * eye
        self._Phi = Phi.reshape(2 * n * (H + 1), 2 * n)
        self._diag = np.arange(H)
        # regularisation residuals r_reg = J_reg·w − b(a_prev): √w_a·a_k and √w_j·(a_k − a_{k−1})
        D = np.eye(n_w) - np.eye(n_w, k=-n)
        self._J_reg = np.vstack([np.sqrt(weights.acceleration) * np.eye(n_w), np.sqrt(weights.jerk) * D])
        self._H_reg = self._J_reg.T @ self._J_reg
        self._sj = float(np.sqrt(weights.jerk))
        lb_s, ub_s = state_row_bounds(lim)
        self.lbg = np.tile(np.concatenate([-lim.tau_max, lb_s]), H)
        self.ubg = np.tile(np.concatenate([lim.tau_max, ub_s]), H)
        self.lbw = np.tile(-lim.a_max, H)
        self.ubw = np.tile(lim.a_max, H)
        self.n_w, self.n_g = n_w, 4 * n * H

    def states(self, w: np.ndarray, q0: np.ndarray, v0: np.ndarray) -> np.ndarray:
        """X (H+1, 2n): x_k = (q_k, v_k) of the plan w from (q0, v0), X = Φ·x0 + S·w."""
        return (self._Phi @ np.concatenate([q0, v0]) + self._S_flat @ w).reshape(self.horizon + 1, 2 * self.n)

    def evaluate(self, w: np.ndarray, X: np.ndarray, p_ref: np.ndarray) -> dict[str, np.ndarray]:
        """Per-node values and Jacobians at the plan (w, X (H+1, 2n)), arrays (H, rows[, cols]) (views)."""
        self._x_now[:] = X[:-1]
        self._x_next[:] = X[1:]
        self._a[:] = w.reshape(self.horizon, self.n)
        self._ref[:] = p_ref[1:]
        self._eval()
        out = self._out
        return {name: out[:, rows].reshape((self.horizon,) + shape) for name, (rows, shape) in self._slices.items()}

    def qp(self, w: np.ndarray, q0: np.ndarray, v0: np.ndarray, p_ref: np.ndarray, a_prev: np.ndarray):
        """(H, c, A, lbA, ubA, lbx, ubx, nodes, X) of the Gauss–Newton QP at w (class docstring)."""
        H, n = self.horizon, self.n
        X = self.states(w, q0, v0)
        nd = self.evaluate(w, X, p_ref)
        J_track = np.matmul(nd["De"], self._Sq_next).reshape(3 * H, self.n_w)
        J_tau = np.matmul(nd["Dgx"], self._S_now)
        J_tau.reshape(H, n, H, n)[self._diag, :, self._diag, :] += nd["M"]  # ∂τ_k/∂a_k = M(q_k)
        J_state = np.matmul(nd["Dgs"], self._S_next)
        A = np.concatenate([J_tau, J_state], axis=1).reshape(self.n_g, self.n_w)
        g = nd["g"].reshape(-1)
        r = nd["e"].reshape(-1)
        hess = J_track.T @ J_track + self._H_reg
        grad = J_track.T @ r + self._H_reg @ w
        grad[:n] -= self.weights.jerk * a_prev  # − J_regᵀ·b, b = √w_j·a_prev in the first jerk row
        return hess, grad, A, self.lbg - g, self.ubg - g, self.lbw - w, self.ubw - w, nd, X

    def cost(self, w: np.ndarray, nodes: dict[str, np.ndarray], a_prev: np.ndarray) -> float:
        """r(w)ᵀr(w) from evaluated nodes."""
        b = np.zeros(2 * self.n_w)
        b[self.n_w:self.n_w + self.n] = self._sj * a_prev
        r_reg = self._J_reg @ w - b
        return float(nodes["e"].ravel() @ nodes["e"].ravel() + r_reg @ r_reg)

    def violation(self, g: np.ndarray, w: np.ndarray, nodes: int | None = None) -> dict[str, float]:
        """Largest violation per kind over the first ``nodes`` nodes (all if None).

        Torque [N·m], velocity [rad/s], position [rad] (of φ±), acceleration [rad/s²].
        """
        n = self.n
        rows = 4 * n * (self.horizon if nodes is None else nodes)
        over = np.maximum(np.maximum(self.lbg[:rows] - g, g - self.ubg[:rows]), 0.0).reshape(-1, 4 * n)
        return {"torque": float(over[:, :n].max()), "velocity": float(over[:, n:2 * n].max()),
                "position": float(over[:, 2 * n:].max()),
                "acceleration": float(np.maximum(np.maximum(self.lbw[:w.size] - w, w - self.ubw[:w.size]), 0.0).max())}
