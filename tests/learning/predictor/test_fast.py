"""The control-rate forecast's features and ridge correction (learning.predictor.fast)."""

from __future__ import annotations

import numpy as np
import pytest

from learning.predictor.fast import FastForecaster, FastInputStream, fast_design, interpolate_slow


def _trial(T: int = 60, d: int = 3, K: int = 2, H1: int = 4, seed: int = 0):
    rng = np.random.default_rng(seed)
    P, V = rng.normal(size=(T, d)), rng.normal(size=(T, d))
    proba = rng.dirichlet(np.ones(K), size=T)
    slow = rng.normal(size=(T, H1, 3))
    return P, V, proba, slow


def test_the_stream_gives_the_offline_rows():
    P, V, proba, slow = _trial()
    lags = (2, 5)
    offline = fast_design(P, V, proba, slow, lags)
    stream = FastInputStream(lags)
    online = np.array([stream.step(P[i], V[i], proba[i], slow[i]) for i in range(len(P))])
    np.testing.assert_allclose(online, offline, rtol=0, atol=1e-12)
    # a lag before the trial's start reads the first sample: P_0 − P_{−l} = 0 at i = 0
    d, nb = P.shape[1], 1 + P.shape[1] * (2 + len(lags))
    assert np.all(offline[0, 1 + d:1 + 3 * d] == 0.0)
    assert offline.shape[1] == proba.shape[1] * nb + slow.shape[1] * 3


def test_interpolation_reads_the_forecast_between_its_points():
    pts = np.arange(4, dtype=float)[None, :, None] * np.array([1.0, 2.0])[None, None, :]  # value = index·(1, 2)
    out = interpolate_slow(np.repeat(pts, 3, axis=0), np.array([0.0, 0.3, 0.9]))
    np.testing.assert_allclose(out[1, :, 0], [0.3, 1.3, 2.3, 3.0])  # last point held past the end
    np.testing.assert_allclose(out[2, :, 1], [1.8, 3.8, 5.8, 6.0])
    np.testing.assert_allclose(out[0], pts[0])


def test_the_ridge_recovers_a_linear_residual_and_round_trips():
    rng = np.random.default_rng(3)
    n, p, H1 = 400, 7, 3
    phi, slow = rng.normal(size=(n, p)), rng.normal(size=(n, H1, 3))
    W, c = rng.normal(size=(H1 * 3, p)), rng.normal(size=H1 * 3)
    truth = slow + (phi @ W.T + c).reshape(n, H1, 3)
    m = FastForecaster(alpha=0.0, lags=(1,)).fit(phi, slow, truth)
    np.testing.assert_allclose(m.coef_, W, atol=1e-9)
    np.testing.assert_allclose(m.predict(phi, slow), truth, atol=1e-9)
    np.testing.assert_allclose(m.predict_one(phi[7], slow[7]), truth[7], atol=1e-9)
    m.channels_, m.preview_skill_ = ("a", "b", "c"), np.array([[0.0, 0.2, -0.1]])
    back = FastForecaster.from_json(m.to_json())
    np.testing.assert_array_equal(back.predict(phi, slow), m.predict(phi, slow))
    assert back.channels_ == ("a", "b", "c") and back.preview_skill_.tolist() == [[0.0, 0.2, -0.1]]


def test_bad_inputs_are_refused():
    rng = np.random.default_rng(0)
    with pytest.raises(ValueError, match="too few steps"):
        FastForecaster().fit(rng.normal(size=(3, 5)), np.zeros((3, 2, 3)), np.zeros((3, 2, 3)))
    with pytest.raises(ValueError, match="lags"):
        FastForecaster(lags=(0,)).fit(rng.normal(size=(30, 5)), np.zeros((30, 2, 3)), np.zeros((30, 2, 3)))
    m = FastForecaster(alpha=1.0, lags=(1,)).fit(rng.normal(size=(30, 5)), np.zeros((30, 2, 3)),
                                                 rng.normal(size=(30, 2, 3)))
    with pytest.raises(ValueError, match=r"phi must be \(n, 5\)"):
        m.predict(np.zeros((2, 4)), np.zeros((2, 2, 3)))
    bad = m.to_json()
    bad["intercept"] = bad["intercept"][:-1]
    with pytest.raises(ValueError, match="do not fit"):
        FastForecaster.from_json(bad)
