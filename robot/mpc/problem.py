"""The tip-tracking optimal control problem of :class:`robot.mpc.tip_mpc.TipMPC`, in CasADi.

Decision variables: the joint accelerations a_0 … a_{H−1} [rad/s²], piecewise
constant over dt [s].  The state x_k = (q_k, v_k) follows exactly (the
dynamics are a double integrator in joint space, linear)

    v_{k+1} = v_k + a_k·dt,      q_{k+1} = q_k + v_k·dt + ½·a_k·dt²

from the measured x_0.  Cost, a sum of squares r(w)ᵀr(w) (Gauss–Newton ready):

    Σ_{k=1}^{H−1} w_p‖p(q_k) − p_ref,k‖² + w_T‖p(q_H) − p_ref,H‖²
      + w_a Σ_k ‖a_k‖² + w_j Σ_k ‖a_k − a_{k−1}‖²                (a_{−1} = a_prev)

Constraints (every node):

* torque  −τ_max ≤ M(q_k)·a_k + h(q_k, v_k) ≤ τ_max,   k = 0 … H−1;
* velocity  |v_k| ≤ v_max,                              k = 1 … H;
* acceleration  |a_k| ≤ a_max;
* viable position (k = 1 … H), per joint with braking deceleration A [rad/s²]:

      φ⁺ = q_k + v₊²/(2A) + v₊·dt/2 + A·dt²/8 ≤ q_max,   v₊ = max(v_k, 0)
      φ⁻ = q_k − v₋²/(2A) − v₋·dt/2 − A·dt²/8 ≥ q_min,   v₋ = max(−v_k, 0)

  (continuously differentiable).  It implies the QP's viable position limit
  (:func:`robot.constraints.viable_velocity_bound`: q + v²/(2A) + A·dt²/8 ≤
  q_max for v > 0, q ≤ q_max otherwise), so the MPC's first step is always
  admissible for the QP, and it is invariant under the discrete braking law
  a = max(−A, −v/dt) (v > 0; mirrored for v < 0): with a = −A, φ⁺ drops by
  A·dt²/2; with a = −v/dt (v⁺ = 0), by v²/(2A).

Recursive feasibility (of the exact problem, model = plant): if the previous
plan is feasible, the shifted plan with one braking step appended is feasible
now — braking keeps φ± within the limits (above), does not increase |v|,
uses |a| ≤ A ≤ a_max, and |a_i| ≤ A_i is torque-feasible at every q within
the limits and |v| ≤ v_max (the SuperLimb's braking accelerations are chosen
so; ``tests/robot/test_superlimb.py::test_braking_is_always_torque_feasible``).
With a real-time iteration the constraints hold to the linearisation error of
one SQP step (measured in the tests and the benchmark).

Two forms of the same problem are built here:

* :class:`CondensedProblem` — per-node CasADi functions (values and small
  Jacobians) plus the constant state sensitivities S = ∂X/∂w of the linear
  dynamics; the Gauss–Newton QP in the 3H accelerations is assembled with
  numpy (block products), the structure-exploiting way.  Letting CasADi
  differentiate the fully condensed expression instead gives a 416 000
  instruction graph (3.3 ms per evaluation; 390 s to compile with gcc -O1,
  still 1.9 ms) — measured and rejected.
* :func:`multiple_shooting_nlp` — the NLP over (x_0, a_0, x_1, …, x_H) with the
  dynamics as equality constraints, in the stage order fatrop's structure
  detection expects, for the ``nlpsol`` solvers (IPOPT, fatrop, sqpmethod).
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from robot.mpc.codegen import compiled
from robot.mpc.symbolic import SymbolicArm
from robot.superlimb import SuperLimbParams


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


def _state_rows(params: SuperLimbParams, dt: float, q: ca.SX, v: ca.SX) -> ca.SX:
    """(v, φ⁺, φ⁻) of one node, 9 rows (module docstring)."""
    A = ca.DM(params.braking_acceleration)
    margin = A * (dt * dt / 8.0)
    vp, vm = ca.fmax(v, 0.0), ca.fmax(-v, 0.0)
    up = q + vp * vp / (2.0 * A) + 0.5 * dt * vp + margin
    low = q - vm * vm / (2.0 * A) - 0.5 * dt * vm - margin
    return ca.vertcat(v, up, low)


def state_row_bounds(params: SuperLimbParams) -> tuple[np.ndarray, np.ndarray]:
    """Bounds of :func:`_state_rows`: |v| ≤ v_max, φ⁺ ≤ q_max, φ⁻ ≥ q_min."""
    inf = np.full(3, np.inf)
    v_max = params.velocity_limit
    return (np.concatenate([-v_max, -inf, params.lower]), np.concatenate([v_max, params.upper, inf]))


def pack_parameters(q0: np.ndarray, v0: np.ndarray, p_ref: np.ndarray, a_prev: np.ndarray) -> np.ndarray:
    """Parameter vector P = (q_0, v_0, p_ref (H+1, 3) row by row, a_prev) of both forms."""
    return np.concatenate([q0, v0, p_ref.reshape(-1), a_prev])


class CondensedProblem:
    """Gauss–Newton QP of the problem in the accelerations w = (a_0, …, a_{H−1}) (3H,).

    ``qp(w, q0, v0, p_ref, a_prev)`` returns the QP in the step Δ

        min ½ΔᵀHΔ + cᵀΔ   s.t.   lbA ≤ AΔ ≤ ubA,   lbx ≤ Δ ≤ ubx

    with H = JᵣᵀJᵣ, c = Jᵣᵀr and rows per node k (12 each): τ_k, then v, φ⁺,
    φ⁻ of node k+1, linearised at w.  One CasADi call (a node function mapped
    over the horizon, compiled to C when a compiler is available, see
    :mod:`robot.mpc.codegen`) evaluates every node's values and Jacobians with
    respect to its own (x, a); the chain rule through the constant
    sensitivities X = s₀(x₀) + S·w is numpy (batched blocks).  Arguments go
    through CasADi's zero-copy ``Function.buffer`` (converting numpy arrays to
    ``DM`` costs more than the evaluation).
    """

    # layout of one node's output column: name → (rows, shape)
    _LAYOUT = (("g", (12,)), ("Dgx", (3, 6)), ("M", (3, 3)), ("Dgs", (9, 6)), ("e", (3,)), ("De", (3, 3)),
               ("tip", (3,)), ("tip_next", (3,)))

    def __init__(self, params: SuperLimbParams, horizon: int, dt: float, weights: Weights,
                 codegen: bool = True) -> None:
        self.params, self.horizon, self.dt, self.weights = params, horizon, dt, weights
        H = horizon
        arm = SymbolicArm(params)
        x, a, xn, ref, s = ca.SX.sym("x", 6), ca.SX.sym("a", 3), ca.SX.sym("xn", 6), ca.SX.sym("r", 3), ca.SX.sym("s")
        tau = arm.inverse_dynamics(x[:3], x[3:], a)
        tip_next = arm.tip_position(xn[:3])
        e = s * (tip_next - ref)
        gs = _state_rows(params, dt, xn[:3], xn[3:])
        parts = {"g": ca.vertcat(tau, gs), "Dgx": ca.jacobian(tau, x), "M": ca.jacobian(tau, a),
                 "Dgs": ca.jacobian(gs, xn), "e": e, "De": ca.jacobian(e, xn[:3]),
                 "tip": arm.tip_position(x[:3]), "tip_next": tip_next}
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
        # zero-copy buffers: CasADi reads (6, H) column-major = numpy (H, 6) row-major
        self._x_now, self._a = np.zeros((H, 6)), np.zeros((H, 3))
        self._x_next, self._ref = np.zeros((H, 6)), np.zeros((H, 3))
        self._s = np.full(H, np.sqrt(weights.tracking))
        self._s[-1] = np.sqrt(weights.terminal)
        self._out = np.zeros((H, offset))
        self._buffer, self._eval = self.nodes.buffer()
        for i, arr in enumerate((self._x_now, self._a, self._x_next, self._ref, self._s)):
            self._buffer.set_arg(i, memoryview(arr))
        self._buffer.set_res(0, memoryview(self._out))

        # constant sensitivities of the exact double integrator: x_k = s0_k(x0) + Σ_{j<k} S[k, :, j] a_j
        n_w = 3 * H
        S = np.zeros((H + 1, 6, n_w))
        eye = np.eye(3)
        for k in range(H + 1):
            for j in range(k):
                S[k, :3, 3 * j:3 * j + 3] = (k - j - 0.5) * dt * dt * eye
                S[k, 3:, 3 * j:3 * j + 3] = dt * eye
        self.S = S
        self._S_now, self._S_next, self._Sq_next = S[:H], S[1:], np.ascontiguousarray(S[1:, :3, :])
        self._S_flat = S.reshape(6 * (H + 1), n_w)
        Phi = np.zeros((H + 1, 6, 6))  # x_k = Φ_k·x0 at zero acceleration: q0 + k·dt·v0, v0
        Phi[:, :, :] = np.eye(6)
        Phi[:, :3, 3:] = (np.arange(H + 1) * dt)[:, None, None] * eye
        self._Phi = Phi.reshape(6 * (H + 1), 6)
        self._diag = np.arange(H)
        # regularisation residuals r_reg = J_reg·w − b(a_prev): √w_a·a_k and √w_j·(a_k − a_{k−1})
        D = np.eye(n_w) - np.eye(n_w, k=-3)
        self._J_reg = np.vstack([np.sqrt(weights.acceleration) * np.eye(n_w), np.sqrt(weights.jerk) * D])
        self._H_reg = self._J_reg.T @ self._J_reg
        self._sj = float(np.sqrt(weights.jerk))
        lb_s, ub_s = state_row_bounds(params)
        tau_max = params.torque_limit
        self.lbg = np.tile(np.concatenate([-tau_max, lb_s]), H)
        self.ubg = np.tile(np.concatenate([tau_max, ub_s]), H)
        self.lbw = np.tile(-params.acceleration_limit, H)
        self.ubw = np.tile(params.acceleration_limit, H)
        self.n_w, self.n_g = n_w, 12 * H

    def states(self, w: np.ndarray, q0: np.ndarray, v0: np.ndarray) -> np.ndarray:
        """X (H+1, 6): x_k = (q_k, v_k) of the plan w from (q0, v0), X = Φ·x0 + S·w."""
        return (self._Phi @ np.concatenate([q0, v0]) + self._S_flat @ w).reshape(self.horizon + 1, 6)

    def evaluate(self, w: np.ndarray, X: np.ndarray, p_ref: np.ndarray) -> dict[str, np.ndarray]:
        """Per-node values and Jacobians at the plan (w, X (H+1, 6)), arrays (H, rows[, cols]) (views)."""
        self._x_now[:] = X[:-1]
        self._x_next[:] = X[1:]
        self._a[:] = w.reshape(self.horizon, 3)
        self._ref[:] = p_ref[1:]
        self._eval()
        out = self._out
        return {name: out[:, rows].reshape((self.horizon,) + shape) for name, (rows, shape) in self._slices.items()}

    def qp(self, w: np.ndarray, q0: np.ndarray, v0: np.ndarray, p_ref: np.ndarray, a_prev: np.ndarray):
        """(H, c, A, lbA, ubA, lbx, ubx, nodes, X) of the Gauss–Newton QP at w (class docstring)."""
        H = self.horizon
        X = self.states(w, q0, v0)
        nd = self.evaluate(w, X, p_ref)
        J_track = np.matmul(nd["De"], self._Sq_next).reshape(3 * H, self.n_w)
        J_tau = np.matmul(nd["Dgx"], self._S_now)
        J_tau.reshape(H, 3, H, 3)[self._diag, :, self._diag, :] += nd["M"]  # ∂τ_k/∂a_k = M(q_k)
        J_state = np.matmul(nd["Dgs"], self._S_next)
        A = np.concatenate([J_tau, J_state], axis=1).reshape(self.n_g, self.n_w)
        g = nd["g"].reshape(-1)
        r = nd["e"].reshape(-1)
        hess = J_track.T @ J_track + self._H_reg
        grad = J_track.T @ r + self._H_reg @ w
        grad[:3] -= self.weights.jerk * a_prev  # − J_regᵀ·b, b = √w_j·a_prev in the first jerk row
        return hess, grad, A, self.lbg - g, self.ubg - g, self.lbw - w, self.ubw - w, nd, X

    def cost(self, w: np.ndarray, nodes: dict[str, np.ndarray], a_prev: np.ndarray) -> float:
        """r(w)ᵀr(w) from evaluated nodes."""
        b = np.zeros(2 * self.n_w)
        b[self.n_w:self.n_w + 3] = self._sj * a_prev
        r_reg = self._J_reg @ w - b
        return float(nodes["e"].ravel() @ nodes["e"].ravel() + r_reg @ r_reg)

    def violation(self, g: np.ndarray, w: np.ndarray, nodes: int | None = None) -> dict[str, float]:
        """Largest violation per kind over the first ``nodes`` nodes (all if None).

        Torque [N·m], velocity [rad/s], position [rad] (of φ±), acceleration [rad/s²].
        """
        rows = 12 * (self.horizon if nodes is None else nodes)
        over = np.maximum(np.maximum(self.lbg[:rows] - g, g - self.ubg[:rows]), 0.0).reshape(-1, 12)
        return {"torque": float(over[:, :3].max()), "velocity": float(over[:, 3:6].max()),
                "position": float(over[:, 6:].max()),
                "acceleration": float(np.maximum(np.maximum(self.lbw[:w.size] - w, w - self.ubw[:w.size]), 0.0).max())}
