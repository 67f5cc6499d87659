"""The predictor's forecast (horizons > 0): what it learns, its stream, persistence, and its scores."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from learning.predictor import ReactivePredictor
from learning.predictor.forecast import forecast_rmse
from learning.predictor.sequences import shifted_targets

SMALL = {"hidden_size": 16, "batch_size": 16, "chunk_len": 25, "burn_in": 10, "max_epochs": 60,
         "patience": 10, "learning_rate": 1e-2}


def oscillators(n_trials: int, T: int, seed: int):
    """Inputs x_t = (sin φ_t, cos φ_t) of an oscillator of per-trial frequency; target y_t = sin φ_t.

    The future of y is a known function of the present input (rotate the phase), so a
    forecast can beat holding y_t; holding cannot."""
    rng = np.random.default_rng(seed)
    xs, ys = [], []
    for _ in range(n_trials):
        w = rng.uniform(0.25, 0.4)  # rad per step
        phi = w * np.arange(T) + rng.uniform(0, 2 * np.pi)
        xs.append(np.column_stack([np.sin(phi), np.cos(phi)]))
        ys.append(np.sin(phi)[:, None])
    return xs, ys


@pytest.fixture(scope="module")
def forecaster():
    xs, ys = oscillators(12, 120, seed=0)
    return ReactivePredictor(**SMALL, horizons=3, seed=0).fit(xs, ys, progress=False)


def test_shifted_targets_repeat_the_last_sample():
    y = np.arange(5.0)[:, None] * np.array([[1.0, 10.0]])
    s = shifted_targets(y, 2)
    assert s.shape == (5, 6)
    np.testing.assert_array_equal(s[0], [0, 0, 1, 10, 2, 20])
    np.testing.assert_array_equal(s[4], [4, 40, 4, 40, 4, 40])


def test_forecast_beats_hold_on_a_predictable_future(forecaster):
    xs, ys = oscillators(4, 120, seed=1)
    F = [forecaster.forecast(x) for x in xs]
    assert F[0].shape == (120, 4, 1)
    np.testing.assert_allclose(F[0][:, 0], forecaster.predict(xs[0]), atol=1e-12)
    res = forecast_rmse(F, ys, [np.arange(120) >= 5 for _ in xs], step_s=0.1)
    assert res["horizons_s"] == [0.0, 0.1, 0.2, 0.3]
    # three steps ahead the phase has turned by ~1 rad: holding errs by ~0.65 RMS
    assert res["hold"][3] > 0.4
    assert res["forecast"][3] < 0.5 * res["hold"][3], res


def test_stream_gives_the_whole_forecast(forecaster):
    xs, _ = oscillators(1, 60, seed=2)
    F = forecaster.forecast(xs[0])
    stream = forecaster.make_stream()
    for t in range(60):
        now = stream.step(xs[0][t])
        np.testing.assert_allclose(now, F[t, 0], atol=1e-5)
        np.testing.assert_allclose(stream.forecast, F[t], atol=1e-5)


def test_forecast_survives_persistence(forecaster):
    clone = ReactivePredictor.from_config(forecaster.get_config()).load_state_dict(forecaster.state_dict())
    xs, _ = oscillators(1, 40, seed=3)
    np.testing.assert_allclose(clone.forecast(xs[0]), forecaster.forecast(xs[0]), atol=1e-5)
    wrong = {**forecaster.state_dict(), "head.weight": torch.zeros(5, 16), "head.bias": torch.zeros(5)}
    with pytest.raises(ValueError, match="multiple of horizons"):
        ReactivePredictor.from_config(forecaster.get_config()).load_state_dict(wrong)


def test_forecast_rmse_against_brute_force():
    rng = np.random.default_rng(0)
    T, H, d = 30, 2, 2
    y = rng.standard_normal((T, d))
    F = rng.standard_normal((T, H + 1, d))
    m = rng.random(T) < 0.7
    res = forecast_rmse([F], [y], [m], step_s=0.5)
    for h in range(H + 1):
        rows = [t for t in range(T - h) if m[t]]
        fc = np.sqrt(np.mean([(F[t, h] - y[t + h]) ** 2 for t in rows]))
        hold = np.sqrt(np.mean([(F[t, 0] - y[t + h]) ** 2 for t in rows]))
        cv = np.sqrt(np.mean([(F[t, 0] + h * (F[t, 0] - F[max(t - 1, 0), 0]) - y[t + h]) ** 2 for t in rows]))
        assert res["forecast"][h] == pytest.approx(fc)
        assert res["hold"][h] == pytest.approx(hold)
        assert res["constant_velocity"][h] == pytest.approx(cv)
        assert res["n_steps"][h] == len(rows)
    assert res["horizons_s"] == [0.0, 0.5, 1.0]


def test_forecast_rmse_errors_name_the_trial():
    with pytest.raises(ValueError, match="trial 0"):
        forecast_rmse([np.zeros((5, 2, 1))], [np.zeros((4, 1))], [np.ones(5, bool)], 0.1)
    with pytest.raises(ValueError, match="one forecast"):
        forecast_rmse([], [], [], 0.1)
    with pytest.raises(ValueError, match="horizons"):
        ReactivePredictor(horizons=-1).fit([np.zeros((5, 1))], [np.zeros((5, 1))])
