"""Causal (filtered) task-mode estimation: offline over whole trials and online per sample.

hmmlearn only runs the forward pass over complete sequences (and only returns
smoothed posteriors), so the causal filter and the streaming :class:`ModeFilter`
are written here. Notation: K modes, start probabilities π, transitions
A_ij = p(s_t = j | s_{t-1} = i), emission densities b_j(o) = N(z(o); μ_j, Σ_j) on
the standardised (and PCA-projected) observation z(o).

Forward recursion, normalised, in log space::

    log α̂_0(j) = log π_j + log b_j(o_0)
    log α̂_t(j) = log b_j(o_t) + log Σ_i p(s_{t-1}=i | o_<t) A_ij
    log p(o_t | o_<t) = logsumexp_j log α̂_t(j)                 (log predictive)
    p(s_t = j | o_≤t) = exp(log α̂_t(j) − log p(o_t | o_<t))    (filtered posterior)

so Σ_t log p(o_t | o_<t) = log p(o_0..o_T), hmmlearn's ``score``.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np
from scipy import linalg

if TYPE_CHECKING:  # pragma: no cover
    from .modes import TaskModes

__all__ = ["ModeFilter", "forward_filter_log"]


def _logsumexp_rows(M: np.ndarray, axis: int) -> np.ndarray:
    """log Σ exp(M) along ``axis``; -inf where every entry is -inf."""
    m = M.max(axis=axis, keepdims=True)
    m = np.where(np.isfinite(m), m, 0.0)
    with np.errstate(divide="ignore"):
        return np.log(np.exp(M - m).sum(axis=axis)) + np.squeeze(m, axis=axis)


def forward_filter_log(log_startprob: np.ndarray, log_transmat: np.ndarray,
                       log_emission: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Filtered log posteriors and log predictives of ONE sequence (pure log space).

    Args:
        log_startprob: (K,) log π.
        log_transmat: (K, K) log A (may hold -inf).
        log_emission: (T, K) log b_j(o_t).
    Returns:
        log_post (T, K): log p(s_t = j | o_0..o_t); log_pred (T,): log p(o_t | o_0..o_{t-1}).
    """
    T, K = log_emission.shape
    log_post = np.empty((T, K))
    log_pred = np.empty(T)
    log_prior = log_startprob
    for t in range(T):
        lj = log_prior + log_emission[t]
        c = _logsumexp_rows(lj[None, :], axis=1)[0]
        log_pred[t] = c
        log_post[t] = lj - c
        # log Σ_i p(s_t = i | o_≤t) A_ij
        log_prior = _logsumexp_rows(log_post[t][:, None] + log_transmat, axis=0)
    return log_post, log_pred


def _full_covars(c: np.ndarray, covariance_type: str, K: int, D: int) -> np.ndarray:
    """(K, D, D) covariance matrices from hmmlearn's compact ``_covars_``."""
    if covariance_type == "full":
        return c.reshape(K, D, D)
    if covariance_type == "tied":
        return np.broadcast_to(c.reshape(D, D), (K, D, D))
    if covariance_type == "diag":
        return c.reshape(K, D)[:, :, None] * np.eye(D)
    return np.broadcast_to(c.reshape(K, -1)[:, :1], (K, D))[:, :, None] * np.eye(D)


