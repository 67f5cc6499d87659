"""The controller on a second robot: UR5 from example-robot-data (6 DOF, redundant for a 3-D tip task)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from robot.limits import JointLimits
from robot.qp import QPConfig, QPController, QPStatus
from robot.solvers import daqp_available

erd = pytest.importorskip("example_robot_data")
TOL = 1e-6
SOLVERS = ["daqp", "osqp"] if daqp_available() else ["osqp"]


@pytest.fixture(scope="module")
def ur5():
    return erd.load("ur5").model


def _limits(model, **changes) -> JointLimits:
    lim = JointLimits.from_model(model, a_max=8.0, a_brake=3.0)
    return replace(lim, **changes) if changes else lim


def _violation(r, lim: JointLimits) -> float:
    return float(max((np.abs(r.tau) - lim.tau_max).max(), (np.abs(r.v_next) - lim.v_max).max(),
                     (r.q_next - lim.q_max).max(), (lim.q_min - r.q_next).max()))


Q0 = np.array([0.0, -1.2, 1.5, -1.9, -1.57, 0.0])


@pytest.mark.parametrize("solver", SOLVERS)
def test_ur5_reaches_a_target(ur5, solver: str) -> None:
    lim = _limits(ur5)
    ctl = QPController(ur5, "tool0", lim, QPConfig(solver=solver, q_posture=Q0))
    q, v = Q0.copy(), np.zeros(6)
    target = ctl.evaluate(q, v).p + np.array([0.15, -0.1, 0.1])
    for _ in range(400):
        r = ctl.step(q, v, target)
        assert r.status is QPStatus.OK and _violation(r, lim) <= TOL
        q, v = r.q_next, r.v_next
    assert r.tip_error < 2e-3 and np.abs(v).max() < 1e-2


def test_ur5_stops_before_a_narrowed_joint_limit(ur5) -> None:
    """Elbow limited to ±1.6 rad, moving at full speed toward it with a target beyond: stops in time."""
    q_max = ur5.upperPositionLimit.copy()
    q_max[2] = 1.6
    lim = _limits(ur5, q_max=q_max)
    ctl = QPController(ur5, "tool0", lim, QPConfig(q_posture=Q0))
    q, v = Q0.copy(), np.zeros(6)
    q[2] = -0.2  # braking from 3.15 rad/s at 3 rad/s² needs 1.65 rad: start viable
    v[2] = lim.v_max[2]
    target = ctl.evaluate(q, np.zeros(6)).p + np.array([-0.4, 0.0, -0.3])  # folds the elbow
    peak = q[2]
    for _ in range(300):
        r = ctl.step(q, v, target)
        assert r.status is QPStatus.OK and _violation(r, lim) <= TOL
        q, v = r.q_next, r.v_next
        peak = max(peak, q[2])
    assert peak <= 1.6 + TOL and peak > 1.55


@settings(max_examples=15, deadline=None)
@given(seed=st.integers(0, 2**31 - 1))
def test_ur5_random_states_respect_limits(ur5, seed: int) -> None:
    rng = np.random.default_rng(seed)
    lim = _limits(ur5)
    ctl = QPController(ur5, "tool0", lim, QPConfig(q_posture=Q0, tip_kp=rng.uniform(50, 1000)))
    q = Q0 + rng.uniform(-0.8, 0.8, 6)
    v = rng.uniform(-0.5, 0.5, 6)
    target = rng.uniform([-0.6, -0.6, -0.2], [0.6, 0.6, 0.9])
    for _ in range(20):
        r = ctl.step(q, v, target)
        assert r.status is QPStatus.OK and _violation(r, lim) <= TOL
        q, v = r.q_next, r.v_next
