"""Trials sampled from a known Gaussian HMM, and a plain hmmlearn copy of a fitted TaskModes (learning.modes tests)."""

from __future__ import annotations

import numpy as np
from hmmlearn.hmm import GaussianHMM

from learning.modes import TaskModes


def sample_hmm(K: int = 4, D: int = 9, n_trials: int = 6, T: int = 400, seed: int = 0,
               sep: float = 3.0, stay: float = 0.97) -> tuple[np.ndarray, np.ndarray, list[int]]:
    """Trials sampled from a known Gaussian HMM (numpy only): X (N, D), states (N,), lengths."""
    rng = np.random.default_rng(seed)
    means = rng.standard_normal((K, D)) * sep
    chols = []
    for _ in range(K):
        Q = rng.standard_normal((D, D)) * 0.3
        chols.append(np.linalg.cholesky(Q @ Q.T + 0.5 * np.eye(D)))
    chols = np.array(chols)
    A = np.full((K, K), (1 - stay) / (K - 1))
    np.fill_diagonal(A, stay)
    Xs, Ss = [], []
    for _ in range(n_trials):
        s = np.empty(T, dtype=int)
        s[0] = rng.integers(K)
        for t in range(1, T):
            s[t] = rng.choice(K, p=A[s[t - 1]])
        Xs.append(means[s] + np.einsum("tij,tj->ti", chols[s], rng.standard_normal((T, D))))
        Ss.append(s)
    return np.concatenate(Xs), np.concatenate(Ss), [T] * n_trials


def vanilla_hmm(m: TaskModes) -> GaussianHMM:
    """A plain hmmlearn GaussianHMM with the fitted parameters (independent reference)."""
    ref = GaussianHMM(m.model_.n_components, "full")
    ref.startprob_ = m.model_.startprob_
    ref.transmat_ = m.model_.transmat_
    ref.means_ = m.model_.means_
    ref.covars_ = m.model_.covars_
    ref.n_features = m.n_components_
    return ref
