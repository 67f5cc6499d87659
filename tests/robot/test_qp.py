"""QP controller on the SuperLimb: limits at random states, braking, saturation, recovery, odd inputs."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from robot.constraints import intersect_by_priority, viable_velocity_bound
from robot.errors import ControllerConfigError, FrameNotFoundError, UnsupportedModelError
from robot.limits import JointLimits
from robot.model_files import build_pinocchio_model
from robot.qp import QPConfig, QPController, QPStatus
from robot.solvers import daqp_available
from robot.superlimb import SuperLimbParams

TOL = 1e-6
SOLVERS = ["daqp", "osqp"] if daqp_available() else ["osqp"]
PARAMS = SuperLimbParams()
LIM = JointLimits.from_superlimb(PARAMS)


def _violation(r, lim: JointLimits = LIM) -> float:
    """Largest excess over any position, velocity or torque limit (≤ 0 when all hold)."""
    return float(max((np.abs(r.tau) - lim.tau_max).max(), (np.abs(r.v_next) - lim.v_max).max(),
                     (r.q_next - lim.q_max).max(), (lim.q_min - r.q_next).max()))


def _viable(q: np.ndarray, v: np.ndarray, dt: float, lim: JointLimits = LIM) -> bool:
    """(q, v) inside the set the position constraint keeps invariant."""
    up = viable_velocity_bound(lim.q_max - q, v, dt, lim.a_brake) + lim.a_brake * dt
    down = viable_velocity_bound(q - lim.q_min, -v, dt, lim.a_brake) + lim.a_brake * dt
    inside = np.all(q >= lim.q_min) and np.all(q <= lim.q_max) and np.all(np.abs(v) <= lim.v_max)
    return bool(inside and np.all(v <= np.maximum(up, 0)) and np.all(-v <= np.maximum(down, 0)))


@pytest.fixture(scope="module", params=SOLVERS)
def controller(request) -> QPController:
    return QPController.for_superlimb(config=QPConfig(solver=request.param))


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**31 - 1), kp=st.floats(10.0, 2000.0), far=st.booleans())
def test_random_states_and_references_respect_every_limit(seed, kp, far) -> None:
    """Random viable state, random reference (possibly unreachable), 25 closed-loop steps."""
    rng = np.random.default_rng(seed)
    for solver in SOLVERS:
        ctl = QPController.for_superlimb(config=QPConfig(solver=solver, tip_kp=kp, tip_kd=2 * np.sqrt(kp)))
        q = rng.uniform(LIM.q_min, LIM.q_max)
        v = rng.uniform(-LIM.v_max, LIM.v_max)
        for _ in range(50):  # shrink v until the state is viable
            if _viable(q, v, ctl.dt):
                break
            v *= 0.7
        p_ref = rng.uniform([-0.5, -1.0, -0.5], [1.0, 0.5, 1.2]) if far else \
            np.array([0.35, -0.2, 0.3]) + rng.uniform(-0.15, 0.15, 3)
        v_ref = rng.normal(scale=0.5, size=3)
        a_ref = rng.normal(scale=5.0, size=3)
        for _ in range(25):
            r = ctl.step(q, v, p_ref, v_ref, a_ref)
            assert r.status is QPStatus.OK, r.reason
            assert "primary QP" not in r.reason  # the first QP answered (no silent fallback)
            assert _violation(r) <= TOL
            np.testing.assert_allclose(r.tau, ctl.evaluate(q, v).M @ r.a + ctl.evaluate(q, v).h,
                                       atol=1e-9)
            q, v = r.q_next, r.v_next


def test_tracks_a_reachable_reference(controller: QPController) -> None:
    q, v = np.array([0.0, 0.5, 1.0]), np.zeros(3)
    start = controller.evaluate(q, v).p
    target = start + np.array([0.08, 0.05, -0.06])
    for _ in range(150):
        r = controller.step(q, v, target)
        q, v = r.q_next, r.v_next
    assert r.status is QPStatus.OK and r.tip_error < 1e-3


@pytest.mark.parametrize("joint", [0, 1, 2])
@pytest.mark.parametrize("direction", [1.0, -1.0])
def test_full_speed_toward_a_position_limit_stops_before_it(joint: int, direction: float) -> None:
    """Start at full speed toward a limit, reference pulling beyond it: q never crosses the limit."""
    ctl = QPController.for_superlimb(config=QPConfig(tip_weight=0.0, posture_weight=1.0, posture_kp=400.0,
                                                     q_posture=np.where(np.arange(3) == joint,
                                                                        np.where(direction > 0, 10.0, -10.0),
                                                                        0.5 * (LIM.q_min + LIM.q_max))))
    limit = LIM.q_max[joint] if direction > 0 else LIM.q_min[joint]
    q = 0.5 * (LIM.q_min + LIM.q_max)
    v = np.zeros(3)
    v[joint] = direction * LIM.v_max[joint]
    peak = q[joint]
    for k in range(300):
        r = ctl.step(q, v)
        assert r.status is QPStatus.OK and _violation(r) <= TOL
        q, v = r.q_next, r.v_next
        peak = max(peak, q[joint]) if direction > 0 else min(peak, q[joint])
    assert direction * (limit - peak) >= -TOL  # never crossed
    assert abs(v[joint]) < 1e-6  # came to rest, pressed against the limit
    assert abs(q[joint] - limit) < 1e-2  # and used the range


def test_reference_beyond_reach_saturates_torque_without_exceeding_it() -> None:
    ctl = QPController.for_superlimb(config=QPConfig(tip_kp=2000.0, tip_kd=90.0, tip_max_error=None))
    q, v = np.array([0.2, 0.3, 1.2]), np.zeros(3)
    target = np.array([2.0, 1.0, -1.5])  # ≈ 2.5 m away, reach is 0.6 m
    ratio_max = 0.0
    for _ in range(200):
        r = ctl.step(q, v, target)
        assert r.status is QPStatus.OK and _violation(r) <= TOL
        ratio_max = max(ratio_max, float((np.abs(r.tau) / LIM.tau_max).max()))
        q, v = r.q_next, r.v_next
    assert ratio_max >= 1.0 - 1e-6  # the torque limit was reached (saturation)
    assert np.all(np.isfinite(q)) and r.tip_error > 1.0


@pytest.mark.parametrize("offset,v0", [(0.25, 0.0), (0.1, 1.5), (-0.2, -1.0)])
def test_start_outside_limits_recovers(offset: float, v0: float) -> None:
    ctl = QPController.for_superlimb()
    q = np.array([0.0, 0.4, 0.0])
    q[2] = (LIM.q_max[2] + offset) if offset > 0 else (LIM.q_min[2] + offset)
    v = np.array([0.0, 0.0, v0])
    target = ctl.tip_position(np.array([0.0, 0.4, 1.0]))
    statuses = []
    for k in range(300):
        r = ctl.step(q, v, target)
        statuses.append(r.status)
        assert np.all(np.abs(r.tau) <= LIM.tau_max + TOL)  # torque is never given up
        q, v = r.q_next, r.v_next
    assert statuses[0] in (QPStatus.RECOVERING, QPStatus.RELAXED)
    assert statuses[-1] is QPStatus.OK
    first_ok = statuses.index(QPStatus.OK)
    assert all(s is QPStatus.OK for s in statuses[first_ok:])
    assert np.all(q >= LIM.q_min - TOL) and np.all(q <= LIM.q_max + TOL)
    assert np.abs(v).max() < 1e-3  # settled (a joint limit may block the exact tip target: local optimum)


def test_over_speed_start_recovers() -> None:
    ctl = QPController.for_superlimb()
    q, v = np.array([0.0, 0.3, 1.0]), np.array([3.0, -3.0, 4.0])
    for _ in range(60):
        r = ctl.step(q, v)
        assert np.all(np.abs(r.tau) <= LIM.tau_max + TOL)
        q, v = r.q_next, r.v_next
    assert np.all(np.abs(v) <= LIM.v_max) and r.status is QPStatus.OK


def test_singular_outstretched_pose() -> None:
    """Knife tip on the upper-arm line (max reach): no exception, reported, limits hold."""
    ctl = QPController.for_superlimb()
    grid = np.linspace(LIM.q_min[2], LIM.q_max[2], 20001)
    manip = [ctl.step(np.array([0.0, 0.2, e]), np.zeros(3)).manipulability for e in grid[::100]]
    e_sing = grid[::100][int(np.argmin(manip))]
    q, v = np.array([0.0, 0.2, e_sing]), np.zeros(3)
    r0 = ctl.step(q, v, np.array([5.0, -0.2, 0.0]))
    assert r0.manipulability < 2e-3 and np.all(np.isfinite(r0.a))
    for _ in range(100):
        r = ctl.step(q, v, np.array([5.0, -0.2, 0.0]))
        assert r.status is QPStatus.OK and _violation(r) <= TOL
        q, v = r.q_next, r.v_next
    assert "singular" in ctl.step(np.array([0.0, 0.2, e_sing]), np.zeros(3), np.array([5.0, 0, 0])).reason


def test_torque_conflict_is_relaxed_with_torque_kept() -> None:
    """A shoulder too weak to hold the arm at its limit: box relaxed, torque limit kept."""
    weak = PARAMS.with_joint("shoulder", torque_limit_override=0.4)
    lim = JointLimits.from_superlimb(weak)
    ctl = QPController.for_superlimb(weak)
    q, v = np.array([0.0, 0.6, 0.3]), np.zeros(3)
    seen = set()
    for _ in range(200):
        r = ctl.step(q, v)
        seen.add(r.status)
        assert np.all(np.abs(r.tau) <= lim.tau_max + TOL)
        if r.status is QPStatus.RELAXED:
            assert r.slack > 0
        q, v = r.q_next, r.v_next
    assert QPStatus.RELAXED in seen


def test_non_finite_inputs_give_safe_answers() -> None:
    ctl = QPController.for_superlimb()
    q, v = np.array([0.0, 0.5, 1.0]), np.zeros(3)
    good = ctl.step(q, v, np.array([0.4, -0.2, 0.2]))
    r = ctl.step(q, v, np.array([np.nan, 0.0, 0.0]))
    assert r.status is QPStatus.INVALID_REFERENCE and np.all(np.isfinite(r.tau)) and _violation(r) <= TOL
    r = ctl.step(q, v, np.array([0.4, -0.2, 0.2]), v_ref=np.array([np.inf, 0, 0]))
    assert r.status is QPStatus.OK and "v_ref" in r.reason
    r = ctl.step(np.array([np.nan, 0.5, 1.0]), v)
    assert r.status is QPStatus.INVALID_STATE and np.all(np.isfinite(r.q_next)) and np.all(r.a == 0)
    assert np.all(np.abs(r.tau) <= LIM.tau_max)
    assert good.ok


def test_misuse_raises_typed_errors() -> None:
    model, _, _ = build_pinocchio_model(PARAMS)
    with pytest.raises(FrameNotFoundError):
        QPController(model, "no_such_frame", LIM)
    with pytest.raises(FrameNotFoundError):
        QPController(model, 10_000, LIM)
    with pytest.raises(ControllerConfigError):
        QPController(model, "knife_tip", JointLimits([0.0], [1.0], [1.0], [1.0], [1.0], [1.0]))
    with pytest.raises(ControllerConfigError):
        QPController(model, "knife_tip", LIM, QPConfig(solver="no_such_solver"))
    with pytest.raises(ControllerConfigError):
        QPController(model, "knife_tip", LIM, QPConfig(dt=0.0))
    with pytest.raises(ControllerConfigError):
        QPController(model, "knife_tip", LIM, QPConfig(q_posture=np.zeros(2)))
    with pytest.raises(UnsupportedModelError):
        QPController(pin.buildSampleModelHumanoidRandom(), 0)
    ctl = QPController(model, "knife_tip", LIM)
    with pytest.raises(ControllerConfigError):
        ctl.step(np.zeros(2), np.zeros(3))
    with pytest.raises(ControllerConfigError):
        ctl.step(np.zeros(3), np.zeros(3), np.zeros(2))


def test_custom_tasks_need_exactly_one_tip_task() -> None:
    from robot.tasks import AccelerationRegularization, PostureTask, TipTrackingTask

    model, _, _ = build_pinocchio_model(PARAMS)
    posture = PostureTask(np.zeros(3))
    with pytest.raises(ControllerConfigError, match="exactly one TipTrackingTask.*found 0.*posture"):
        QPController(model, "knife_tip", LIM, tasks=[posture, AccelerationRegularization()])
    with pytest.raises(ControllerConfigError, match="found 2"):
        QPController(model, "knife_tip", LIM, tasks=[TipTrackingTask(), TipTrackingTask(), posture])
    tip = TipTrackingTask(weight=2.0)
    ctl = QPController(model, "knife_tip", LIM, tasks=[posture, tip, AccelerationRegularization()])
    assert ctl.tip_task is tip
    q = np.array([0.0, 0.5, 1.0])
    target = ctl.tip_position(q) + np.array([0.05, 0.0, 0.0])
    r = ctl.step(q, np.zeros(3), target)
    assert tip.p_ref is not None and r.tip_error == pytest.approx(0.05, abs=1e-12)


def test_evaluate_is_the_state_the_controller_sees() -> None:
    ctl = QPController.for_superlimb()
    q, v = np.array([0.1, 0.4, 0.9]), np.array([0.2, -0.1, 0.3])
    s = ctl.evaluate(q, v)
    model, data, fid = build_pinocchio_model(PARAMS)
    pin.forwardKinematics(model, data, q)
    np.testing.assert_allclose(s.p, pin.updateFramePlacement(model, data, fid).translation, atol=1e-12)
    upper = np.triu(pin.crba(model, data, q))  # crba fills (at least) the upper triangle
    np.testing.assert_allclose(s.M, upper + np.triu(upper, 1).T, atol=1e-12)
    np.testing.assert_allclose(ctl.tip_position(q), s.p, atol=1e-15)
    q[0] = 5.0  # the state holds its own copy
    assert s.q[0] == 0.1
    with pytest.raises(ControllerConfigError, match="q must have shape"):
        ctl.evaluate(np.zeros(2), np.zeros(3))


def test_solvers_agree() -> None:
    a = QPController.for_superlimb(config=QPConfig(solver="daqp"))
    b = QPController.for_superlimb(config=QPConfig(solver="osqp"))
    c = QPController.for_superlimb(config=QPConfig(solver="qpsolvers:daqp"))
    rng = np.random.default_rng(5)
    for _ in range(20):
        q = rng.uniform(LIM.q_min, LIM.q_max)
        v = 0.3 * rng.uniform(-LIM.v_max, LIM.v_max)
        p = rng.uniform([0.0, -0.6, -0.2], [0.8, 0.2, 0.8])
        ra, rb, rc = a.step(q, v, p), b.step(q, v, p), c.step(q, v, p)
        np.testing.assert_allclose(ra.a, rb.a, atol=1e-4 * (1 + np.abs(ra.a).max()))
        np.testing.assert_allclose(ra.a, rc.a, atol=1e-8 * (1 + np.abs(ra.a).max()))


def test_commanded_torque_produces_the_commanded_acceleration_in_mujoco() -> None:
    """τ from the QP applied to the MuJoCo model (same source) gives back a: dynamics are consistent."""
    import mujoco

    from robot.model_files import to_mjcf

    m = mujoco.MjModel.from_xml_string(to_mjcf(PARAMS))
    d = mujoco.MjData(m)
    ctl = QPController.for_superlimb()
    rng = np.random.default_rng(11)
    q = np.array([0.1, 0.4, 1.1])
    v = np.zeros(3)
    for k in range(60):
        target = np.array([0.45, -0.15, 0.2]) + 0.1 * rng.normal(size=3) * (k % 20 == 0)
        r = ctl.step(q, v, target)
        d.qpos[:], d.qvel[:], d.ctrl[:] = q, v, r.tau
        mujoco.mj_forward(m, d)
        np.testing.assert_allclose(d.qacc, r.a, atol=1e-6 * (1 + np.abs(r.a).max()))
        q, v = r.q_next, r.v_next


# ---------------------------------------------------------------- both parties' references in the cost
def _blended_and_fused(solver: str, alpha: float, offsets: tuple[np.ndarray, np.ndarray]):
    """The QP with both references weighed α, 1 − α, and the plain QP given their blend, from the same state."""
    from robot.tasks import BlendedTipTrackingTask

    model = build_pinocchio_model(PARAMS).model
    cfg = QPConfig(solver=solver, tip_max_error=None)
    blended = QPController(model, "knife_tip", LIM, cfg,
                           tip_task=BlendedTipTrackingTask(cfg.tip_weight, cfg.tip_kp, cfg.tip_kd, None))
    fused = QPController(model, "knife_tip", LIM, cfg)
    q, v = 0.5 * (LIM.q_min + LIM.q_max) + 0.1, np.array([0.05, -0.1, 0.02])
    tip = fused.tip_position(q)
    (p_r, v_r), (p_v, v_v) = [(tip + d, 10.0 * d) for d in offsets]
    blended.tip_task.set_second(1.0 - alpha, p_v, v_v, np.zeros(3))
    res_b = blended.step(q, v, p_r, v_r, np.zeros(3))
    res_f = fused.step(q, v, alpha * p_r + (1 - alpha) * p_v, alpha * v_r + (1 - alpha) * v_v, np.zeros(3))
    return blended, res_b, res_f, q, v, (p_r, v_r), (p_v, v_v)


@pytest.mark.parametrize("solver", SOLVERS)
def test_both_references_in_the_cost_unconstrained_is_the_stacked_least_squares(solver):
    """No limit binds: the answer is the float64 least-squares solution of every task's rows stacked."""
    alpha = 0.35
    qp, res, res_f, q, v, (p_r, v_r), (p_v, v_v) = _blended_and_fused(
        solver, alpha, (np.array([0.002, -0.001, 0.001]), np.array([-0.001, 0.002, 0.0])))
    s = qp.evaluate(q, v)
    cfg = qp.config
    rows, rhs = [], []
    for w, p, vel in ((alpha, p_r, v_r), (1 - alpha, p_v, v_v)):
        x = cfg.tip_kd * (vel - s.p_dot) + cfg.tip_kp * (p - s.p)
        rows.append(np.sqrt(w * cfg.tip_weight) * s.J)
        rhs.append(np.sqrt(w * cfg.tip_weight) * (x - s.drift))
    post = next(t for t in qp.tasks if t.name == "posture")
    rows.append(np.sqrt(post.weight) * np.eye(3))
    rhs.append(np.sqrt(post.weight) * (post.kp * (post.q_ref - q) - post.kd * v))
    for t in qp.tasks:
        if t.name == "damping":
            rows.append(np.sqrt(t.weight) * np.eye(3))
            rhs.append(-np.sqrt(t.weight) * t.kd * v)
        if t.name == "regularization":
            rows.append(np.sqrt(t.weight) * np.eye(3))
            rhs.append(np.zeros(3))
    a_ls = np.linalg.lstsq(np.vstack(rows), np.concatenate(rhs), rcond=None)[0]
    lo, hi, _ = intersect_by_priority([c.bounds(s) for c in qp.box_constraints])
    assert res.status is QPStatus.OK and np.all(a_ls > lo + 1e-3) and np.all(a_ls < hi - 1e-3)  # nothing binds
    np.testing.assert_allclose(res.a, a_ls, rtol=1e-6, atol=1e-6 * (1 + np.abs(a_ls).max()))
    np.testing.assert_allclose(res.a, res_f.a, rtol=1e-7, atol=1e-7)


