"""The joint servo against MuJoCo itself: its step prediction, the viable bound, limits at 1 kHz."""

import math

import mujoco
import numpy as np
import pytest

from robot.superlimb import SuperLimbParams
from sim.scene import EatingScene
from sim.servo import JointServo, ServoConfig, viable_next_velocity


def test_mujoco_step_is_the_semi_implicit_euler_the_servo_assumes():
    s = EatingScene()
    m, d = s.model, s.data
    rng = np.random.default_rng(0)
    p = SuperLimbParams()
    M = np.zeros((3, 3))
    for _ in range(20):
        s.set_state(rng.uniform(p.lower, p.upper), rng.uniform(-1, 1, 3) * p.velocity_limit, 0.0)
        mujoco.mj_step1(m, d)
        q, v = d.qpos[:3].copy(), d.qvel[:3].copy()
        mujoco.mj_fullM(m, d, M)
        tau = rng.uniform(-1, 1, 3) * p.torque_limit
        v_pred = v + m.opt.timestep * np.linalg.solve(M, tau - d.qfrc_bias[:3])
        d.ctrl[:3] = tau
        mujoco.mj_step2(m, d)
        np.testing.assert_allclose(d.qvel[:3], v_pred, atol=1e-12)
        np.testing.assert_allclose(d.qpos[:3], q + m.opt.timestep * v_pred, atol=1e-14)
        np.testing.assert_allclose(d.actuator_force[:3], tau, atol=1e-12)


@pytest.mark.parametrize("A,h", [(10.0, 0.001), (20.0, 0.001), (15.0, 0.01)])
def test_viable_bound_lets_braking_stop_before_the_limit(A, h):
    """Brute force: from v⁺ at the bound, semi-implicit braking stops before the limit, within one step of it."""
    rng = np.random.default_rng(1)
    for gap in np.concatenate([rng.uniform(0, 0.5, 200), [0.0, 1e-9, 1e-5]]):
        u = viable_next_velocity(float(gap), A, h)

        def overshoot(v_next: float, gap: float = float(gap)) -> float:
            q, v = h * v_next, v_next  # q measured from the current position, after this step
            worst = q
            while v > 0:
                v = max(v - A * h, 0.0)
                q += h * v
                worst = max(worst, q)
            return worst - gap

        assert overshoot(u) <= 1e-12
        assert overshoot(u) >= -h * u - 1e-12  # nearly tight: at most one step's travel is given away
    assert math.isclose(viable_next_velocity(-0.001, A, h), -0.001 / h)


def _run_servo(q0, v0, q_cmd, v_cmd, a_cmd, steps, servo_cls=JointServo):
    s = EatingScene()
    m, d = s.model, s.data
    s.set_state(np.asarray(q0, float), np.asarray(v0, float), 0.0)
    srv = servo_cls(m, d)
    srv.set_segment(q_cmd, v_cmd, a_cmd, 0.0)  # r = 0: a fixed set point (q_cmd, v_cmd)
    q_hist, v_hist, f_hist = [], [], []
    for _ in range(steps):
        mujoco.mj_step1(m, d)
        d.ctrl[:3] = srv.torque()
        mujoco.mj_step2(m, d)
        q_hist.append(d.qpos[:3].copy())
        v_hist.append(d.qvel[:3].copy())
        f_hist.append(d.actuator_force[:3].copy())
    return np.array(q_hist), np.array(v_hist), np.array(f_hist), srv


def test_servo_stops_at_position_limits_when_driven_through_them():
    p = SuperLimbParams()
    v0 = 0.95 * p.velocity_limit * np.array([1, 1, -1])
    target = np.array([p.upper[0] + 0.5, p.upper[1] + 0.5, p.lower[2] - 0.5])  # beyond the limits
    q, v, f, srv = _run_servo([p.upper[0] - 0.3, p.upper[1] - 0.3, p.lower[2] + 0.3], v0, target,
                              v0, np.zeros(3), 600)
    assert np.all(q <= p.upper + 1e-6) and np.all(q >= p.lower - 1e-6)
    assert np.all(np.abs(v) <= p.velocity_limit + 1e-6)
    assert np.all(np.abs(f) <= p.torque_limit + 1e-9)
    assert abs(q[-1, 0] - p.upper[0]) < 1e-3 and abs(q[-1, 2] - p.lower[2]) < 1e-3  # it does get there
    assert srv.brake_infeasible == 0


