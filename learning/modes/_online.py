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
from dataclasses import dataclass, fields
from typing import Any

import numpy as np
from scipy import linalg

__all__ = ["HMMFilterParams", "ModeFilter", "forward_filter_log"]


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


def _frozen(name: str, value: Any, shape: tuple[int | None, ...]) -> np.ndarray:
    """A read-only float64 copy of ``value`` with the given shape (None = any size)."""
    a = np.array(value, dtype=float)
    if a.ndim != len(shape) or any(n is not None and n != m for n, m in zip(shape, a.shape)):
        want = "(" + ", ".join("?" if n is None else str(n) for n in shape) + ")"
        raise ValueError(f"HMMFilterParams.{name} must have shape {want}, got {a.shape}")
    if not np.isfinite(a).all():
        raise ValueError(f"HMMFilterParams.{name} contains NaN or inf")
    a.setflags(write=False)
    return a


@dataclass(frozen=True)
class HMMFilterParams:
    """A fitted task-mode HMM as plain read-only arrays: what :class:`ModeFilter` needs.

    The observation model is z = PCA(standardise(o)), b_j(o) = N(z; μ_j, Σ_j):
    ``(o − scaler_mean) / scaler_scale``, then, if ``pca_components`` is given,
    ``(· − pca_mean) @ pca_componentsᵀ``.

    Attributes:
        startprob: (K,) π.  transmat: (K, K) A, rows sum to 1.
        means: (K, D) μ_j.  covars: (K, D, D) full covariance matrices Σ_j.
        scaler_mean, scaler_scale: (D_in,) standardisation of the raw observation.
        pca_mean: (D_in,) or None.  pca_components: (D, D_in) or None (then D = D_in).
    """

    startprob: np.ndarray
    transmat: np.ndarray
    means: np.ndarray
    covars: np.ndarray
    scaler_mean: np.ndarray
    scaler_scale: np.ndarray
    pca_mean: np.ndarray | None = None
    pca_components: np.ndarray | None = None

    def __post_init__(self) -> None:
        K = np.shape(self.startprob)[0] if np.ndim(self.startprob) == 1 else None
        means = _frozen("means", self.means, (K, None))
        K, D = means.shape
        def set_(name: str, value: object) -> None:
            object.__setattr__(self, name, value)

        set_("means", means)
        set_("startprob", _frozen("startprob", self.startprob, (K,)))
        set_("transmat", _frozen("transmat", self.transmat, (K, K)))
        set_("covars", _frozen("covars", self.covars, (K, D, D)))
        D_in = np.shape(self.scaler_mean)[0] if np.ndim(self.scaler_mean) == 1 else None
        set_("scaler_mean", _frozen("scaler_mean", self.scaler_mean, (D_in,)))
        D_in = self.scaler_mean.shape[0]
        set_("scaler_scale", _frozen("scaler_scale", self.scaler_scale, (D_in,)))
        if (self.pca_mean is None) != (self.pca_components is None):
            raise ValueError("HMMFilterParams: pca_mean and pca_components go together (both or none)")
        if self.pca_components is not None:
            set_("pca_mean", _frozen("pca_mean", self.pca_mean, (D_in,)))
            set_("pca_components", _frozen("pca_components", self.pca_components, (D, D_in)))
        elif D != D_in:
            raise ValueError(f"HMMFilterParams: means have {D} features but the scaler {D_in} "
                             "(and no PCA maps one onto the other)")
        if (self.scaler_scale <= 0).any():
            raise ValueError("HMMFilterParams.scaler_scale must be > 0")
        for name, p in (("startprob", self.startprob), ("transmat", self.transmat)):
            if (p < 0).any() or not np.allclose(p.sum(axis=-1), 1.0, atol=1e-8):
                raise ValueError(f"HMMFilterParams.{name} must be probabilities summing to 1 per row")

    @property
    def n_modes(self) -> int:
        return int(self.means.shape[0])

    @property
    def n_features_in(self) -> int:
        return int(self.scaler_mean.shape[0])

    def to_dict(self) -> dict[str, np.ndarray]:
        """The arrays by field name (fields that are None left out), e.g. for ``np.savez``."""
        return {f.name: getattr(self, f.name) for f in fields(self) if getattr(self, f.name) is not None}

    @classmethod
    def from_dict(cls, arrays: dict[str, Any]) -> HMMFilterParams:
        """Inverse of :meth:`to_dict`; unknown keys are an error naming them."""
        names = {f.name for f in fields(cls)}
        unknown = sorted(set(arrays) - names)
        if unknown:
            raise ValueError(f"HMMFilterParams: unknown field(s) {unknown} (fields: {sorted(names)})")
        return cls(**{k: arrays[k] for k in arrays})


