"""ruckig reference smoother: limits, convergence, a target moving every cycle, odd inputs."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from robot.errors import ControllerConfigError
from robot.smoothing import ReferenceSmoother, SmoothingStatus

V, A, J, DT = 0.3, 2.0, 30.0, 0.01


def _run(sm: ReferenceSmoother, targets) -> tuple[np.ndarray, np.ndarray, np.ndarray, list]:
    out = [sm.update(t) for t in targets]
    return (np.array([o.position for o in out]), np.array([o.velocity for o in out]),
            np.array([o.acceleration for o in out]), [o.status for o in out])


def _check_limits(p, v, a) -> None:
    assert np.abs(v).max() <= V + 1e-9
    assert np.abs(a).max() <= A + 1e-9
    assert np.abs(np.diff(a, axis=0)).max() <= J * DT + 1e-9  # jerk over one cycle
    # the outputs are consistent: position integrates the velocity
    np.testing.assert_allclose(np.diff(p, axis=0), 0.5 * (v[1:] + v[:-1]) * DT, atol=J * DT**3)


def test_a_jump_is_smoothed_and_reached() -> None:
    sm = ReferenceSmoother(3, DT, V, A, J)
    sm.reset([0.0, 0.0, 0.0])
    targets = [np.array([0.2, -0.1, 0.05])] * 300
    p, v, a, status = _run(sm, targets)
    _check_limits(p, v, a)
    assert status[0] is SmoothingStatus.WORKING and status[-1] is SmoothingStatus.FINISHED
    np.testing.assert_allclose(p[-1], targets[-1], atol=1e-9)
    assert np.abs(p[0]).max() < 1e-3  # no jump in the first cycle


@settings(max_examples=20, deadline=None)
@given(seed=st.integers(0, 2**31 - 1))
def test_target_moving_every_cycle_with_jumps(seed: int) -> None:
    """A target random-walking every cycle with occasional jumps (hand-overs): no error, limits hold."""
    rng = np.random.default_rng(seed)
    steps = 400
    walk = np.cumsum(rng.normal(scale=0.004, size=(steps, 3)), axis=0)
    jumps = np.cumsum((rng.random((steps, 1)) < 0.02) * rng.normal(scale=0.2, size=(steps, 3)), axis=0)
    sm = ReferenceSmoother(3, DT, V, A, J)
    p, v, a, status = _run(sm, walk + jumps)
    _check_limits(p, v, a)
    assert set(status) <= {SmoothingStatus.WORKING, SmoothingStatus.FINISHED}


def test_follows_a_slow_moving_target_with_feedforward() -> None:
    sm = ReferenceSmoother(3, DT, V, A, J)
    t = np.arange(600) * DT
    path = np.stack([0.1 * np.sin(t), 0.05 * np.cos(t), 0.02 * t], axis=1)
    vel = np.stack([0.1 * np.cos(t), -0.05 * np.sin(t), 0.02 + 0 * t], axis=1)
    out = [sm.update(p, v) for p, v in zip(path, vel)]
    err = np.abs(out[-1].position - path[-1]).max()
    assert err < 1e-3


def test_non_finite_target_keeps_the_previous_one() -> None:
    sm = ReferenceSmoother(3, DT, V, A, J)
    sm.reset([0.0, 0.0, 0.0])
    for _ in range(20):
        sm.update([0.1, 0.0, 0.0])
    r = sm.update([np.nan, 0.0, 0.0])
    assert r.status is SmoothingStatus.INVALID_TARGET and np.all(np.isfinite(r.position))
    for _ in range(200):
        r = sm.update([np.inf, 0.0, 0.0])
    np.testing.assert_allclose(r.position, [0.1, 0.0, 0.0], atol=1e-9)
    fresh = ReferenceSmoother(3, DT, V, A, J).update([np.nan, 1.0, 1.0])
    assert fresh.status is SmoothingStatus.INVALID_TARGET


def test_target_velocity_beyond_the_limit_is_clipped() -> None:
    sm = ReferenceSmoother(3, DT, V, A, J)
    sm.reset([0.0, 0.0, 0.0])
    r = sm.update([0.5, 0.0, 0.0], [5.0, 0.0, 0.0], [0.0, 0.0, 50.0])
    assert r.status is SmoothingStatus.CLIPPED and np.abs(r.velocity).max() <= V


def test_rejected_input_falls_back_to_braking(monkeypatch) -> None:
    sm = ReferenceSmoother(3, DT, V, A, J)
    sm.reset([0.0, 0.0, 0.0])
    for _ in range(30):
        r = sm.update([1.0, 0.0, 0.0])
    v_before = r.velocity[0]
    assert v_before > 0.1

    class Broken:
        def update(self, *args):
            raise RuntimeError("[ruckig] rejected")

    monkeypatch.setattr(sm, "_otg", Broken())
    speeds = []
    for _ in range(100):
        r = sm.update([1.0, 0.0, 0.0], [0.1, 0.0, 0.0])
        assert r.status is SmoothingStatus.FALLBACK and "braking" in r.reason
        speeds.append(abs(r.velocity[0]))
    assert speeds[0] < v_before and speeds[-1] < 1e-9  # decelerated to rest
    assert np.abs(np.diff(speeds)).max() <= A * DT + 1e-9


def test_misuse_raises() -> None:
    with pytest.raises(ControllerConfigError):
        ReferenceSmoother(3, DT, max_velocity=-1.0)
    with pytest.raises(ControllerConfigError):
        ReferenceSmoother(3, 0.0)
    with pytest.raises(ControllerConfigError):
        ReferenceSmoother(3, DT).update([0.0, 0.0])
    with pytest.raises(ControllerConfigError):
        ReferenceSmoother(3, DT).reset([np.nan, 0, 0])
