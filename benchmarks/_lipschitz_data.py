"""The data sets of benchmarks/bench_lipschitz.py: smooth windowed trials, the eating demonstrations, iid Gaussians."""

from __future__ import annotations

import math

import numpy as np


def smooth_signals(rng: np.random.Generator, T: int, channels: int, rate_hz: float = 10.0,
                   n_sin: int = 3) -> np.ndarray:
    """(T, channels) sums of ``n_sin`` random sinusoids (0.05–1 Hz), amplitude ~1."""
    t = np.arange(T) / rate_hz
    f = rng.uniform(0.05, 1.0, size=(channels, n_sin))
    ph = rng.uniform(0, 2 * np.pi, size=(channels, n_sin))
    amp = rng.uniform(0.3, 1.0, size=(channels, n_sin))
    return (amp[None] * np.sin(2 * np.pi * f[None] * t[:, None, None] + ph[None])).sum(-1)


def lowpass_noise(rng: np.random.Generator, T: int, channels: int, alpha: float = 0.8
                  ) -> np.ndarray:
    """(T, channels) first-order low-pass filtered white noise, unit input variance."""
    e = rng.normal(size=(T, channels))
    out = np.empty_like(e)
    out[0] = e[0]
    for k in range(1, T):
        out[k] = alpha * out[k - 1] + (1 - alpha) * e[k]
    return out


def windowed_data(n: int, d: int, dy: int, seed: int, trial_len: int = 600, lags: int = 10,
                  latent: int = 3, noise: float = 0.05) -> tuple[np.ndarray, np.ndarray]:
    """Causal windows (o_t, o_{t−1}, …) of smooth trials and partly predictable outputs.

    Each trial: ``latent`` smooth motions (sums of sinusoids) drive the
    ⌈d/lags⌉ observed channels through a fixed random mixing and a tanh (the
    channels of a fork's pose and force move together), plus low-pass sensor
    noise of relative size ``noise``. Outputs: a smooth function of the window
    (reactive part) plus 0.3 × an independent smooth signal (voluntary part).
    """
    rng = np.random.default_rng(seed)
    ch = math.ceil(d / lags)
    per = trial_len - lags + 1
    n_trials = math.ceil(n / per)
    mix = rng.normal(size=(latent, ch)) / np.sqrt(latent)
    Wmix = rng.normal(size=(ch * lags, dy)) / np.sqrt(ch * lags)
    Xs, Ys = [], []
    for _ in range(n_trials):
        lat = smooth_signals(rng, trial_len, latent)
        o = np.tanh(lat @ mix) + noise * lowpass_noise(rng, trial_len, ch) * 3.0
        win = np.stack([o[lags - 1 - k: trial_len - k] for k in range(lags)], axis=1)
        win = win.reshape(per, ch * lags)  # row t: o_t, o_{t-1}, ..., o_{t-lags+1}
        react = np.tanh(win @ Wmix * 2.0)
        vol = smooth_signals(rng, per, dy)
        Xs.append(win[:, :d])
        Ys.append(react + 0.3 * vol)
    X = np.concatenate(Xs)[:n]
    Y = np.concatenate(Ys)[:n]
    X = (X - X.mean(0)) / X.std(0)
    Y = (Y - Y.mean(0)) / Y.std(0)
    return X, Y


def demo_data(n: int, seed: int, subjects: int = 3) -> tuple[np.ndarray, np.ndarray]:
    """The synthetic eating demonstrations, preprocessed exactly as ``mpcshare analyze``
    does by default (10 Hz, per-sensor scaling, 1 s causal √L-normalised windows):
    d = 90, d_y = 9; the first ``n`` windows of enough minutes per subject."""
    from learning.preprocessing.preprocess import Standardizer, causal_windows, downsample
    from sim.demonstrator import generate_demonstrations

    minutes = math.ceil(n / (subjects * 600 * 0.98)) + 1  # 600 windows a minute, less trial edges
    low = downsample(generate_demonstrations(subjects, minutes, seed=seed), 10.0)
    std = Standardizer("sensor", field="act").fit_transform(
        Standardizer("sensor", field="obs").fit_transform(low))
    w = causal_windows(std, 1.0, rms=True)
    if len(w) < n:  # pragma: no cover - the estimate above has a margin
        raise RuntimeError(f"demonstrations gave {len(w)} windows, fewer than --n {n}")
    return np.ascontiguousarray(w.X[:n]), np.ascontiguousarray(w.Y[:n])


def iid_data(n: int, d: int, dy: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    return rng.normal(size=(n, d)), rng.normal(size=(n, dy))
