"""Tests of learning.preprocessing.preprocess: downsampling, standardisation, causal windows."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from learning.data import Demonstrations, Trial, split_by_trial
from learning.preprocessing.preprocess import (
    Preprocessor,
    Standardizer,
    causal_windows,
    downsample,
    preprocess,
    window_lags,
)


def make_demos(lengths=(300, 250, 400, 350), rate=100.0, d_o=6, d_u=3, seed=0,
               subjects=None, modes=True) -> Demonstrations:
    rng = np.random.default_rng(seed)
    trials = []
    for i, n in enumerate(lengths):
        trials.append(Trial(obs=rng.normal(size=(n, d_o)) * (1 + np.arange(d_o)) + 3.0,
                            act=rng.normal(size=(n, d_u)) - 2.0, t=np.arange(n) / rate, trial_id=i,
                            subject=(i % 2) if subjects is None else subjects[i],
                            mode=(np.arange(n) // 37) % 4 if modes else None,
                            voluntary=rng.normal(size=(n, 2))))
    return Demonstrations(trials, rate)


def tone_demos(freq_hz: float, T: int = 3000, rate: float = 100.0) -> Demonstrations:
    t = np.arange(T) / rate
    x = np.stack([np.sin(2 * np.pi * freq_hz * t) + 5.0, np.cos(2 * np.pi * freq_hz * t)], axis=1)
    return Demonstrations([Trial(obs=x, act=x[:, :1], t=t, trial_id=0, subject=4,
                                 mode=(t >= 12.34).astype(int))], rate)


# ---------------------------------------------------------------- downsample


def test_downsample_passes_low_frequency_sine() -> None:
    d = downsample(tone_demos(0.3), 10.0)
    tr = d[0]
    assert d.rate_hz == 10.0 and len(tr) == 300
    np.testing.assert_allclose(tr.t, np.arange(300) / 10.0, atol=1e-12)
    ref = np.sin(2 * np.pi * 0.3 * tr.t) + 5.0
    err = np.abs(tr.obs[:, 0] - ref)
    assert err.max() < 0.05  # edges included
    assert err[20:-20].max() < 2e-3  # interior: no delay, no distortion
    assert np.abs(tr.act[:, 0] - ref).max() < 0.05


@pytest.mark.parametrize("freq_hz", [6.0, 7.5, 20.0, 45.0])
def test_downsample_attenuates_tone_above_new_nyquist(freq_hz: float) -> None:
    d = downsample(tone_demos(freq_hz), 10.0)
    x = d[0].obs[20:-20, 1]  # the zero-mean cosine channel
    gain_db = 20 * np.log10(np.sqrt(np.mean(x ** 2)) / np.sqrt(0.5))
    assert gain_db < -20.0


def test_downsample_carries_modes_subject_and_time() -> None:
    src = make_demos()
    d = downsample(src, 10.0)
    assert d.obs_names == src.obs_names and d.trial_ids == src.trial_ids
    for a, b in zip(src, d):
        assert len(b) == -(-len(a) // 10)
        np.testing.assert_array_equal(b.mode, a.mode[::10])
        np.testing.assert_allclose(b.t, a.t[::10])
        assert b.subject == a.subject and b.voluntary.shape == (len(b), 2)
    d.validate()
    assert src.rate_hz == 100.0 and len(src[0]) == 300  # input untouched


def test_downsample_rational_factor() -> None:
    d = downsample(tone_demos(0.5, T=1000), 40.0)  # up/down = 2/5
    tr = d[0]
    assert d.rate_hz == 40.0 and len(tr) == 400
    np.testing.assert_allclose(np.diff(tr.t), 1 / 40.0, atol=1e-12)
    ref = np.sin(2 * np.pi * 0.5 * tr.t) + 5.0
    assert np.abs(tr.obs[10:-10, 0] - ref[10:-10]).max() < 2e-3
    # the mode label switches at 12.34 s → at the nearest kept instant
    src_mode = tone_demos(0.5, T=1000)[0].mode
    np.testing.assert_array_equal(tr.mode, src_mode[np.minimum(np.rint(np.arange(400) * 2.5).astype(int), 999)])


def test_downsample_same_rate_is_a_copy() -> None:
    src = make_demos()
    d = downsample(src, 100.0)
    assert d[0].obs is not src[0].obs
    np.testing.assert_array_equal(d[0].obs, src[0].obs)


def test_downsample_errors() -> None:
    with pytest.raises(ValueError, match="above the data's rate"):
        downsample(make_demos(), 200.0)
    with pytest.raises(ValueError, match="trial 2 has 9 samples"):
        downsample(make_demos(lengths=(300, 200, 9)), 10.0)
    with pytest.raises(ValueError, match="target_hz"):
        downsample(make_demos(), 0.0)


# ------------------------------------------------------------- standardise


def test_channel_standardizer_fitted_on_train_only() -> None:
    d = make_demos()
    train, test = split_by_trial(d, 0.25, seed=1)
    s = Standardizer("channel", field="obs").fit(train)
    x_train = np.concatenate([tr.obs for tr in train])
    np.testing.assert_allclose(s.mean_, x_train.mean(axis=0))
    np.testing.assert_allclose(s.scale_, x_train.std(axis=0))
    z = s.transform(x_train)
    np.testing.assert_allclose(z.mean(axis=0), 0, atol=1e-12)
    np.testing.assert_allclose(z.std(axis=0), 1, atol=1e-12)
    # the test trials are transformed with the training statistics, not their own
    zt = s.transform(test)
    x_test = np.concatenate([tr.obs for tr in test])
    np.testing.assert_allclose(np.concatenate([tr.obs for tr in zt]), (x_test - s.mean_) / s.scale_)
    assert not np.allclose(s.mean_, x_test.mean(axis=0))
    np.testing.assert_allclose(np.concatenate([tr.act for tr in zt]), np.concatenate([tr.act for tr in test]))
    np.testing.assert_allclose(s.inverse_transform(z), x_train)


def test_sensor_scaling_gives_unit_rms_magnitude() -> None:
    rng = np.random.default_rng(3)
    x = np.hstack([rng.normal(size=(500, 3)) * [0.01, 0.02, 0.05] + 0.3,   # position [m]
                   rng.normal(size=(500, 3)) * 0.5,                         # orientation [rad]
                   rng.normal(size=(500, 3)) * [5, 2, 20] - 4])            # force [N]
    s = Standardizer("sensor").fit(x)
    z = s.transform(x)
    np.testing.assert_allclose(z.mean(axis=0), 0, atol=1e-12)
    for g in range(3):
        rms = np.sqrt(np.mean(np.sum(z[:, 3 * g:3 * g + 3] ** 2, axis=1)))
        assert rms == pytest.approx(1.0, rel=1e-12)
    # one scale per sensor: relative magnitudes within a sensor are kept
    assert np.all(s.scale_[0:3] == s.scale_[0]) and np.all(s.scale_[6:9] == s.scale_[6])
    assert z[:, 8].std() > 3 * z[:, 7].std()
    custom = Standardizer("sensor", sensors=[[0, 4], [1, 2, 3], [5, 6, 7, 8]]).fit(x)
    zc = custom.transform(x)
    assert np.sqrt(np.mean(np.sum(zc[:, [0, 4]] ** 2, axis=1))) == pytest.approx(1.0)


def test_standardizer_constant_channel_and_sensor() -> None:
    x = np.ones((50, 4)) * 7.0
    x[:, 1] = np.linspace(0, 1, 50)
    for scope in ("channel", "sensor"):
        s = Standardizer(scope, sensors=2).fit(x)
        z = s.transform(x)
        assert np.isfinite(z).all()
        np.testing.assert_allclose(z[:, [0, 2, 3]], 0.0)
        assert s.scale_[3] == 1.0 and s.scale_[2] == 1.0
        np.testing.assert_allclose(s.inverse_transform(z), x)


def test_standardizer_errors() -> None:
    with pytest.raises(ValueError, match="scope"):
        Standardizer("global")
    with pytest.raises(RuntimeError, match="not fitted"):
        Standardizer().transform(np.zeros((3, 2)))
    s = Standardizer().fit(np.random.default_rng(0).normal(size=(10, 3)))
    with pytest.raises(ValueError, match="expected 3 channels"):
        s.transform(np.zeros((4, 2)))
    with pytest.raises(ValueError, match="partition"):
        Standardizer("sensor", sensors=[[0, 1], [1, 2]]).fit(np.zeros((5, 3)))
    with pytest.raises(ValueError, match="non-finite"):
        Standardizer().fit(np.array([[1.0], [np.nan]]))


# ------------------------------------------------------------------ windows


def labelled_demos(lengths) -> Demonstrations:
    """obs[:, 0] = 1000·trial + sample index, obs[:, 1] = −same: identifies each sample."""
    trials = []
    for i, n in enumerate(lengths):
        code = 1000.0 * i + np.arange(n)
        trials.append(Trial(obs=np.stack([code, -code], axis=1), act=code[:, None] + 0.5,
                            t=np.arange(n) / 10.0, trial_id=i, subject=7 + i, mode=np.arange(n) % 3))
    return Demonstrations(trials, 10.0)


def test_window_lags() -> None:
    assert window_lags(1.0, 10.0) == 10
    assert window_lags(0.0, 10.0) == 1
    assert window_lags(0.04, 10.0) == 1
    assert window_lags(0.26, 10.0) == 3
    with pytest.raises(ValueError):
        window_lags(-1.0, 10.0)


def test_causal_windows_lag_order_and_boundaries() -> None:
    d = labelled_demos((12, 5, 8))
    w = causal_windows(d, 0.4)  # L = 4
    assert w.lags == 4 and w.obs_dim == 2
    assert len(w) == (12 - 3) + (5 - 3) + (8 - 3)
    assert w.X.shape == (len(w), 8) and w.Y.shape == (len(w), 1)
    code_t = w.Y[:, 0] - 0.5  # the code of the sample at t
    for l in range(4):
        np.testing.assert_array_equal(w.lag(l)[:, 0], code_t - l)          # o_{t−l}, lag-major
        np.testing.assert_array_equal(w.X[:, 2 * l + 1], -(code_t - l))
    # a window never mixes trials: every lag's trial code equals the row's trial
    for l in range(4):
        np.testing.assert_array_equal(w.lag(l)[:, 0] // 1000, w.trial)
    np.testing.assert_array_equal(w.trial, np.repeat([0, 1, 2], [9, 2, 5]))
    np.testing.assert_array_equal(w.subject, w.trial + 7)
    stacked = d.stacked()
    np.testing.assert_array_equal(stacked["obs"][w.source_index], w.lag(0))
    np.testing.assert_array_equal(stacked["mode"][w.source_index], w.mode)
    np.testing.assert_allclose(stacked["t"][w.source_index], w.t)
    assert w.t[0] == pytest.approx(0.3)  # the first L−1 samples are dropped
    assert w.voluntary is None


def test_causal_windows_single_lag_keeps_everything() -> None:
    d = labelled_demos((4, 3))
    w = causal_windows(d, 0.0)
    assert w.lags == 1 and len(w) == 7
    np.testing.assert_array_equal(w.X, d.stacked()["obs"])


def test_causal_windows_short_trials() -> None:
    d = labelled_demos((12, 3, 8))
    with pytest.warns(UserWarning, match=r"1 trial\(s\) shorter .* skipped: \[1\]"):
        w = causal_windows(d, 0.5)
    assert set(w.trial.tolist()) == {0, 2}
    np.testing.assert_array_equal(d.stacked()["obs"][w.source_index], w.lag(0))
    with pytest.raises(ValueError, match="no trial is long enough"):
        causal_windows(labelled_demos((3, 4)), 1.0)


@settings(max_examples=40, deadline=None)
@given(lengths=st.lists(st.integers(2, 30), min_size=1, max_size=5), L=st.integers(1, 8))
def test_causal_windows_property(lengths, L) -> None:
    d = labelled_demos(lengths)
    if max(lengths) < L:
        with pytest.raises(ValueError):
            causal_windows(d, L / 10.0)
        return
    import warnings
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        w = causal_windows(d, L / 10.0)
    assert len(w) == sum(max(0, n - L + 1) for n in lengths)
    stacked_obs = d.stacked()["obs"]
    for l in range(L):
        np.testing.assert_array_equal(w.lag(l), stacked_obs[w.source_index - l])
        np.testing.assert_array_equal(w.lag(l)[:, 0] // 1000, w.trial)


# ---------------------------------------------------------------- pipeline


def test_preprocess_pipeline_and_reuse() -> None:
    d = make_demos()
    train, test = split_by_trial(d, 0.25, seed=0)
    w, pre = preprocess(train, target_hz=10.0, window_s=1.0)
    assert isinstance(pre, Preprocessor)
    assert w.lags == 10 and w.X.shape[1] == 6 * 10 and w.Y.shape[1] == 3
    assert w.rate_hz == 10.0
    low = downsample(train, 10.0)
    np.testing.assert_allclose(pre.obs.mean_, np.concatenate([tr.obs for tr in low]).mean(axis=0))
    np.testing.assert_allclose(pre.act.mean_, np.concatenate([tr.act for tr in low]).mean(axis=0))
    # Y is the standardised action at t
    np.testing.assert_allclose(w.Y, (low.stacked()["act"][w.source_index] - pre.act.mean_) / pre.act.scale_)
    np.testing.assert_allclose(w.lag(0), (low.stacked()["obs"][w.source_index] - pre.obs.mean_) / pre.obs.scale_)
    # the test set goes through the same fitted scalers
    wt, pre2 = preprocess(test, standardizer=pre)
    assert pre2 is pre
    wt2 = pre.transform(test)
    np.testing.assert_array_equal(wt.X, wt2.X)
    np.testing.assert_array_equal(wt.Y, wt2.Y)
    assert set(wt.trial.tolist()) == set(test.trial_ids)
    with pytest.raises(TypeError):
        preprocess(test, standardizer=Standardizer())


def test_preprocess_sensor_scope() -> None:
    w, pre = preprocess(make_demos(), scope="sensor", window_s=0.5)
    assert pre.obs.scope == "sensor" and w.lags == 5
    assert len(pre.obs.groups_) == 2 and len(pre.act.groups_) == 1
