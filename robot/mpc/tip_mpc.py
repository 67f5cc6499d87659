"""Knife-tip MPC: joint accelerations over a short horizon, within every joint limit.

:class:`TipMPC` plans H piecewise-constant joint accelerations (dt [s]) that track a knife-tip
reference p_ref (H+1, 3) [m] in the Pinocchio model's world frame, within the position (viable,
with braking), velocity, acceleration and torque limits at every node; the problem, its terminal
and braking condition and why it stays feasible are in :mod:`robot.mpc.problem`.

Solvers (``solver=``):

* ``"rti-<qp>"`` — real-time iteration: Gauss–Newton SQP on the condensed problem, warm-started
  from the previous plan shifted by one step (a braking step appended), ``max_iterations`` QP
  solves per call (1 = RTI), stopping early when the step is below ``tolerance``. ``<qp>``:
  ``daqp`` (the DAQP package, warm-started working set; the default ``rti-daqp``), or a CasADi
  ``conic`` plugin through zero-copy buffers: ``qpoases``, ``osqp``, ``casadi-daqp``.
* ``"ipopt"``, ``"fatrop"``, ``"sqpmethod"`` — CasADi ``nlpsol`` on the multiple-shooting NLP,
  solved to convergence from the shifted warm start.

The default was chosen by measurement (``benchmarks/bench_mpc.py``; docs/results.md, "Benchmarks").
``solve`` never raises for runtime data (non-finite or mis-shaped inputs, solver failures, time-outs):
it returns ``ok=False`` and a status saying why. Bad settings (solver, horizon, dt) raise ``ValueError``.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from robot.default_arm import as_description
from robot.description import RobotDescription
from robot.mpc.problem import CondensedProblem, Weights
from robot.mpc.qp import ConicQP, DaqpQP

RTI_SOLVERS = ("rti-daqp", "rti-qpoases", "rti-osqp", "rti-casadi-daqp")
NLP_SOLVERS = ("ipopt", "fatrop", "sqpmethod")
SOLVERS = RTI_SOLVERS + NLP_SOLVERS
DEFAULT_SOLVER = "rti-daqp"


@dataclass
class MPCResult:
    """One MPC solve.

    ``a`` (n,) first joint acceleration [rad/s²]; ``q_plan``, ``v_plan`` (H+1, n)
    planned joint positions [rad] and velocities [rad/s], ``tip_plan`` (H+1, 3)
    planned tip positions [m] (row 0: the given state); ``ok``; ``status`` ("ok"
    or why not); ``solve_time`` [s]; ``iterations`` (SQP iterations, or the
    NLP solver's); ``qp_iterations`` (active-set/interior-point iterations,
    summed); ``violation`` the largest constraint violation of the plan per
    kind (torque [N·m], velocity [rad/s], position [rad], acceleration [rad/s²]);
    ``tracking_error`` ‖tip_plan − p_ref‖ at node 1 [m].
    """

    a: np.ndarray
    q_plan: np.ndarray
    v_plan: np.ndarray
    tip_plan: np.ndarray
    ok: bool
    status: str
    solve_time: float
    iterations: int
    qp_iterations: int = 0
    violation: dict[str, float] = field(default_factory=dict)
    tracking_error: float = float("nan")


class TipMPC:
    """Tip-tracking MPC of any arm (module docstring).

    Parameters: ``robot`` (:class:`~robot.description.RobotDescription`; None or a
    ``SuperLimbParams``: the SuperLimb; ``params`` is the old name of the argument);
    ``horizon`` H ≥ 2 steps; ``dt`` [s]; ``solver`` one of :data:`SOLVERS`;
    ``weights`` (:class:`~robot.mpc.problem.Weights`);
    ``max_iterations`` SQP iterations per solve for the RTI solvers (1 = RTI);
    ``tolerance`` [rad/s²] step size that ends the SQP loop early;
    ``violation_tolerance`` the first step's constraint violation (relative to
    each limit; τ_0 is linear in a_0, so the QP meets it to its tolerance) above
    which a solve reports ``ok=False`` (later nodes: linearisation error of the
    real-time iteration, reported in ``MPCResult.violation``); ``codegen`` compile the
    model to C (cached; falls back to the CasADi virtual machine).
    """

    def __init__(self, robot: RobotDescription | None = None, horizon: int = 20, dt: float = 0.01,
                 solver: str = DEFAULT_SOLVER, weights: Weights | None = None, max_iterations: int = 1,
                 tolerance: float = 1e-6, violation_tolerance: float = 1e-6, codegen: bool = True,
                 params=None) -> None:
        if solver not in SOLVERS:
            raise ValueError(f"unknown MPC solver {solver!r}; valid choices: {', '.join(SOLVERS)}")
        if isinstance(horizon, bool) or not isinstance(horizon, (int, np.integer)) or horizon < 2:
            raise ValueError(f"horizon must be an integer ≥ 2 (steps of dt), got {horizon!r}")
        if not (isinstance(dt, (int, float)) and math.isfinite(dt) and dt > 0):
            raise ValueError(f"dt must be a finite number > 0 [s], got {dt!r}")
        if isinstance(max_iterations, bool) or not isinstance(max_iterations, int) or max_iterations < 1:
            raise ValueError(f"max_iterations must be an integer ≥ 1, got {max_iterations!r}")
        if not (math.isfinite(tolerance) and tolerance >= 0):
            raise ValueError(f"tolerance must be finite and ≥ 0, got {tolerance!r}")
        self.robot = as_description(robot if robot is not None else params)
        self.params = getattr(self.robot, "params", None)  # the SuperLimb's parameters (None for other arms)
        self.n = self.robot.n
        self.horizon, self.dt, self.solver = int(horizon), float(dt), solver
        self.weights = weights or Weights()
        self.weights.check()
        self.max_iterations, self.tolerance = max_iterations, float(tolerance)
        self.violation_tolerance = float(violation_tolerance)
        self.problem = CondensedProblem(self.robot, self.horizon, self.dt, self.weights, codegen=codegen)
        self.evaluation_ = self.problem.evaluation
        n_w, n_g = self.problem.n_w, self.problem.n_g
        self._nlp = None
        if solver == "rti-daqp":
            self._qp = DaqpQP(n_w, n_g)
        elif solver in RTI_SOLVERS:
            self._qp = ConicQP(solver.removeprefix("rti-").removeprefix("casadi-"), n_w, n_g)
        else:
            from robot.mpc.nlp import NlpSolver

            self._qp = None
            self._nlp = NlpSolver(solver, self.robot, self.horizon, self.dt, self.weights)
        lim = self.robot.limits
        self._a_brake = lim.a_brake
        self._scale = {"torque": lim.tau_max.min(), "velocity": lim.v_max.min(),
                       "position": 1.0, "acceleration": lim.a_max.min()}
        self._guess: np.ndarray | None = None
        self._a_prev = np.zeros(self.n)

    # ------------------------------------------------------------------
    def reset(self) -> None:
        """Forget the warm start (plan, QP working set, last acceleration)."""
        self._guess = None
        self._a_prev = np.zeros(self.n)
        if self._qp is not None:
            self._qp.reset()
        if self._nlp is not None:
            self._nlp.reset()

    def _braking_plan(self, v: np.ndarray) -> np.ndarray:
        """w (nH,) braking with a = clip(−v/dt, ±A) each step (the cold start; feasible from a viable state)."""
        w = np.empty((self.horizon, self.n))
        for k in range(self.horizon):
            a = np.clip(-v / self.dt, -self._a_brake, self._a_brake)
            w[k] = a
            v = v + a * self.dt
        return w.reshape(-1)

    def _shifted(self, w: np.ndarray, v_end: np.ndarray) -> np.ndarray:
        """Previous plan shifted by one step, a braking step appended (the recursive-feasibility candidate)."""
        tail = np.clip(-v_end / self.dt, -self._a_brake, self._a_brake)
        return np.concatenate([w[self.n:], tail])

    def _check(self, q: object, v: object, p_ref: object) -> tuple[np.ndarray, np.ndarray, np.ndarray] | str:
        shapes = {"q": (self.n,), "v": (self.n,), "p_ref": (self.horizon + 1, 3)}
        arrays = []
        for name, value in (("q", q), ("v", v), ("p_ref", p_ref)):
            try:
                arr = np.asarray(value, dtype=float)
            except (TypeError, ValueError):
                return f"invalid_input: {name} is not numeric"
            if arr.shape != shapes[name]:
                return f"invalid_input: {name} has shape {arr.shape}, expected {shapes[name]}"
            if not np.isfinite(arr).all():
                return f"invalid_input: {name} is not finite"
            arrays.append(arr)
        return arrays[0], arrays[1], arrays[2]

    def _failure(self, status: str, t0: float, q: object = None, v: object = None,
                 iterations: int = 0, qp_iterations: int = 0) -> MPCResult:
        """ok=False; the plan is the braking plan where the state is usable, else NaN."""
        self._guess = None
        H, n = self.horizon, self.n
        nan, nan_q = np.full((H + 1, 3), np.nan), np.full((H + 1, n), np.nan)
        try:
            q_arr, v_arr = np.asarray(q, dtype=float), np.asarray(v, dtype=float)
            usable = q_arr.shape == (n,) and v_arr.shape == (n,) and np.isfinite(q_arr).all() \
                and np.isfinite(v_arr).all()
        except (TypeError, ValueError):
            usable = False
        if not usable:
            return MPCResult(np.zeros(n), nan_q, nan_q.copy(), nan, False, status,
                             time.perf_counter() - t0, iterations, qp_iterations)
        w = self._braking_plan(v_arr)
        X = self.problem.states(w, q_arr, v_arr)
        return MPCResult(w[:n].copy(), X[:, :n].copy(), X[:, n:].copy(), nan, False, status,
                         time.perf_counter() - t0, iterations, qp_iterations)

    # ------------------------------------------------------------------
    def solve(self, q: np.ndarray, v: np.ndarray, p_ref: np.ndarray, deadline_s: float | None = None) -> MPCResult:
        """Plan from (q [rad], v [rad/s]) along p_ref (H+1, 3) [m]; row 0 is the reference now.

        ``deadline_s``: time budget [s] from the call; no new SQP iteration
        starts when the last one would not fit, and a solve that ends after it
        returns ``ok=False`` with status "timeout" (its plan still warm-starts
        the next solve).  Never raises for runtime data.
        """
        t0 = time.perf_counter()
        checked = self._check(q, v, p_ref)
        if isinstance(checked, str):
            return self._failure(checked, t0, q, v)
        q, v, p_ref = checked
        try:
            if self._nlp is not None:
                return self._solve_nlp(q, v, p_ref, deadline_s, t0)
            return self._solve_rti(q, v, p_ref, deadline_s, t0)
        except Exception as exc:  # noqa: BLE001 — a solver error must not escape the control loop
            return self._failure(f"solver_error: {type(exc).__name__}: {exc}", t0, q, v)

    def _solve_rti(self, q: np.ndarray, v: np.ndarray, p_ref: np.ndarray, deadline_s: float | None,
                   t0: float) -> MPCResult:
        prob = self.problem
        w = self._braking_plan(v) if self._guess is None else self._guess
        iterations = qp_iterations = 0
        status = "ok"
        last = 0.0
        while iterations < self.max_iterations:
            t_it = time.perf_counter()
            if deadline_s is not None and iterations > 0 and t_it - t0 + last > deadline_s:
                break
            Hm, c, A, lbA, ubA, lbx, ubx, _, _ = prob.qp(w, q, v, p_ref, self._a_prev)
            out = self._qp.solve(Hm, c, A, lbA, ubA, lbx, ubx)
            iterations += 1
            qp_iterations += out.iterations
            if out.x is None:
                return self._failure(f"qp_failed: {out.status}", t0, q, v, iterations, qp_iterations)
            w = w + out.x
            last = time.perf_counter() - t_it
            if float(np.abs(out.x).max()) <= self.tolerance:
                break
        return self._finish(w, q, v, p_ref, iterations, qp_iterations, status, deadline_s, t0)

    def _solve_nlp(self, q: np.ndarray, v: np.ndarray, p_ref: np.ndarray, deadline_s: float | None,
                   t0: float) -> MPCResult:
        w0 = self._braking_plan(v) if self._guess is None else self._guess
        w, iterations, why = self._nlp.solve(w0, q, v, p_ref, self._a_prev)
        if w is None:
            return self._failure(f"nlp_failed: {why}", t0, q, v, iterations)
        return self._finish(w, q, v, p_ref, iterations, 0, "ok", deadline_s, t0)

    def _finish(self, w: np.ndarray, q: np.ndarray, v: np.ndarray, p_ref: np.ndarray, iterations: int,
                qp_iterations: int, status: str, deadline_s: float | None, t0: float) -> MPCResult:
        prob = self.problem
        X = prob.states(w, q, v)
        nodes = prob.evaluate(w, X, p_ref)
        violation = prob.violation(nodes["g"].reshape(-1), w)
        tips = np.vstack([nodes["tip"][:1], nodes["tip_next"]])
        if not (np.isfinite(w).all() and np.isfinite(tips).all()):
            return self._failure("nonfinite_solution", t0, q, v, iterations, qp_iterations)
        self._guess = self._shifted(w, X[-1, self.n:])
        n = self.n
        self._a_prev = w[:n].copy()
        first = prob.violation(nodes["g"][0], w[:n], nodes=1)  # what the arm executes now
        worst = max(first[k] / self._scale[k] for k in first)
        ok = True
        if worst > self.violation_tolerance:
            kind = max(first, key=lambda k: first[k] / self._scale[k])
            ok, status = False, f"constraint_violation: first step, {kind} ({worst:.3g} of the limit)"
        elapsed = time.perf_counter() - t0
        if deadline_s is not None and elapsed > deadline_s:
            ok, status = False, f"timeout: {elapsed * 1e3:.2f} ms > {deadline_s * 1e3:.2f} ms"
        return MPCResult(w[:n].copy(), X[:, :n].copy(), X[:, n:].copy(), tips.copy(), ok, status, elapsed,
                         iterations, qp_iterations, violation, float(np.linalg.norm(tips[1] - p_ref[1])))
