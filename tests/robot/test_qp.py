"""QP controller on the SuperLimb: limits at random states, braking, saturation, recovery, odd inputs."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from robot.constraints import viable_velocity_bound
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
