"""Windows of data with a hidden regime that the observation does not reveal, for the analysis tests."""

import math

import numpy as np
from scipy import signal


def hidden_regime_data(n_trials: int, T: int, seed: int):
    """Windows whose action map switches between 3 regimes every 10 s while the observation
    (a slow 1-D leader signal through 3 channels) carries no trace of the regime."""
    rng = np.random.default_rng(seed)
    b, a = signal.butter(2, 0.05)
    C = np.array([1.0, -1.0, 0.3])
    X, Y, trial, src, regime, feats = [], [], [], [], [], []
    start = 0
    for k in range(n_trials):
        z = signal.lfilter(b, a, rng.standard_normal(T + 200))[200:]
        z /= z.std()
        s = (np.arange(T) // 100 + k) % 3
        o = np.outer(z, [1.0, 0.5, -0.8]) + rng.normal(0, 0.02, (T, 3))
        u = (C[s] * z)[:, None] + rng.normal(0, 0.02, (T, 1))
        lags = 5
        for t in range(lags - 1, T):
            X.append(o[t - lags + 1:t + 1][::-1].ravel() / math.sqrt(lags))
            Y.append(u[t])
            trial.append(k)
            src.append(start + t)
        regime.append(s)
        feats.append(o)
        start += T
    return (np.array(X), np.array(Y), np.array(trial), np.array(src), np.concatenate(feats),
            np.concatenate(regime))
