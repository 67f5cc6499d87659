"""QP back-ends: each solves small QPs to the answer of an exact active-set enumeration."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from robot.errors import ControllerConfigError
from robot.solvers import DaqpBackend, OsqpBackend, QpsolversBackend, daqp_available, make_backend


def _reference(P, c, lb, ub, G, h):
    """Exact minimiser of ½xᵀPx + cᵀx s.t. lb ≤ x ≤ ub, Gx ≤ h (P ≻ 0) by trying every active set
    of at most n rows: the KKT point that is feasible with non-negative multipliers (float64)."""
    n = len(c)
    A = np.vstack([np.eye(n), -np.eye(n), G])
    b = np.concatenate([ub, -lb, h])
    for k in range(n + 1):
        for S in itertools.combinations(range(len(b)), k):
            S = list(S)
            K = np.block([[P, A[S].T], [A[S], np.zeros((k, k))]])
            try:
                sol = np.linalg.solve(K, np.concatenate([-c, b[S]]))
            except np.linalg.LinAlgError:
                continue
            x, lam = sol[:n], sol[n:]
            if np.all(A @ x <= b + 1e-10) and np.all(lam >= -1e-10):
                return x
    raise AssertionError("no KKT point: infeasible test problem")


def _problem(seed: int, n: int = 3, m: int = 4):
    rng = np.random.default_rng(seed)
    R = rng.normal(size=(n, n))
    P = R @ R.T + 0.5 * np.eye(n)
    c = rng.normal(scale=5.0, size=n)
    lb, ub = -rng.uniform(0.2, 1.0, n), rng.uniform(0.2, 1.0, n)
    G = rng.normal(size=(m, n))
    h = rng.uniform(0.1, 1.0, m)  # x = 0 is strictly feasible
    return P, c, lb, ub, G, h


# qpsolvers warns about dense matrices, OSQP about a future default and a primal-infeasible exit: expected here
pytestmark = pytest.mark.filterwarnings("ignore::UserWarning", "ignore::PendingDeprecationWarning")

BACKENDS = {
    "osqp": lambda n, m: OsqpBackend(n, m, eps=1e-10, max_iter=20000),
    "daqp": lambda n, m: DaqpBackend(n, m),
    "qpsolvers:osqp": lambda n, m: QpsolversBackend("osqp", eps_abs=1e-10, eps_rel=1e-10, max_iter=20000),
}
TOL = {"osqp": 1e-6, "daqp": 1e-9, "qpsolvers:osqp": 1e-6}


@pytest.mark.parametrize("name", list(BACKENDS))
def test_backend_matches_the_exact_solution_over_a_sequence(name: str) -> None:
    backend = BACKENDS[name](3, 4)
    active = 0
    for seed in range(12):  # one backend object: the persistent workspace is updated, not rebuilt
        P, c, lb, ub, G, h = _problem(seed)
        ref = _reference(P, c, lb, ub, G, h)
        out = backend.solve(P, c, lb, ub, G, h)
        assert out.x is not None and not out.infeasible, out.status
        np.testing.assert_allclose(out.x, ref, atol=TOL[name])
        active += bool(np.any(np.isclose(G @ ref, h, atol=1e-9)) or np.any(np.isclose(ref, ub)))
    assert active >= 4  # the sequence exercises active constraints, not only interior optima


@pytest.mark.parametrize("name", list(BACKENDS))
def test_backend_accepts_read_only_inputs(name: str) -> None:
    """Limits and tasks return read-only arrays; every back-end must take them as they are."""
    problem = _problem(4)
    for a in problem:
        a.flags.writeable = False
    out = BACKENDS[name](3, 4).solve(*problem)
    assert out.x is not None, out.status
    np.testing.assert_allclose(out.x, _reference(*problem), atol=TOL[name])


def test_daqp_and_osqp_agree_with_infinite_bounds() -> None:
    P, c, _, _, G, h = _problem(3, n=4, m=3)
    lb, ub = np.full(4, -1e30), np.full(4, 1e30)  # 1e30: "no bound" for both
    xa = DaqpBackend(4, 3).solve(P, c, lb, ub, G, h).x
    xb = OsqpBackend(4, 3, eps=1e-10, max_iter=20000).solve(P, c, lb, ub, G, h).x
    ref = _reference(P, c, np.full(4, -1e6), np.full(4, 1e6), G, h)
    np.testing.assert_allclose(xa, ref, atol=1e-9)
    np.testing.assert_allclose(xb, ref, atol=1e-6)


@pytest.mark.parametrize("name", list(BACKENDS))
def test_infeasible_problem_gives_no_answer(name: str) -> None:
    n = 2
    P, c = np.eye(n), np.zeros(n)
    lb, ub = np.full(n, -1.0), np.full(n, 1.0)
    G, h = np.array([[1.0, 0.0]]), np.array([-2.0])  # x0 ≤ −2 contradicts x0 ≥ −1
    out = BACKENDS[name](n, 1).solve(P, c, lb, ub, G, h)
    assert out.x is None
    assert out.infeasible or name == "qpsolvers:osqp" and out.status == "no solution"


def test_make_backend_names() -> None:
    assert isinstance(make_backend("osqp", 3, 6), OsqpBackend)
    assert isinstance(make_backend("qpsolvers:osqp", 3, 6), QpsolversBackend)
    expected = DaqpBackend if daqp_available() else OsqpBackend
    assert isinstance(make_backend("auto", 3, 6), expected)
    with pytest.raises(ControllerConfigError, match="not installed; available"):
        make_backend("no_such_solver", 3, 6)
