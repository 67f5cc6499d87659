"""QP tasks: each objective ½·aᵀHa + cᵀa equals its analytic w·‖A·a − b‖² up to a constant."""

from __future__ import annotations

import numpy as np
import pytest

from robot.errors import ControllerConfigError
from robot.state import ControlState
from robot.tasks import (
    AccelerationRegularization,
    BlendedTipTrackingTask,
    DampingTask,
    Objective,
    PostureTask,
    Task,
    TipTrackingTask,
)

N = 3


def _state(seed: int, n: int = N) -> ControlState:
    rng = np.random.default_rng(seed)
    A = rng.normal(size=(n, n))
    return ControlState(q=rng.normal(size=n), v=rng.normal(size=n), dt=0.01, M=A @ A.T + n * np.eye(n),
                        h=rng.normal(size=n), p=rng.normal(size=3), p_dot=rng.normal(size=3),
                        J=rng.normal(size=(3, n)), drift=rng.normal(size=3))


def _assert_same_up_to_constant(obj: Objective, residual, weight: float, seed: int) -> None:
    """f(a) = ½aᵀHa + cᵀa and g(a) = w‖r(a)‖² differ by the same constant at every a."""
    rng = np.random.default_rng(seed + 100)
    diffs = []
    for a in rng.normal(scale=3.0, size=(6, obj.c.size)):
        f = 0.5 * a @ obj.H @ a + obj.c @ a
        r = residual(a)
        diffs.append(f - weight * (r @ r))
    np.testing.assert_allclose(diffs, diffs[0], rtol=0, atol=1e-9 * (1 + abs(diffs[0])))
    np.testing.assert_allclose(obj.H, obj.H.T, atol=1e-12)


@pytest.mark.parametrize("seed", range(4))
def test_tip_tracking_objective_is_the_pd_residual(seed: int) -> None:
    s = _state(seed)
    rng = np.random.default_rng(seed)
    p_ref, v_ref, a_ref = rng.normal(size=3), rng.normal(size=3), rng.normal(size=3)
    task = TipTrackingTask(weight=0.7, kp=30.0, kd=5.0)
    task.set_reference(p_ref, v_ref, a_ref)
    desired = a_ref + 5.0 * (v_ref - s.p_dot) + 30.0 * (p_ref - s.p)
    np.testing.assert_allclose(task.desired_acceleration(s), desired, atol=1e-12)
    _assert_same_up_to_constant(task.compute_qp_objective(s), lambda a: s.J @ a + s.drift - desired, 0.7, seed)


def test_tip_tracking_clips_the_position_error() -> None:
    s = _state(7)
    direction = np.array([3.0, 0.0, 4.0]) / 5.0
    task = TipTrackingTask(weight=1.0, kp=100.0, kd=0.0, max_error=0.02)
    task.set_reference(s.p + 0.5 * direction)  # 0.5 m away, clipped to 0.02 m
    np.testing.assert_allclose(task.desired_acceleration(s), 100.0 * 0.02 * direction, atol=1e-12)
    task.set_reference(s.p + 0.01 * direction)  # inside: not clipped
    np.testing.assert_allclose(task.desired_acceleration(s), 100.0 * 0.01 * direction, atol=1e-12)


def test_tip_tracking_minimiser_reaches_the_desired_acceleration() -> None:
    s = _state(3)  # J (3×3) is full rank: the unconstrained minimum has J·a + drift = ẍ_des exactly
    task = TipTrackingTask(weight=2.0, kp=50.0, kd=10.0)
    task.set_reference(s.p + 0.01, np.zeros(3), np.zeros(3))
    H, c = task.compute_qp_objective(s)
    a = np.linalg.solve(H, -c)
    np.testing.assert_allclose(s.J @ a + s.drift, task.desired_acceleration(s), atol=1e-9)


def test_tip_tracking_without_reference_contributes_nothing() -> None:
    s = _state(1)
    task = TipTrackingTask()
    H, c = task.compute_qp_objective(s)
    assert not H.any() and not c.any()
    with pytest.raises(ControllerConfigError, match="reference"):
        task.desired_acceleration(s)
    task.set_reference(np.ones(3))
    assert task.compute_qp_objective(s).H.any()
    task.clear_reference()
    assert not task.compute_qp_objective(s).H.any()


