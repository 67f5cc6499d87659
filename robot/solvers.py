"""QP back-ends for a small problem of fixed structure.

Problem (x ∈ Rⁿˣ):   minimise ½·xᵀP·x + cᵀx   s.t.   lb ≤ x ≤ ub,   G·x ≤ h.

* :class:`OsqpBackend` uses the ``osqp`` API directly: qpsolvers builds a new
  OSQP workspace on every call and cannot keep it, so the workspace is set up
  once (fixed dense sparsity pattern) and then only updated (``Px``, ``Ax``,
  ``q``, ``l``, ``u``) and warm-started every step. Solution polishing is off
  (OSQP 1.x prints "Polishing not needed" to stdout on every solve without an
  active set, whatever ``verbose`` says); instead ``eps`` is tight (1e-9,
  termination checked every iteration) and the controller clips to the box and
  verifies the torque limits afterwards, so limits hold to 1e-6.
* :class:`DaqpBackend` calls DAQP (a dense active-set solver: exact on the
  active constraints, ≈ 5 µs here) directly; through qpsolvers the same solve
  costs ≈ 40 µs more in argument conversion, which is most of the 150 µs budget.
* :class:`QpsolversBackend` calls :func:`qpsolvers.solve_qp` with dense
  matrices and any installed solver (names ``"qpsolvers:<solver>"`` or any
  qpsolvers solver other than ``osqp``/``daqp``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from .errors import ControllerConfigError


@dataclass
class SolveOutcome:
    """x (None when no solution), ``status`` text, ``infeasible`` flag, iterations."""

    x: np.ndarray | None
    status: str
    infeasible: bool
    iterations: int


class OsqpBackend:
    """Persistent OSQP workspace for a problem with dense P (n×n) and dense G (m×n)."""

    def __init__(self, n: int, m: int, eps: float = 1e-9, max_iter: int = 1000) -> None:
        import osqp

        self._osqp = osqp
        self.n, self.m = n, m
        self.eps, self.max_iter = eps, max_iter
        # P: full upper triangle, column-major (CSC) order.
        cols_p, rows_p = [], []
        for j in range(n):
            for i in range(j + 1):
                rows_p.append(i)
                cols_p.append(j)
        self._p_idx = (np.array(rows_p), np.array(cols_p))
        # A = [I; G]: CSC order is column by column: the identity entry, then G's column.
        rows_a, cols_a = [], []
        for j in range(n):
            rows_a.append(j)
            cols_a.append(j)
            rows_a.extend(range(n, n + m))
            cols_a.extend([j] * m)
        self._a_rows, self._a_cols = np.array(rows_a), np.array(cols_a)
        self._g_pos = self._a_rows >= n  # which Ax entries come from G
        self._g_idx = (self._a_rows[self._g_pos] - n, self._a_cols[self._g_pos])
        self._ax = np.ones(len(rows_a))
        self._solver = None

    def _matrices(self, P: np.ndarray, G: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        px = P[self._p_idx]
        self._ax[self._g_pos] = G[self._g_idx]
        return px, self._ax

    def solve(self, P: np.ndarray, c: np.ndarray, lb: np.ndarray, ub: np.ndarray,
              G: np.ndarray, h: np.ndarray) -> SolveOutcome:
        px, ax = self._matrices(P, G)
        lower = np.concatenate([lb, np.full(self.m, -np.inf)])
        upper = np.concatenate([ub, h])
        if self._solver is None:
            n, m = self.n, self.m
            P_csc = sp.csc_matrix((px, self._p_idx), shape=(n, n))
            A_csc = sp.csc_matrix((ax.copy(), (self._a_rows, self._a_cols)), shape=(n + m, n))
            self._solver = self._osqp.OSQP()
            self._solver.setup(P=P_csc, q=c, A=A_csc, l=lower, u=upper, verbose=False, eps_abs=self.eps,
                               eps_rel=self.eps, polishing=False, check_termination=1,
                               max_iter=self.max_iter, warm_starting=True, adaptive_rho=True)
        else:
            self._solver.update(q=c, l=lower, u=upper, Px=px, Ax=ax)
        res = self._solver.solve(raise_error=False)  # failures are reported through the status
        status = res.info.status_val
        st = self._osqp.SolverStatus
        infeasible = status in (st.OSQP_PRIMAL_INFEASIBLE, st.OSQP_PRIMAL_INFEASIBLE_INACCURATE)
        # An iterate stopped by max_iter is still close to optimal: the controller clips it into the
        # box and verifies the torque rows, so it is used rather than relaxing the problem.
        usable = status in (st.OSQP_SOLVED, st.OSQP_SOLVED_INACCURATE, st.OSQP_MAX_ITER_REACHED,
                            st.OSQP_TIME_LIMIT_REACHED)
        x = np.array(res.x) if usable and res.x is not None and math.isfinite(float(res.x @ res.x)) else None
        return SolveOutcome(x, str(res.info.status), infeasible, int(res.info.iter))


class DaqpBackend:
    """Dense DAQP solve (``daqp.solve``); bounds first, then the rows of G."""

    def __init__(self, n: int, m: int, primal_tol: float = 1e-12, iter_limit: int = 1000) -> None:
        import daqp

        self._solve = daqp.solve
        self.n, self.m = n, m
        self._sense = np.zeros(n + m, dtype=np.int32)
        self._settings = {"primal_tol": primal_tol, "iter_limit": iter_limit}
        self._upper = np.empty(n + m)
        self._lower = np.full(n + m, -1e30)  # rows of G are one-sided (G·x ≤ h)

    def solve(self, P: np.ndarray, c: np.ndarray, lb: np.ndarray, ub: np.ndarray,
              G: np.ndarray, h: np.ndarray) -> SolveOutcome:
        """Bounds must be finite or ±1e30 (DAQP's infinity).

        DAQP's wrapper takes writable buffers only: read-only inputs (limits and
        tasks return read-only arrays) are copied.
        """
        n = self.n
        if not P.flags.writeable:
            P = P.copy()
        if not c.flags.writeable:
            c = c.copy()
        if not G.flags.writeable:
            G = G.copy()
        self._upper[:n] = ub
        self._upper[n:] = h
        self._lower[:n] = lb
        try:
            x, _, flag, info = self._solve(P, c, G, self._upper, self._lower, self._sense, **self._settings)
        except Exception as exc:  # a solver error must not escape the control loop
            return SolveOutcome(None, f"error: {exc}", False, 0)
        # exit flags: 1 optimal, 2 soft optimal, -1 infeasible, others: limits / numerical trouble
        if flag in (1, 2) and math.isfinite(float(x @ x)):
            return SolveOutcome(x, "solved", False, info["iterations"])
        return SolveOutcome(None, f"daqp exitflag {flag}", flag == -1, info["iterations"])


class QpsolversBackend:
    """Dense solve through :func:`qpsolvers.solve_qp` with the named solver."""

    def __init__(self, solver: str, **settings: object) -> None:
        import qpsolvers

        if solver not in qpsolvers.available_solvers:
            raise ControllerConfigError(
                f"QP solver {solver!r} is not installed; available: {qpsolvers.available_solvers}")
        self._solve_qp = qpsolvers.solve_qp
        self.solver = solver
        defaults: dict[str, object] = {"daqp": {"primal_tol": 1e-12}}.get(solver, {})  # type: ignore[assignment]
        self.settings = {**defaults, **settings}
        self._last: np.ndarray | None = None

    def solve(self, P: np.ndarray, c: np.ndarray, lb: np.ndarray, ub: np.ndarray,
              G: np.ndarray, h: np.ndarray) -> SolveOutcome:
        try:
            x = self._solve_qp(P, c, G, h, lb=lb, ub=ub, solver=self.solver,
                               initvals=self._last, **self.settings)
        except Exception as exc:  # a solver error must not escape the control loop
            return SolveOutcome(None, f"error: {exc}", False, 0)
        if x is None or not np.all(np.isfinite(x)):
            # qpsolvers does not say why; the caller treats it as infeasible and relaxes.
            return SolveOutcome(None, "no solution", True, 0)
        self._last = x
        return SolveOutcome(np.asarray(x), "solved", False, 0)


def daqp_available() -> bool:
    """Whether the ``daqp`` package can be imported."""
    import importlib.util

    return importlib.util.find_spec("daqp") is not None


def make_backend(solver: str, n: int, m: int, eps: float = 1e-9) -> OsqpBackend | DaqpBackend | QpsolversBackend:
    """``"osqp"`` → persistent :class:`OsqpBackend`; ``"daqp"`` → :class:`DaqpBackend`;
    ``"auto"`` → DAQP when installed, else OSQP; ``"qpsolvers:<name>"`` or any other
    qpsolvers name → :class:`QpsolversBackend`."""
    if solver == "auto":
        solver = "daqp" if daqp_available() else "osqp"
    if solver == "osqp":
        return OsqpBackend(n, m, eps=eps)
    if solver == "daqp":
        try:
            return DaqpBackend(n, m)
        except ImportError as exc:
            raise ControllerConfigError("solver 'daqp' needs the daqp package (pip install daqp)") from exc
    return QpsolversBackend(solver.removeprefix("qpsolvers:"))
