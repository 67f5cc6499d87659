"""The forecast as a trajectory between model ticks, and a known trajectory (oracle)."""

from __future__ import annotations

import numpy as np
import pytest

from mpcshare.control.forecast import ForecastTrack, KnownTrajectory


def test_spline_passes_through_the_forecast_and_extrapolates_at_its_end_velocity():
    track = ForecastTrack(0.1)
    assert not track.ready
    assert np.isnan(track.at(0.0)[0]).all()
    pts = np.column_stack([np.linspace(0, 0.5, 6) ** 2, np.zeros(6), np.ones(6)])
    track.update(1.0, pts)
    p, v, _ = track.sample(1.0 + 0.1 * np.arange(6))
    np.testing.assert_allclose(p, pts, atol=1e-12)
    p_end, v_end, a_end = track.at(1.0 + 0.5 + 0.2)
    np.testing.assert_allclose(p_end, pts[-1] + 0.2 * v[-1], atol=1e-12)
    np.testing.assert_allclose(a_end, 0.0)
    np.testing.assert_allclose(track.at(0.5)[0], pts[0])  # before the tick: held


def test_single_point_forecast_is_a_hold():
    track = ForecastTrack(0.1)
    track.update(0.0, np.array([[1.0, 2.0, 3.0]]))
    p, v, a = track.sample(np.array([0.0, 0.05, 0.3]))
    np.testing.assert_allclose(p, [[1, 2, 3]] * 3)
    assert not v.any() and not a.any()


def test_cross_fade_is_continuous_and_its_derivatives_are_consistent():
    track = ForecastTrack(0.1, fade_s=0.1)
    t0 = np.linspace(0, 0.5, 6)
    track.update(0.0, np.column_stack([t0, 0 * t0, 0 * t0]))  # moving at 1 m/s along x
    before = track.at(0.1 - 1e-9)[0]
    track.update(0.1, np.column_stack([0.1 + 0 * t0, 0.05 + 0 * t0, 0 * t0]))  # then: stand still elsewhere
    np.testing.assert_allclose(track.at(0.1)[0], before, atol=1e-6)  # no jump at the tick
    np.testing.assert_allclose(track.at(0.2)[0], [0.1, 0.05, 0.0], atol=1e-12)  # faded in after one period
    ts = np.linspace(0.1, 0.2, 201)
    p, v, a = track.sample(ts)
    h = ts[1] - ts[0]
    np.testing.assert_allclose(np.gradient(p, h, axis=0)[2:-2], v[2:-2], atol=2e-3)
    np.testing.assert_allclose(np.gradient(v, h, axis=0)[2:-2], a[2:-2], atol=0.5)


def test_bad_forecasts_are_refused_and_leave_the_track():
    track = ForecastTrack(0.1)
    track.update(0.0, np.zeros((3, 3)))
    with pytest.raises(ValueError, match="not finite"):
        track.update(0.1, np.full((3, 3), np.nan))
    np.testing.assert_allclose(track.at(0.05)[0], 0.0)
    with pytest.raises(ValueError, match="step_s"):
        ForecastTrack(0.0)
    track.reset()
    assert not track.ready


def test_known_trajectory_is_the_trajectory():
    t = np.arange(200) * 0.01
    pos = np.column_stack([np.sin(t), np.cos(t), t])
    known = KnownTrajectory(pos, 0.01)
    p, v, _ = known.sample(np.array([0.5, 1.234]))
    np.testing.assert_allclose(p, np.column_stack([np.sin([0.5, 1.234]), np.cos([0.5, 1.234]), [0.5, 1.234]]),
                               atol=1e-7)
    np.testing.assert_allclose(v[0], [np.cos(0.5), -np.sin(0.5), 1.0], atol=1e-4)
    with pytest.raises(ValueError, match="shape"):
        KnownTrajectory(pos[:, :2], 0.01)


def test_the_uniform_spline_equals_scipys_natural_spline():
    from scipy.interpolate import CubicSpline

    from mpcshare.control.forecast import _UniformSpline

    rng = np.random.default_rng(2)
    for n in (2, 3, 6):
        pts = rng.normal(size=(n, 3))
        t0, h = 3.7, 0.1
        times = t0 + h * np.arange(n)
        ref = CubicSpline(times, pts, axis=0, bc_type="natural")
        sp = _UniformSpline(t0, h, pts)
        t = np.linspace(t0 + 1e-9, times[-1] - 1e-9, 57)
        p, v, a = sp(t)
        np.testing.assert_allclose(p, ref(t), atol=1e-12)
        np.testing.assert_allclose(v, ref(t, 1), atol=1e-10)
        np.testing.assert_allclose(a, ref(t, 2), atol=1e-8)
        np.testing.assert_allclose(sp.end_velocity, ref(times[-1], 1), atol=1e-10)
        pa, va, _ = sp(np.array([times[-1] + 0.2]))
        np.testing.assert_allclose(pa[0], pts[-1] + 0.2 * ref(times[-1], 1), atol=1e-10)