class _NaiveServo(JointServo):
    """Tracks without the viable box (torque clipped only): what the limits look like without it."""

    def torque(self):
        saved = self._joints  # per joint (q_min, q_max, v_max, A, free gap)
        self._joints = [(-1e9, 1e9, 1e9, A, free) for _, _, _, A, free in saved]
        try:
            return super().torque()
        finally:
            self._joints = saved


def test_without_the_viable_box_the_same_command_violates_the_limits():
    p = SuperLimbParams()
    v0 = 0.95 * p.velocity_limit * np.array([1, 1, -1])
    target = np.array([p.upper[0] + 0.5, p.upper[1] + 0.5, p.lower[2] - 0.5])
    q, v, _, _ = _run_servo([p.upper[0] - 0.3, p.upper[1] - 0.3, p.lower[2] + 0.3], v0, target, v0, np.zeros(3),
                            600, _NaiveServo)
    assert np.any(q > p.upper + 1e-6) or np.any(q < p.lower - 1e-6) or np.any(np.abs(v) > p.velocity_limit + 1e-6)


def test_servo_tracks_a_smooth_feasible_segment_closely():
    # constant acceleration from rest: reference q(s) = q0 + ½ a s²
    q0, a = np.array([0.2, 0.4, 0.9]), np.array([2.0, -3.0, 4.0])
    s = EatingScene()
    m, d = s.model, s.data
    s.set_state(q0, np.zeros(3), 0.0)
    srv = JointServo(m, d, config=ServoConfig())
    T = 0.01
    for k in range(20):
        t0 = k * T
        t1 = t0 + T
        srv.set_segment(q0 + 0.5 * a * t1**2, a * t1, a, t1)
        for _ in range(10):
            mujoco.mj_step1(m, d)
            d.ctrl[:3] = srv.torque()
            mujoco.mj_step2(m, d)
    np.testing.assert_allclose(d.qpos[:3], q0 + 0.5 * a * 0.2**2, atol=2e-4)
    np.testing.assert_allclose(d.qvel[:3], a * 0.2, atol=2e-2)
    assert srv.qp_steps == 0


def test_servo_refuses_a_model_it_cannot_predict():
    s = EatingScene()
    s.model.opt.integrator = mujoco.mjtIntegrator.mjINT_RK4
    with pytest.raises(ValueError, match="Euler"):
        JointServo(s.model, s.data)


def test_braking_that_needs_more_than_the_torque_limit_is_counted():
    """With a braking acceleration the motors cannot deliver, the servo's check says so."""
    p = SuperLimbParams().with_joint("shoulder", braking_acceleration=99.0)
    s = EatingScene()
    m, d = s.model, s.data
    s.set_state(np.array([0.0, p.upper[1] - 0.2, 0.5]), np.array([0.0, 1.9, 0.0]), 0.0)
    srv = JointServo(m, d, p)
    srv.set_segment(np.array([0.0, p.upper[1] + 0.5, 0.5]), np.array([0.0, 1.9, 0.0]), np.zeros(3), 0.0)
    for _ in range(300):
        mujoco.mj_step1(m, d)
        d.ctrl[:3] = srv.torque()
        mujoco.mj_step2(m, d)
    assert srv.brake_infeasible > 0
    with_default = _run_servo([0.0, p.upper[1] - 0.2, 0.5], [0.0, 1.9, 0.0], [0.0, p.upper[1] + 0.5, 0.5],
                              [0.0, 1.9, 0.0], np.zeros(3), 300)[3]
    assert with_default.brake_infeasible == 0


def test_torque_into_writes_the_torque_into_the_given_array():
    p = SuperLimbParams()
    s = EatingScene()
    m, d = s.model, s.data
    s.set_state(np.array([0.0, p.upper[1] - 0.02, 0.3]), np.array([0.0, 0.9 * p.velocity_limit[1], 0.0]), 0.0)
    srv = JointServo(m, d)
    for target in (np.zeros(3), np.array([0.0, p.upper[1] + 0.5, 0.5])):  # free, then at the limits
        srv.set_segment(target, np.zeros(3), np.zeros(3), 0.0)
        mujoco.mj_step1(m, d)
        out = np.full(3, np.nan)
        assert srv.torque_into(out) is out
        assert np.array_equal(out, srv.torque())
        assert np.all(np.abs(out) <= p.torque_limit + 1e-9)