@pytest.mark.parametrize("seed", range(3))
def test_posture_damping_and_regularization_objectives(seed: int) -> None:
    s = _state(seed)
    q_ref = np.random.default_rng(seed).normal(size=N)
    posture = PostureTask(q_ref, weight=0.3, kp=25.0, kd=10.0)
    _assert_same_up_to_constant(posture.compute_qp_objective(s),
                                lambda a: a - (25.0 * (q_ref - s.q) - 10.0 * s.v), 0.3, seed)
    damping = DampingTask(weight=0.2, kd=4.0)
    _assert_same_up_to_constant(damping.compute_qp_objective(s), lambda a: a + 4.0 * s.v, 0.2, seed)
    reg = AccelerationRegularization(1e-3)
    _assert_same_up_to_constant(reg.compute_qp_objective(s), lambda a: a, 1e-3, seed)


def test_cached_arrays_are_read_only_and_every_task_follows_the_protocol() -> None:
    s = _state(0)
    tasks = [TipTrackingTask(), PostureTask(np.zeros(N)), DampingTask(), AccelerationRegularization()]
    for task in tasks:
        assert isinstance(task, Task)
        assert isinstance(task.compute_qp_objective(s), Objective)
    for task in (PostureTask(np.zeros(N)), AccelerationRegularization()):
        H, _ = task.compute_qp_objective(s)
        with pytest.raises(ValueError):
            H[0, 0] = 1.0


@pytest.mark.parametrize("make", [
    lambda: TipTrackingTask(weight=-1.0), lambda: TipTrackingTask(kp=float("nan")),
    lambda: PostureTask(np.zeros(N), kd=-2.0), lambda: DampingTask(weight=float("inf")),
    lambda: AccelerationRegularization(0.0),
])
def test_bad_gains_raise(make) -> None:
    with pytest.raises(ControllerConfigError):
        make()


def test_posture_of_the_wrong_size_names_the_shapes() -> None:
    with pytest.raises(ControllerConfigError, match=r"shape \(3,\), got \(2,\)"):
        PostureTask(np.zeros(2)).compute_qp_objective(_state(0))


@pytest.mark.parametrize("seed", range(3))
def test_blended_tip_objective_is_the_weighted_sum_and_the_blend(seed: int) -> None:
    """α·w·‖r_r‖² + (1 − α)·w·‖r_v‖² and w·‖J·a + J̇v − (α·ẍ_r + (1 − α)·ẍ_v)‖² differ from it by constants."""
    s = _state(seed)
    rng = np.random.default_rng(seed + 10)
    refs = [(s.p + 0.01 * rng.normal(size=3), rng.normal(size=3), rng.normal(size=3)) for _ in range(2)]
    alpha, w = 0.3, 0.7
    task = BlendedTipTrackingTask(weight=w, kp=30.0, kd=5.0)
    task.set_reference(*refs[0])
    task.set_second(1.0 - alpha, *refs[1])
    x_r, x_v = (a + 5.0 * (v - s.p_dot) + 30.0 * (p - s.p) for p, v, a in refs)
    obj = task.compute_qp_objective(s)

    def weighted(a):
        r_r, r_v = s.J @ a + s.drift - x_r, s.J @ a + s.drift - x_v
        return np.concatenate([np.sqrt(alpha) * r_r, np.sqrt(1.0 - alpha) * r_v])

    _assert_same_up_to_constant(obj, weighted, w, seed)
    _assert_same_up_to_constant(obj, lambda a: s.J @ a + s.drift - (alpha * x_r + (1 - alpha) * x_v), w, seed)


def test_blended_tip_task_without_a_second_is_the_tip_task_and_checks_its_weight() -> None:
    s = _state(5)
    plain, blended = TipTrackingTask(0.5, 30.0, 5.0), BlendedTipTrackingTask(0.5, 30.0, 5.0)
    for t in (plain, blended):
        t.set_reference(s.p + 0.01, np.ones(3), np.zeros(3))
    blended.set_second(0.4, s.p - 0.01)
    blended.clear_second()
    for a, b in zip(plain.compute_qp_objective(s), blended.compute_qp_objective(s)):
        np.testing.assert_array_equal(a, b)
    with pytest.raises(ControllerConfigError, match="weight must be in"):
        blended.set_second(1.5, s.p)
