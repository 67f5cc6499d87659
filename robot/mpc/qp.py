"""Dense QP solves through CasADi's ``conic`` plugins with zero-copy buffers.

Problem (x ∈ Rⁿ, m rows):   min ½xᵀHx + cᵀx   s.t.   lbA ≤ A·x ≤ ubA,   lbx ≤ x ≤ ubx.

The solver is created once with dense sparsity; every solve writes the
numbers into preallocated numpy arrays that CasADi reads in place
(``Function.buffer``: column-major, so A is stored as Aᵀ row-major), and
warm-starts from the previous primal and dual solution.  Calling the conic
with numpy arrays instead converts each to a ``DM`` first, which costs more
than the solve for this size (measured in ``benchmarks/bench_mpc.py``).
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

QP_PLUGINS = ("daqp", "qrqp", "osqp", "hpipm", "qpoases", "proxqp", "piqp")

_OPTIONS: dict[str, dict] = {
    "daqp": {},
    "qrqp": {"print_iter": False, "print_header": False, "print_info": False, "max_iter": 200},
    "osqp": {"osqp": {"verbose": False, "eps_abs": 1e-7, "eps_rel": 1e-7, "max_iter": 4000, "polish": True},
             "warm_start_primal": True, "warm_start_dual": True},
    "hpipm": {"hpipm": {"iter_max": 100, "tol_stat": 1e-8, "tol_eq": 1e-8, "tol_ineq": 1e-8, "tol_comp": 1e-8}},
    "qpoases": {"printLevel": "none", "sparse": False, "max_schur": 0},
    "proxqp": {"proxqp": {"eps_abs": 1e-8}},
    "piqp": {},
}


@dataclass
class QPOutcome:
    """x (None when the solver failed), its duals, ``status`` text and iterations."""

    x: np.ndarray | None
    status: str
    iterations: int


class ConicQP:
    """A warm-started dense QP of fixed size n × m solved by CasADi conic ``plugin``."""

    def __init__(self, plugin: str, n: int, m: int) -> None:
        if plugin not in QP_PLUGINS:
            raise ValueError(f"unknown QP plugin {plugin!r}; valid choices: {', '.join(QP_PLUGINS)}")
        opts = {**_OPTIONS[plugin], "error_on_fail": False}
        if plugin == "qpoases":
            opts.pop("max_schur")
        self.plugin, self.n, self.m = plugin, n, m
        self.solver = ca.conic(f"tip_mpc_{plugin}", plugin,
                               {"h": ca.Sparsity.dense(n, n), "a": ca.Sparsity.dense(m, n)}, opts)
        self._in = {"h": np.zeros((n, n)), "g": np.zeros(n), "a": np.zeros((n, m)), "lba": np.zeros(m),
                    "uba": np.zeros(m), "lbx": np.zeros(n), "ubx": np.zeros(n), "x0": np.zeros(n),
                    "lam_x0": np.zeros(n), "lam_a0": np.zeros(m)}
        self._out = {"x": np.zeros(n), "cost": np.zeros(1), "lam_a": np.zeros(m), "lam_x": np.zeros(n)}
        self._buffer, self._eval = self.solver.buffer()
        for name, arr in self._in.items():
            self._buffer.set_arg(self.solver.index_in(name), memoryview(arr))
        for name, arr in self._out.items():
            self._buffer.set_res(self.solver.index_out(name), memoryview(arr))

    def reset(self) -> None:
        """Forget the warm start (primal and dual)."""
        for name in ("x0", "lam_x0", "lam_a0"):
            self._in[name][:] = 0.0

    def solve(self, H: np.ndarray, c: np.ndarray, A: np.ndarray, lbA: np.ndarray, ubA: np.ndarray,
              lbx: np.ndarray, ubx: np.ndarray, x0: np.ndarray | None = None) -> QPOutcome:
        """Solve; the duals of this solve warm-start the next.  Never raises."""
        inp = self._in
        inp["h"][:] = H
        inp["g"][:] = c
        inp["a"][:] = A.T
        inp["lba"][:] = lbA
        inp["uba"][:] = ubA
        inp["lbx"][:] = lbx
        inp["ubx"][:] = ubx
        inp["x0"][:] = 0.0 if x0 is None else x0
        try:
            self._eval()
            stats = self._buffer.stats()
        except Exception as exc:  # noqa: BLE001 — a solver error must not escape the control loop
            return QPOutcome(None, f"{self.plugin} error: {exc}", 0)
        iterations = int(stats.get("iter_count", stats.get("iterations", 0)) or 0)
        x = self._out["x"]
        if not stats.get("success", False) or not np.isfinite(x).all():
            return QPOutcome(None, f"{self.plugin}: {stats.get('return_status', 'failed')}", iterations)
        inp["lam_x0"][:] = self._out["lam_x"]
        inp["lam_a0"][:] = self._out["lam_a"]
        return QPOutcome(x.copy(), "solved", iterations)


class DaqpQP:
    """The same QP solved by the DAQP package directly (dense active set), working set warm-started.

    DAQP takes the simple bounds first, then the rows; infinite bounds become
    ±1e30 (DAQP's infinity).  The constraints active at the previous solution
    are passed as the initial working set (``sense`` = 1, 3 for a lower bound),
    which is what a real-time iteration's nearly unchanged QP profits from.
    """

    ACTIVE, LOWER = 1, 2

    def __init__(self, n: int, m: int, primal_tol: float = 1e-9, iter_limit: int = 2000) -> None:
        import daqp

        self._solve = daqp.solve
        self.n, self.m = n, m
        self._upper, self._lower = np.empty(n + m), np.empty(n + m)
        self._sense = np.zeros(n + m, dtype=np.int32)
        self._settings = {"primal_tol": primal_tol, "iter_limit": iter_limit}

    def reset(self) -> None:
        self._sense[:] = 0

    def solve(self, H: np.ndarray, c: np.ndarray, A: np.ndarray, lbA: np.ndarray, ubA: np.ndarray,
              lbx: np.ndarray, ubx: np.ndarray, x0: np.ndarray | None = None) -> QPOutcome:
        n = self.n
        self._upper[:n] = ubx
        self._upper[n:] = ubA
        self._lower[:n] = lbx
        self._lower[n:] = lbA
        np.minimum(self._upper, 1e30, out=self._upper)  # ±inf → DAQP's infinity
        np.maximum(self._lower, -1e30, out=self._lower)
        try:
            x, _, flag, info = self._solve(H, c, A, self._upper, self._lower, self._sense, **self._settings)
        except Exception as exc:  # noqa: BLE001 — a solver error must not escape the control loop
            self._sense[:] = 0
            return QPOutcome(None, f"daqp error: {exc}", 0)
        iterations = int(info.get("iterations", 0))
        if flag not in (1, 2) or not np.isfinite(x).all():
            self._sense[:] = 0
            return QPOutcome(None, f"daqp exit flag {flag}", iterations)
        lam = np.asarray(info["lam"])
        self._sense[:] = np.where(lam > 0, self.ACTIVE, np.where(lam < 0, self.ACTIVE | self.LOWER, 0))
        return QPOutcome(np.asarray(x), "solved", iterations)
