"""Streaming front end: streamed features equal the offline pipeline; Kalman behaviour."""

from __future__ import annotations

from functools import lru_cache

import numpy as np
import pytest
from filterpy.common import Q_discrete_white_noise
from filterpy.kalman import KalmanFilter

from learning.modes import TaskModes
from learning.preprocessing.preprocess import Standardizer, causal_windows
from learning.preprocessing.resample import causal_downsample
from mpcshare.control.frontend import ForkKalman, StreamingFrontEnd
from sim.demonstrator import GeneratorConfig, generate_demonstrations


@lru_cache(maxsize=4)
def _fitted(seed: int, single_regime: bool = False):
    demos = generate_demonstrations(n_subjects=1, minutes=1.0, seed=seed,
                                    config=GeneratorConfig(trial_minutes=0.5, single_regime=single_regime))
    low = causal_downsample(demos, 10.0)
    std = Standardizer("sensor", field="obs").fit(low)
    low_std = std.transform(low)
    X = np.concatenate([tr.obs for tr in low_std.trials])
    modes = TaskModes(n_modes=1 if single_regime else 3, n_restarts=1, seed=seed).fit(
        X, [len(tr) for tr in low_std.trials])
    return demos, std, low_std, modes


@pytest.mark.parametrize("seed,single", [(0, False), (3, True)])
def test_streamed_windows_equal_offline(seed, single):
    demos, std, low_std, modes = _fitted(seed, single)
    tr, tr_low = demos.trials[1], low_std.trials[1]
    offline = causal_windows(low_std.select([tr.trial_id]), 1.0, rms=True)
    post = modes.filter_proba(tr_low.obs)
    nov = -modes.log_predictive(tr_low.obs)
    fe = StreamingFrontEnd(std, modes, rate_hz=100.0, model_hz=10.0, window_s=1.0)
    samples, windows, probas, novelty = [], [], [], []
    for k in range(len(tr)):
        out = fe.step(tr.t[k], tr.obs[k])
        np.testing.assert_array_equal(out.feature_sample, tr.obs[k])  # raw sample goes on
        if out.tick is not None:
            samples.append(out.tick.sample)
            probas.append(out.tick.mode_proba)
            novelty.append(out.tick.novelty)
            if out.tick.window is not None:
                windows.append(out.tick.window)
    assert len(samples) == len(tr_low)
    np.testing.assert_allclose(np.array(samples), tr_low.obs, rtol=0, atol=1e-9)
    assert len(windows) == len(offline)
    np.testing.assert_allclose(np.array(windows), offline.X, rtol=0, atol=1e-9)
    np.testing.assert_allclose(np.array(probas), post, rtol=0, atol=1e-9)
    np.testing.assert_allclose(np.array(novelty), nov, rtol=1e-9, atol=1e-9)


