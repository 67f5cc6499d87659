import numpy as np
import pytest

from learning.preprocessing.resample import (
    StreamingDecimator,
    causal_downsample,
    decimation_factor,
    lowpass_sos,
)
from sim.demonstrator import generate_demonstrations


def test_streaming_equals_offline_on_a_recorded_trial():
    demos = generate_demonstrations(1, 1.0, seed=3)
    low = causal_downsample(demos, 10.0)
    tr, lo = demos.trials[0], low.trials[0]
    dec = StreamingDecimator(demos.rate_hz, 10.0, demos.obs_dim)
    kept = [y for y in (dec.push(x) for x in tr.obs) if y is not None]
    np.testing.assert_allclose(np.array(kept), lo.obs, rtol=0, atol=1e-9)
    np.testing.assert_array_equal(lo.t, tr.t[::10])
    assert low.rate_hz == 10.0


def test_filter_is_causal_and_attenuates_above_new_nyquist():
    rate, target = 100.0, 10.0
    t = np.arange(2000) / rate
    x = np.sin(2 * np.pi * 8.0 * t)[:, None]  # 8 Hz: above the 5 Hz Nyquist of 10 Hz
    sos = lowpass_sos(rate, target)
    from scipy import signal
    _, h = signal.sosfreqz(sos, worN=[1.0, 8.0], fs=rate)
    assert abs(h[0]) > 0.95 and abs(h[1]) < 0.1
    dec = StreamingDecimator(rate, target, 1)
    y = np.array([v for v in (dec.push(s) for s in x) if v is not None])
    assert np.max(np.abs(y[20:])) < 0.1
    # causality: changing the future does not change the past
    x2 = x.copy()
    x2[1000:] = 5.0
    dec2 = StreamingDecimator(rate, target, 1)
    y2 = np.array([v for v in (dec2.push(s) for s in x2) if v is not None])
    np.testing.assert_array_equal(y[:100], y2[:100])


def test_bad_factors_are_refused():
    with pytest.raises(ValueError, match="integer factor"):
        decimation_factor(100.0, 30.0)
    with pytest.raises(ValueError, match="integer factor"):
        decimation_factor(10.0, 100.0)
    dec = StreamingDecimator(100.0, 10.0, 3)
    with pytest.raises(ValueError, match="shape"):
        dec.push(np.zeros(2))


def test_zero_phase_actions_have_no_delay_while_obs_stay_causal():
    demos = generate_demonstrations(1, 1.0, seed=5)
    causal = causal_downsample(demos, 10.0)
    zero = causal_downsample(demos, 10.0, zero_phase_act=True)
    raw = demos.trials[0].act[::10]
    err_causal = np.sqrt(np.mean((causal.trials[0].act - raw) ** 2))
    err_zero = np.sqrt(np.mean((zero.trials[0].act - raw) ** 2))
    assert err_zero < 0.5 * err_causal  # the causal filter's delay is gone
    np.testing.assert_array_equal(zero.trials[0].obs, causal.trials[0].obs)  # inputs unchanged (causal)