class ModeFilter:
    """Online, causal task-mode posterior for the control loop.

    ``step(o)`` runs one step of the forward recursion (module docstring) on one raw
    observation ``o`` (the same features ``TaskModes.fit`` saw, before scaling): it applies
    the fitted scaler and PCA, evaluates the K Gaussian log densities through Cholesky
    factors precomputed here, and updates the posterior: O(K² + K·D·D_in) per step
    (D = model dimension after PCA; scaler, PCA and each L_j⁻¹ are folded into one
    D_in × K·D matrix at construction), no hmmlearn call. The result equals ``TaskModes.filter_proba`` on the same prefix.

    With ``fixed_lag = L > 0``, ``step`` returns the fixed-lag smoothed posterior
    p(s_{t−L} | o_0..o_t) (a backward pass over the last L steps, O(L·K²) more); during the
    first L steps of a trial it returns p(s_0 | o_0..o_t). ``posterior_time`` says which
    time index the returned posterior is about; ``filtered`` always holds p(s_t | o_0..o_t).

    Attributes (after each ``step``):
        log_predictive: log p(o_t | o_0..o_{t−1}) — a novelty score: very low values flag an
            observation unlike anything in the training data.
        filtered: (K,) causal posterior of the current step.
        posterior: (K,) what ``step`` returned last.
        posterior_time: time index of ``posterior`` (t − L, or 0 early on).
        n_steps: number of observations since ``reset``.
    """

    def __init__(self, modes: "TaskModes", fixed_lag: int = 0) -> None:
        from sklearn.utils.validation import check_is_fitted

        check_is_fitted(modes, "model_")
        if int(fixed_lag) != fixed_lag or fixed_lag < 0:
            raise ValueError(f"fixed_lag must be a non-negative integer, got {fixed_lag!r}")
        self.fixed_lag = int(fixed_lag)
        hmm = modes.model_
        K = int(hmm.n_components)
        self.n_modes = K
        self.n_features_in = int(modes.n_features_in_)

        # Preprocessing as one affine map: z = ((o - m) / s - c_pca) @ Vᵀ  →  z = (o - m) @ P - c.
        scaler = modes.scaler_
        P = np.diag(1.0 / scaler.scale_)
        c = np.zeros(self.n_features_in)
        if modes.pca_ is not None:
            c = modes.pca_.mean_ @ modes.pca_.components_.T
            P = P @ modes.pca_.components_.T
        Dz = P.shape[1]
        self._dz = Dz
        # Emissions: log b_j = −½(Dz log 2π + log|Σ_j|) − ½‖L_j⁻¹(z − μ_j)‖², Σ_j = L_j L_jᵀ.
        covars = _full_covars(np.asarray(hmm._covars_, dtype=float), hmm.covariance_type, K, Dz)
        G = np.empty((self.n_features_in, K * Dz))
        h = np.empty(K * Dz)
        lognorm = np.empty(K)
        for j in range(K):
            L = linalg.cholesky(covars[j], lower=True)
            Linv = linalg.solve_triangular(L, np.eye(Dz), lower=True)
            G[:, j * Dz:(j + 1) * Dz] = P @ Linv.T
            h[j * Dz:(j + 1) * Dz] = Linv @ (c + hmm.means_[j])
            lognorm[j] = -0.5 * (Dz * np.log(2 * np.pi)) - np.log(np.diag(L)).sum()
        self._center = np.array(scaler.mean_, dtype=float)
        self._G, self._h, self._lognorm = G, h, lognorm
        self._A = np.array(hmm.transmat_, dtype=float)
        self._pi = np.array(hmm.startprob_, dtype=float)
        with np.errstate(divide="ignore"):
            self._logA = np.log(self._A)
        self._has_zeros = bool((self._A <= 0).any() or (self._pi <= 0).any())
        self.reset()

    def reset(self) -> None:
        """Forget the past: the next ``step`` is the first sample of a trial."""
        K, L = self.n_modes, self.fixed_lag
        self.n_steps = 0
        self.log_predictive = float("nan")
        self.filtered = self._pi.copy()
        self.posterior = self._pi.copy()
        self.posterior_time = -1
        if L:
            self._buf_logpost = np.zeros((L + 1, K))  # log p(s_τ | o_≤τ), τ = t−L..t
            self._buf_logb = np.zeros((L + 1, K))     # log b(o_τ), τ = t−L..t

    def log_emission(self, o: np.ndarray) -> np.ndarray:
        """(K,) log b_j(o) for one raw observation (no state change)."""
        x = np.asarray(o, dtype=float)
        if x.shape != self._center.shape:
            raise ValueError(f"observation has shape {x.shape}, expected ({self.n_features_in},)")
        y = ((x - self._center) @ self._G - self._h).reshape(self.n_modes, self._dz)
        return self._lognorm - 0.5 * np.einsum("kd,kd->k", y, y)

    def step(self, o: np.ndarray) -> np.ndarray:
        """Absorb one raw observation; return the (K,) mode posterior (see class docstring)."""
        logb = self.log_emission(o)
        prior = self._pi if self.n_steps == 0 else self.filtered @ self._A
        if self._has_zeros:
            with np.errstate(divide="ignore"):
                lj = np.log(prior) + logb
        else:
            lj = np.log(prior) + logb
        m = lj.max()
        if not math.isfinite(m):
            raise ValueError("observation gives a non-finite likelihood "
                             "(NaN/inf in the observation, or numerically impossible under every mode)")
        e = np.exp(lj - m)
        s = e.sum()
        self.log_predictive = float(m + math.log(s))
        post = e / s
        self.filtered = post
        t = self.n_steps
        self.n_steps = t + 1
        L = self.fixed_lag
        if not L:
            self.posterior, self.posterior_time = post, t
            return post
        return self._smooth(lj - self.log_predictive, logb, t)

    def _smooth(self, log_post: np.ndarray, logb: np.ndarray, t: int) -> np.ndarray:
        """Fixed-lag posterior p(s_τ | o_0..o_t), τ = max(t − L, 0), by a backward pass.

        log β_t = 0;  log β_τ(i) = logsumexp_j [log A_ij + log b_j(o_{τ+1}) + log β_{τ+1}(j)];
        p(s_τ | o_≤t) ∝ p(s_τ | o_≤τ) β_τ.
        """
        L = self.fixed_lag
        lp, lb = self._buf_logpost, self._buf_logb
        if t >= L + 1:  # buffers full: shift one step
            lp[:-1] = lp[1:]
            lb[:-1] = lb[1:]
        i_now = min(t, L)
        lp[i_now] = log_post
        lb[i_now] = logb
        log_beta = np.zeros(self.n_modes)
        for i in range(i_now - 1, -1, -1):  # τ = t−1 … max(t−L, 0)
            M = self._logA + (lb[i + 1] + log_beta)
            mx = M.max(axis=1)
            log_beta = np.log(np.exp(M - mx[:, None]).sum(axis=1)) + mx
            log_beta -= log_beta.max()
        g = lp[0] + log_beta
        g = np.exp(g - g.max())
        post = g / g.sum()
        self.posterior, self.posterior_time = post, t - i_now
        return post
