"""Constraint rows: viability of the position limit, priority intersection, torque rows."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from robot.constraints import (
    AccelerationLimit,
    PositionLimit,
    TorqueLimit,
    VelocityLimit,
    intersect_by_priority,
    viable_velocity_bound,
)
from robot.limits import JointLimits
from robot.state import ControlState

finite = dict(allow_nan=False, allow_infinity=False)


def _state(q, v, dt=0.01, M=None, h=None) -> ControlState:
    n = len(q)
    M = np.eye(n) if M is None else M
    h = np.zeros(n) if h is None else h
    z3 = np.zeros(3)
    return ControlState(np.asarray(q, float), np.asarray(v, float), dt, M, h, z3, z3, np.zeros((3, n)), z3)


def _brake_until_rest(q: float, v: float, dt: float, a_brake: float) -> float:
    """Largest position reached when braking at a = max(−A, −v/dt) (exact integration)."""
    q_max_seen = q
    for _ in range(100000):
        if v <= 0:
            break
        a = max(-a_brake, -v / dt)
        q += v * dt + 0.5 * a * dt * dt
        v += a * dt
        q_max_seen = max(q_max_seen, q)
    return q_max_seen


@settings(max_examples=300, deadline=None)
@given(gap=st.floats(0.0, 2.0, **finite), v=st.floats(-3.0, 3.0, **finite),
       dt=st.floats(1e-3, 0.02, **finite), a_brake=st.floats(0.5, 50.0, **finite))
def test_viable_bound_lets_the_joint_stop_before_the_limit(gap, v, dt, a_brake) -> None:
    """From any next velocity ≤ the bound (and inside the limit) braking never crosses the limit."""
    u = float(viable_velocity_bound(np.array([gap]), np.array([v]), dt, np.array([a_brake]))[0])
    q_next = dt * (v + u) / 2.0  # position change with v⁺ = u, relative to q = 0, limit at `gap`
    assert q_next <= gap + 1e-12
    if u > 0:
        assert _brake_until_rest(q_next, u, dt, a_brake) <= gap + 1e-9


@settings(max_examples=200, deadline=None)
@given(q0=st.floats(0.0, 1.0, **finite), v0=st.floats(-2.0, 3.0, **finite), frac=st.floats(0.0, 1.0, **finite),
       dt=st.floats(1e-3, 0.02, **finite), a_brake=st.floats(1.0, 30.0, **finite))
def test_viable_set_is_invariant_under_braking(q0, v0, frac, dt, a_brake) -> None:
    """A state the constraint allowed stays allowed: braking is always admissible and stops in time."""
    q_max, A = 1.0, np.array([a_brake])

    def bound(q: float, v: float) -> float:
        return float(viable_velocity_bound(np.array([q_max - q]), np.array([v]), dt, A)[0])

    u0 = bound(q0, v0)
    v = frac * u0 if u0 > 0 else u0  # any next velocity the constraint admits
    q = q0 + dt * (v0 + v) / 2.0
    assert q <= q_max + 1e-12
    for _ in range(5000):
        if v <= 0:
            break
        a = max(-a_brake, -v / dt)
        v_next = v + a * dt
        assert v_next <= bound(q, v) + 1e-9  # the braking action satisfies the constraint
        q, v = q + (v + 0.5 * a * dt) * dt, v_next
        assert q <= q_max + 1e-9
    assert v <= 0


def test_viable_bound_is_not_overly_conservative() -> None:
    """Far from the limit at rest the bound is the continuous √(2A·gap) up to O(A·dt)."""
    gap, dt, A = np.array([0.5]), 0.01, np.array([10.0])
    u = viable_velocity_bound(gap, np.zeros(1), dt, A)[0]
    assert np.sqrt(2 * A[0] * gap[0]) - A[0] * dt <= u <= np.sqrt(2 * A[0] * gap[0])


def test_position_limit_brakes_the_upper_side_and_mirrors_the_lower() -> None:
    lim = JointLimits([-1.0], [1.0], [2.0], [50.0], [10.0], [5.0])
    pos = PositionLimit(lim)
    lo, hi = pos.bounds(_state([0.9], [2.0]))
    assert hi[0] < 0  # must decelerate: 0.1 rad left, 2 rad/s needs 0.2 rad at 10 rad/s²
    lo2, hi2 = pos.bounds(_state([-0.9], [-2.0]))
    np.testing.assert_allclose([lo2[0], hi2[0]], [-hi[0], -lo[0]])


@settings(max_examples=200, deadline=None)
@given(boxes=st.lists(st.tuples(st.floats(-5, 5, **finite), st.floats(-5, 5, **finite)), min_size=1, max_size=4))
def test_intersect_by_priority(boxes) -> None:
    arrays = [(np.array([min(a, b)]), np.array([max(a, b)])) for a, b in boxes]
    lo, hi, conflict = intersect_by_priority(arrays)
    assert lo[0] <= hi[0]
    # the first (most important) box always holds
    assert arrays[0][0][0] <= lo[0] and hi[0] <= arrays[0][1][0]
    plain_lo = max(a[0][0] for a in arrays)
    plain_hi = min(a[1][0] for a in arrays)
    if plain_lo <= plain_hi:
        assert conflict[0] == 0 and lo[0] == plain_lo and hi[0] == plain_hi
    else:
        assert conflict[0] > 0 and lo[0] == hi[0]


def test_intersect_collapses_toward_the_violated_limit() -> None:
    accel = (np.array([-10.0]), np.array([10.0]))
    beyond_upper = (np.array([-1e3]), np.array([-500.0]))  # position wants a ≤ −500
    lo, hi, conflict = intersect_by_priority([accel, beyond_upper])
    assert lo[0] == hi[0] == -10.0 and conflict[0] == 1


@settings(max_examples=100, deadline=None)
@given(seed=st.integers(0, 2**31 - 1))
def test_torque_rows_match_inverse_dynamics(seed) -> None:
    rng = np.random.default_rng(seed)
    n = 3
    B = rng.normal(size=(n, n))
    M = B @ B.T + n * np.eye(n)
    h = rng.normal(size=n)
    tau_max = rng.uniform(0.5, 5.0, n)
    lim = JointLimits(-np.ones(n), np.ones(n), np.ones(n), np.ones(n) * 100, np.ones(n), tau_max)
    G, hh = TorqueLimit(lim).compute_qp_inequalities(_state(np.zeros(n), np.zeros(n), M=M, h=h))
    for _ in range(20):
        a = rng.normal(scale=2.0, size=n)
        inside = bool(np.all(G @ a <= hh))
        assert inside == bool(np.all(np.abs(M @ a + h) <= tau_max))


def test_box_rows_and_bounds_agree() -> None:
    lim = JointLimits([-1, -1], [1, 1], [2, 3], [20, 30], [10, 10], [5, 5])
    s = _state([0.2, -0.3], [1.0, -2.5])
    for c in (AccelerationLimit(lim), VelocityLimit(lim), PositionLimit(lim)):
        lo, hi = c.bounds(s)
        G, h = c.compute_qp_inequalities(s)
        assert G.shape == (4, 2) and c.num_rows(2) == 4
        np.testing.assert_allclose(G @ hi, np.concatenate([hi, -hi]))
        assert np.all(G @ lo <= h + 1e-12) and np.all(G @ hi <= h + 1e-12)
    lo, hi = VelocityLimit(lim).bounds(s)
    np.testing.assert_allclose(s.v + hi * s.dt, lim.v_max)
    np.testing.assert_allclose(s.v + lo * s.dt, -lim.v_max)


def test_limits_return_named_read_only_rows() -> None:
    from robot.constraints import Bounds, Constraint, Limit, default_constraints

    lim = JointLimits([-1, -1], [1, 1], [2, 3], [20, 30], [10, 10], [5, 5])
    s = _state([0.2, -0.3], [1.0, -2.5])
    boxes, rows = default_constraints(lim)
    for c in [*boxes, *rows]:
        assert isinstance(c, Limit)
        out = c.compute_qp_inequalities(s)
        assert isinstance(out, Constraint) and out.G.shape == (4, 2) and out.h.shape == (4,)
        with pytest.raises(ValueError):
            out.G[0, 0] = 1.0
    assert all(isinstance(b.bounds(s), Bounds) for b in boxes)
    with pytest.raises(ValueError):  # limit arrays are read-only
        lim.q_max[0] = 2.0
    with pytest.raises(ValueError):
        AccelerationLimit(lim).bounds(s).lo[0] = 0.0


@settings(max_examples=200, deadline=None)
@given(gap=st.floats(-0.5, 2.0, **finite), v=st.floats(-3.0, 3.0, **finite),
       dt=st.floats(1e-3, 0.02, **finite), a_brake=st.floats(0.5, 50.0, **finite))
def test_scalar_and_vector_viable_bounds_agree(gap, v, dt, a_brake) -> None:
    """PositionLimit uses a scalar loop for speed; it must equal the documented vector formula."""
    from robot.constraints import _viable_bound_scalar

    vec = float(viable_velocity_bound(np.array([gap]), np.array([v]), dt, np.array([a_brake]))[0])
    assert _viable_bound_scalar(gap, v, dt, a_brake) == pytest.approx(vec, rel=1e-12, abs=1e-12)