def test_kalman_equals_filterpy_per_channel():
    """The vectorised filter equals filterpy's KalmanFilter run channel by channel (gaps, irregular dt)."""
    rng = np.random.default_rng(5)
    d, n = 4, 400
    accel, meas = rng.uniform(0.5, 3.0, d), rng.uniform(1e-3, 1e-2, d)
    t = np.cumsum(rng.uniform(0.005, 0.02, n))
    Z = np.cumsum(rng.normal(scale=0.01, size=(n, d)), axis=0)
    Z[rng.random((n, d)) < 0.2] = np.nan
    Z[0] = rng.normal(size=d)
    ours = ForkKalman(d, 0.01, accel, meas)
    refs = []
    p00, p11 = ours.initial_covariance()
    for j in range(d):
        kf = KalmanFilter(dim_x=2, dim_z=1)
        kf.x, kf.P = np.array([Z[0, j], 0.0]), np.diag([p00[j], p11[j]])
        kf.H, kf.R = np.array([[1.0, 0.0]]), np.array([[meas[j] ** 2]])
        refs.append(kf)
    ours.step(t[0], Z[0])
    for k in range(1, n):
        prior = ours.step(t[k], Z[k])
        dt = t[k] - t[k - 1]
        for j, kf in enumerate(refs):
            kf.predict(F=np.array([[1.0, dt], [0.0, 1.0]]), Q=Q_discrete_white_noise(2, dt=dt, var=accel[j] ** 2))
            assert prior[j] == pytest.approx(kf.x[0], rel=1e-12, abs=1e-12)
            if np.isfinite(Z[k, j]):
                kf.update(Z[k, j])
        np.testing.assert_allclose(ours.position, [kf.x[0] for kf in refs], rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(ours.velocity, [kf.x[1] for kf in refs], rtol=1e-10, atol=1e-10)
        np.testing.assert_allclose(ours.p01, [kf.P[0, 1] for kf in refs], rtol=1e-10, atol=1e-16)


def test_kalman_predicts_through_gaps_and_tracks_velocity():
    dt = 0.01
    kf = ForkKalman(2, dt, accel_std=np.array([1.0, 1.0]), meas_std=np.array([1e-4, 1e-4]))
    vel = np.array([0.2, -0.1])
    for k in range(200):
        kf.step(k * dt, np.array([0.1, 0.3]) + vel * k * dt)
    np.testing.assert_allclose(kf.velocity, vel, atol=1e-3)
    # 30 samples missing: the prediction continues the line, predicting_for_s grows
    for k in range(200, 230):
        prior = kf.step(k * dt, None)
    np.testing.assert_allclose(prior, np.array([0.1, 0.3]) + vel * 229 * dt, atol=1e-3)
    assert kf.predicting_for(229 * dt) == pytest.approx(0.30, abs=1e-9)
    # one channel missing: the other one still updates
    kf.step(2.30, np.array([np.nan, 0.3 + vel[1] * 2.30]))
    assert kf.predicting_for(2.30) == 0.0


def test_frontend_substitutes_missing_and_stale_samples():
    demos, std, _, modes = _fitted(0)
    tr = demos.trials[0]
    fe = StreamingFrontEnd(std, modes)
    for k in range(50):
        fe.step(tr.t[k], tr.obs[k])
    gap = tr.obs[50].copy()
    gap[[0, 4]] = np.nan
    out = fe.step(tr.t[50], gap)
    assert out.missing.tolist() == [j in (0, 4) for j in range(9)]
    assert np.all(np.isfinite(out.feature_sample))
    np.testing.assert_array_equal(out.feature_sample[1:4], tr.obs[50, 1:4])
    assert abs(out.feature_sample[0] - tr.obs[50, 0]) < 0.01  # KF prediction of a smooth signal
    fe.step(tr.t[51], tr.obs[51])
    out = fe.step(tr.t[52], tr.obs[51])  # frozen sensor: same bytes again
    assert out.stale and out.missing.all() and out.predicting_for_s == pytest.approx(0.01)
    out = fe.step(tr.t[53], None)
    assert out.predicting_for_s == pytest.approx(0.02)
    assert np.all(np.isfinite(out.fork_velocity))


def test_frontend_without_any_measurement_raises_clearly():
    _, std, _, modes = _fitted(0)
    fe = StreamingFrontEnd(std, modes)
    with pytest.raises(ValueError, match="no fork measurement"):
        fe.step(0.0, np.full(9, np.nan))


def test_the_batch_kalman_equals_stepping_the_filter():
    from mpcshare.control.frontend import fork_kalman, kalman_batch

    rng = np.random.default_rng(4)
    Z = np.cumsum(rng.normal(size=(400, 6)), axis=0) * 0.01
    scale = np.array([0.05, 0.05, 0.05, 0.3, 0.3, 2.0])
    kf = fork_kalman(scale, 100.0)
    X, V = kalman_batch(kf, Z)
    ref = fork_kalman(scale, 100.0)
    for i in range(len(Z)):
        ref.step(i * 0.01, Z[i])
        np.testing.assert_allclose(X[i], ref.x, rtol=1e-12, atol=1e-15)
        np.testing.assert_allclose(V[i], ref.v, rtol=1e-9, atol=1e-12)