class ModeFilter:
    """Online, causal task-mode posterior for the control loop.

    Built from a fitted :class:`~learning.modes.TaskModes` (``ModeFilter(modes)`` or
    ``modes.make_filter()``) or directly from its :class:`HMMFilterParams`
    (``ModeFilter(params)``, e.g. from a model bundle); ``params`` keeps them.

    ``step(o)`` runs one step of the forward recursion (module docstring) on one raw
    observation ``o`` (the same features ``TaskModes.fit`` saw, before scaling): it applies
    the fitted scaler and PCA, evaluates the K Gaussian log densities through Cholesky
    factors precomputed here, and updates the posterior: O(K² + K·D·D_in) per step
    (D = model dimension after PCA; scaler, PCA and each L_j⁻¹ are folded into one
    D_in × K·D matrix at construction), no hmmlearn call. The result equals
    ``TaskModes.filter_proba`` on the same prefix.

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

    def __init__(self, modes: Any, fixed_lag: int = 0) -> None:
        params = modes if isinstance(modes, HMMFilterParams) else None
        if params is None:
            if not hasattr(modes, "filter_params"):
                raise TypeError("ModeFilter needs a fitted TaskModes or an HMMFilterParams, got "
                                f"{type(modes).__name__}")
            params = modes.filter_params()  # raises NotFittedError if not fitted
        if int(fixed_lag) != fixed_lag or fixed_lag < 0:
            raise ValueError(f"fixed_lag must be a non-negative integer, got {fixed_lag!r}")
        self.params = params
        self.fixed_lag = int(fixed_lag)
        K = params.n_modes
        self.n_modes = K
        self.n_features_in = params.n_features_in

        # Preprocessing as one affine map: z = ((o - m) / s - c_pca) @ Vᵀ  →  z = (o - m) @ P - c.
        P = np.diag(1.0 / params.scaler_scale)
        c = np.zeros(self.n_features_in)
        if params.pca_components is not None:
            c = params.pca_mean @ params.pca_components.T
            P = P @ params.pca_components.T
        Dz = P.shape[1]
        self._dz = Dz
        # Emissions: log b_j = −½(Dz log 2π + log|Σ_j|) − ½‖L_j⁻¹(z − μ_j)‖², Σ_j = L_j L_jᵀ.
        covars = params.covars
        G = np.empty((self.n_features_in, K * Dz))
        h = np.empty(K * Dz)
        lognorm = np.empty(K)
        for j in range(K):
            L = linalg.cholesky(covars[j], lower=True)
            Linv = linalg.solve_triangular(L, np.eye(Dz), lower=True)
            G[:, j * Dz:(j + 1) * Dz] = P @ Linv.T
            h[j * Dz:(j + 1) * Dz] = Linv @ (c + params.means[j])
            lognorm[j] = -0.5 * (Dz * np.log(2 * np.pi)) - np.log(np.diag(L)).sum()
        self._center = np.array(params.scaler_mean)
        self._G, self._h, self._lognorm = G, h, lognorm
        self._A = np.array(params.transmat)
        self._pi = np.array(params.startprob)
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