@pytest.mark.parametrize("solver", SOLVERS)
def test_both_references_in_the_cost_equal_the_blend_where_the_limits_bind(solver):
    """References far away (unclipped) ask for more than the acceleration box and the torque limits: both bind, and
    the answer is still exactly that of tracking the blended reference (the weighted cost is the blend's plus a
    constant)."""
    qp, res, res_f, q, v, *_ = _blended_and_fused(
        solver, 0.6, (np.array([0.6, -0.3, 0.2]), np.array([-0.5, 0.8, -0.4])))
    lo, hi, _ = intersect_by_priority([c.bounds(qp.evaluate(q, v)) for c in qp.box_constraints])
    assert (np.isclose(res.a, lo, atol=1e-6) | np.isclose(res.a, hi, atol=1e-6)).any()
    assert np.isclose(np.abs(res.tau), LIM.tau_max, atol=1e-6).any()
    np.testing.assert_allclose(res.a, res_f.a, rtol=1e-7, atol=1e-7)


def test_both_references_under_a_hand_built_box_and_half_space_match_an_independent_solve():
    """A hand-built QP: the blended tip cost and the regularisation, a box and one half-space row G·a ≤ h that bind;
    the project's solver, an exact float64 active-set enumeration on the weighted residuals, and the fused-target
    cost agree."""
    from itertools import combinations

    from robot.solvers import make_backend
    from robot.state import ControlState
    from robot.tasks import AccelerationRegularization, BlendedTipTrackingTask, TipTrackingTask

    rng = np.random.default_rng(3)
    s = ControlState(q=np.zeros(3), v=np.zeros(3), dt=0.01, M=np.eye(3), h=np.zeros(3), p=np.zeros(3),
                     p_dot=np.zeros(3), J=rng.normal(size=(3, 3)), drift=rng.normal(size=3))
    alpha, p_r, p_v = 0.7, np.array([0.05, 0.0, 0.02]), np.array([-0.02, 0.04, 0.0])
    task = BlendedTipTrackingTask(1.0, 400.0, 40.0)
    task.set_reference(p_r)
    task.set_second(1.0 - alpha, p_v)
    reg = AccelerationRegularization(1e-6)
    H, c = (x + y for x, y in zip(task.compute_qp_objective(s), reg.compute_qp_objective(s)))
    fused = TipTrackingTask(1.0, 400.0, 40.0)
    fused.set_reference(alpha * p_r + (1 - alpha) * p_v)
    H_f, c_f = (x + y for x, y in zip(fused.compute_qp_objective(s), reg.compute_qp_objective(s)))
    a_free = np.linalg.solve(H, -c)
    lo, hi = -np.full(3, 5.0), np.full(3, 5.0)
    a_box = np.clip(a_free, lo, hi)
    G, h = np.array([[1.0, -1.0, 0.0]]), np.array([float(a_box[0] - a_box[1]) - 1.0])  # cuts the box's corner
    # independent: the weighted residuals stacked, minimised over every active set of C·a ≤ d (exact KKT solves)
    A = np.vstack([np.sqrt(alpha) * s.J, np.sqrt(1 - alpha) * s.J, np.sqrt(1e-6) * np.eye(3)])
    b = np.concatenate([np.sqrt(alpha) * (400.0 * p_r - s.drift), np.sqrt(1 - alpha) * (400.0 * p_v - s.drift),
                        np.zeros(3)])
    C, d = np.vstack([np.eye(3), -np.eye(3), G]), np.concatenate([hi, -lo, h])
    best, best_cost = None, np.inf
    for k in range(4):
        for S in combinations(range(len(d)), k):
            K = np.block([[A.T @ A, C[list(S)].T], [C[list(S)], np.zeros((k, k))]])
            try:
                a = np.linalg.solve(K, np.concatenate([A.T @ b, d[list(S)]]))[:3]
            except np.linalg.LinAlgError:
                continue
            r = A @ a - b
            if np.all(C @ a <= d + 1e-9) and r @ r < best_cost:
                best, best_cost = a, r @ r
    ours = make_backend("auto", 3, 1).solve(H, c, lo, hi, G, h).x
    ours_f = make_backend("auto", 3, 1).solve(H_f, c_f, lo, hi, G, h).x
    assert abs((G @ ours)[0] - h[0]) < 1e-6 or np.any(np.isclose(ours, lo) | np.isclose(ours, hi))  # binds
    assert np.linalg.norm(ours - a_free) > 0.1
    np.testing.assert_allclose(ours, best, atol=1e-6 * (1 + np.abs(best).max()))
    np.testing.assert_allclose(ours, ours_f, atol=1e-8)
