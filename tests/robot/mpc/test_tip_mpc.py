"""TipMPC: limits in closed loop, tracking, warm start, failure paths, construction errors."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pinocchio as pin
import pytest

from robot.constraints import viable_velocity_bound
from robot.model_files import build_pinocchio_model
from robot.mpc import codegen
from robot.mpc.tip_mpc import SOLVERS, TipMPC
from robot.superlimb import SuperLimbParams

H, DT = 20, 0.01
PARAMS = SuperLimbParams()
# The arm executes a_0 only: τ_0 = M(q_0)·a_0 + h(q_0, v_0) is linear in a_0 and the next state is
# linear too, so the QP meets those rows to DAQP's tolerance (1e-9); 1e-6 of each limit is the
# rounding allowance (the same order as the robot QP's contract).
REL_TOL = 1e-6


@pytest.fixture(scope="module")
def mpc() -> TipMPC:
    return TipMPC(PARAMS, horizon=H, dt=DT)


@pytest.fixture(scope="module")
def pin_model():
    return build_pinocchio_model(PARAMS)


def _tip(pin_model, q: np.ndarray) -> np.ndarray:
    model, data, fid = pin_model
    pin.framesForwardKinematics(model, data, q)
    return data.oMf[fid].translation.copy()


def _circle(t: np.ndarray, centre: np.ndarray, radius: float = 0.04, omega: float = 2.0) -> np.ndarray:
    return centre + radius * np.stack([np.cos(omega * t), np.sin(omega * t), 0.5 * np.sin(2 * omega * t)], -1)


def _rollout(mpc: TipMPC, pin_model, reference, steps: int, q0: np.ndarray):
    """Closed loop with the model: integrate the planned first acceleration exactly; check limits every step."""
    model, data, _ = pin_model
    p = mpc.params
    q, v = q0.copy(), np.zeros(3)
    errors, statuses = [], []
    mpc.reset()
    horizon = mpc.horizon
    for k in range(steps):
        p_ref = reference(DT * (k + np.arange(horizon + 1)))
        res = mpc.solve(q, v, p_ref)
        statuses.append(res.status)
        assert res.a.shape == (3,) and res.q_plan.shape == (horizon + 1, 3) and res.tip_plan.shape == (horizon + 1, 3)
        a = res.a
        tau = pin.rnea(model, data, q, v, a)
        assert np.all(np.abs(a) <= p.acceleration_limit * (1 + REL_TOL)), (k, a)
        assert np.all(np.abs(tau) <= p.torque_limit * (1 + REL_TOL)), (k, tau / p.torque_limit)
        q_next, v_next = q + v * DT + 0.5 * a * DT * DT, v + a * DT
        assert np.all(np.abs(v_next) <= p.velocity_limit * (1 + REL_TOL)), (k, v_next)
        assert np.all(q_next <= p.upper + 1e-9) and np.all(q_next >= p.lower - 1e-9), (k, q_next)
        # the executed step is admissible for the robot QP's viable position limit
        bound_up = viable_velocity_bound(p.upper - q, v, DT, p.braking_acceleration)
        bound_low = viable_velocity_bound(q - p.lower, -v, DT, p.braking_acceleration)
        # A step reported ok meets the φ± rows to the MPC's violation_tolerance ε [rad] (the real-time
        # iteration linearises φ± at the kink v = 0, so the true row may exceed the linear one by up to ε);
        # the QP's bound is in v⁺ with slope ≥ dt/2, so v⁺ may exceed it by ε/(dt/2), plus rounding.
        v_tol = REL_TOL * p.velocity_limit + mpc.violation_tolerance * 2.0 / DT
        assert np.all(v_next <= bound_up + v_tol) and np.all(-v_next <= bound_low + v_tol), k
        if res.ok:
            np.testing.assert_allclose(res.tip_plan[0], _tip(pin_model, q), atol=1e-9)
            np.testing.assert_allclose(res.q_plan[1], q_next, atol=1e-12)
        errors.append(np.linalg.norm(_tip(pin_model, q) - p_ref[0]))
        q, v = q_next, v_next
    return np.array(errors), statuses, q, v


def test_tracks_a_reachable_moving_reference_within_limits(mpc, pin_model) -> None:
    q0 = np.array([0.1, 0.6, 1.1])
    centre = _tip(pin_model, q0) + np.array([0.02, 0.01, -0.02])
    errors, statuses, _, _ = _rollout(mpc, pin_model, lambda t: _circle(t, centre), 150, q0)
    assert statuses.count("ok") == len(statuses), set(statuses)
    assert errors[50:].max() < 2e-3, errors[50:].max()  # after the 0.5 s transient: below 2 mm


def test_unreachable_reference_stays_within_limits(mpc, pin_model) -> None:
    """A reference 2 m away (beyond the 0.6 m reach): the arm stretches toward it within every limit."""
    q0 = np.array([0.0, 0.3, 0.5])
    far = np.array([2.0, -1.5, 1.5])
    errors, statuses, q, v = _rollout(mpc, pin_model, lambda t: np.tile(far, (t.size, 1)), 120, q0)
    assert all(isinstance(s, str) for s in statuses)
    assert errors[-1] < errors[0] - 0.1  # it moved toward the reference (limits checked every step)
    assert np.isfinite(q).all() and np.isfinite(v).all()


def test_moving_into_the_joint_limits_brakes_in_time(mpc, pin_model) -> None:
    """A reference that drags the elbow past its upper limit at speed: position limits hold every step."""
    q0 = np.array([0.0, 0.2, 1.6])
    start = _tip(pin_model, q0)
    target = _tip(pin_model, np.array([0.0, 0.2, 2.9]))  # elbow far beyond 2.40 rad

    def reference(t):
        s = np.clip(t / 0.4, 0.0, 1.0)[:, None]
        return start + s * (target - start)

    _, _, q, _ = _rollout(mpc, pin_model, reference, 100, q0)
    assert q[2] > PARAMS.upper[2] - 0.05  # it did go to the limit


def test_other_parameters_compile_into_a_fresh_cache(tmp_path, monkeypatch) -> None:
    """Changed limits and links reach the MPC (new code generated, compiled, cached, reused)."""
    monkeypatch.setenv("MPCSHARE_CACHE", str(tmp_path))
    params = SuperLimbParams(knife_length=0.18).with_joint("elbow", upper=2.0, braking_acceleration=12.0)
    mpc = TipMPC(params, horizon=15, dt=DT)
    assert mpc.evaluation_.startswith("compiled") and str(tmp_path) in mpc.evaluation_
    assert TipMPC(params, horizon=15, dt=DT).evaluation_ == mpc.evaluation_  # found in the cache
    pin_model = build_pinocchio_model(params)
    q0 = np.array([0.0, 0.2, 1.6])
    start, target = _tip(pin_model, q0), _tip(pin_model, np.array([0.0, 0.2, 2.6]))

    def reference(t):
        return start + np.clip(t / 0.3, 0.0, 1.0)[:, None] * (target - start)

    _, _, q, _ = _rollout(mpc, pin_model, reference, 80, q0)
    assert 2.0 - 0.05 < q[2] <= 2.0 + 1e-9


def test_warm_start_needs_fewer_iterations(pin_model) -> None:
    """Solved to convergence (SQP), the shifted warm start takes fewer iterations than a cold start."""
    mpc = TipMPC(PARAMS, horizon=H, dt=DT, max_iterations=30, tolerance=1e-7)
    q, v = np.array([0.1, 0.6, 1.1]), np.zeros(3)
    centre = _tip(pin_model, q) + np.array([0.03, 0.0, -0.02])
    warm, cold = [], []
    for k in range(40):
        p_ref = _circle(DT * (k + np.arange(H + 1)), centre)
        a_before = mpc._a_prev.copy()
        res = mpc.solve(q, v, p_ref)
        assert res.ok, res.status
        if k >= 10:
            warm.append(res.iterations)
            saved = mpc._guess, mpc._a_prev.copy()
            mpc.reset()  # cold: braking guess, empty working set, same problem (same a_prev)
            mpc._a_prev = a_before
            cold_res = mpc.solve(q, v, p_ref)
            assert cold_res.ok, cold_res.status
            cold.append(cold_res.iterations)
            np.testing.assert_allclose(cold_res.a, res.a, atol=1e-4)  # same optimum either way
            mpc._guess, mpc._a_prev = saved
        q, v = q + v * DT + 0.5 * res.a * DT * DT, v + res.a * DT
    assert np.mean(warm) < 0.7 * np.mean(cold), (np.mean(warm), np.mean(cold))


@pytest.mark.parametrize("bad", ["nan_q", "inf_v", "nan_ref", "shape_ref", "shape_q", "text"])
def test_bad_input_returns_not_ok(mpc, bad: str) -> None:
    q, v, p_ref = np.array([0.1, 0.6, 1.1]), np.zeros(3), np.tile([0.5, -0.2, 0.3], (H + 1, 1))
    if bad == "nan_q":
        q[1] = np.nan
    elif bad == "inf_v":
        v[0] = np.inf
    elif bad == "nan_ref":
        p_ref[5, 2] = np.nan
    elif bad == "shape_ref":
        p_ref = p_ref[:-1]
    elif bad == "shape_q":
        q = np.zeros(4)
    else:
        q = "abc"
    res = mpc.solve(q, v, p_ref)
    assert not res.ok and res.status.startswith("invalid_input"), res.status
    assert res.a.shape == (3,) and np.isfinite(res.a).all()


def test_infeasible_state_and_solver_errors_return_not_ok(mpc, monkeypatch) -> None:
    p_ref = np.tile([0.5, -0.2, 0.3], (H + 1, 1))
    # beyond the speed limit next to the upper limit: no plan can stop in time
    q = PARAMS.upper - 0.01
    v = 3.0 * PARAMS.velocity_limit
    res = mpc.solve(q, v, p_ref)
    assert not res.ok and res.status != "ok"
    np.testing.assert_allclose(res.a, np.clip(-v / DT, -PARAMS.braking_acceleration, PARAMS.braking_acceleration))

    def broken(*args, **kwargs):
        raise RuntimeError("solver exploded")

    monkeypatch.setattr(mpc._qp, "solve", broken)
    res = mpc.solve(np.array([0.1, 0.6, 1.1]), np.zeros(3), p_ref)
    assert not res.ok and "solver exploded" in res.status


def test_deadline_reports_timeout(mpc) -> None:
    res = mpc.solve(np.array([0.1, 0.6, 1.1]), np.zeros(3), np.tile([0.5, -0.2, 0.3], (H + 1, 1)), deadline_s=1e-9)
    assert not res.ok and res.status.startswith("timeout")
    assert np.isfinite(res.a).all()


def test_construction_errors_name_the_choices() -> None:
    with pytest.raises(ValueError, match="valid choices: " + ", ".join(SOLVERS)):
        TipMPC(solver="magic")
    for horizon in (0, 1, 2.5, True):
        with pytest.raises(ValueError, match="horizon"):
            TipMPC(horizon=horizon)
    with pytest.raises(ValueError, match="dt"):
        TipMPC(dt=-0.01)
    with pytest.raises(ValueError, match="max_iterations"):
        TipMPC(max_iterations=0)


def test_virtual_machine_equals_compiled_and_fallback(monkeypatch, mpc) -> None:
    vm = TipMPC(PARAMS, horizon=H, dt=DT, codegen=False)
    assert vm.evaluation_.startswith("virtual machine")
    q, v = np.array([0.1, 0.6, 1.1]), np.array([0.2, -0.3, 0.1])
    p_ref = np.tile([0.5, -0.2, 0.3], (H + 1, 1))
    mpc.reset()
    a, b = vm.solve(q, v, p_ref), mpc.solve(q, v, p_ref)
    np.testing.assert_allclose(a.a, b.a, atol=1e-8)
    np.testing.assert_allclose(a.tip_plan, b.tip_plan, atol=1e-10)
    monkeypatch.setattr(codegen, "find_compiler", lambda: None)
    x = ca.SX.sym("x")
    f, how = codegen.compiled(ca.Function("f", [x], [2 * x]))
    assert "no C compiler" in how and float(f(3.0)) == 6.0


def test_second_arm_tracks_within_its_limits() -> None:
    """The MPC generated for a 7-joint arm (Panda, example-robot-data): the executed steps keep every limit and
    the tip converges onto a moving reference."""
    from tests.sim.second_arm import panda

    robot = panda()
    lim, model = robot.limits, robot.model
    data = model.createData()
    mpc = TipMPC(robot, horizon=10, dt=DT, codegen=False)
    q, v = robot.q_home.copy(), np.zeros(robot.n)
    pin.framesForwardKinematics(model, data, q)
    start = data.oMf[robot.tip_frame_id].translation.copy()
    errors = []
    for k in range(60):
        t = DT * (k + np.arange(11))
        p_ref = start + np.minimum(t / 0.3, 1.0)[:, None] * np.array([0.06, -0.04, 0.05])
        res = mpc.solve(q, v, p_ref)
        assert res.ok, res.status
        a = res.a
        tau = pin.rnea(model, data, q, v, a)
        assert np.all(np.abs(tau) <= lim.tau_max * (1 + REL_TOL)) and np.all(np.abs(a) <= lim.a_max * (1 + REL_TOL))
        q, v = q + v * DT + 0.5 * a * DT * DT, v + a * DT
        assert np.all(np.abs(v) <= lim.v_max * (1 + REL_TOL))
        assert np.all(q <= lim.q_max + 1e-9) and np.all(q >= lim.q_min - 1e-9)
        pin.framesForwardKinematics(model, data, q)
        errors.append(float(np.linalg.norm(data.oMf[robot.tip_frame_id].translation - p_ref[1])))
    assert errors[-1] < 1e-3 < max(errors)
